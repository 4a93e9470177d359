#include "models/spring_network.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "src/core/memo.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim {

Vec3 PinPath::at(double t) const {
  if (move_time <= 0.0 || t >= move_time) return end;
  const double s = std::max(0.0, t / move_time);
  return start + s * (end - start);
}

namespace {

// A spring's force F on end a (free index fa) and -F on end b, into a 3-per-free-dof array;
// a pinned end (index < 0) takes nothing.
void add_spring_pair(double* out, int fa, int fb, Vec3 F) {
  if (fa >= 0) {
    out[3 * fa] += F.x;
    out[3 * fa + 1] += F.y;
    out[3 * fa + 2] += F.z;
  }
  if (fb >= 0) {
    out[3 * fb] -= F.x;
    out[3 * fb + 1] -= F.y;
    out[3 * fb + 2] -= F.z;
  }
}
}  // namespace

SpringNetwork::SpringNetwork(SpringNetworkSpec spec) : spec_(std::move(spec)) {
  const int np = particle_count();
  if (static_cast<int>(spec_.masses.size()) != np)
    throw std::invalid_argument("spring network: one mass per particle is required");
  if (spec_.pinned.size() != spec_.pin_paths.size())
    throw std::invalid_argument("spring network: one pin path per pinned particle is required");
  if (!(spec_.damping >= 0.0) || !std::isfinite(spec_.damping))
    throw std::invalid_argument("spring network: damping must be >= 0 N s/m");
  if (!(spec_.limit_stiffness_factor >= 0.0))
    throw std::invalid_argument("spring network: limit_stiffness_factor must be >= 0");
  for (const Vec3& p : spec_.positions)
    if (!is_finite(p)) throw std::invalid_argument("spring network: non-finite particle position");

  free_index_.assign(np, 0);
  pin_slot_.assign(np, -1);
  for (size_t k = 0; k < spec_.pinned.size(); ++k) {
    const int p = spec_.pinned[k];
    if (p < 0 || p >= np) throw std::invalid_argument("spring network: pin index out of range");
    if (pin_slot_[p] >= 0) throw std::invalid_argument("spring network: particle pinned twice");
    pin_slot_[p] = static_cast<int>(k);
    free_index_[p] = -1;
    pin_move_time_ = std::max(pin_move_time_, spec_.pin_paths[k].move_time);
  }
  free_count_ = 0;
  for (int p = 0; p < np; ++p)
    if (free_index_[p] >= 0) free_index_[p] = free_count_++;

  const int n = dof();
  dof_mass_.resize(n);
  inv_mass_.resize(n);
  gamma_.resize(n);
  double mass_sum = 0.0;
  for (int p = 0; p < np; ++p) {
    const int f = free_index_[p];
    if (f < 0) continue;
    const double m = spec_.masses[p];
    if (!(m > 0.0) || !std::isfinite(m))
      throw std::invalid_argument("spring network: particle masses must be > 0 kg");
    mass_sum += m;
    for (int c = 0; c < 3; ++c) {
      dof_mass_[3 * f + c] = m;
      inv_mass_[3 * f + c] = 1.0 / m;
      gamma_[3 * f + c] = spec_.damping / m;
    }
  }
  const double g = norm(spec_.gravity);
  if (spec_.residual_force_scale > 0.0) {
    residual_scale_ = spec_.residual_force_scale;
  } else if (free_count_ > 0 && g > 0.0) {
    residual_scale_ = mass_sum / free_count_ * g;
  } else {
    throw std::invalid_argument(
        "spring network: residual_force_scale must be > 0 N when there is no gravity");
  }

  // Springs: validate; their stiffness pattern is built on first use (stiffness_layout).
  throw_if_stop_requested();  // a grid near its cap: each pass takes about a second
  for (const Spring& s : spec_.springs) {
    if (s.a < 0 || s.a >= np || s.b < 0 || s.b >= np || s.a == s.b)
      throw std::invalid_argument("spring network: spring end out of range or self-loop");
    if (!(s.rest > 0.0) || !std::isfinite(s.rest))
      throw std::invalid_argument("spring network: spring rest length must be > 0 m");
    if (!(s.stiffness > 0.0) || !std::isfinite(s.stiffness))
      throw std::invalid_argument("spring network: spring stiffness must be > 0 N/m");
  }
  throw_if_stop_requested();
  for (const Stencil& st : spec_.stencils) {
    int count = 0;
    while (count < 4 && st.particles[count] >= 0) ++count;
    for (int i = 0; i < 4; ++i) {
      const int p = st.particles[i];
      if (i >= count ? p >= 0 : (p >= np || !std::isfinite(st.weights[i])))
        throw std::invalid_argument("spring network: stencil particle out of range or bad weight");
      for (int j = 0; j < i && i < count; ++j)
        if (st.particles[j] == p)
          throw std::invalid_argument("spring network: stencil names a particle twice");
    }
    if (count < 2) throw std::invalid_argument("spring network: a stencil needs 2-4 particles");
    if (!(st.stiffness > 0.0) || !std::isfinite(st.stiffness))
      throw std::invalid_argument("spring network: stencil stiffness must be > 0 N/m");
  }
  if (!(spec_.plane_stiffness >= 0.0) || !std::isfinite(spec_.plane_stiffness))
    throw std::invalid_argument("spring network: plane_stiffness must be >= 0 N/m and finite");
  if (planar()) {
    bool flat = spec_.gravity.z == 0.0 && spec_.stencils.empty();
    for (const Vec3& q : spec_.positions) flat = flat && q.z == 0.0;
    for (const PinPath& pin : spec_.pin_paths)
      flat = flat && pin.start.z == 0.0 && pin.end.z == 0.0;
    if (!flat)
      throw std::invalid_argument(
          "spring network: a planar network (plane_stiffness > 0) needs every particle and pin at "
          "z = 0, no gravity along z and no stencils");
  }
  structure_ = std::make_shared<StiffnessStructure>();
}

