#include "models/yarn_rods.hpp"

#include "models/rod_elements.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "src/core/invalid_field.hpp"
#include "src/geometry/segment_distance.hpp"

namespace knitsim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kStandardGravity = 9.81;  // m/s^2, only for the default residual scale
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
// The step filter's reach, in d: a step is cut so that no vertex moves more than
// kStepReach (1 - step_keep) d, which bounds its broad phase's boxes (admissible_step).
constexpr double kStepReach = 2.0;
// Edge pairs whose segments are farther apart than kSkipBeyond d have no sample pair within d.
constexpr double kSkipBeyond = 1.0 + 1e-9;

// Throws unless value is in the interval (lo or [lo, hi] or hi); `range` names it.
void check_range(const char* field, double value, double lo, double hi, bool lo_open,
                 const char* range, bool hi_open = false) {
  const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) &&
                  (hi_open ? value < hi : value <= hi);
  // An InvalidField, so the key table can name the key and state its range (src/scene).
  if (!ok) bad_field(std::string("yarn.") + field, value, std::string("must be in ") + range);
}

double component(Vec3 v, int c) { return c == 0 ? v.x : (c == 1 ? v.y : v.z); }

// The shifted IPC barrier psi(D) = kappa (d - d0)^2 phi(g) and its first two derivatives in D.
struct Barrier {
  double e, de, dde;
};
Barrier barrier(double D, double d, double d0, double kappa) {
  const double w = d - d0, g = (D - d0) / w, lg = std::log(g), gm = g - 1.0;
  const double phi = -gm * gm * lg;
  const double dphi = -2.0 * gm * lg - gm * gm / g;
  const double ddphi = -2.0 * lg - 4.0 * gm / g + gm * gm / (g * g);
  return {kappa * w * w * phi, kappa * w * dphi, kappa * ddphi};
}

}  // namespace

ContactBarrier contact_barrier(double D, double d, double d0, double kappa) {
  const Barrier b = barrier(D, d, d0, kappa);
  return {b.e, b.de, b.dde};
}

bool bend_element(const Vec3& x0, const Vec3& x1, const Vec3& x2, double K, double kappa0,
                  int order, BendElement& out) {
  const Vec3 e0 = x1 - x0, e1 = x2 - x1;
  const double a = norm(e0), b = norm(e1), c = dot(e0, e1), q = a * b, s = q + c;
  if (!(s > 0.0) || !(a > 0.0) || !(b > 0.0)) return false;  // folded back (or degenerate)
  const double f = 4.0 * (q - c) / s;                         // kappa^2
  double G, dG, ddG;  // G(f) and its derivatives in f
  if (kappa0 == 0.0) {
    G = K * f, dG = K, ddG = 0.0;
  } else {
    const double kappa = std::sqrt(f);
    if (!(kappa > 0.0) && order > 0) return false;  // the cone of a bent rest shape at straight
    G = K * (kappa - kappa0) * (kappa - kappa0);
    dG = K * (1.0 - kappa0 / kappa);
    ddG = K * kappa0 / (2.0 * kappa * kappa * kappa);
  }
  out.energy = G;
  if (order == 0) return true;
  // Gradients in y = (e0, e1) of q = ab and c, then of f.
  const double y0[3] = {e0.x, e0.y, e0.z}, y1[3] = {e1.x, e1.y, e1.z};
  double gq[6], gc[6], gf[6];
  for (int i = 0; i < 3; ++i) {
    gq[i] = b * y0[i] / a;
    gq[3 + i] = a * y1[i] / b;
    gc[i] = y1[i];
    gc[3 + i] = y0[i];
  }
  const double s2 = s * s, s3 = s2 * s;
  const double fq = 8.0 * c / s2, fc = -8.0 * q / s2;
  for (int i = 0; i < 6; ++i) gf[i] = fq * gq[i] + fc * gc[i];
  // dE/dx0 = -dE/de0, dE/dx1 = dE/de0 - dE/de1, dE/dx2 = dE/de1
  for (int i = 0; i < 3; ++i) {
    out.grad[i] = -dG * gf[i];
    out.grad[3 + i] = dG * (gf[i] - gf[3 + i]);
    out.grad[6 + i] = dG * gf[3 + i];
  }
  if (order == 1) return true;
  // Hessian in y: f_q H_q + f_c H_c + f_qq gq gq^T + f_cc gc gc^T + f_qc (gq gc^T + gc gq^T),
  // H_q = b H_a + a H_b + ga gb^T + gb ga^T, H_a = (I - n0 n0^T) / a on the e0 block.
  const double fqq = -16.0 * c / s3, fcc = 16.0 * q / s3, fqc = 8.0 * (q - c) / s3;
  double ga[6] = {y0[0] / a, y0[1] / a, y0[2] / a, 0, 0, 0};
  double gb[6] = {0, 0, 0, y1[0] / b, y1[1] / b, y1[2] / b};
  double Hy[6][6];
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      double hq = ga[i] * gb[j] + gb[i] * ga[j];
      double hc = 0.0;
      if (i < 3 && j < 3) hq += b * ((i == j ? 1.0 : 0.0) - ga[i] * ga[j]) / a;
      if (i >= 3 && j >= 3) hq += a * ((i == j ? 1.0 : 0.0) - gb[i] * gb[j]) / b;
      if ((i < 3) != (j < 3) && i % 3 == j % 3) hc = 1.0;
      const double hf = fq * hq + fc * hc + fqq * gq[i] * gq[j] + fcc * gc[i] * gc[j] +
                        fqc * (gq[i] * gc[j] + gc[i] * gq[j]);
      Hy[i][j] = dG * hf + ddG * gf[i] * gf[j];
    }
  // x = (x0, x1, x2): e0 = x1 - x0, e1 = x2 - x1.
  static constexpr double kMap[2][3] = {{-1.0, 1.0, 0.0}, {0.0, -1.0, 1.0}};
  for (int r = 0; r < 3; ++r)
    for (int cc = 0; cc < 3; ++cc)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          double sum = 0.0;
          for (int P = 0; P < 2; ++P)
            for (int Q = 0; Q < 2; ++Q) sum += kMap[P][r] * kMap[Q][cc] * Hy[3 * P + i][3 * Q + j];
          out.hess[9 * (3 * r + i) + 3 * cc + j] = sum;
        }
  return true;
}

