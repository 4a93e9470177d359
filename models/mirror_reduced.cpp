#include "models/mirror_reduced.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

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

MirrorReduced::MirrorReduced(const SpringNetwork& full, const MirrorPlanes& planes)
    : full_(std::make_unique<SpringNetwork>(full)),
      gravity_(full.spec().gravity),
      residual_scale_(full.residual_force_scale()),
      full_dof_count_(full.dof()) {
  const SpringNetworkSpec& spec = full.spec();
  const int np = full.particle_count();
  const std::vector<int>& ix = planes.image_x;
  const std::vector<int>& iy = planes.image_y;
  const std::vector<int>& id = planes.image_d;
  const bool has_y = !iy.empty(), diagonal = !id.empty();
  group_order_ = diagonal ? 8 : has_y ? 4 : 2;  // elements g = 0 .. |G| - 1 (bits below)
  const double plane[3] = {planes.x_plane, planes.y_plane, 0.0};  // no mirror in z
  if (diagonal && !has_y) asymmetric("a diagonal mirror needs the y mirror too");
  if (static_cast<int>(ix.size()) != np || (has_y && static_cast<int>(iy.size()) != np) ||
      (diagonal && static_cast<int>(id.size()) != np))
    asymmetric("the image maps need one entry per particle (" + std::to_string(np) + ")");
  if (gravity_.x != 0.0 || gravity_.y != 0.0) asymmetric("gravity has an x or y component");

  // Group element g: bit 0 X, bit 1 Y, bit 2 D, acting as Y^(bit 1) X^(bit 0) D^(bit 2).
  auto image = [&](int g, int p) {
    if (g & 4) p = id[p];
    if (g & 1) p = ix[p];
    if (g & 2) p = iy[p];
    return p;
  };
  auto mirror = [&](Vec3 v, int g) {
    if (g & 4) v = {plane[0] + v.y - plane[1], plane[1] + v.x - plane[0], v.z};
    if (g & 1) v.x = 2.0 * plane[0] - v.x;
    if (g & 2) v.y = 2.0 * plane[1] - v.y;
    return v;
  };
  double extent = 0.0;
  for (const Vec3& p : spec.positions)
    extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  const double tol = 1e-9 * (extent > 0.0 ? extent : 1.0);
  std::vector<int> pin_slot(np, -1);
  for (size_t k = 0; k < spec.pinned.size(); ++k) pin_slot[spec.pinned[k]] = static_cast<int>(k);
  std::vector<int> generators = {1};
  if (has_y) generators.push_back(2);
  if (diagonal) generators.push_back(4);
  for (int p = 0; p < np; ++p) {
    auto who = [p] { return "particle " + std::to_string(p); };  // built only to throw
    auto valid = [np](int q) { return q >= 0 && q < np; };
    if (!valid(ix[p]) || ix[ix[p]] != p)
      asymmetric(who() + ": the x image map is not an involution");
    if (has_y && (!valid(iy[p]) || iy[iy[p]] != p || ix[iy[p]] != iy[ix[p]]))
      asymmetric(who() + ": the image maps are not two commuting involutions");
    if (diagonal && (!valid(id[p]) || id[id[p]] != p || id[ix[p]] != iy[id[p]]))
      asymmetric(who() + ": the diagonal image map is not an involution with D X = Y D");
    for (int g : generators) {
      const int q = image(g, p);
      const char* plane_name = g == 1 ? "x plane" : g == 2 ? "y plane" : "diagonal";
      if (!close(spec.positions[q], mirror(spec.positions[p], g), tol))
        asymmetric(who() + " and its image " + std::to_string(q) + " across the " + plane_name +
                   " are not mirror positions");
      if (q != p && close(spec.positions[p], mirror(spec.positions[p], g), tol))
        asymmetric(who() + " lies on the " + plane_name + " but is not its own image");
      if (!same_value(spec.masses[p], spec.masses[q]))
        asymmetric(who() + " and its image " + std::to_string(q) + " have different masses");
      if ((pin_slot[p] < 0) != (pin_slot[q] < 0))
        asymmetric(who() + " is pinned and its image " + std::to_string(q) +
                   " is not (or vice versa)");
      if (pin_slot[p] >= 0) {
        const PinPath& a = spec.pin_paths[pin_slot[p]];
        const PinPath& b = spec.pin_paths[pin_slot[q]];
        if (!close(b.start, mirror(a.start, g), tol) || !close(b.end, mirror(a.end, g), tol) ||
            a.move_time != b.move_time)
          asymmetric("the pin paths of particles " + std::to_string(p) + " and " +
                     std::to_string(q) + " are not mirror images");
      }
    }
  }

  // Fold: every particle's domain image d(p) and the element taking d(p) to p (p = g(d)).
  std::vector<int> domain_of(np), element(np);
  for (int p = 0; p < np; ++p) {
    int g = 0;
    if (ix[p] != p && spec.positions[p].x > plane[0]) g |= 1;
    if (has_y && iy[p] != p && spec.positions[p].y > plane[1]) g |= 2;
    int d = image(g, p);  // x <= c_x (and y <= c_y: the quarter, which D maps onto itself)
    const Vec3& r = spec.positions[d];
    if (diagonal && id[d] != d && r.y - plane[1] > r.x - plane[0]) {
      d = id[d];
      g |= 4;
    }
    domain_of[p] = d;
    element[p] = g;
  }

  // The unknowns q: free coordinates of the free domain particles, in particle order. Each
  // domain coordinate (d, c) is x_d[c] = q[q_of] + base (q_of -1: the constant base).
  std::vector<int> q_of(3 * np, -1);
  std::vector<double> base(3 * np, 0.0);
  for (int p = 0; p < np; ++p) {
    if (domain_of[p] != p || full.free_index(p) < 0) continue;
    int orbit = 0;
    for (int g = 0; g < group_order_; ++g) {
      bool seen = false;
      for (int h = 0; h < g; ++h) seen = seen || image(h, p) == image(g, p);
      if (!seen) ++orbit;
    }
    const double w = orbit / static_cast<double>(group_order_);
    const double m = spec.masses[p];
    particle_begin_.push_back(static_cast<int>(mass_.size()));
    weight_.push_back(w);
    for (int c = 0; c < 3; ++c) {
      if ((c == 0 && ix[p] == p) || (c == 1 && has_y && iy[p] == p)) {  // held on the plane
        base[3 * p + c] = plane[c];
        continue;
      }
      if (c == 1 && diagonal && id[p] == p) {  // on the diagonal: y - c_y = x - c_x
        if (q_of[3 * p] < 0)  // x held on the x plane, y on the diagonal: only the centre
          asymmetric("particle " + std::to_string(p) +
                     " lies on the x plane and the diagonal but is not its own y image");
        q_of[3 * p + 1] = q_of[3 * p];
        base[3 * p + 1] = plane[1] - plane[0];
        multiplicity_[q_of[3 * p]] += 1.0;
        continue;
      }
      q_of[3 * p + c] = static_cast<int>(mass_.size());
      full_dof_.push_back(3 * full.free_index(p) + c);
      coordinate_.push_back(c);
      mass_.push_back(w * m);  // x the multiplicity, below
      multiplicity_.push_back(1.0);
      gamma_.push_back(spec.damping / m);
      initial_.push_back(component(spec.positions[p], c));
    }
  }
  particle_begin_.push_back(static_cast<int>(mass_.size()));
  for (size_t j = 0; j < mass_.size(); ++j) mass_[j] *= multiplicity_[j];

  // The tie of every full free dof to q: coordinate c of p = g(d) is the mirrored coordinate
  // src of d (D swaps x and y, X and Y flip them).
  tie_dof_.assign(full_dof_count_, -1);
  tie_sign_.assign(full_dof_count_, 1.0);
  tie_offset_.assign(full_dof_count_, 0.0);
  for (int p = 0; p < np; ++p) {
    if (full.free_index(p) < 0) continue;
    const int d = domain_of[p], g = element[p];
    for (int c = 0; c < 3; ++c) {
      const int k = 3 * full.free_index(p) + c;
      const int src = (g & 4) && c < 2 ? 1 - c : c;
      const int j = q_of[3 * d + src];
      double offset = base[3 * d + src] + ((g & 4) && c < 2 ? plane[c] - plane[src] : 0.0);
      const bool flipped = (c == 0 && (g & 1)) || (c == 1 && (g & 2));
      if (flipped) offset = 2.0 * plane[c] - offset;
      tie_dof_[k] = j;
      tie_sign_[k] = j >= 0 && flipped ? -1.0 : 1.0;
      tie_offset_[k] = offset;
    }
  }

  // Springs: every mirror image present with the same data; one weighted representative per
  // orbit, chosen with as many ends in the domain as possible (the rest become ghosts).
  auto key = [np](int a, int b) {
    return static_cast<long long>(std::min(a, b)) * np + std::max(a, b);
  };
  // (key, spring) sorted by key: a lookup table without a node per spring (an unordered_map
  // spent ~0.1 of this constructor's time in its allocations).
  std::vector<std::pair<long long, int>> by_key(spec.springs.size());
  for (size_t s = 0; s < spec.springs.size(); ++s)
    by_key[s] = {key(spec.springs[s].a, spec.springs[s].b), static_cast<int>(s)};
  std::sort(by_key.begin(), by_key.end());
  for (size_t k = 1; k < by_key.size(); ++k)
    if (by_key[k].first == by_key[k - 1].first) {
      const Spring& dup = spec.springs[by_key[k].second];
      asymmetric("two springs join particles " + std::to_string(dup.a) + " and " +
                 std::to_string(dup.b) + " (not supported)");
    }
  auto spring_of = [&](long long k) {  // the spring with this key, or -1
    const auto it = std::lower_bound(by_key.begin(), by_key.end(), std::make_pair(k, -1));
    return it != by_key.end() && it->first == k ? it->second : -1;
  };
  std::vector<int> net_of(np, -1);
  SpringNetworkSpec q;
  std::vector<int> net_full;  // reduced network particle -> full particle
  auto add_particle = [&](int p) {
    net_of[p] = static_cast<int>(net_full.size());
    net_full.push_back(p);
    q.positions.push_back(spec.positions[p]);
    q.masses.push_back(spec.masses[p]);
    if (pin_slot[p] >= 0) {
      q.pinned.push_back(net_of[p]);
      q.pin_paths.push_back(spec.pin_paths[pin_slot[p]]);
    }
  };
  for (int p = 0; p < np; ++p)
    if (domain_of[p] == p) add_particle(p);
  std::vector<char> done(spec.springs.size(), 0);
  for (size_t s = 0; s < spec.springs.size(); ++s) {
    if (done[s]) continue;
    const Spring& sp = spec.springs[s];
    int members[8], count = 0, best = 0, best_inside = -1;
    for (int g = 0; g < group_order_; ++g) {
      const int a = image(g, sp.a), b = image(g, sp.b);
      const int match = spring_of(key(a, b));
      if (match < 0 || !same_value(sp.rest, spec.springs[match].rest) ||
          !same_value(sp.stiffness, spec.springs[match].stiffness))
        asymmetric("spring " + std::to_string(sp.a) + "-" + std::to_string(sp.b) +
                   " has no mirror image with the same rest length and stiffness (" +
                   std::to_string(a) + "-" + std::to_string(b) + ")");
      if (std::find(members, members + count, match) == members + count) members[count++] = match;
      const int inside = (domain_of[a] == a) + (domain_of[b] == b);
      if (inside > best_inside) best_inside = inside, best = g;
    }
    for (int i = 0; i < count; ++i) done[members[i]] = 1;
    const int a = image(best, sp.a), b = image(best, sp.b);
    for (int p : {a, b})
      if (net_of[p] < 0) add_particle(p);  // a ghost: tied to its domain image
    q.springs.push_back(
        {net_of[a], net_of[b], sp.rest, count / static_cast<double>(group_order_) * sp.stiffness});
  }
  q.damping = 0.0;  // the reduction's damping and gravity act on q directly
  q.elongation_limit = spec.elongation_limit;
  q.limit_stiffness_factor = spec.limit_stiffness_factor;
  q.gravity = {0.0, 0.0, 0.0};
  q.residual_force_scale = 1.0;  // unused: static_residual() is the reduction's own
  net_ = std::make_unique<SpringNetwork>(std::move(q));

  // Reduced network dof -> full dof, and the Jacobian P^T K P into the q pattern.
  net_full_dof_.assign(net_->dof(), -1);
  for (int k = 0; k < net_->particle_count(); ++k) {
    const int f = net_->free_index(k);
    if (f < 0) continue;
    for (int c = 0; c < 3; ++c) net_full_dof_[3 * f + c] = 3 * full.free_index(net_full[k]) + c;
  }
  const CscPattern& kp = net_->stiffness_pattern();
  std::vector<std::pair<int, int>> entries;
  for (int col = 0; col < kp.cols; ++col)
    for (int e = kp.colptr[col]; e < kp.colptr[col + 1]; ++e) {
      const int r = tie_dof_[net_full_dof_[kp.rowind[e]]], c = tie_dof_[net_full_dof_[col]];
      if (r >= 0 && c >= 0) entries.emplace_back(r, c);
    }
  std::vector<int> entry_position;
  pattern_ =
      make_csc_pattern(dof(), dof(), std::move(entries), /*with_diagonal=*/true, &entry_position);
  jac_target_.assign(kp.nnz(), -1);
  jac_factor_.assign(kp.nnz(), 0.0);
  int next_entry = 0;  // the entries in the order listed above
  for (int col = 0; col < kp.cols; ++col)
    for (int e = kp.colptr[col]; e < kp.colptr[col + 1]; ++e) {
      const int kr = net_full_dof_[kp.rowind[e]], kc = net_full_dof_[col];
      const int r = tie_dof_[kr], c = tie_dof_[kc];
      if (r < 0 || c < 0) continue;
      jac_target_[e] = entry_position[next_entry++];
      // The network's values are rows of M_net^-1 dF/dx; the reduction's are M_q^-1 dF/dq.
      jac_factor_[e] = tie_sign_[kr] * tie_sign_[kc] * net_->mass()[kp.rowind[e]] / mass_[r];
    }
  x_net_.resize(net_->dof());
  f_net_.resize(net_->dof());
  k_net_.resize(kp.nnz());
  f_red_.resize(dof());
  x_full_.resize(full_dof_count_);
}

