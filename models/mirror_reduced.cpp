#include "models/mirror_reduced.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "src/core/memo.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim {

namespace {

[[noreturn]] void asymmetric(const std::string& what) {
  throw std::invalid_argument("not mirror-symmetric: " + what);
}

double component(Vec3 p, int c) { return c == 0 ? p.x : (c == 1 ? p.y : p.z); }

bool close(Vec3 a, Vec3 b, double tol) {
  return std::abs(a.x - b.x) <= tol && std::abs(a.y - b.y) <= tol && std::abs(a.z - b.z) <= tol;
}

bool same_value(double a, double b) { return std::abs(a - b) <= 1e-12 * std::abs(a); }

}  // namespace

// The integer part of a reduction: a pure function of its key (the image maps, the pinned
// particles, the springs' ends, each particle's sides of the mirrors), shared by every network
// with that key whatever its values.
struct MirrorReduced::Structure {
  // The key.
  std::vector<int> image_x, image_y, image_d, pinned, ends;  // ends: a, b per spring
  std::vector<unsigned char> sides;                          // per particle: side_bits
  // q entries and the domain's free particles (layouts as in the header comment).
  int group_order = 2;
  std::vector<int> q_particle;       // q entry -> its domain particle
  std::vector<int> full_dof;         // q entry -> full free dof
  std::vector<int> coordinate;       // q entry -> 0, 1, 2 (x, y, z)
  std::vector<double> multiplicity;  // q entry -> coordinates of its particle tied to it
  std::vector<int> particle_begin;   // q entries of domain free particle r: [begin r, begin r+1)
  std::vector<double> weight;        // per domain free particle: w_p
  // The tie x_full[k] = tie_sign[k] q[tie_dof[k]] + offset(k) of every full free dof k; the
  // offset is a function of the planes (tie_offsets).
  std::vector<int> tie_dof;
  std::vector<double> tie_sign;
  std::vector<int> tie_source;             // 3 d + src: the domain coordinate k copies
  std::vector<unsigned char> tie_element;  // g with p = g(d)
  std::vector<unsigned char> source_base;  // per 3 d + c: Base of that domain coordinate
  // The reduced network: its particles (domain, then ghosts), pins and springs.
  std::vector<int> net_full;                  // reduced network particle -> full particle
  std::vector<int> net_pinned, net_pin_slot;  // its pinned particles, their full pin slots
  std::vector<int> net_ends, net_source;      // per reduced spring: its ends, its full spring
  std::vector<double> net_weight;             // per reduced spring: w_s = |O| / |G|
  // The spring orbits, for the value checks: per orbit its first spring and the spring image
  // g(s) for every g.
  std::vector<int> orbit_first, orbit_images;
  std::vector<int> net_full_dof;  // reduced network free dof -> full free dof
  CscPattern pattern;             // of dF/dq
  std::vector<int> jac_target;    // per reduced network nnz: q pattern position or -1

  // The base of a domain coordinate: 0, held on its plane, or tied to x by the diagonal.
  enum Base : unsigned char { kZero, kPlane, kDiagonal };
  int image(int g, int p) const {  // g: bit 0 X, bit 1 Y, bit 2 D; Y^(bit 1) X^(bit 0) D^(bit 2)
    if (g & 4) p = image_d[p];
    if (g & 1) p = image_x[p];
    if (g & 2) p = image_y[p];
    return p;
  }
  std::size_t footprint() const;  // the integers it holds (doubles count 2)
};