void YarnParams::validate() const {
  check_range("tex", tex, 0.0, 1e4, true, "(0, 1e4] tex");
  check_range("fibre_density", fibre_density, 500.0, 3000.0, false, "[500, 3000] kg/m^3");
  check_range("packing_fraction", packing_fraction, 0.1, 0.9, true, "(0.1, 0.9]");
  check_range("tensile_modulus", tensile_modulus, 0.0, 100.0, true, "(0, 100] N/tex");
  check_range("bending_rigidity", bending_rigidity, 0.0, 1e-3, true, "(0, 1e-3] N m^2");
  check_range("relaxation_time", relaxation_time, 0.0, 1e6, true, "(0, 1e6] s");
  check_range("contact_stiffness", contact_stiffness, 0.0, 1e9, false, "[0, 1e9] N/m");
  check_range("core_fraction", core_fraction, 0.25, 1.0, true, "(0.25, 1)", true);
  check_range("same_yarn_gap", same_yarn_gap, 1.0, 100.0, false, "[1, 100] diameters");
  check_range("pattern_radius", pattern_radius, 1.0, 1e3, false, "[1, 1e3] diameters");
  check_range("step_keep", step_keep, 0.0, 1.0, false, "[0, 1)", true);
}

double YarnParams::diameter() const {
  return std::sqrt(4.0 * linear_density() / (kPi * fibre_density * packing_fraction));
}

double YarnParams::contact_kappa() const {
  if (contact_stiffness > 0.0) return contact_stiffness;
  const double d = diameter();
  return 10.0 * bending_rigidity / (d * d * d);
}

// Where an evaluation writes: the energy always; -dE/dx per dof (Force); -M^-1 d2E/dx2 into the
// pattern's values (Stiffness). `bad` is set by a state outside the energy's domain.
struct YarnRods::Accumulator {
  double energy = 0.0;
  double* force = nullptr;
  double* values = nullptr;
  bool bad = false;
};

