// ContactNetwork: a SpringNetwork plus the yarn-contact barrier (header).
#include "models/yarn_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace knitsim {

namespace {

struct Box {
  double x0, x1, y0, y1;
};

// Calls on_pair(a, b), a < b, once for every two boxes that overlap, from a front-view grid of
// cells of at least `cell` (grown so the grid has at most ~4 cells per box). Boxes must be
// finite.
template <class OnPair>
void overlapping_boxes(const std::vector<Box>& boxes, double cell, OnPair on_pair) {
  const int n = static_cast<int>(boxes.size());
  if (n < 2) return;
  double x0 = boxes[0].x0, x1 = boxes[0].x1, y0 = boxes[0].y0, y1 = boxes[0].y1;
  double widest = 0.0;
  for (const Box& b : boxes) {
    x0 = std::min(x0, b.x0), x1 = std::max(x1, b.x1);
    y0 = std::min(y0, b.y0), y1 = std::max(y1, b.y1);
    widest = std::max({widest, b.x1 - b.x0, b.y1 - b.y0});
  }
  cell = std::max({cell, widest, 1e-300});
  auto cells_along = [&](double span) { return static_cast<long>(span / cell) + 1; };
  while (cells_along(x1 - x0) * cells_along(y1 - y0) > 4L * n + 16) cell *= 2.0;
  const long nx = cells_along(x1 - x0), ny = cells_along(y1 - y0);
  auto ix = [&](double x) { return std::min(nx - 1, static_cast<long>((x - x0) / cell)); };
  auto iy = [&](double y) { return std::min(ny - 1, static_cast<long>((y - y0) / cell)); };
  // Counting sort of (cell, box) entries: a box enters every cell it overlaps (at most 4, as
  // no box is wider than a cell).
  std::vector<long> start(nx * ny + 1, 0);
  for (const Box& b : boxes)
    for (long j = iy(b.y0); j <= iy(b.y1); ++j)
      for (long i = ix(b.x0); i <= ix(b.x1); ++i) ++start[j * nx + i + 1];
  for (long c = 0; c < nx * ny; ++c) start[c + 1] += start[c];
  std::vector<int> entries(start.back());
  std::vector<long> fill(start.begin(), start.end() - 1);
  for (int k = 0; k < n; ++k)
    for (long j = iy(boxes[k].y0); j <= iy(boxes[k].y1); ++j)
      for (long i = ix(boxes[k].x0); i <= ix(boxes[k].x1); ++i) entries[fill[j * nx + i]++] = k;
  for (long c = 0; c < nx * ny; ++c)
    for (long p = start[c]; p < start[c + 1]; ++p)
      for (long q = p + 1; q < start[c + 1]; ++q) {
        const Box& a = boxes[entries[p]];
        const Box& b = boxes[entries[q]];
        if (a.x1 < b.x0 || b.x1 < a.x0 || a.y1 < b.y0 || b.y1 < a.y0) continue;
        // Report the pair only in the cell holding the corner (max x0, max y0) of the overlap.
        if (ix(std::max(a.x0, b.x0)) + nx * iy(std::max(a.y0, b.y0)) != c) continue;
        on_pair(std::min(entries[p], entries[q]), std::max(entries[p], entries[q]));
      }
}

Box around(Vec3 p, double half) { return {p.x - half, p.x + half, p.y - half, p.y + half}; }

}  // namespace