namespace {

// The stiffness layouts of the latest meshes: a fit builds the same few (grid size x topology
// x reduction) for thousands of drapes, each of which would otherwise build its layout again.
// A hit is the layout itself, bit for bit what a fresh build gives.
PatternMemo<SpringNetwork::StiffnessLayout>& layout_memo() {
  static PatternMemo<SpringNetwork::StiffnessLayout> memo(std::size_t{1} << 23);  // 32 MB
  return memo;
}

// The layout of springs with these free ends (2 per spring) and stencils with these (4 per
// stencil) among `free_count` free particles. Each element (a spring or a stencil) couples
// every ordered pair of its free ends by a 3x3 block: a spring's is full, a stencil's diagonal.
SpringNetwork::StiffnessLayout build_layout(int free_count, std::vector<int> ends,
                                            std::vector<int> stencil_ends) {
  SpringNetwork::StiffnessLayout layout;
  std::vector<std::pair<int, int>> pairs;  // the pairs of free ends, element by element
  pairs.reserve(2 * ends.size() + 4 * stencil_ends.size());
  auto add_pairs = [&](const std::vector<int>& el_ends, int k) {
    for (std::size_t first = 0; first < el_ends.size(); first += k)
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
          const int r = el_ends[first + i], c = el_ends[first + j];
          if (r >= 0 && c >= 0) pairs.emplace_back(r, c);
        }
  };
  add_pairs(ends, 2);
  add_pairs(stencil_ends, 4);
  std::vector<int> pair_entry;
  const CscPattern nodes = make_csc_pattern(free_count, free_count, std::move(pairs),
                                            /*with_diagonal=*/true, &pair_entry);
  layout.pattern = expand_node_pattern(nodes);
  // Per element, k x k blocks (i, j) of 9 value positions (3 p + q), or of 3 (p) if diagonal;
  // -1 where an end is pinned or absent.
  int next_pair = 0;  // the pairs in the order added above
  auto place = [&](const std::vector<int>& el_ends, int k, bool diagonal, std::vector<int>& slots) {
    const int per_block = diagonal ? 3 : 9;
    slots.assign(el_ends.size() * k * per_block, -1);
    for (std::size_t el = 0; el < el_ends.size() / k; ++el) {
      const int* end = &el_ends[el * k];
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
          if (end[i] < 0 || end[j] < 0) continue;
          const int e = pair_entry[next_pair++];
          int* block = &slots[((el * k + i) * k + j) * per_block];
          for (int p = 0; p < 3; ++p)
            for (int q = diagonal ? p : 0; q < (diagonal ? p + 1 : 3); ++q)
              block[diagonal ? p : 3 * p + q] = node_block_entry(nodes, e, end[j], p, q);
        }
    }
  };
  place(ends, 2, /*diagonal=*/false, layout.slots);
  place(stencil_ends, 4, /*diagonal=*/true, layout.stencil_slots);
  layout.free_count = free_count;
  layout.ends = std::move(ends);
  layout.stencil_ends = std::move(stencil_ends);
  return layout;
}

}  // namespace