namespace {

// Which side of each mirror p lies on: bit 0 beyond the x plane, bit 1 beyond the y plane, bit
// 2 above the diagonal (y - c_y > x - c_x). The fold into the domain reads only these.
unsigned char side_bits(Vec3 p, const MirrorPlanes& planes) {
  return static_cast<unsigned char>((p.x > planes.x_plane) | (p.y > planes.y_plane) << 1 |
                                    (p.y - planes.y_plane > p.x - planes.x_plane) << 2);
}

// Whether `e` is the structure of (spec, planes): its key compared in place.
bool same_key(const MirrorReduced::Structure& e, const SpringNetworkSpec& spec,
              const MirrorPlanes& planes) {
  if (e.sides.size() != spec.positions.size() || e.ends.size() != 2 * spec.springs.size() ||
      e.image_x != planes.image_x || e.image_y != planes.image_y || e.image_d != planes.image_d ||
      e.pinned != spec.pinned)
    return false;
  for (std::size_t s = 0; s < spec.springs.size(); ++s)
    if (e.ends[2 * s] != spec.springs[s].a || e.ends[2 * s + 1] != spec.springs[s].b) return false;
  for (std::size_t p = 0; p < spec.positions.size(); ++p)
    if (e.sides[p] != side_bits(spec.positions[p], planes)) return false;
  return true;
}

// The mirrors' group acting on positions, as Structure::image on particles.
Vec3 mirror(Vec3 v, int g, const double plane[3]) {
  if (g & 4) v = {plane[0] + v.y - plane[1], plane[1] + v.x - plane[0], v.z};
  if (g & 1) v.x = 2.0 * plane[0] - v.x;
  if (g & 2) v.y = 2.0 * plane[1] - v.y;
  return v;
}

// The per-particle conditions (values included): image maps that are involutions of the
// dihedral group, mirror positions, masses, pins and pin paths; throws naming the first
// offender.
void check_particles(const SpringNetwork& full, const MirrorPlanes& planes) {
  const SpringNetworkSpec& spec = full.spec();
  const int np = full.particle_count();
  const std::vector<int>& ix = planes.image_x;
  const std::vector<int>& iy = planes.image_y;
  const std::vector<int>& id = planes.image_d;
  const bool has_y = !iy.empty(), diagonal = !id.empty();
  const double plane[3] = {planes.x_plane, planes.y_plane, 0.0};  // no mirror in z
  if (diagonal && !has_y) asymmetric("a diagonal mirror needs the y mirror too");
  if (!spec.stencils.empty())
    throw std::invalid_argument("mirror reduction: a network with stencils is not reduced");
  if (static_cast<int>(ix.size()) != np || (has_y && static_cast<int>(iy.size()) != np) ||
      (diagonal && static_cast<int>(id.size()) != np))
    asymmetric("the image maps need one entry per particle (" + std::to_string(np) + ")");
  if (spec.gravity.x != 0.0 || spec.gravity.y != 0.0) asymmetric("gravity has an x or y component");
  auto image = [&](int g, int p) { return g == 1 ? ix[p] : g == 2 ? iy[p] : id[p]; };
  double extent = 0.0;
  for (const Vec3& p : spec.positions)
    extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  const double tol = 1e-9 * (extent > 0.0 ? extent : 1.0);
  std::vector<int> pin_slot(np, -1);
  for (size_t k = 0; k < spec.pinned.size(); ++k) pin_slot[spec.pinned[k]] = static_cast<int>(k);
  const int generators[] = {1, 2, 4};
  const int generator_count = diagonal ? 3 : has_y ? 2 : 1;
  for (int p = 0; p < np; ++p) {
    if ((p & 0xffff) == 0) throw_if_stop_requested();            // seconds near max_particles
    auto who = [p] { return "particle " + std::to_string(p); };  // built only to throw
    auto valid = [np](int q) { return q >= 0 && q < np; };
    if (!valid(ix[p]) || ix[ix[p]] != p)
      asymmetric(who() + ": the x image map is not an involution");
    if (has_y && (!valid(iy[p]) || iy[iy[p]] != p || ix[iy[p]] != iy[ix[p]]))
      asymmetric(who() + ": the image maps are not two commuting involutions");
    if (diagonal && (!valid(id[p]) || id[id[p]] != p || id[ix[p]] != iy[id[p]]))
      asymmetric(who() + ": the diagonal image map is not an involution with D X = Y D");
    for (int i = 0; i < generator_count; ++i) {
      const int g = generators[i];
      const int q = image(g, p);
      const char* plane_name = g == 1 ? "x plane" : g == 2 ? "y plane" : "diagonal";
      if (!close(spec.positions[q], mirror(spec.positions[p], g, plane), tol))
        asymmetric(who() + " and its image " + std::to_string(q) + " across the " + plane_name +
                   " are not mirror positions");
      if (q != p && close(spec.positions[p], mirror(spec.positions[p], g, plane), tol))
        asymmetric(who() + " lies on the " + plane_name + " but is not its own image");
      if (!same_value(spec.masses[p], spec.masses[q]))
        asymmetric(who() + " and its image " + std::to_string(q) + " have different masses");
      if ((pin_slot[p] < 0) != (pin_slot[q] < 0))
        asymmetric(who() + " is pinned and its image " + std::to_string(q) +
                   " is not (or vice versa)");
      if (pin_slot[p] >= 0) {
        const PinPath& a = spec.pin_paths[pin_slot[p]];
        const PinPath& b = spec.pin_paths[pin_slot[q]];
        if (!close(b.start, mirror(a.start, g, plane), tol) ||
            !close(b.end, mirror(a.end, g, plane), tol) || a.move_time != b.move_time)
          asymmetric("the pin paths of particles " + std::to_string(p) + " and " +
                     std::to_string(q) + " are not mirror images");
      }
    }
  }
}

// The message of a spring without a mirror image of the same data (g(s) = a-b).
[[noreturn]] void no_spring_image(const Spring& sp, int a, int b) {
  asymmetric("spring " + std::to_string(sp.a) + "-" + std::to_string(sp.b) +
             " has no mirror image with the same rest length and stiffness (" + std::to_string(a) +
             "-" + std::to_string(b) + ")");
}

// The per-spring conditions on values: every spring's images have its rest length and
// stiffness (their existence is the structure's).
void check_springs(const SpringNetworkSpec& spec, const MirrorReduced::Structure& s) {
  const int order = s.group_order;
  for (std::size_t o = 0; o < s.orbit_first.size(); ++o) {
    const Spring& sp = spec.springs[s.orbit_first[o]];
    for (int g = 0; g < order; ++g) {
      const Spring& match = spec.springs[s.orbit_images[o * order + g]];
      if (!same_value(sp.rest, match.rest) || !same_value(sp.stiffness, match.stiffness))
        no_spring_image(sp, s.image(g, sp.a), s.image(g, sp.b));
    }
  }
}

// The reduced network: `spec`'s values on the structure's springs and particles (no damping, no
// gravity: the reduction's own act on q directly).
SpringNetworkSpec reduced_network_spec(const SpringNetworkSpec& spec,
                                       const MirrorReduced::Structure& s) {
  SpringNetworkSpec q;
  q.positions.reserve(s.net_full.size());
  q.masses.reserve(s.net_full.size());
  for (int p : s.net_full) {
    q.positions.push_back(spec.positions[p]);
    q.masses.push_back(spec.masses[p]);
  }
  q.pinned = s.net_pinned;
  q.pin_paths.reserve(s.net_pin_slot.size());
  for (int slot : s.net_pin_slot) q.pin_paths.push_back(spec.pin_paths[slot]);
  q.springs.reserve(s.net_source.size());
  for (std::size_t k = 0; k < s.net_source.size(); ++k) {
    const Spring& sp = spec.springs[s.net_source[k]];
    q.springs.push_back(
        {s.net_ends[2 * k], s.net_ends[2 * k + 1], sp.rest, s.net_weight[k] * sp.stiffness});
  }
  q.damping = 0.0;
  q.elongation_limit = spec.elongation_limit;
  q.limit_stiffness_factor = spec.limit_stiffness_factor;
  q.gravity = {0.0, 0.0, 0.0};
  q.residual_force_scale = 1.0;  // unused: static_residual() is the reduction's own
  return q;
}

// The structure's key: the image maps, the pinned particles, the springs' ends and each
// particle's sides of the mirrors; and the order of the mirrors' group.
void record_key(MirrorReduced::Structure& s, const SpringNetworkSpec& spec,
                const MirrorPlanes& planes) {
  s.image_x = planes.image_x;
  s.image_y = planes.image_y;
  s.image_d = planes.image_d;
  s.pinned = spec.pinned;
  for (const Spring& sp : spec.springs) s.ends.insert(s.ends.end(), {sp.a, sp.b});
  for (const Vec3& p : spec.positions) s.sides.push_back(side_bits(p, planes));
  s.group_order = !s.image_d.empty() ? 8 : !s.image_y.empty() ? 4 : 2;
}

// The fold into the domain: every particle's domain image d(p) and the element g taking d(p)
// to p (p = g(d)).
struct Fold {
  std::vector<int> domain_of, element;
};

Fold fold_into_domain(const MirrorReduced::Structure& s) {
  const std::vector<int>& ix = s.image_x;
  const std::vector<int>& iy = s.image_y;
  const std::vector<int>& id = s.image_d;
  const bool has_y = !iy.empty(), diagonal = !id.empty();
  const int np = static_cast<int>(s.sides.size());
  Fold fold{std::vector<int>(np), std::vector<int>(np)};
  for (int p = 0; p < np; ++p) {
    if ((p & 0xffff) == 0) throw_if_stop_requested();  // each loop: seconds near max_particles
    int g = 0;
    if (ix[p] != p && (s.sides[p] & 1)) g |= 1;
    if (has_y && iy[p] != p && (s.sides[p] & 2)) g |= 2;
    int d = s.image(g, p);  // x <= c_x (and y <= c_y: the quarter, which D maps onto itself)
    if (diagonal && id[d] != d && (s.sides[d] & 4)) {
      d = id[d];
      g |= 4;
    }
    fold.domain_of[p] = d;
    fold.element[p] = g;
  }
  return fold;
}

// The unknowns q: free coordinates of the free domain particles, in particle order, with their
// particles, weights and multiplicities. Returns q_of: domain coordinate (d, c) is
// x_d[c] = q[q_of] + base (q_of -1: the constant base, s.source_base). Throws (asymmetric) for a
// particle on the x plane and the diagonal that is not the centre.
std::vector<int> choose_unknowns(MirrorReduced::Structure& s, const SpringNetwork& full,
                                 const Fold& fold) {
  using Structure = MirrorReduced::Structure;
  const std::vector<int>& ix = s.image_x;
  const std::vector<int>& iy = s.image_y;
  const std::vector<int>& id = s.image_d;
  const bool has_y = !iy.empty(), diagonal = !id.empty();
  const int np = full.particle_count(), order = s.group_order;
  std::vector<int> q_of(3 * np, -1);
  s.source_base.assign(3 * np, Structure::kZero);
  for (int p = 0; p < np; ++p) {
    if ((p & 0xffff) == 0) throw_if_stop_requested();
    if (fold.domain_of[p] != p || full.free_index(p) < 0) continue;
    int orbit = 0;
    for (int g = 0; g < order; ++g) {
      bool seen = false;
      for (int h = 0; h < g; ++h) seen = seen || s.image(h, p) == s.image(g, p);
      if (!seen) ++orbit;
    }
    s.particle_begin.push_back(static_cast<int>(s.q_particle.size()));
    s.weight.push_back(orbit / static_cast<double>(order));
    for (int c = 0; c < 3; ++c) {
      if ((c == 0 && ix[p] == p) || (c == 1 && has_y && iy[p] == p)) {  // held on the plane
        s.source_base[3 * p + c] = Structure::kPlane;
        continue;
      }
      if (c == 1 && diagonal && id[p] == p) {  // on the diagonal: y - c_y = x - c_x
        if (q_of[3 * p] < 0)  // x held on the x plane, y on the diagonal: only the centre
          asymmetric("particle " + std::to_string(p) +
                     " lies on the x plane and the diagonal but is not its own y image");
        q_of[3 * p + 1] = q_of[3 * p];
        s.source_base[3 * p + 1] = Structure::kDiagonal;
        s.multiplicity[q_of[3 * p]] += 1.0;
        continue;
      }
      q_of[3 * p + c] = static_cast<int>(s.q_particle.size());
      s.q_particle.push_back(p);
      s.full_dof.push_back(3 * full.free_index(p) + c);
      s.coordinate.push_back(c);
      s.multiplicity.push_back(1.0);
    }
  }
  s.particle_begin.push_back(static_cast<int>(s.q_particle.size()));
  return q_of;
}

// The tie of every full free dof to q: coordinate c of p = g(d) is the mirrored coordinate src
// of d (D swaps x and y, X and Y flip them).
void tie_full_dofs(MirrorReduced::Structure& s, const SpringNetwork& full, const Fold& fold,
                   const std::vector<int>& q_of) {
  const int full_dofs = full.dof();
  s.tie_dof.assign(full_dofs, -1);
  s.tie_sign.assign(full_dofs, 1.0);
  s.tie_source.assign(full_dofs, 0);
  s.tie_element.assign(full_dofs, 0);
  for (int p = 0; p < full.particle_count(); ++p) {
    if ((p & 0xffff) == 0) throw_if_stop_requested();
    if (full.free_index(p) < 0) continue;
    const int d = fold.domain_of[p], g = fold.element[p];
    for (int c = 0; c < 3; ++c) {
      const int k = 3 * full.free_index(p) + c;
      const int src = (g & 4) && c < 2 ? 1 - c : c;
      const int j = q_of[3 * d + src];
      const bool flipped = (c == 0 && (g & 1)) || (c == 1 && (g & 2));
      s.tie_dof[k] = j;
      s.tie_sign[k] = j >= 0 && flipped ? -1.0 : 1.0;
      s.tie_source[k] = 3 * d + src;
      s.tie_element[k] = static_cast<unsigned char>(g);
    }
  }
}

// The springs of a network by their unordered pair of ends: (key, spring) sorted by key, a
// lookup table without a node per spring. Throws (asymmetric) when two springs join one pair.
class SpringsByEnds {
 public:
  SpringsByEnds(const SpringNetworkSpec& spec, int np) : np_(np), by_key_(spec.springs.size()) {
    for (size_t k = 0; k < spec.springs.size(); ++k)
      by_key_[k] = {key(spec.springs[k].a, spec.springs[k].b), static_cast<int>(k)};
    throw_if_stop_requested();
    std::sort(by_key_.begin(), by_key_.end());
    throw_if_stop_requested();
    for (size_t k = 1; k < by_key_.size(); ++k)
      if (by_key_[k].first == by_key_[k - 1].first) {
        const Spring& dup = spec.springs[by_key_[k].second];
        asymmetric("two springs join particles " + std::to_string(dup.a) + " and " +
                   std::to_string(dup.b) + " (not supported)");
      }
  }
  // The spring joining a and b, or -1.
  int find(int a, int b) const {
    const long long k = key(a, b);
    const auto it = std::lower_bound(by_key_.begin(), by_key_.end(), std::make_pair(k, -1));
    return it != by_key_.end() && it->first == k ? it->second : -1;
  }