ContactNetwork::ContactNetwork(SpringNetwork network, YarnContactSpec contact)
    : net_(std::move(network)), spec_(std::move(contact)) {
  const YarnContactSpec& c = spec_;
  if (!(c.core > 0.0 && c.touching > c.core && std::isfinite(c.touching)))
    throw std::invalid_argument("yarn contact: need 0 < core < touching distance");
  if (!(c.stiffness > 0.0 && std::isfinite(c.stiffness)))
    throw std::invalid_argument("yarn contact: stiffness must be positive and finite");
  if (!(c.same_yarn_gap >= 0.0 && c.skin >= 0.0 && c.pattern_radius >= 0.0 && c.step_cap >= 0.0 &&
        c.filter_keep > 0.0 && c.filter_keep < 1.0 && c.renew_keep > 0.0 && c.renew_keep < 1.0))
    throw std::invalid_argument("yarn contact: bad gap, skin, pattern radius or filter fraction");
  if (spec_.skin == 0.0) spec_.skin = c.touching - c.core;
  if (spec_.pattern_radius == 0.0) spec_.pattern_radius = 2.0 * c.touching;
  if (spec_.step_cap == 0.0) spec_.step_cap = 4.0 * c.touching;
  reach_ = spec_.touching + spec_.skin;
  update_wmax();
  if (c.refresh_tol < 0.0 || c.refresh_move < 0.0)
    throw std::invalid_argument("yarn contact: negative refresh tolerance or move");
  if (c.exact && c.linearise) {
    int yarns = 0;
    for (std::size_t k = 0; k < c.points.size(); ++k) {
      if (c.points[k].yarn < yarns - 1 || c.points[k].yarn < 0)
        throw std::invalid_argument("yarn contact: renewable points must be ordered by yarn");
      while (yarns <= c.points[k].yarn) yarn_begin_.push_back(static_cast<int>(k)), ++yarns;
    }
    yarn_begin_.push_back(static_cast<int>(c.points.size()));
    std::vector<double> x0(net_.dof()), v0(net_.dof());
    net_.initial_state(x0.data(), v0.data());
    net_.all_positions(0.0, x0.data(), renewed_at_);
  }
  const CscPattern& np = net_.stiffness_pattern();
  if (!has_node_triples(np))
    throw std::invalid_argument("yarn contact: the network's unknowns must be whole particles");

  // The pattern: the network's particle blocks, and those of every pair near at the start.
  std::vector<std::pair<int, int>> blocks;
  for (int col = 0; col < np.cols; col += 3)
    for (int k = np.colptr[col]; k < np.colptr[col + 1]; k += 3)
      blocks.emplace_back(np.rowind[k] / 3, col / 3);
  std::vector<double> x(dof()), v(dof());
  net_.initial_state(x.data(), v.data());
  positions(0.0, x.data());
  std::vector<Box> boxes(pts_.size());
  for (std::size_t k = 0; k < pts_.size(); ++k)
    boxes[k] = around(pts_[k], 0.5 * spec_.pattern_radius);
  overlapping_boxes(boxes, spec_.pattern_radius, [&](int a, int b) {
    if (!may_pair(a, b) || norm(pts_[a] - pts_[b]) >= spec_.pattern_radius) return;
    for (int i = 0; i < kContactParticles && spec_.points[a].particles[i] >= 0; ++i)
      for (int j = 0; j < kContactParticles && spec_.points[b].particles[j] >= 0; ++j) {
        const int fa = net_.free_index(spec_.points[a].particles[i]);
        const int fb = net_.free_index(spec_.points[b].particles[j]);
        if (fa < 0 || fb < 0) continue;
        blocks.emplace_back(fa, fb);
        blocks.emplace_back(fb, fa);
      }
  });
  const int nf = dof() / 3;
  nodes_ = make_csc_pattern(nf, nf, std::move(blocks), /*with_diagonal=*/true);
  pattern_ = expand_node_pattern(nodes_);
  net_entry_.resize(np.nnz());
  for (int col = 0; col < np.cols; ++col)
    for (int k = np.colptr[col]; k < np.colptr[col + 1]; ++k)
      net_entry_[k] = pattern_.find(np.rowind[k], col);
  net_values_.resize(np.nnz());
  force_.resize(dof());
}

bool ContactNetwork::may_pair(int a, int b) const {
  const ContactPoint& p = spec_.points[a];
  const ContactPoint& q = spec_.points[b];
  return p.yarn != q.yarn || std::abs(p.arc - q.arc) >= spec_.same_yarn_gap;
}