const SpringNetwork::StiffnessLayout& SpringNetwork::stiffness_layout() const {
  StiffnessStructure& st = *structure_;
  std::call_once(st.once, [&] {
    std::vector<int> ends;
    ends.reserve(2 * spec_.springs.size());
    for (const Spring& s : spec_.springs) {
      ends.push_back(free_index_[s.a]);
      ends.push_back(free_index_[s.b]);
    }
    std::vector<int> stencil_ends;
    stencil_ends.reserve(4 * spec_.stencils.size());
    for (const Stencil& s : spec_.stencils)
      for (int p : s.particles) stencil_ends.push_back(p < 0 ? -1 : free_index_[p]);
    st.layout = layout_memo().find([&](const StiffnessLayout& e) {
      return e.free_count == free_count_ && e.ends == ends && e.stencil_ends == stencil_ends;
    });
    if (!st.layout) {
      auto fresh = std::make_shared<const StiffnessLayout>(
          build_layout(free_count_, std::move(ends), std::move(stencil_ends)));
      const std::size_t held = fresh->ends.size() + fresh->slots.size() +
                               fresh->stencil_ends.size() + fresh->stencil_slots.size() +
                               fresh->pattern.colptr.size() + fresh->pattern.rowind.size();
      st.layout = layout_memo().insert(std::move(fresh), held);
    }
  });
  return *st.layout;
}

void SpringNetwork::initial_state(double* x, double* v) const {
  for (int p = 0; p < particle_count(); ++p) {
    const int f = free_index_[p];
    if (f < 0) continue;
    const Vec3& q = spec_.positions[p];
    x[3 * f] = q.x;
    x[3 * f + 1] = q.y;
    x[3 * f + 2] = q.z;
  }
  std::fill(v, v + dof(), 0.0);
}

std::vector<Vec3> SpringNetwork::pins_at(double t) const {
  std::vector<Vec3> pins(spec_.pinned.size());
  for (size_t k = 0; k < pins.size(); ++k) pins[k] = spec_.pin_paths[k].at(t);
  return pins;
}

inline Vec3 SpringNetwork::end_position(int particle, const double* x,
                                        const std::vector<Vec3>& pins) const {
  const int f = free_index_[particle];
  if (f >= 0) return {x[3 * f], x[3 * f + 1], x[3 * f + 2]};
  return pins[pin_slot_[particle]];
}

// b's position minus a's; in the plane (z dropped) for a planar network (header, "Planar").
inline Vec3 SpringNetwork::spring_vector(const Spring& s, const double* x,
                                         const std::vector<Vec3>& pins) const {
  Vec3 d = end_position(s.b, x, pins) - end_position(s.a, x, pins);
  if (planar()) d.z = 0.0;
  return d;
}

inline void SpringNetwork::spring_force_law(const Spring& s, double L, double& f,
                                            double& df) const {
  f = s.stiffness * (L - s.rest);
  df = s.stiffness;
  if (spec_.elongation_limit > 0.0) {
    const double over = L - s.rest * (1.0 + spec_.elongation_limit);
    if (over > 0.0) {
      const double klim = spec_.limit_stiffness_factor * s.stiffness;
      f += klim * over;
      df += klim;
    }
  }
}

inline Vec3 SpringNetwork::stencil_vector(const Stencil& st, const double* x,
                                          const std::vector<Vec3>& pins) const {
  Vec3 v{};
  for (int i = 0; i < 4 && st.particles[i] >= 0; ++i)
    v = v + st.weights[i] * end_position(st.particles[i], x, pins);
  return v;
}