YarnRods::YarnRods(YarnRodsSpec spec) : spec_(std::move(spec)) {
  const YarnParams& p = spec_.yarn;
  p.validate();
  d_ = p.diameter();
  d0_ = p.core_fraction * d_;
  kappa_c_ = p.contact_kappa();
  gap_ = p.same_yarn_gap * d_;
  const int yarns = static_cast<int>(spec_.rest.size());
  if (yarns == 0) throw std::invalid_argument("yarn rods: no yarn given (rest is empty)");
  if (!spec_.initial.empty() && static_cast<int>(spec_.initial.size()) != yarns)
    throw std::invalid_argument("yarn rods: initial must be empty or have one polyline per yarn");
  if (!spec_.rest_curvature.empty() && static_cast<int>(spec_.rest_curvature.size()) != yarns)
    throw std::invalid_argument("yarn rods: rest_curvature must be empty or one list per yarn");

  for (int y = 0; y < yarns; ++y) {
    const auto& r = spec_.rest[y];
    const int n = static_cast<int>(r.size());
    if (n < 2)
      throw std::invalid_argument("yarn rods: yarn " + std::to_string(y) +
                                  " has fewer than 2 vertices");
    if (!spec_.initial.empty() && static_cast<int>(spec_.initial[y].size()) != n)
      throw std::invalid_argument("yarn rods: initial[" + std::to_string(y) +
                                  "] must have as many vertices as rest");
    if (!spec_.rest_curvature.empty() && static_cast<int>(spec_.rest_curvature[y].size()) != n)
      throw std::invalid_argument("yarn rods: rest_curvature[" + std::to_string(y) +
                                  "] must have one value per vertex");
    yarn_first_.push_back(static_cast<int>(vertex_yarn_.size()));
    double arc = 0.0;
    for (int i = 0; i < n; ++i) {
      const Vec3 s = spec_.initial.empty() ? r[i] : spec_.initial[y][i];
      if (!is_finite(r[i]) || !is_finite(s))
        throw std::invalid_argument("yarn rods: a vertex of yarn " + std::to_string(y) +
                                    " is not finite");
      vertex_yarn_.push_back(y);
      start_.push_back(s);
      if (i + 1 < n) {
        const double l = norm(r[i + 1] - r[i]);
        if (!(l > 0.0))
          throw std::invalid_argument("yarn rods: yarn " + std::to_string(y) + " edge " +
                                      std::to_string(i) + " has zero rest length");
        const int v = yarn_first_[y] + i;
        const int samples = std::max(1, static_cast<int>(std::ceil(4.0 * l / d_)));
        edges_.push_back({v, v + 1, l, arc, y, samples});
        arc += l;
      }
    }
    for (int i = 1; i + 1 < n; ++i) {
      const int v = yarn_first_[y] + i;
      const double k0 = spec_.rest_curvature.empty() ? 0.0 : spec_.rest_curvature[y][i];
      if (!(std::isfinite(k0) && k0 >= 0.0))
        throw std::invalid_argument("yarn rods: rest_curvature must be finite and >= 0");
      const double lbar = 0.5 * (norm(r[i] - r[i - 1]) + norm(r[i + 1] - r[i]));
      bends_.push_back({{v - 1, v, v + 1}, lbar, k0});
    }
  }
  yarn_first_.push_back(static_cast<int>(vertex_yarn_.size()));

  const int nv = vertex_count();
  std::vector<bool> pinned(nv, false);
  for (const YarnVertex& pin : spec_.pins) {
    if (pin.yarn < 0 || pin.yarn >= yarns || pin.vertex < 0 ||
        pin.vertex >= yarn_first_[pin.yarn + 1] - yarn_first_[pin.yarn])
      throw std::invalid_argument("yarn rods: pin out of range");
    const int v = vertex_index(pin.yarn, pin.vertex);
    if (pinned[v]) throw std::invalid_argument("yarn rods: a vertex is pinned twice");
    pinned[v] = true;
  }
  free_index_.assign(nv, -1);
  for (int v = 0; v < nv; ++v)
    if (!pinned[v]) free_index_[v] = free_count_++;

  vertex_mass_.assign(nv, 0.0);
  for (const Edge& e : edges_) {
    vertex_mass_[e.a] += 0.5 * p.linear_density() * e.rest;
    vertex_mass_[e.b] += 0.5 * p.linear_density() * e.rest;
  }
  dof_mass_.assign(dof(), 0.0);
  gamma_.assign(dof(), 1.0 / p.relaxation_time);
  double free_mass = 0.0;
  for (int v = 0; v < nv; ++v)
    if (free_index_[v] >= 0) {
      for (int c = 0; c < 3; ++c) dof_mass_[3 * free_index_[v] + c] = vertex_mass_[v];
      free_mass += vertex_mass_[v];
    }
  load_.assign(dof(), 0.0);
  for (const YarnLoad& l : spec_.loads) {
    if (l.at.yarn < 0 || l.at.yarn >= yarns || l.at.vertex < 0 ||
        l.at.vertex >= yarn_first_[l.at.yarn + 1] - yarn_first_[l.at.yarn] || !is_finite(l.force))
      throw std::invalid_argument("yarn rods: load out of range or not finite");
    const int f = free_index_[vertex_index(l.at.yarn, l.at.vertex)];
    if (f < 0) continue;  // a load on a pin does nothing
    load_[3 * f] += l.force.x;
    load_[3 * f + 1] += l.force.y;
    load_[3 * f + 2] += l.force.z;
  }
  if (!is_finite(spec_.gravity)) throw std::invalid_argument("yarn rods: gravity not finite");
  if (!(std::isfinite(spec_.residual_force_scale) && spec_.residual_force_scale >= 0.0))
    throw std::invalid_argument("yarn rods: residual_force_scale must be >= 0 N");
  residual_scale_ = spec_.residual_force_scale > 0.0
                        ? spec_.residual_force_scale
                        : (free_count_ > 0 ? free_mass / free_count_ * kStandardGravity : 1.0);

  // The pattern: stretching and bending stencils, and the edge pairs near at the start.
  std::vector<std::pair<int, int>> node_pairs;
  auto add_block = [&](int r, int c) {
    const int fr = free_index_[r], fc = free_index_[c];
    if (fr >= 0 && fc >= 0) node_pairs.emplace_back(fr, fc);
  };
  for (const Edge& e : edges_)
    for (int r : {e.a, e.b})
      for (int c : {e.a, e.b}) add_block(r, c);
  for (const Bend& b : bends_)
    for (int r : b.v)
      for (int c : b.v) add_block(r, c);
  std::vector<std::pair<int, int>> near;
  if (spec_.contact) {
    const double radius = p.pattern_radius * d_;
    edge_pairs(start_, 0.5 * radius, near);
    near.erase(
        std::remove_if(
            near.begin(), near.end(),
            [&](const std::pair<int, int>& q) {
              const Edge &a = edges_[q.first], &b = edges_[q.second];
              return !may_pair(q.first, q.second) ||
                     closest_points(start_[a.a], start_[a.b], start_[b.a], start_[b.b]).distance >=
                         radius;
            }),
        near.end());
    for (const auto& [i, j] : near) {
      const int v[4] = {edges_[i].a, edges_[i].b, edges_[j].a, edges_[j].b};
      for (int r : v)
        for (int c : v) add_block(r, c);
    }
  }
  nodes_ = make_csc_pattern(free_count_, free_count_, std::move(node_pairs), true);
  pattern_ = expand_node_pattern(nodes_);
  auto entry = [&](int r, int c) {
    const int fr = free_index_[r], fc = free_index_[c];
    return fr >= 0 && fc >= 0 ? nodes_.find(fr, fc) : -1;
  };
  for (const Edge& e : edges_)
    edge_blocks_.push_back({entry(e.a, e.a), entry(e.a, e.b), entry(e.b, e.a), entry(e.b, e.b)});
  for (const Bend& b : bends_) {
    std::array<int, 9> blocks;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) blocks[3 * r + c] = entry(b.v[r], b.v[c]);
    bend_blocks_.push_back(blocks);
  }
  std::sort(near.begin(), near.end());
  contact_first_.assign(edges_.size() + 1, 0);
  for (const auto& [i, j] : near) {
    const int v[4] = {edges_[i].a, edges_[i].b, edges_[j].a, edges_[j].b};
    std::array<int, 16> blocks;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) blocks[4 * r + c] = entry(v[r], v[c]);
    contact_blocks_.push_back(blocks);
    contact_partner_.push_back(j);
    ++contact_first_[i + 1];
  }
  for (size_t i = 0; i < edges_.size(); ++i) contact_first_[i + 1] += contact_first_[i];
  pos_.resize(nv);
}