void ContactNetwork::update_wmax() const {
  wmax_ = 0.0;
  for (const ContactPoint& p : spec_.points) {
    double w = 0.0;
    int count = 0;
    for (int i = 0; i < kContactParticles && p.particles[i] >= 0; ++i, ++count) {
      if (p.particles[i] >= net_.particle_count())
        throw std::invalid_argument("yarn contact: a point's particle is out of range");
      double f2 = 0.0;
      for (double v : p.weights[i]) {
        if (!std::isfinite(v)) throw std::invalid_argument("yarn contact: a weight is not finite");
        f2 += v * v;
      }
      w += std::sqrt(f2);
    }
    if (count == 0 || !is_finite(p.offset))
      throw std::invalid_argument("yarn contact: a point has no particle or a non-finite offset");
    wmax_ = std::max(wmax_, w);
  }
}

bool ContactNetwork::refresh(double t, const double* x) const {
  if (yarn_begin_.empty() || !(spec_.refresh_tol > 0.0)) return false;
  net_.all_positions(t, x, pos_);
  double moved = 0.0;
  for (std::size_t i = 0; i < pos_.size(); ++i) {
    if (!is_finite(pos_[i])) return false;
    moved = std::max(
        {moved, std::abs(pos_[i].x - renewed_at_[i].x), std::abs(pos_[i].y - renewed_at_[i].y)});
  }
  if (moved < spec_.refresh_move) return false;
  const std::vector<Vec3> particles = pos_;
  spec_.exact(particles, exact_);
  if (exact_.size() != spec_.points.size())
    throw std::logic_error("yarn contact: exact positions of another number of points");
  positions(t, x);
  // Each straying yarn is renewed on its own: its points move from where they are to their exact
  // positions, as far along that as the step filter allows (a renewal is a step of the points).
  long renewed = 0, cut = 0;
  std::vector<Vec3> move(pts_.size());
  for (int y = 0; y + 1 < static_cast<int>(yarn_begin_.size()); ++y) {
    const int begin = yarn_begin_[y], end = yarn_begin_[y + 1];
    double drift = 0.0;
    for (int k = begin; k < end; ++k) drift = std::max(drift, norm(exact_[k] - pts_[k]));
    if (!(drift > spec_.refresh_tol)) continue;
    std::vector<ContactPoint> fresh = spec_.linearise(particles, y);
    if (static_cast<int>(fresh.size()) != end - begin)
      throw std::logic_error("yarn contact: a renewed yarn has another number of points");
    std::fill(move.begin(), move.end(), Vec3{0.0, 0.0, 0.0});
    for (int k = begin; k < end; ++k) move[k] = exact_[k] - pts_[k];
    const double s = sweep_fraction(pts_, move, spec_.renew_keep);
    if (s < 1.0) {
      ++cut_renewals_, ++cut;
      // Part way: the fresh map (its weights, the tangent here) moved to put each point s of the
      // way from where it is to its exact position; the rest is taken up at later checks.
      for (int k = begin; k < end; ++k)
        fresh[k - begin].offset = fresh[k - begin].offset - (1.0 - s) * move[k];
    }
    auto first = spec_.points.begin() + begin;
    const std::vector<ContactPoint> old(first, first + (end - begin));
    std::copy(fresh.begin(), fresh.end(), first);
    listed_at_.clear();  // points moved: the near-pair list is rebuilt (wmax_ only sets when)
    if (min_distance(t, x) > spec_.core) {  // pts_ now holds the renewed points
      ++renewed;
    } else {  // round-off at the filter's floor: the old points are kept
      std::copy(old.begin(), old.end(), first);
      listed_at_.clear();
      positions(t, x);
    }
  }
  if (renewed == 0) return false;
  update_wmax();  // once, for the points kept (it also checks them)
  if (cut == 0) renewed_at_ = particles;  // a cut renewal is taken up again at the next check
  refreshes_ += renewed;
  return true;
}