// F_i = -k w_i v on each free particle i of a stencil with k v = kv.
void SpringNetwork::add_stencil_force(const Stencil& st, Vec3 kv, double* out) const {
  for (int i = 0; i < 4 && st.particles[i] >= 0; ++i) {
    const int f = free_index_[st.particles[i]];
    if (f < 0) continue;
    out[3 * f] -= st.weights[i] * kv.x;
    out[3 * f + 1] -= st.weights[i] * kv.y;
    out[3 * f + 2] -= st.weights[i] * kv.z;
  }
}

void SpringNetwork::net_force(double t, const double* x, double* force) const {
  const std::vector<Vec3> pins = pins_at(t);
  const int n = dof();
  for (int i = 0; i < n; i += 3) {
    force[i] = dof_mass_[i] * spec_.gravity.x;
    force[i + 1] = dof_mass_[i] * spec_.gravity.y;
    force[i + 2] = dof_mass_[i] * spec_.gravity.z - spec_.plane_stiffness * x[i + 2];
  }
  for (const Spring& s : spec_.springs) {
    const int fa = free_index_[s.a], fb = free_index_[s.b];
    if (fa < 0 && fb < 0) continue;
    const Vec3 d = spring_vector(s, x, pins);
    const double L = norm(d);
    double f, df;
    spring_force_law(s, L, f, df);
    const Vec3 F = (f / L) * d;  // force on a
    add_spring_pair(force, fa, fb, F);
  }
  for (const Stencil& st : spec_.stencils)
    add_stencil_force(st, st.stiffness * stencil_vector(st, x, pins), force);
}

void SpringNetwork::net_force_tangent(double t, const double* x, const SpringNetworkTangent& dp,
                                      double* df) const {
  auto check = [](size_t size, size_t expected, const char* what) {
    if (size != 0 && size != expected)
      throw std::invalid_argument(std::string("net_force_tangent: ") + what + " has " +
                                  std::to_string(size) + " entries, expected " +
                                  std::to_string(expected) + " (or none)");
  };
  check(dp.stiffness.size(), spec_.springs.size(), "stiffness");
  check(dp.rest.size(), spec_.springs.size(), "rest");
  check(dp.mass.size(), spec_.positions.size(), "mass");
  check(dp.pin_position.size(), spec_.pinned.size(), "pin_position");
  const std::vector<Vec3> pins = pins_at(t);
  const int n = dof();
  std::fill(df, df + n, 0.0);
  if (!dp.mass.empty())
    for (int p = 0; p < particle_count(); ++p) {
      const int f = free_index_[p];
      if (f < 0) continue;
      df[3 * f] += dp.mass[p] * spec_.gravity.x;
      df[3 * f + 1] += dp.mass[p] * spec_.gravity.y;
      df[3 * f + 2] += dp.mass[p] * spec_.gravity.z;
    }
  auto pin_tangent = [&](int particle) {
    const int slot = pin_slot_[particle];
    return (slot < 0 || dp.pin_position.empty()) ? Vec3{} : dp.pin_position[slot];
  };
  for (size_t si = 0; si < spec_.springs.size(); ++si) {
    const Spring& s = spec_.springs[si];
    const int fa = free_index_[s.a], fb = free_index_[s.b];
    if (fa < 0 && fb < 0) continue;
    const Vec3 d = spring_vector(s, x, pins);
    const double L = norm(d);
    double f, dfdL;
    spring_force_law(s, L, f, dfdL);
    const double dk = dp.stiffness.empty() ? 0.0 : dp.stiffness[si];
    const double dL0 = dp.rest.empty() ? 0.0 : dp.rest[si];
    double dfp = dk * (L - s.rest) - s.stiffness * dL0;
    if (spec_.elongation_limit > 0.0) {
      const double over = L - s.rest * (1.0 + spec_.elongation_limit);
      if (over > 0.0)
        dfp += spec_.limit_stiffness_factor *
               (dk * over - s.stiffness * (dL0 * (1.0 + spec_.elongation_limit) +
                                           s.rest * dp.elongation_limit));
    }
    Vec3 dF = (dfp / L) * d;  // on a
    Vec3 dd = pin_tangent(s.b) - pin_tangent(s.a);
    if (planar()) dd.z = 0.0;
    if (dd.x != 0.0 || dd.y != 0.0 || dd.z != 0.0) {
      const Vec3 u = (1.0 / L) * d;
      dF = dF + ((dfdL - f / L) * dot(u, dd)) * u + (f / L) * dd;
    }
    add_spring_pair(df, fa, fb, dF);
  }
  if (!dp.pin_position.empty())
    for (const Stencil& st : spec_.stencils) {
      Vec3 dv{};
      for (int i = 0; i < 4 && st.particles[i] >= 0; ++i)
        dv = dv + st.weights[i] * pin_tangent(st.particles[i]);
      add_stencil_force(st, st.stiffness * dv, df);
    }
}