const std::array<int, 16>* YarnRods::contact_blocks(int i, int j) const {
  const auto first = contact_partner_.begin() + contact_first_[i];
  const auto last = contact_partner_.begin() + contact_first_[i + 1];
  const auto it = std::lower_bound(first, last, j);
  return it != last && *it == j ? &contact_blocks_[it - contact_partner_.begin()] : nullptr;
}

void YarnRods::initial_state(double* x, double* v) const {
  for (int i = 0; i < vertex_count(); ++i) {
    const int f = free_index_[i];
    if (f < 0) continue;
    x[3 * f] = start_[i].x;
    x[3 * f + 1] = start_[i].y;
    x[3 * f + 2] = start_[i].z;
  }
  std::fill(v, v + dof(), 0.0);
}

void YarnRods::all_positions(const double* x, std::vector<Vec3>& out) const {
  out.resize(vertex_count());
  for (int i = 0; i < vertex_count(); ++i) {
    const int f = free_index_[i];
    out[i] = f < 0 ? start_[i] : Vec3{x[3 * f], x[3 * f + 1], x[3 * f + 2]};
  }
}

bool YarnRods::samples_pair(int i, double si, int j, double sj) const {
  const Edge &a = edges_[i], &b = edges_[j];
  if (a.yarn != b.yarn) return true;
  return std::abs((a.arc + si * a.rest) - (b.arc + sj * b.rest)) >= gap_;
}

bool YarnRods::may_pair(int i, int j) const {
  const Edge &a = edges_[i], &b = edges_[j];
  if (i == j) return false;
  if (a.yarn != b.yarn) return true;
  const double a_lo = a.arc + 0.5 * a.rest / a.samples,
               a_hi = a.arc + a.rest - 0.5 * a.rest / a.samples;
  const double b_lo = b.arc + 0.5 * b.rest / b.samples,
               b_hi = b.arc + b.rest - 0.5 * b.rest / b.samples;
  return std::max(b_hi - a_lo, a_hi - b_lo) >= gap_;
}