 private:
  long long key(int a, int b) const {
    return static_cast<long long>(std::min(a, b)) * np_ + std::max(a, b);
  }
  int np_;
  std::vector<std::pair<long long, int>> by_key_;
};

// The reduced network's particles (the domain's, then ghosts) and springs: every spring's mirror
// images present (else asymmetric); one weighted representative per orbit, chosen with as many
// ends in the domain as possible (the rest become ghosts); the orbits for check_springs.
void reduce_springs(MirrorReduced::Structure& s, const SpringNetworkSpec& spec, const Fold& fold) {
  const int np = static_cast<int>(spec.positions.size()), order = s.group_order;
  std::vector<int> pin_slot(np, -1);
  for (size_t k = 0; k < spec.pinned.size(); ++k) pin_slot[spec.pinned[k]] = static_cast<int>(k);
  const SpringsByEnds springs(spec, np);
  std::vector<int> net_of(np, -1);
  auto add_particle = [&](int p) {
    net_of[p] = static_cast<int>(s.net_full.size());
    s.net_full.push_back(p);
    if (pin_slot[p] >= 0) {
      s.net_pinned.push_back(net_of[p]);
      s.net_pin_slot.push_back(pin_slot[p]);
    }
  };
  for (int p = 0; p < np; ++p)
    if (fold.domain_of[p] == p) add_particle(p);
  std::vector<char> done(spec.springs.size(), 0);
  for (size_t k = 0; k < spec.springs.size(); ++k) {
    if ((k & 0xffff) == 0) throw_if_stop_requested();
    if (done[k]) continue;
    const Spring& sp = spec.springs[k];
    int members[8], count = 0, best = 0, best_inside = -1;
    s.orbit_first.push_back(static_cast<int>(k));
    for (int g = 0; g < order; ++g) {
      const int a = s.image(g, sp.a), b = s.image(g, sp.b);
      const int match = springs.find(a, b);
      if (match < 0) no_spring_image(sp, a, b);
      s.orbit_images.push_back(match);
      if (std::find(members, members + count, match) == members + count) members[count++] = match;
      const int inside = (fold.domain_of[a] == a) + (fold.domain_of[b] == b);
      if (inside > best_inside) best_inside = inside, best = g;
    }
    for (int i = 0; i < count; ++i) done[members[i]] = 1;
    const int a = s.image(best, sp.a), b = s.image(best, sp.b);
    for (int p : {a, b})
      if (net_of[p] < 0) add_particle(p);  // a ghost: tied to its domain image
    s.net_ends.insert(s.net_ends.end(), {net_of[a], net_of[b]});
    s.net_source.push_back(static_cast<int>(k));
    s.net_weight.push_back(count / static_cast<double>(order));
  }
}

// Reduced network dof -> full dof, and the Jacobian P^T K P into the q pattern (the network's
// free particles and pattern follow from its integers; this drape's values stand in).
void map_jacobian(MirrorReduced::Structure& s, const SpringNetwork& full) {
  const SpringNetwork net(reduced_network_spec(full.spec(), s));
  s.net_full_dof.assign(net.dof(), -1);
  for (int k = 0; k < net.particle_count(); ++k) {
    const int f = net.free_index(k);
    if (f < 0) continue;
    for (int c = 0; c < 3; ++c) s.net_full_dof[3 * f + c] = 3 * full.free_index(s.net_full[k]) + c;
  }
  const CscPattern& kp = net.stiffness_pattern();
  std::vector<std::pair<int, int>> entries;
  throw_if_stop_requested();
  for (int col = 0; col < kp.cols; ++col)
    for (int e = kp.colptr[col]; e < kp.colptr[col + 1]; ++e) {
      const int r = s.tie_dof[s.net_full_dof[kp.rowind[e]]], c = s.tie_dof[s.net_full_dof[col]];
      if (r >= 0 && c >= 0) entries.emplace_back(r, c);
    }
  const int dof = static_cast<int>(s.q_particle.size());
  std::vector<int> entry_position;
  s.pattern =
      make_csc_pattern(dof, dof, std::move(entries), /*with_diagonal=*/true, &entry_position);
  s.jac_target.assign(kp.nnz(), -1);
  throw_if_stop_requested();
  int next_entry = 0;  // the entries in the order listed above
  for (int col = 0; col < kp.cols; ++col)
    for (int e = kp.colptr[col]; e < kp.colptr[col + 1]; ++e) {
      const int r = s.tie_dof[s.net_full_dof[kp.rowind[e]]], c = s.tie_dof[s.net_full_dof[col]];
      if (r >= 0 && c >= 0) s.jac_target[e] = entry_position[next_entry++];
    }
}

// The structure of a network that passed check_particles. Throws (asymmetric) where its
// integers break the mirrors: two springs on one pair, a spring without an image, a particle on
// the x plane and the diagonal that is not the centre.
std::shared_ptr<const MirrorReduced::Structure> build_structure(const SpringNetwork& full,
                                                                const MirrorPlanes& planes) {
  auto made = std::make_shared<MirrorReduced::Structure>();
  MirrorReduced::Structure& s = *made;
  record_key(s, full.spec(), planes);
  const Fold fold = fold_into_domain(s);
  const std::vector<int> q_of = choose_unknowns(s, full, fold);
  tie_full_dofs(s, full, fold, q_of);
  reduce_springs(s, full.spec(), fold);
  map_jacobian(s, full);
  return made;
}

// The structures of the latest meshes: a fit's drapes (thousands) share a few (grid size x
// topology x reduction), each of which would otherwise build its structure again. A hit is bit
// for bit what a fresh build gives. At most 32 MB of integers.
PatternMemo<MirrorReduced::Structure>& structure_memo() {
  static PatternMemo<MirrorReduced::Structure> memo(std::size_t{1} << 23);
  return memo;
}

std::shared_ptr<const MirrorReduced::Structure> structure_of(const SpringNetwork& full,
                                                             const MirrorPlanes& planes) {
  std::shared_ptr<const MirrorReduced::Structure> s = structure_memo().find(
      [&](const MirrorReduced::Structure& e) { return same_key(e, full.spec(), planes); });
  if (!s) {
    std::shared_ptr<const MirrorReduced::Structure> fresh = build_structure(full, planes);
    s = structure_memo().insert(fresh, fresh->footprint());
  }
  return s;
}

}  // namespace