void SpringNetwork::conservative_acceleration(double t, const double* x, double* a) const {
  net_force(t, x, a);
  for (int i = 0; i < dof(); ++i) a[i] *= inv_mass_[i];
}

void SpringNetwork::constant_acceleration(double /*t*/, double* a) const {
  for (int i = 0; i < dof(); i += 3) {
    a[i] = spec_.gravity.x;
    a[i + 1] = spec_.gravity.y;
    a[i + 2] = spec_.gravity.z;
  }
}

void SpringNetwork::stiffness_values(double t, const double* x, double* values) const {
  const std::vector<Vec3> pins = pins_at(t);
  const StiffnessLayout& st = stiffness_layout();
  std::fill(values, values + st.pattern.nnz(), 0.0);
  for (size_t si = 0; si < spec_.springs.size(); ++si) {
    const Spring& s = spec_.springs[si];
    const int fa = free_index_[s.a], fb = free_index_[s.b];
    if (fa < 0 && fb < 0) continue;
    const Vec3 d = spring_vector(s, x, pins);
    const double L = norm(d);
    double f, df;
    spring_force_law(s, L, f, df);
    const double u[3] = {d.x / L, d.y / L, d.z / L};
    const double fl = f / L;
    double B[9];
    for (int p = 0; p < 3; ++p)
      for (int q = 0; q < 3; ++q) B[3 * p + q] = (df - fl) * u[p] * u[q] + (p == q ? fl : 0.0);
    if (planar()) B[8] = 0.0;  // its length does not depend on z
    // Blocks aa = -B, ab = +B, ba = +B, bb = -B; row r scaled by 1/m_r.
    const int* slot = &st.slots[si * 36];
    const int ends[2] = {fa, fb};
    for (int blk = 0; blk < 4; ++blk) {
      const int row_end = ends[blk / 2];
      if (row_end < 0 || ends[blk % 2] < 0) continue;
      const double sign = (blk == 0 || blk == 3) ? -1.0 : 1.0;
      const double scale = sign * inv_mass_[3 * row_end];
      for (int e = 0; e < 9; ++e) values[slot[blk * 9 + e]] += scale * B[e];
    }
  }
  // The plane: -k_p / m on each free particle's z diagonal (the diagonal blocks are in the
  // pattern).
  if (planar())
    for (int f = 0; f < free_count_; ++f) {
      const int e = st.pattern.find(3 * f + 2, 3 * f + 2);
      values[e] -= spec_.plane_stiffness * inv_mass_[3 * f + 2];
    }
  // Stencils: block (i, j) = -k w_i w_j I, row i scaled by 1/m_i.
  for (size_t si = 0; si < spec_.stencils.size(); ++si) {
    const Stencil& s = spec_.stencils[si];
    const int* slot = &st.stencil_slots[si * 48];
    for (int i = 0; i < 4 && s.particles[i] >= 0; ++i) {
      const int fi = free_index_[s.particles[i]];
      if (fi < 0) continue;
      for (int j = 0; j < 4 && s.particles[j] >= 0; ++j) {
        if (slot[(4 * i + j) * 3] < 0) continue;
        const double value = -s.stiffness * s.weights[i] * s.weights[j] * inv_mass_[3 * fi];
        for (int p = 0; p < 3; ++p) values[slot[(4 * i + j) * 3 + p]] += value;
      }
    }
  }
}