void MirrorReduced::expand(const double* q) const {
  for (size_t k = 0; k < x_net_.size(); ++k) x_net_[k] = tied_value(q, net_full_dof_[k]);
}

void MirrorReduced::reduced_force(double t, const double* q) const {
  expand(q);
  net_->net_force(t, x_net_.data(), f_net_.data());
  std::fill(f_red_.begin(), f_red_.end(), 0.0);
  for (size_t k = 0; k < f_net_.size(); ++k) {
    const int full = net_full_dof_[k];
    const int j = tie_dof_[full];
    if (j >= 0) f_red_[j] += tie_sign_[full] * f_net_[k];
  }
}

void MirrorReduced::initial_state(double* q, double* v) const {
  std::copy(initial_.begin(), initial_.end(), q);
  std::fill(v, v + dof(), 0.0);
}

void MirrorReduced::conservative_acceleration(double t, const double* q, double* a) const {
  reduced_force(t, q);
  const double g[3] = {gravity_.x, gravity_.y, gravity_.z};
  for (int j = 0; j < dof(); ++j) a[j] = f_red_[j] / mass_[j] + g[coordinate_[j]];
}

void MirrorReduced::constant_acceleration(double /*t*/, double* a) const {
  const double g[3] = {gravity_.x, gravity_.y, gravity_.z};
  for (int j = 0; j < dof(); ++j) a[j] = g[coordinate_[j]];
}