std::size_t MirrorReduced::Structure::footprint() const {
  const std::size_t ints =
      image_x.size() + image_y.size() + image_d.size() + pinned.size() + ends.size() +
      sides.size() + q_particle.size() + full_dof.size() + coordinate.size() +
      particle_begin.size() + tie_dof.size() + tie_source.size() + tie_element.size() +
      source_base.size() + net_full.size() + net_pinned.size() + net_pin_slot.size() +
      net_ends.size() + net_source.size() + orbit_first.size() + orbit_images.size() +
      net_full_dof.size() + pattern.colptr.size() + pattern.rowind.size() + jac_target.size();
  const std::size_t doubles =
      multiplicity.size() + weight.size() + tie_sign.size() + net_weight.size();
  return ints + 2 * doubles;
}

void MirrorReduced::clear_structure_memo() { structure_memo().clear(); }

MirrorReduced::MirrorReduced(const SpringNetwork& full, const MirrorPlanes& planes)
    : full_(std::make_unique<SpringNetwork>(full)),
      gravity_(full.spec().gravity),
      residual_scale_(full.residual_force_scale()) {
  check_particles(full, planes);
  s_ = structure_of(full, planes);
  const Structure& s = *s_;
  const SpringNetworkSpec& spec = full.spec();
  check_springs(spec, s);

  // Per q entry: mass w_p m_p mult_j, damping rate c / m_p, the start.
  const int n = static_cast<int>(s.q_particle.size());
  mass_.resize(n);
  gamma_.resize(n);
  initial_.resize(n);
  for (size_t r = 0; r + 1 < s.particle_begin.size(); ++r)
    for (int j = s.particle_begin[r]; j < s.particle_begin[r + 1]; ++j) {
      const int p = s.q_particle[j];
      const double m = spec.masses[p];
      mass_[j] = s.weight[r] * m * s.multiplicity[j];
      gamma_[j] = spec.damping / m;
      initial_[j] = component(spec.positions[p], s.coordinate[j]);
    }

  // The ties' offsets: a domain coordinate's base (0, its plane, or the diagonal's c_y - c_x),
  // moved by D's swap and X's and Y's flips.
  const double plane[3] = {planes.x_plane, planes.y_plane, 0.0};
  tie_offset_.resize(s.tie_dof.size());
  for (size_t k = 0; k < s.tie_dof.size(); ++k) {
    const int c = static_cast<int>(k % 3), g = s.tie_element[k];
    const int src = s.tie_source[k] % 3;
    const unsigned char kind = s.source_base[s.tie_source[k]];
    const double base = kind == Structure::kPlane      ? plane[src]
                        : kind == Structure::kDiagonal ? plane[1] - plane[0]
                                                       : 0.0;
    double offset = base + ((g & 4) && c < 2 ? plane[c] - plane[src] : 0.0);
    const bool flipped = (c == 0 && (g & 1)) || (c == 1 && (g & 2));
    if (flipped) offset = 2.0 * plane[c] - offset;
    tie_offset_[k] = offset;
  }

  net_ = std::make_unique<SpringNetwork>(reduced_network_spec(spec, s));
  const CscPattern& kp = net_->stiffness_pattern();
  jac_factor_.assign(kp.nnz(), 0.0);
  for (int col = 0; col < kp.cols; ++col)
    for (int e = kp.colptr[col]; e < kp.colptr[col + 1]; ++e) {
      if (s.jac_target[e] < 0) continue;
      const int kr = s.net_full_dof[kp.rowind[e]], kc = s.net_full_dof[col];
      // The network's values are rows of M_net^-1 dF/dx; the reduction's are M_q^-1 dF/dq.
      jac_factor_[e] =
          s.tie_sign[kr] * s.tie_sign[kc] * net_->mass()[kp.rowind[e]] / mass_[s.tie_dof[kr]];
    }
  x_net_.resize(net_->dof());
  f_net_.resize(net_->dof());
  k_net_.resize(kp.nnz());
  f_red_.resize(dof());
  x_full_.resize(s.tie_dof.size());
}