double SpringNetwork::static_residual(double t, const double* x) const {
  std::vector<double> scratch(dof());
  net_force(t, x, scratch.data());
  double worst = 0.0;
  for (int i = 0; i < dof(); i += 3) {
    const double f2 =
        scratch[i] * scratch[i] + scratch[i + 1] * scratch[i + 1] + scratch[i + 2] * scratch[i + 2];
    if (!(f2 <= worst)) worst = f2;  // NaN propagates
  }
  return std::sqrt(worst) / residual_scale_;
}

double SpringNetwork::residual_roundoff(double t, const double* x) const {
  const std::vector<Vec3> pins = pins_at(t);
  std::vector<double> scratch(dof(), 0.0);  // per free particle, at 3 f
  for (const Spring& s : spec_.springs) {
    const int fa = free_index_[s.a], fb = free_index_[s.b];
    if (fa < 0 && fb < 0) continue;
    const double e = s.stiffness * std::numeric_limits<double>::epsilon() *
                     (norm(end_position(s.a, x, pins)) + norm(end_position(s.b, x, pins)));
    if (fa >= 0) scratch[3 * fa] += e;
    if (fb >= 0) scratch[3 * fb] += e;
  }
  // A stencil's k v carries up to k eps sum_j |w_j| |x_j|; particle i gets |w_i| of it.
  for (const Stencil& st : spec_.stencils) {
    double e = 0.0;
    for (int j = 0; j < 4 && st.particles[j] >= 0; ++j)
      e += std::abs(st.weights[j]) * norm(end_position(st.particles[j], x, pins));
    e *= st.stiffness * std::numeric_limits<double>::epsilon();
    for (int i = 0; i < 4 && st.particles[i] >= 0; ++i) {
      const int f = free_index_[st.particles[i]];
      if (f >= 0) scratch[3 * f] += std::abs(st.weights[i]) * e;
    }
  }
  if (scratch.empty()) return 0.0;
  return *std::max_element(scratch.begin(), scratch.end()) / residual_scale_;
}

bool SpringNetwork::project(double t, double* x, double* /*v*/) const {
  if (spec_.elongation_limit <= 0.0) return false;
  const std::vector<Vec3> pins = pins_at(t);
  bool moved = false;
  for (const Spring& s : spec_.springs) {
    const int fa = free_index_[s.a], fb = free_index_[s.b];
    if (fa < 0 && fb < 0) continue;
    const Vec3 d = spring_vector(s, x, pins);
    const double Lmax = s.rest * (1.0 + spec_.elongation_limit);
    const double L2 = dot(d, d);
    if (!(L2 > Lmax * Lmax)) continue;  // the common case costs no square root
    const double L = std::sqrt(L2);
    const Vec3 excess = ((L - Lmax) / L) * d;  // shortening vector, a -> b direction
    const double wa = (fa >= 0 && fb >= 0) ? 0.5 : (fa >= 0 ? 1.0 : 0.0);
    const double wb = 1.0 - wa;
    if (fa >= 0) {
      x[3 * fa] += wa * excess.x;
      x[3 * fa + 1] += wa * excess.y;
      x[3 * fa + 2] += wa * excess.z;
    }
    if (fb >= 0) {
      x[3 * fb] -= wb * excess.x;
      x[3 * fb + 1] -= wb * excess.y;
      x[3 * fb + 2] -= wb * excess.z;
    }
    moved = true;
  }
  return moved;
}