Vec3 position_of(const ContactPoint& point, const std::vector<Vec3>& particles) {
  Vec3 s = point.offset;
  for (int i = 0; i < kContactParticles && point.particles[i] >= 0; ++i) {
    const Vec3& q = particles[point.particles[i]];
    const std::array<double, 6>& W = point.weights[i];
    s.x += W[0] * q.x + W[1] * q.y;
    s.y += W[2] * q.x + W[3] * q.y;
    s.z += W[4] * q.x + W[5] * q.y;
  }
  return s;
}

void ContactNetwork::positions(double t, const double* x) const {
  net_.all_positions(t, x, pos_);
  pts_.resize(spec_.points.size());
  for (std::size_t k = 0; k < spec_.points.size(); ++k)
    pts_[k] = position_of(spec_.points[k], pos_);
}

void ContactNetwork::refresh_pairs() const {
  if (listed_at_.size() == pos_.size()) {
    double moved = 0.0;
    for (std::size_t i = 0; i < pos_.size(); ++i)
      moved = std::max(
          {moved, std::abs(pos_[i].x - listed_at_[i].x), std::abs(pos_[i].y - listed_at_[i].y)});
    // A point moves at most wmax sqrt(2) moved; two points at most twice that.
    if (2.0 * wmax_ * std::sqrt(2.0) * moved <= spec_.skin) return;
  }
  listed_at_ = pos_;
  ++rebuilds_;
  pairs_.clear();
  std::vector<Box> boxes(pts_.size());
  for (std::size_t k = 0; k < pts_.size(); ++k) boxes[k] = around(pts_[k], 0.5 * reach_);
  overlapping_boxes(boxes, reach_, [&](int a, int b) {
    if (may_pair(a, b) && norm(pts_[a] - pts_[b]) < reach_) pairs_.push_back({a, b});
  });
}

bool ContactNetwork::pairs_of(double t, const double* x) const {
  positions(t, x);
  for (const Vec3& p : pts_)
    if (!is_finite(p)) return false;
  refresh_pairs();
  return true;
}

void ContactNetwork::barrier(double D, double& e, double& de, double& d2e) const {
  const double span = spec_.touching - spec_.core;
  const double g = (D - spec_.core) / span;
  e = de = d2e = 0.0;
  if (g >= 1.0) return;
  if (!(g > 0.0)) {
    e = std::numeric_limits<double>::infinity();
    de = d2e = std::nan("");
    return;
  }
  const double k = spec_.stiffness, lg = std::log(g), gm = g - 1.0;
  e = -k * span * span * gm * gm * lg;
  de = -k * span * (2.0 * gm * lg + gm * gm / g);
  d2e = -k * (2.0 * lg + 4.0 * gm / g - gm * gm / (g * g));
}

double ContactNetwork::contact_energy(double t, const double* x) const {
  if (!pairs_of(t, x)) return std::nan("");
  double E = 0.0;
  for (const Pair& pr : pairs_) {
    double e, de, d2e;
    barrier(norm(pts_[pr.a] - pts_[pr.b]), e, de, d2e);
    E += e;
  }
  return E;
}

double ContactNetwork::potential_energy(double t, const double* x) const {
  return net_.potential_energy(t, x) + contact_energy(t, x);
}

double ContactNetwork::min_distance(double t, const double* x, int* in_contact) const {
  double best = std::numeric_limits<double>::infinity();
  int touching = 0;
  if (pairs_of(t, x))
    for (const Pair& pr : pairs_) {
      const double D = norm(pts_[pr.a] - pts_[pr.b]);
      best = std::min(best, D);
      touching += D < spec_.touching;
    }
  else
    best = std::nan("");
  if (in_contact != nullptr) *in_contact = touching;
  return best;
}