template <class Visit>
void YarnRods::visit_edge_pairs(const std::vector<Vec3>& pos, double grow,
                                const std::vector<double>* edge_grow, Visit&& visit) const {
  const int ne = static_cast<int>(edges_.size());
  scratch_.resize(6 * static_cast<size_t>(ne));
  double* box = scratch_.data();  // per edge lo (3), hi (3)
  double cell = 0.0, origin[3] = {kInf, kInf, kInf}, top[3] = {-kInf, -kInf, -kInf};
  for (int e = 0; e < ne; ++e) {
    const Vec3 a = pos[edges_[e].a], b = pos[edges_[e].b];
    const double g = edge_grow ? grow + (*edge_grow)[e] : grow;
    for (int c = 0; c < 3; ++c) {
      const double lo = std::min(component(a, c), component(b, c)) - g;
      const double hi = std::max(component(a, c), component(b, c)) + g;
      box[6 * e + c] = lo;
      box[6 * e + 3 + c] = hi;
      cell = std::max(cell, hi - lo);
      origin[c] = std::min(origin[c], lo);
      top[c] = std::max(top[c], hi);
    }
  }
  if (!(cell > 0.0) || !std::isfinite(cell)) return;  // a non-finite state: no pairs
  constexpr double kCells = 1 << 20;                  // cells per axis, so a key fits 63 bits
  for (int c = 0; c < 3; ++c) cell = std::max(cell, (top[c] - origin[c]) / kCells);
  auto index = [&](double v, int c) {
    return static_cast<std::uint64_t>(std::floor((v - origin[c]) / cell));
  };
  auto key = [](std::uint64_t i, std::uint64_t j, std::uint64_t k) {
    return (i << 42) | (j << 21) | k;
  };
  cells_.clear();
  for (int e = 0; e < ne; ++e) {
    const double* b = box + 6 * e;
    for (std::uint64_t i = index(b[0], 0); i <= index(b[3], 0); ++i)
      for (std::uint64_t j = index(b[1], 1); j <= index(b[4], 1); ++j)
        for (std::uint64_t k = index(b[2], 2); k <= index(b[5], 2); ++k)
          cells_.emplace_back(key(i, j, k), e);
  }
  std::sort(cells_.begin(), cells_.end());
  for (size_t g = 0; g < cells_.size();) {
    size_t end = g + 1;
    while (end < cells_.size() && cells_[end].first == cells_[g].first) ++end;
    for (size_t p = g; p < end; ++p)
      for (size_t q = p + 1; q < end; ++q) {
        const int i = cells_[p].second, j = cells_[q].second;
        const double *bi = box + 6 * i, *bj = box + 6 * j;
        bool overlap = true;
        for (int c = 0; c < 3 && overlap; ++c) overlap = bi[c] <= bj[3 + c] && bj[c] <= bi[3 + c];
        if (!overlap) continue;
        // Reported once: in the cell holding the low corner of the overlap.
        const std::uint64_t owner =
            key(index(std::max(bi[0], bj[0]), 0), index(std::max(bi[1], bj[1]), 1),
                index(std::max(bi[2], bj[2]), 2));
        if (owner == cells_[g].first) visit(std::min(i, j), std::max(i, j));
      }
    g = end;
  }
}

void YarnRods::edge_pairs(const std::vector<Vec3>& pos, double grow,
                          std::vector<std::pair<int, int>>& out,
                          const std::vector<double>* edge_grow) const {
  out.clear();
  visit_edge_pairs(pos, grow, edge_grow, [&](int i, int j) { out.emplace_back(i, j); });
}

void YarnRods::evaluate(const double* x, Mode mode, Accumulator& acc) const {
  all_positions(x, pos_);
  const YarnParams& p = spec_.yarn;
  const double EA = p.stretch_stiffness();
  // Adds the energy-Hessian block h (3 x 3, row-major) at node entry e (row vertex r, column
  // vertex c) as -h / m_r into the values.
  auto add_block = [&](int e, int r, int c, const double* h) {
    if (e < 0) return;
    const int fc = free_index_[c];
    const double inv_m = 1.0 / vertex_mass_[r];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        acc.values[node_block_entry(nodes_, e, fc, a, b)] -= h[3 * a + b] * inv_m;
  };
  auto add_force = [&](int v, const double* g, double scale) {  // force -= scale g
    const int f = free_index_[v];
    if (f < 0) return;
    for (int c = 0; c < 3; ++c) acc.force[3 * f + c] -= scale * g[c];
  };

  for (size_t k = 0; k < edges_.size(); ++k) {
    const Edge& e = edges_[k];
    const Vec3 u = pos_[e.b] - pos_[e.a];
    const double L = norm(u), stiff = EA / e.rest, ext = L - e.rest;
    acc.energy += 0.5 * stiff * ext * ext;
    if (mode == Mode::Energy) continue;
    const double n[3] = {u.x / L, u.y / L, u.z / L};
    if (mode == Mode::Force) {
      const double g[3] = {stiff * ext * n[0], stiff * ext * n[1], stiff * ext * n[2]};
      add_force(e.b, g, 1.0);
      add_force(e.a, g, -1.0);
      continue;
    }
    double h[9], mh[9];
    const double t = stiff * ext / L;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        h[3 * a + b] = (stiff - t) * n[a] * n[b] + (a == b ? t : 0.0);
        mh[3 * a + b] = -h[3 * a + b];
      }
    const auto& bl = edge_blocks_[k];
    add_block(bl[0], e.a, e.a, h);
    add_block(bl[1], e.a, e.b, mh);
    add_block(bl[2], e.b, e.a, mh);
    add_block(bl[3], e.b, e.b, h);
  }

  for (size_t k = 0; k < bends_.size(); ++k) {
    const Bend& bd = bends_[k];
    BendElement el;
    const int order = mode == Mode::Energy ? 0 : (mode == Mode::Force ? 1 : 2);
    if (!bend_element(pos_[bd.v[0]], pos_[bd.v[1]], pos_[bd.v[2]],
                      p.bending_rigidity / (2.0 * bd.lbar), bd.kappa0, order, el)) {
      acc.bad = true;
      continue;
    }
    acc.energy += el.energy;
    if (mode == Mode::Energy) continue;
    if (mode == Mode::Force) {
      for (int r = 0; r < 3; ++r) add_force(bd.v[r], el.grad + 3 * r, 1.0);
      continue;
    }
    const auto& bl = bend_blocks_[k];
    for (int r = 0; r < 3; ++r)
      for (int cc = 0; cc < 3; ++cc) {
        if (bl[3 * r + cc] < 0) continue;
        double h[9];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) h[3 * i + j] = el.hess[9 * (3 * r + i) + 3 * cc + j];
        add_block(bl[3 * r + cc], bd.v[r], bd.v[cc], h);
      }
  }

  if (spec_.contact) contact_terms(pos_, mode, acc);

  // Dead loads and gravity: E -= F . x over free vertices.
  for (int v = 0; v < vertex_count(); ++v) {
    const int f = free_index_[v];
    if (f < 0) continue;
    const double xv[3] = {pos_[v].x, pos_[v].y, pos_[v].z};
    const double gv[3] = {spec_.gravity.x, spec_.gravity.y, spec_.gravity.z};
    for (int c = 0; c < 3; ++c) {
      const double F = load_[3 * f + c] + vertex_mass_[v] * gv[c];
      acc.energy -= F * xv[c];
      if (mode == Mode::Force) acc.force[3 * f + c] += F;
    }
  }
}