double SpringNetwork::potential_energy(double t, const double* x) const {
  const std::vector<Vec3> pins = pins_at(t);
  double e = 0.0;
  for (const Spring& s : spec_.springs) {
    if (free_index_[s.a] < 0 && free_index_[s.b] < 0) continue;
    const double L = norm(spring_vector(s, x, pins));
    e += 0.5 * s.stiffness * (L - s.rest) * (L - s.rest);
    if (spec_.elongation_limit > 0.0) {
      const double over = L - s.rest * (1.0 + spec_.elongation_limit);
      if (over > 0.0) e += 0.5 * spec_.limit_stiffness_factor * s.stiffness * over * over;
    }
  }
  for (const Stencil& st : spec_.stencils) {
    bool moves = false;
    for (int i = 0; i < 4 && st.particles[i] >= 0; ++i) moves |= free_index_[st.particles[i]] >= 0;
    if (!moves) continue;
    const Vec3 v = stencil_vector(st, x, pins);
    e += 0.5 * st.stiffness * dot(v, v);
  }
  for (int i = 0; i < dof(); i += 3)
    e += 0.5 * spec_.plane_stiffness * x[i + 2] * x[i + 2] -
         dof_mass_[i] *
             (spec_.gravity.x * x[i] + spec_.gravity.y * x[i + 1] + spec_.gravity.z * x[i + 2]);
  return e;
}

void SpringNetwork::set_held_positions(const std::vector<Vec3>& p) {
  if (p.size() != spec_.pinned.size())
    throw std::invalid_argument("spring network: " + std::to_string(p.size()) +
                                " held positions for " + std::to_string(spec_.pinned.size()) +
                                " pins");
  for (const Vec3& q : p)
    if (!is_finite(q)) throw std::invalid_argument("spring network: non-finite held position");
  for (size_t k = 0; k < p.size(); ++k) spec_.pin_paths[k] = {p[k], p[k], 0.0};
  pin_move_time_ = 0.0;
}

void SpringNetwork::held_reactions(double t, const double* x, std::vector<Vec3>& out) const {
  const std::vector<Vec3> pins = pins_at(t);
  out.assign(pins.size(), Vec3{});
  // The model's forces on each held point: its weight, the plane's hold, springs and stencils.
  for (size_t k = 0; k < pins.size(); ++k) {
    const double m = spec_.masses[spec_.pinned[k]];
    out[k] = m * spec_.gravity;
    out[k].z -= spec_.plane_stiffness * pins[k].z;
  }
  for (const Spring& s : spec_.springs) {
    const int ha = pin_slot_[s.a], hb = pin_slot_[s.b];
    if (ha < 0 && hb < 0) continue;
    const Vec3 d = spring_vector(s, x, pins);
    const double L = norm(d);
    double f, df;
    spring_force_law(s, L, f, df);
    const Vec3 F = (f / L) * d;  // on a
    if (ha >= 0) out[ha] = out[ha] + F;
    if (hb >= 0) out[hb] = out[hb] - F;
  }
  for (const Stencil& st : spec_.stencils) {
    const Vec3 kv = st.stiffness * stencil_vector(st, x, pins);
    for (int i = 0; i < 4 && st.particles[i] >= 0; ++i) {
      const int h = pin_slot_[st.particles[i]];
      if (h >= 0) out[h] = out[h] - st.weights[i] * kv;
    }
  }
  for (Vec3& r : out) r = -1.0 * r;  // the hold's force balances them
}

void SpringNetwork::all_positions(double t, const double* x, std::vector<Vec3>& out) const {
  const std::vector<Vec3> pins = pins_at(t);
  out.resize(particle_count());
  for (int p = 0; p < particle_count(); ++p) out[p] = end_position(p, x, pins);
}

double SpringNetwork::max_strain(double t, const double* x) const {
  const std::vector<Vec3> pins = pins_at(t);
  double worst = -1.0;
  for (const Spring& s : spec_.springs) {
    const double L = norm(spring_vector(s, x, pins));
    worst = std::max(worst, (L - s.rest) / s.rest);
  }
  return worst;
}

bool SpringNetwork::free_floating() const {
  return spec_.free_floating && spec_.pinned.empty() && spec_.gravity.x == 0.0 &&
         spec_.gravity.y == 0.0 && spec_.gravity.z == 0.0;
}

std::string SpringNetwork::describe() const {
  std::ostringstream os;
  os << particle_count() << " particles (" << free_count_ << " free), " << spec_.springs.size()
     << " springs, ";
  if (!spec_.stencils.empty()) os << spec_.stencils.size() << " bending stencils, ";
  if (planar()) os << "planar, ";
  os << dof() << " dof, Jacobian nnz " << stiffness_pattern().nnz();
  return os.str();
}

}  // namespace knitsim