namespace {

// Adds W_i^T F (F a force on point p) to p's free particles' x and y, divided by their mass if
// `mass` is given.
void spread(const ContactPoint& p, const SpringNetwork& net, Vec3 F, double* out,
            const std::vector<double>* mass) {
  for (int i = 0; i < kContactParticles && p.particles[i] >= 0; ++i) {
    const int f = net.free_index(p.particles[i]);
    if (f < 0) continue;
    const std::array<double, 6>& W = p.weights[i];
    const double s = mass ? 1.0 / (*mass)[3 * f] : 1.0;
    out[3 * f] += s * (W[0] * F.x + W[2] * F.y + W[4] * F.z);
    out[3 * f + 1] += s * (W[1] * F.x + W[3] * F.y + W[5] * F.z);
  }
}

}  // namespace

template <class OnContact>
bool ContactNetwork::for_each_contact(double t, const double* x, OnContact on_contact) const {
  if (!pairs_of(t, x)) return false;
  for (const Pair& pr : pairs_) {
    const Vec3 d = pts_[pr.a] - pts_[pr.b];
    const double D = norm(d);
    if (D >= spec_.touching) continue;
    double e, de, d2e;
    barrier(D, e, de, d2e);
    if (!std::isfinite(de)) return false;
    on_contact(pr, d, D, de, d2e);
  }
  return true;
}

bool ContactNetwork::add_contact_forces(double t, const double* x, double* out,
                                        const std::vector<double>* mass) const {
  return for_each_contact(t, x, [&](const Pair& pr, Vec3 d, double D, double de, double) {
    const Vec3 F = (-de / D) * d;  // on a; b gets the opposite
    spread(spec_.points[pr.a], net_, F, out, mass);
    spread(spec_.points[pr.b], net_, -1.0 * F, out, mass);
  });
}

void ContactNetwork::conservative_acceleration(double t, const double* x, double* a) const {
  net_.conservative_acceleration(t, x, a);
  if (!add_contact_forces(t, x, a, &net_.mass())) std::fill(a, a + dof(), std::nan(""));
}

double ContactNetwork::static_residual(double t, const double* x) const {
  net_.net_force(t, x, force_.data());
  if (!add_contact_forces(t, x, force_.data(), nullptr)) return std::nan("");
  double worst = 0.0;
  for (int i = 0; i < dof(); i += 3) {
    const double f2 =
        force_[i] * force_[i] + force_[i + 1] * force_[i + 1] + force_[i + 2] * force_[i + 2];
    if (!(f2 <= worst)) worst = f2;
  }
  return std::sqrt(worst) / net_.residual_force_scale();
}

void ContactNetwork::stiffness_values(double t, const double* x, double* values) const {
  net_.stiffness_values(t, x, net_values_.data());
  std::fill(values, values + pattern_.nnz(), 0.0);
  for (std::size_t k = 0; k < net_values_.size(); ++k) values[net_entry_[k]] = net_values_[k];
  const std::vector<double>& m = net_.mass();
  const bool finite =
      for_each_contact(t, x, [&](const Pair& pr, Vec3 d, double D, double de, double d2e) {
        const double u[3] = {d.x / D, d.y / D, d.z / D}, s = de / D;
        // H = d2e u u^T + (de / D)(I - u u^T)
        double H[3][3];
        for (int p = 0; p < 3; ++p)
          for (int q = 0; q < 3; ++q) H[p][q] = (d2e - s) * u[p] * u[q] + (p == q ? s : 0.0);
        bool missed = false;
        const ContactPoint* pt[2] = {&spec_.points[pr.a], &spec_.points[pr.b]};
        for (int A = 0; A < 2; ++A)
          for (int i = 0; i < kContactParticles && pt[A]->particles[i] >= 0; ++i) {
            const int fr = net_.free_index(pt[A]->particles[i]);
            if (fr < 0) continue;
            const std::array<double, 6>& Wi = pt[A]->weights[i];
            // G = Wi^T H, 2 x 3 (Wi row-major 3 x 2: Wi[2 k + p] is row k, column p)
            double G[2][3];
            for (int p = 0; p < 2; ++p)
              for (int q = 0; q < 3; ++q)
                G[p][q] = Wi[p] * H[0][q] + Wi[2 + p] * H[1][q] + Wi[4 + p] * H[2][q];
            for (int B = 0; B < 2; ++B)
              for (int j = 0; j < kContactParticles && pt[B]->particles[j] >= 0; ++j) {
                const int fc = net_.free_index(pt[B]->particles[j]);
                if (fc < 0) continue;
                const int e_node = nodes_.find(fr, fc);
                if (e_node < 0) {
                  missed = true;
                  continue;
                }
                const std::array<double, 6>& Wj = pt[B]->weights[j];
                // dF_r/dx_c = -s_r s_c Wi^T H Wj; the Jacobian row is divided by r's mass.
                const double f = -(A == B ? 1.0 : -1.0) / m[3 * fr];
                for (int p = 0; p < 2; ++p)
                  for (int q = 0; q < 2; ++q)
                    values[node_block_entry(nodes_, e_node, fc, p, q)] +=
                        f * (G[p][0] * Wj[q] + G[p][1] * Wj[2 + q] + G[p][2] * Wj[4 + q]);
              }
          }
        pattern_misses_ += missed;
      });
  if (!finite) std::fill(values, values + pattern_.nnz(), std::nan(""));
}