const CscPattern& MirrorReduced::stiffness_pattern() const { return s_->pattern; }

const std::vector<int>& MirrorReduced::full_dof() const { return s_->full_dof; }

int MirrorReduced::group_order() const { return s_->group_order; }

inline double MirrorReduced::tied_value(const double* q, int k) const {
  const int j = s_->tie_dof[k];
  return (j >= 0 ? s_->tie_sign[k] * q[j] : 0.0) + tie_offset_[k];
}

void MirrorReduced::expand(const double* q) const {
  for (size_t k = 0; k < x_net_.size(); ++k) x_net_[k] = tied_value(q, s_->net_full_dof[k]);
}

void MirrorReduced::reduced_force(double t, const double* q) const {
  expand(q);
  net_->net_force(t, x_net_.data(), f_net_.data());
  std::fill(f_red_.begin(), f_red_.end(), 0.0);
  const Structure& s = *s_;
  for (size_t k = 0; k < f_net_.size(); ++k) {
    const int full = s.net_full_dof[k];
    const int j = s.tie_dof[full];
    if (j >= 0) f_red_[j] += s.tie_sign[full] * f_net_[k];
  }
}

void MirrorReduced::initial_state(double* q, double* v) const {
  std::copy(initial_.begin(), initial_.end(), q);
  std::fill(v, v + dof(), 0.0);
}