void MirrorReduced::stiffness_values(double t, const double* q, double* values) const {
  expand(q);
  net_->stiffness_values(t, x_net_.data(), k_net_.data());
  std::fill(values, values + pattern_.nnz(), 0.0);
  for (size_t e = 0; e < k_net_.size(); ++e)
    if (jac_target_[e] >= 0) values[jac_target_[e]] += jac_factor_[e] * k_net_[e];
}

double MirrorReduced::static_residual(double t, const double* q) const {
  reduced_force(t, q);
  const double g[3] = {gravity_.x, gravity_.y, gravity_.z};
  double worst = 0.0;
  for (size_t r = 0; r + 1 < particle_begin_.size(); ++r) {
    double f2 = 0.0;
    for (int j = particle_begin_[r]; j < particle_begin_[r + 1]; ++j) {
      const double f = (f_red_[j] + mass_[j] * g[coordinate_[j]]) / weight_[r];
      f2 += f * f / multiplicity_[j];
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
  for (size_t k = 0; k < x_net_.size(); ++k) {
    const int full = net_full_dof_[k];
    const int j = tie_dof_[full];
    if (j >= 0 && full_dof_[j] == full) q[j] = x_net_[k];  // its own coordinate
  }
  return true;
}

double MirrorReduced::potential_energy(double t, const double* q) const {
  expand(q);
  double e = net_->potential_energy(t, x_net_.data());  // springs (the network has no gravity)
  const double g[3] = {gravity_.x, gravity_.y, gravity_.z};
  for (int j = 0; j < dof(); ++j) e -= mass_[j] * g[coordinate_[j]] * q[j];
  return e;
}

void MirrorReduced::unfold(const double* q, double* x_full) const {
  for (int k = 0; k < full_dof_count_; ++k) x_full[k] = tied_value(q, k);
}

std::string MirrorReduced::describe() const {
  std::ostringstream os;
  os << (group_order_ == 8   ? "mirror eighth: "
         : group_order_ == 4 ? "mirror quarter: "
                             : "mirror half: ")
     << weight_.size() << " free particles, " << dof() << " dof (" << full_dof_count_
     << " in the full model), " << net_->spec().springs.size() << " springs, Jacobian nnz "
     << pattern_.nnz();
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