void YarnRods::contact_terms(const std::vector<Vec3>& pos, Mode mode, Accumulator& acc) const {
  // Integrators evaluate forces, stiffness and energy at one state in turn: the pairs found at
  // the same positions (compared exactly; a NaN never compares equal) are reused.
  bool same = pairs_pos_.size() == pos.size();
  for (size_t v = 0; same && v < pos.size(); ++v)
    same =
        pos[v].x == pairs_pos_[v].x && pos[v].y == pairs_pos_[v].y && pos[v].z == pairs_pos_[v].z;
  if (!same) {
    edge_pairs(pos, 0.5 * d_, pairs_);
    pairs_pos_ = pos;
  }
  const double d2 = d_ * d_;
  for (const auto& [i, j] : pairs_) {
    if (!may_pair(i, j)) continue;
    const Edge &A = edges_[i], &B = edges_[j];
    // Every sample pair is at least the segments' distance apart: a pair of edges farther than d
    // (with a margin for the round-off of the two distances) adds nothing, so its samples are
    // not visited (most of the broad phase's pairs on a knit: boxes grown by d/2 meet first).
    if (closest_points(pos[A.a], pos[A.b], pos[B.a], pos[B.b]).distance > kSkipBeyond * d_)
      continue;
    const int verts[4] = {A.a, A.b, B.a, B.b};
    double local[12][12];  // the pair's energy Hessian over its 4 vertices (Stiffness)
    bool active = false;
    const double w = (A.rest / A.samples) * (B.rest / B.samples) / d2;
    for (int k = 0; k < A.samples; ++k) {
      const double s = (k + 0.5) / A.samples;
      const Vec3 P = (1.0 - s) * pos[A.a] + s * pos[A.b];
      for (int m = 0; m < B.samples; ++m) {
        const double t = (m + 0.5) / B.samples;
        const Vec3 Q = (1.0 - t) * pos[B.a] + t * pos[B.b];
        const Vec3 u = P - Q;
        const double D = norm(u);
        if (!(D < d_)) continue;
        if (!samples_pair(i, s, j, t)) continue;
        if (!(D > d0_)) {
          acc.bad = true;
          continue;
        }
        const Barrier bar = barrier(D, d_, d0_, kappa_c_);
        acc.energy += w * bar.e;
        if (mode == Mode::Energy) continue;
        const double n[3] = {u.x / D, u.y / D, u.z / D};
        const double coef[4] = {1.0 - s, s, -(1.0 - t), -t};
        if (mode == Mode::Force) {
          const double g[3] = {w * bar.de * n[0], w * bar.de * n[1], w * bar.de * n[2]};
          for (int r = 0; r < 4; ++r) {
            const int f = free_index_[verts[r]];
            if (f < 0) continue;
            for (int c = 0; c < 3; ++c) acc.force[3 * f + c] -= coef[r] * g[c];
          }
          continue;
        }
        if (!active) {
          active = true;
          std::fill(&local[0][0], &local[0][0] + 144, 0.0);
        }
        double H[9];
        const double t1 = bar.de / D;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            H[3 * a + b] = w * ((bar.dde - t1) * n[a] * n[b] + (a == b ? t1 : 0.0));
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c)
            for (int a = 0; a < 3; ++a)
              for (int b = 0; b < 3; ++b)
                local[3 * r + a][3 * c + b] += coef[r] * coef[c] * H[3 * a + b];
      }
    }
    if (!active) continue;
    const std::array<int, 16>* blocks = contact_blocks(i, j);
    if (!blocks) {
      ++pattern_misses_;
      continue;
    }
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) {
        const int e = (*blocks)[4 * r + c];
        if (e < 0) continue;
        const int fc = free_index_[verts[c]];
        const double inv_m = 1.0 / vertex_mass_[verts[r]];
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            acc.values[node_block_entry(nodes_, e, fc, a, b)] -=
                local[3 * r + a][3 * c + b] * inv_m;
      }
  }
}

void YarnRods::net_force(const double* x, double* f) const {
  std::fill(f, f + dof(), 0.0);
  Accumulator acc;
  acc.force = f;
  evaluate(x, Mode::Force, acc);
  if (acc.bad) std::fill(f, f + dof(), kNaN);
}