void MirrorReduced::conservative_acceleration(double t, const double* q, double* a) const {
  reduced_force(t, q);
  const double g[3] = {gravity_.x, gravity_.y, gravity_.z};
  const std::vector<int>& coordinate = s_->coordinate;
  for (int j = 0; j < dof(); ++j) a[j] = f_red_[j] / mass_[j] + g[coordinate[j]];
}

void MirrorReduced::constant_acceleration(double /*t*/, double* a) const {
  const double g[3] = {gravity_.x, gravity_.y, gravity_.z};
  for (int j = 0; j < dof(); ++j) a[j] = g[s_->coordinate[j]];
}

void MirrorReduced::stiffness_values(double t, const double* q, double* values) const {
  expand(q);
  net_->stiffness_values(t, x_net_.data(), k_net_.data());
  std::fill(values, values + s_->pattern.nnz(), 0.0);
  const std::vector<int>& target = s_->jac_target;
  for (size_t e = 0; e < k_net_.size(); ++e)
    if (target[e] >= 0) values[target[e]] += jac_factor_[e] * k_net_[e];
}

double MirrorReduced::static_residual(double t, const double* q) const {
  reduced_force(t, q);
  const double g[3] = {gravity_.x, gravity_.y, gravity_.z};
  const Structure& s = *s_;
  double worst = 0.0;
  for (size_t r = 0; r + 1 < s.particle_begin.size(); ++r) {
    double f2 = 0.0;
    for (int j = s.particle_begin[r]; j < s.particle_begin[r + 1]; ++j) {
      const double f = (f_red_[j] + mass_[j] * g[s.coordinate[j]]) / s.weight[r];
      f2 += f * f / s.multiplicity[j];
    }
    if (!(f2 <= worst)) worst = f2;  // NaN propagates
  }
  return std::sqrt(worst) / residual_scale_;
}