double ContactNetwork::admissible_step(double t, const double* x, const double* dx) const {
  if (!pairs_of(t, x)) return 1.0;
  const std::vector<Vec3> start = pts_;
  std::vector<double> end(x, x + dof());
  for (int i = 0; i < dof(); ++i) end[i] += dx[i];
  positions(t, end.data());
  std::vector<Vec3> move(pts_.size());
  double longest = 0.0;
  for (std::size_t k = 0; k < pts_.size(); ++k) {
    move[k] = pts_[k] - start[k];
    longest = std::max(longest, norm(move[k]));
  }
  pts_ = start;  // the cached points describe x again (the pair list is x's)
  if (!(longest < std::numeric_limits<double>::infinity())) return 0.0;
  // A step that moves a point by more than step_cap is cut to that first (a yarn jumping several
  // diameters in one Newton step is not trusted, the swept boxes stay small, and renewable
  // points stray less from their exact positions within one step).
  const double cap = longest > spec_.step_cap ? spec_.step_cap / longest : 1.0;
  for (Vec3& m : move) m = cap * m;
  return cap * sweep_fraction(start, move, spec_.filter_keep);
}

double ContactNetwork::sweep_fraction(const std::vector<Vec3>& start, const std::vector<Vec3>& move,
                                      double keep) const {
  std::vector<Box> boxes(start.size());
  for (std::size_t k = 0; k < start.size(); ++k) {
    const Vec3 e = start[k] + move[k];
    boxes[k] = {std::min(start[k].x, e.x) - 0.5 * spec_.touching,
                std::max(start[k].x, e.x) + 0.5 * spec_.touching,
                std::min(start[k].y, e.y) - 0.5 * spec_.touching,
                std::max(start[k].y, e.y) + 0.5 * spec_.touching};
  }
  double fraction = 1.0;
  overlapping_boxes(boxes, spec_.touching, [&](int a, int b) {
    if (!may_pair(a, b)) return;
    const Vec3 d0 = start[a] - start[b];
    const Vec3 dd = move[a] - move[b];
    const double D0 = norm(d0);
    const double floor = spec_.core + keep * (std::min(D0, spec_.touching) - spec_.core);
    const double A = dot(dd, dd), B = dot(d0, dd), C = D0 * D0 - floor * floor;
    if (!(A > 0.0) || B >= 0.0 || C <= 0.0) return;
    const double disc = B * B - A * C;
    if (disc < 0.0) return;
    const double tau = (-B - std::sqrt(disc)) / A;  // first time the distance reaches floor
    fraction = std::min(fraction, std::max(0.0, tau));
  });
  return fraction;
}

std::string ContactNetwork::describe() const {
  std::ostringstream o;
  o << net_.describe() << "; yarn contact: " << spec_.points.size() << " points, barrier from "
    << spec_.touching << " m to its core " << spec_.core << " m, kappa " << spec_.stiffness
    << " N/m";
  return o.str();
}

}  // namespace knitsim