void YarnRods::conservative_acceleration(double /*t*/, const double* x, double* a) const {
  net_force(x, a);
  for (int i = 0; i < dof(); ++i) a[i] /= dof_mass_[i];
}

void YarnRods::constant_acceleration(double /*t*/, double* a) const {
  for (int i = 0; i < dof(); i += 3) {
    a[i] = spec_.gravity.x;
    a[i + 1] = spec_.gravity.y;
    a[i + 2] = spec_.gravity.z;
  }
}

void YarnRods::stiffness_values(double /*t*/, const double* x, double* values) const {
  std::fill(values, values + pattern_.nnz(), 0.0);
  Accumulator acc;
  acc.values = values;
  evaluate(x, Mode::Stiffness, acc);
  if (acc.bad) std::fill(values, values + pattern_.nnz(), kNaN);
}

double YarnRods::potential_energy(double /*t*/, const double* x) const {
  Accumulator acc;
  evaluate(x, Mode::Energy, acc);
  return acc.bad ? kInf : acc.energy;
}

double YarnRods::static_residual(double /*t*/, const double* x) const {
  std::vector<double> f(dof());
  net_force(x, f.data());
  double worst = 0.0;
  for (int i = 0; i < dof(); i += 3) {
    const double f2 = f[i] * f[i] + f[i + 1] * f[i + 1] + f[i + 2] * f[i + 2];
    if (!(f2 <= worst)) worst = f2;  // NaN propagates
  }
  return std::sqrt(worst) / residual_scale_;
}

// Round-off floor: an edge's length carries eps (|x_a| + |x_b|), so its force k times that; a
// bend's force B kappa / (lbar l) carries, through kappa's error ~ eps |x| / l, about
// 8 B eps sum |x_j| / (lbar l^2) (l the shorter edge). A bound for scale, not a typical value.
double YarnRods::residual_roundoff(double /*t*/, const double* x) const {
  all_positions(x, pos_);
  constexpr double eps = std::numeric_limits<double>::epsilon();
  std::vector<double> floor_(vertex_count(), 0.0);
  for (const Edge& e : edges_) {
    const double r =
        spec_.yarn.stretch_stiffness() / e.rest * eps * (norm(pos_[e.a]) + norm(pos_[e.b]));
    floor_[e.a] += r;
    floor_[e.b] += r;
  }
  for (size_t k = 0; k < bends_.size(); ++k) {
    const Bend& b = bends_[k];
    const int e0 = b.v[0] - vertex_yarn_[b.v[0]];  // a yarn of n vertices has n - 1 edges
    const double l = std::min(edges_[e0].rest, edges_[e0 + 1].rest);
    double sx = 0.0;
    for (int v : b.v) sx += norm(pos_[v]);
    const double r = 8.0 * spec_.yarn.bending_rigidity * eps * sx / (b.lbar * l * l);
    for (int v : b.v) floor_[v] += r;
  }
  double worst = 0.0;
  for (int v = 0; v < vertex_count(); ++v)
    if (free_index_[v] >= 0) worst = std::max(worst, floor_[v]);
  return worst / residual_scale_;
}

double YarnRods::admissible_step(double /*t*/, const double* x, const double* dx) const {
  if (!spec_.contact) return 1.0;
  all_positions(x, pos_);
  std::vector<double> move(vertex_count(), 0.0);
  double largest = 0.0;
  for (int v = 0; v < vertex_count(); ++v) {
    const int f = free_index_[v];
    if (f < 0) continue;
    move[v] = std::sqrt(dx[3 * f] * dx[3 * f] + dx[3 * f + 1] * dx[3 * f + 1] +
                        dx[3 * f + 2] * dx[3 * f + 2]);
    if (!(move[v] <= largest)) largest = move[v];
  }
  if (!std::isfinite(largest)) return 0.0;
  if (largest == 0.0) return 1.0;
  // A pair at D whose edges move m_a, m_b along the step cut to a fraction f <= cap can bind
  // only if D < d0 + f (m_a + m_b) / (1 - keep): each edge's box grows by d0 / 2 plus its own
  // share f m_e / (1 - keep), m_e its vertices' larger move. The cap bounds that growth by
  // kStepReach d, so a step whose largest move is many d (a Newton step along a soft mode) does
  // not make every pair a candidate (its boxes grown by the largest move took 2.4 GB on
  // tucks40); such a step is cut to move no vertex more than kStepReach (1 - keep) d.
  const double keep = spec_.yarn.step_keep;
  const double cap = std::min(1.0, kStepReach * d_ * (1.0 - keep) / largest);
  std::vector<double> grow(edges_.size());
  for (size_t e = 0; e < edges_.size(); ++e)
    grow[e] = cap * std::max(move[edges_[e].a], move[edges_[e].b]) / (1.0 - keep);
  // The pairs are visited as the broad phase finds them, not stored: a large step's candidates
  // take no memory.
  double admit = cap;
  bool inside = false;  // a sample pair already inside a core: nothing is admitted
  visit_edge_pairs(pos_, 0.5 * d0_, &grow, [&](int i, int j) {
    if (inside || !may_pair(i, j)) return;
    const Edge &A = edges_[i], &B = edges_[j];
    const double reach = std::max(move[A.a], move[A.b]) + std::max(move[B.a], move[B.b]);
    // Every sample pair is at least the segments' distance apart: where that distance already
    // keeps the bound, it stands for all of them (the samples only where it is inside the core).
    const double D = closest_points(pos_[A.a], pos_[A.b], pos_[B.a], pos_[B.b]).distance;
    if (D > d0_) {
      if (D - reach < d0_ + keep * (D - d0_))
        admit = std::min(admit, (1.0 - keep) * (D - d0_) / reach);
      return;
    }
    for (int k = 0; k < A.samples; ++k) {
      const double s = (k + 0.5) / A.samples;
      const Vec3 P = (1.0 - s) * pos_[A.a] + s * pos_[A.b];
      for (int m = 0; m < B.samples; ++m) {
        const double t = (m + 0.5) / B.samples;
        if (!samples_pair(i, s, j, t)) continue;
        const double Ds = norm(P - ((1.0 - t) * pos_[B.a] + t * pos_[B.b]));
        if (!(Ds > d0_)) {
          inside = true;
          return;
        }
        if (Ds - reach < d0_ + keep * (Ds - d0_))
          admit = std::min(admit, (1.0 - keep) * (Ds - d0_) / reach);
      }
    }
  });
  return inside ? 0.0 : admit;
}