double MirrorReduced::residual_roundoff(double t, const double* q) const {
  unfold(q, x_full_.data());
  return full_->residual_roundoff(t, x_full_.data());
}

bool MirrorReduced::project(double t, double* q, double* /*v*/) const {
  expand(q);
  // SpringNetwork::project moves positions only (velocities unchanged), so v is not passed.
  if (!net_->project(t, x_net_.data(), nullptr)) return false;
  const Structure& s = *s_;
  for (size_t k = 0; k < x_net_.size(); ++k) {
    const int full = s.net_full_dof[k];
    const int j = s.tie_dof[full];
    if (j >= 0 && s.full_dof[j] == full) q[j] = x_net_[k];  // its own coordinate
  }
  return true;
}

double MirrorReduced::potential_energy(double t, const double* q) const {
  expand(q);
  double e = net_->potential_energy(t, x_net_.data());  // springs (the network has no gravity)
  const double g[3] = {gravity_.x, gravity_.y, gravity_.z};
  for (int j = 0; j < dof(); ++j) e -= mass_[j] * g[s_->coordinate[j]] * q[j];
  return e;
}

void MirrorReduced::unfold(const double* q, double* x_full) const {
  for (size_t k = 0; k < tie_offset_.size(); ++k) x_full[k] = tied_value(q, static_cast<int>(k));
}