double YarnRods::stretch_energy(const double* x) const {
  all_positions(x, pos_);
  double e = 0.0;
  for (const Edge& ed : edges_) {
    const double ext = norm(pos_[ed.b] - pos_[ed.a]) - ed.rest;
    e += 0.5 * spec_.yarn.stretch_stiffness() / ed.rest * ext * ext;
  }
  return e;
}

double YarnRods::bend_energy(const double* x) const {
  all_positions(x, pos_);
  double e = 0.0;
  for (const Bend& b : bends_) {
    const Vec3 e0 = pos_[b.v[1]] - pos_[b.v[0]], e1 = pos_[b.v[2]] - pos_[b.v[1]];
    const double q = norm(e0) * norm(e1), c = dot(e0, e1);
    const double kappa = std::sqrt(std::max(0.0, 4.0 * (q - c) / (q + c)));
    e += spec_.yarn.bending_rigidity / (2.0 * b.lbar) * (kappa - b.kappa0) * (kappa - b.kappa0);
  }
  return e;
}

double YarnRods::contact_energy(const double* x) const {
  if (!spec_.contact) return 0.0;
  all_positions(x, pos_);
  Accumulator acc;
  contact_terms(pos_, Mode::Energy, acc);
  return acc.bad ? kInf : acc.energy;
}

double YarnRods::yarn_length(int yarn, const double* x) const {
  all_positions(x, pos_);
  double L = 0.0;
  for (int v = yarn_first_[yarn]; v + 1 < yarn_first_[yarn + 1]; ++v)
    L += norm(pos_[v + 1] - pos_[v]);
  return L;
}

double YarnRods::rest_length(int yarn) const {
  double L = 0.0;
  for (const Edge& e : edges_)
    if (e.yarn == yarn) L += e.rest;
  return L;
}

double YarnRods::min_clearance(const double* x) const {
  all_positions(x, pos_);
  std::vector<std::pair<int, int>> pairs;
  edge_pairs(pos_, d_, pairs);
  double best = kInf;
  for (const auto& [i, j] : pairs) {
    if (!may_pair(i, j)) continue;
    const Edge &A = edges_[i], &B = edges_[j];
    // Edges wholly more than the gap apart along the yarn: their exact distance. Otherwise only
    // their parts the gap apart count (adjacent edges share a vertex): the least distance over
    // the contact's sample pairs that pair (within d/8 of the true clearance, "Contact").
    const bool whole = A.yarn != B.yarn || std::max(A.arc, B.arc) -
                                                   std::min(A.arc + A.rest, B.arc + B.rest) >=
                                               gap_;
    if (whole) {
      best = std::min(best, closest_points(pos_[A.a], pos_[A.b], pos_[B.a], pos_[B.b]).distance);
      continue;
    }
    for (int k = 0; k < A.samples; ++k) {
      const double sa = (k + 0.5) / A.samples;
      const Vec3 p = (1.0 - sa) * pos_[A.a] + sa * pos_[A.b];
      for (int m = 0; m < B.samples; ++m) {
        const double sb = (m + 0.5) / B.samples;
        if (!samples_pair(i, sa, j, sb)) continue;
        best = std::min(best, norm((1.0 - sb) * pos_[B.a] + sb * pos_[B.b] - p));
      }
    }
  }
  return best < 2.0 * d_ ? best : kInf;
}

std::string YarnRods::describe() const {
  std::ostringstream s;
  s << "yarn rods: " << spec_.rest.size() << " yarns, " << vertex_count() << " vertices ("
    << free_count_ << " free), d = " << d_ * 1e3 << " mm, EA = " << spec_.yarn.stretch_stiffness()
    << " N, B = " << spec_.yarn.bending_rigidity << " N m^2"
    << (spec_.contact ? ", contact" : ", no contact");
  return s.str();
}

}  // namespace knitsim