std::string MirrorReduced::describe() const {
  std::ostringstream os;
  os << (s_->group_order == 8   ? "mirror eighth: "
         : s_->group_order == 4 ? "mirror quarter: "
                                : "mirror half: ")
     << s_->weight.size() << " free particles, " << dof() << " dof (" << tie_offset_.size()
     << " in the full model), " << net_->spec().springs.size() << " springs, Jacobian nnz "
     << s_->pattern.nnz();
  return os.str();
}

MirrorPlanes drape_mirror_planes(const DrapeGrid& grid, DrapeSymmetry symmetry) {
  const int n = grid.n;
  MirrorPlanes planes;
  planes.x_plane = planes.y_plane = 0.5 * n * grid.params.natural_length;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      planes.image_x.push_back(grid.index(i, n - j));
      if (symmetry != DrapeSymmetry::Half) planes.image_y.push_back(grid.index(n - i, j));
      if (symmetry == DrapeSymmetry::Eighth) planes.image_d.push_back(grid.index(j, i));
    }
  return planes;
}

MirrorReduced make_drape_reduced(const DrapeGrid& grid, DrapeSymmetry symmetry) {
  DrapeParams p = grid.params;
  p.symmetry = symmetry;
  p.validate();  // the layout and perturbation conditions, with their field names
  if (p.symmetry == DrapeSymmetry::None)
    throw std::invalid_argument("model.symmetry = none: no mirror reduction to build");
  try {
    return MirrorReduced(grid.network, drape_mirror_planes(grid, symmetry));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("model.symmetry = ") + to_string(p.symmetry) +
                                ": topology " + p.topology + " is " + e.what());
  }
}

}  // namespace knitsim
