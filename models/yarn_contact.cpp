// ContactNetwork: a SpringNetwork plus the yarn-contact barrier (header).
#include "models/yarn_contact.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
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
  // Each box's cells (i0, i1, j0, j1), and a counting sort of (cell, box) entries: a box enters
  // every cell it overlaps (at most 4, as no box is wider than a cell). A cell's entries are
  // copied with their boxes before its pairs are tested, so they are tested on contiguous memory
  // while the sort holds only the boxes' indices (4 bytes an entry, not 48).
  struct Cells {
    int i0, i1, j0, j1;
  };
  std::vector<Cells> cells(n);
  std::vector<long> start(nx * ny + 1, 0);
  for (int k = 0; k < n; ++k) {
    const Box& b = boxes[k];
    Cells& c = cells[k];
    c = {static_cast<int>(ix(b.x0)), static_cast<int>(ix(b.x1)), static_cast<int>(iy(b.y0)),
         static_cast<int>(iy(b.y1))};
    for (long j = c.j0; j <= c.j1; ++j)
      for (long i = c.i0; i <= c.i1; ++i) ++start[j * nx + i + 1];
  }
  for (long c = 0; c < nx * ny; ++c) start[c + 1] += start[c];
  std::vector<int> entries(start.back());
  {
    std::vector<long> fill(start.begin(), start.end() - 1);
    for (int k = 0; k < n; ++k) {
      const Cells& c = cells[k];
      for (long j = c.j0; j <= c.j1; ++j)
        for (long i = c.i0; i <= c.i1; ++i) entries[fill[j * nx + i]++] = k;
    }
  }
  struct Entry {
    Box box;
    int i0, j0, k;
  };
  std::vector<Entry> in_cell;  // one cell's entries
  for (long c = 0; c < nx * ny; ++c) {
    in_cell.clear();
    for (long p = start[c]; p < start[c + 1]; ++p) {
      const int k = entries[p];
      in_cell.push_back({boxes[k], cells[k].i0, cells[k].j0, k});
    }
    for (std::size_t p = 0; p < in_cell.size(); ++p)
      for (std::size_t q = p + 1; q < in_cell.size(); ++q) {
        const Entry& ea = in_cell[p];
        const Entry& eb = in_cell[q];
        const Box& a = ea.box;
        const Box& b = eb.box;
        if (a.x1 < b.x0 || b.x1 < a.x0 || a.y1 < b.y0 || b.y1 < a.y0) continue;
        // Report the pair only in the cell holding the corner (max x0, max y0) of the overlap.
        if (std::max(ea.i0, eb.i0) + nx * std::max(ea.j0, eb.j0) != c) continue;
        on_pair(std::min(ea.k, eb.k), std::max(ea.k, eb.k));
      }
  }
}

Box around(Vec3 p, double half) { return {p.x - half, p.x + half, p.y - half, p.y + half}; }

// Throws std::invalid_argument on a bad point.
void check_points(const std::vector<ContactPoint>& points, const SpringNetwork& net) {
  for (const ContactPoint& p : points) {
    int count = 0;
    for (int i = 0; i < kContactParticles && p.particles[i] >= 0; ++i, ++count) {
      if (p.particles[i] >= net.particle_count())
        throw std::invalid_argument("yarn contact: a point's particle is out of range");
      for (double v : p.weights[i])
        if (!std::isfinite(v)) throw std::invalid_argument("yarn contact: a weight is not finite");
    }
    if (count == 0 || !is_finite(p.offset))
      throw std::invalid_argument("yarn contact: a point has no particle or a non-finite offset");
    if (p.turn[0] >= 0 || p.turn[1] >= 0) {
      const double a2 = p.axis[0] * p.axis[0] + p.axis[1] * p.axis[1];
      if (p.turn[0] < 0 || p.turn[1] < 0 || p.turn[0] >= count || p.turn[1] >= count ||
          p.turn[0] == p.turn[1] || !(std::abs(a2 - 1.0) < 1e-9))
        throw std::invalid_argument(
            "yarn contact: a point's turning pair must be two of its particles, its axis a unit "
            "vector");
    }
  }
}

}  // namespace

ContactModel::ContactModel(SpringNetwork network, YarnContactSpec contact)
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
  if (spec_.pattern_radius == 0.0) spec_.pattern_radius = 6.0 * c.touching;
  if (spec_.step_cap == 0.0) spec_.step_cap = 4.0 * c.touching;
  reach_ = spec_.touching + spec_.skin;
  check_points(spec_.points, net_);
  point_count_ = static_cast<int>(spec_.points.size());
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
  }
  if (c.remake_at_start && yarn_begin_.empty())
    throw std::invalid_argument("yarn contact: remake_at_start needs renewal (exact, linearise)");
  const CscPattern& np = net_.stiffness_pattern();
  if (!has_node_triples(np))
    throw std::invalid_argument("yarn contact: the network's unknowns must be whole particles");

  // The pattern: the network's particle blocks, and those of every pair near at the start.
  std::vector<std::pair<int, int>> blocks;
  for (int col = 0; col < np.cols; col += 3)
    for (int k = np.colptr[col]; k < np.colptr[col + 1]; k += 3)
      blocks.emplace_back(np.rowind[k] / 3, col / 3);
  {
    std::vector<double> x(net_.dof()), v(net_.dof());
    net_.initial_state(x.data(), v.data());
    net_.all_positions(0.0, x.data(), start_);
  }
  std::vector<Vec3> pts(spec_.points.size());
  for (std::size_t k = 0; k < spec_.points.size(); ++k)
    pts[k] = position_of(spec_.points[k], start_);
  auto may_pair = [&](int a, int b) {
    const ContactPoint& pa = spec_.points[a];
    const ContactPoint& pb = spec_.points[b];
    return pa.yarn != pb.yarn || std::abs(pa.arc - pb.arc) >= spec_.same_yarn_gap;
  };
  // Points share their particle sets in runs along a yarn: pairs are kept per two distinct sets
  // (a near pair of points adds the blocks between their sets' particles; every set also gets the
  // blocks within it, for a point's own J^T H J and its map's curvature). The sets are paired by
  // boxes round their points (a set's pairs then tested point by point, to the first near one):
  // a few per cent of the box tests of pairing the points themselves, the same set pairs.
  using Set = std::array<int, kContactParticles>;
  std::vector<Set> sets;
  sets.reserve(spec_.points.size());
  for (const ContactPoint& p : spec_.points) sets.push_back(p.particles);
  std::sort(sets.begin(), sets.end());
  sets.erase(std::unique(sets.begin(), sets.end()), sets.end());
  std::vector<int> member_begin(sets.size() + 1, 0), members(spec_.points.size());
  {
    std::vector<std::uint32_t> set_of(spec_.points.size());
    for (std::size_t k = 0; k < spec_.points.size(); ++k) {
      set_of[k] = static_cast<std::uint32_t>(
          std::lower_bound(sets.begin(), sets.end(), spec_.points[k].particles) - sets.begin());
      ++member_begin[set_of[k] + 1];
    }
    for (std::size_t s = 0; s < sets.size(); ++s) member_begin[s + 1] += member_begin[s];
    std::vector<int> next(member_begin.begin(), member_begin.end() - 1);
    for (std::size_t k = 0; k < spec_.points.size(); ++k)
      members[next[set_of[k]]++] = static_cast<int>(k);
  }
  const double R = spec_.pattern_radius;
  std::vector<Box> boxes(sets.size());
  for (std::size_t s = 0; s < sets.size(); ++s) {
    Box& b = boxes[s];
    b = around(pts[members[member_begin[s]]], 0.5 * R);
    for (int m = member_begin[s] + 1; m < member_begin[s + 1]; ++m) {
      const Box p = around(pts[members[m]], 0.5 * R);
      b = {std::min(b.x0, p.x0), std::max(b.x1, p.x1), std::min(b.y0, p.y0), std::max(b.y1, p.y1)};
    }
  }
  std::vector<std::vector<std::uint32_t>> near_sets(sets.size());
  for (std::uint32_t s = 0; s < sets.size(); ++s) near_sets[s].push_back(s);
  overlapping_boxes(boxes, R, [&](int sa, int sb) {
    for (int i = member_begin[sa]; i < member_begin[sa + 1]; ++i)
      for (int j = member_begin[sb]; j < member_begin[sb + 1]; ++j) {
        const int a = members[i], b = members[j];
        if (!may_pair(a, b) || norm(pts[a] - pts[b]) >= R) continue;
        near_sets[sa].push_back(static_cast<std::uint32_t>(sb));
        near_sets[sb].push_back(static_cast<std::uint32_t>(sa));
        return;
      }
  });
  // Each free particle's blocks: the particles of every set near a set it belongs to, each once
  // (a marker per particle; near sets share most of their particles, so listing every set pair's
  // 8 x 8 blocks would list each block many times over).
  std::vector<std::vector<std::uint32_t>> sets_of(net_.particle_count());
  for (std::uint32_t k = 0; k < sets.size(); ++k)
    for (int i = 0; i < kContactParticles && sets[k][i] >= 0; ++i) sets_of[sets[k][i]].push_back(k);
  std::vector<int> marked(net_.particle_count(), -1);
  for (int p = 0; p < net_.particle_count(); ++p) {
    const int fa = net_.free_index(p);
    if (fa < 0) continue;
    for (std::uint32_t own : sets_of[p])
      for (std::uint32_t other : near_sets[own])
        for (int j = 0; j < kContactParticles && sets[other][j] >= 0; ++j) {
          const int q = sets[other][j], fb = net_.free_index(q);
          if (fb < 0 || marked[q] == p) continue;
          marked[q] = p;
          blocks.emplace_back(fa, fb);
        }
  }
  const int nf = net_.dof() / 3;
  nodes_ = make_csc_pattern(nf, nf, std::move(blocks), /*with_diagonal=*/true);
  pattern_ = expand_node_pattern(nodes_);
  net_entry_.resize(np.nnz());
  for (int col = 0; col < np.cols; ++col)
    for (int k = np.colptr[col]; k < np.colptr[col + 1]; ++k)
      net_entry_[k] = pattern_.find(np.rowind[k], col);
  if (spec_.remake_at_start) std::vector<ContactPoint>().swap(spec_.points);  // each run's own
}

ContactNetwork::ContactNetwork(std::shared_ptr<const ContactModel> model)
    : model_(std::move(model)), net_(model_->net_), spec_(model_->spec_), reach_(model_->reach_) {
  renewed_at_ = model_->start_;
  const int yarns = std::max(0, static_cast<int>(model_->yarn_begin_.size()) - 1);
  made_at_.resize(yarns);
  cut_offsets_.resize(yarns);
  if (spec_.remake_at_start) {
    points_.reserve(model_->point_count_);
    const auto at = std::make_shared<const std::vector<Vec3>>(renewed_at_);
    for (int y = 0; y < yarns; ++y) {
      made_at_[y] = at;
      const std::vector<ContactPoint> yarn = linearised(renewed_at_, y);
      points_.insert(points_.end(), yarn.begin(), yarn.end());
    }
    check_points(points_, net_);
  } else {
    points_ = spec_.points;
  }
  points_changed();
  net_values_.resize(net_.stiffness_pattern().nnz());
  force_.resize(dof());
}

ContactNetwork::ContactNetwork(SpringNetwork network, YarnContactSpec contact)
    : ContactNetwork(std::make_shared<const ContactModel>(std::move(network), std::move(contact))) {
}

bool ContactNetwork::may_pair(int a, int b) const {
  return yarn_of_[a] != yarn_of_[b] || std::abs(arc_of_[a] - arc_of_[b]) >= spec_.same_yarn_gap;
}

std::vector<ContactPoint> ContactNetwork::linearised(const std::vector<Vec3>& particles,
                                                     int y) const {
  std::vector<ContactPoint> fresh = spec_.linearise(particles, y);
  if (static_cast<int>(fresh.size()) != model_->yarn_begin_[y + 1] - model_->yarn_begin_[y])
    throw std::logic_error("yarn contact: a renewed yarn has another number of points");
  return fresh;
}

bool ContactNetwork::update(double t, const double* x) {
  if (model_->yarn_begin_.empty() || !(spec_.refresh_tol > 0.0)) return false;
  std::vector<Vec3> particles;
  net_.all_positions(t, x, particles);
  double moved = 0.0;
  for (std::size_t i = 0; i < particles.size(); ++i) {
    const Vec3& p = particles[i];
    if (!is_finite(p)) return false;
    moved = std::max({moved, std::abs(p.x - renewed_at_[i].x), std::abs(p.y - renewed_at_[i].y)});
  }
  if (moved < spec_.refresh_move) return false;
  std::vector<Vec3> exact;  // every point's exact position
  spec_.exact(particles, exact);
  if (exact.size() != points_.size())
    throw std::logic_error("yarn contact: exact positions of another number of points");
  positions(t, x);
  // Each straying yarn is renewed: its points move from where they are to their exact positions,
  // as far along that as the step filter allows (a renewal is a step of the points). All at once
  // where the filter admits every move whole (one sweep and one check of the pairs); else each on
  // its own.
  long renewed = 0, cut = 0;
  std::vector<int> straying;
  for (int y = 0; y + 1 < static_cast<int>(model_->yarn_begin_.size()); ++y) {
    double drift = 0.0;
    for (int k = model_->yarn_begin_[y]; k < model_->yarn_begin_[y + 1]; ++k)
      drift = std::max(drift, norm(exact[k] - pts_[k]));
    if (drift > spec_.refresh_tol) straying.push_back(y);
  }
  // A point's move: to its exact position if its yarn is renewed, else none.
  std::vector<char> renewing(model_->yarn_begin_.size(), 0);
  for (const int y : straying) renewing[y] = 1;
  auto move = [&](std::size_t k) { return renewing[yarn_of_[k]] ? exact[k] - pts_[k] : Vec3{}; };
  // The fresh maps are written over the old ones, one yarn at a time: a check that fails remakes
  // the old ones from their recipes (remake), so no second set of maps is held.
  const auto at = std::make_shared<const std::vector<Vec3>>(particles);
  bool batch = !straying.empty() && sweep_fraction(pts_, move, spec_.renew_keep) >= 1.0;
  if (batch) {
    for (const int y : straying) {
      const std::vector<ContactPoint> fresh = linearised(particles, y);
      std::copy(fresh.begin(), fresh.end(), points_.begin() + model_->yarn_begin_[y]);
    }
    points_changed();
    if (min_distance(t, x) > spec_.core) {  // pts_ now holds the renewed points
      renewed = static_cast<long>(straying.size());
      for (const int y : straying) made_at_[y] = at, std::vector<Vec3>().swap(cut_offsets_[y]);
    } else {
      for (const int y : straying) remake(y);
      points_changed();
      positions(t, x);
      batch = false;
    }
  }
  for (std::size_t i = 0; !batch && i < straying.size(); ++i) {
    const int y = straying[i], begin = model_->yarn_begin_[y], end = model_->yarn_begin_[y + 1];
    std::vector<ContactPoint> fresh = linearised(particles, y);
    std::fill(renewing.begin(), renewing.end(), 0);
    renewing[y] = 1;
    const double s = sweep_fraction(pts_, move, spec_.renew_keep);
    if (s < 1.0) {
      ++cut_renewals_, ++cut;
      // Part way: the fresh map (its weights, the tangent here) moved to put each point s of the
      // way from where it is to its exact position; the rest is taken up at later checks.
      for (int k = begin; k < end; ++k)
        fresh[k - begin].offset = fresh[k - begin].offset - (1.0 - s) * move(k);
    }
    // Swapped in: fresh then holds the old maps, and swapping again restores them.
    std::swap_ranges(fresh.begin(), fresh.end(), points_.begin() + begin);
    points_changed();
    if (min_distance(t, x) > spec_.core) {  // pts_ now holds the renewed points
      ++renewed;
      made_at_[y] = at;
      cut_offsets_[y].clear();
      if (s < 1.0)
        for (int k = begin; k < end; ++k) cut_offsets_[y].push_back(points_[k].offset);
      cut_offsets_[y].shrink_to_fit();
    } else {  // round-off at the filter's floor: the old points are kept
      std::swap_ranges(fresh.begin(), fresh.end(), points_.begin() + begin);
      points_changed();
      positions(t, x);
    }
  }
  if (renewed == 0) return false;
  check_points(points_, net_);            // once, for the points kept
  if (cut == 0) renewed_at_ = particles;  // a cut renewal is taken up again at the next check
  refreshes_ += renewed;
  return true;
}

void ContactNetwork::remake(int y) {
  const int begin = model_->yarn_begin_[y], end = model_->yarn_begin_[y + 1];
  if (made_at_[y] == nullptr) {  // the model's own points
    std::copy(spec_.points.begin() + begin, spec_.points.begin() + end, points_.begin() + begin);
    return;
  }
  const std::vector<ContactPoint> maps = linearised(*made_at_[y], y);
  std::copy(maps.begin(), maps.end(), points_.begin() + begin);
  const std::vector<Vec3>& offsets = cut_offsets_[y];
  for (std::size_t k = 0; k < offsets.size(); ++k) points_[begin + k].offset = offsets[k];
}

bool ContactNetwork::renew(double t, const double* x) {
  if (model_->yarn_begin_.empty() || !spec_.linearise) return false;
  std::vector<Vec3> particles;
  net_.all_positions(t, x, particles);
  for (const Vec3& p : particles)
    if (!is_finite(p)) return false;
  const int yarns = static_cast<int>(model_->yarn_begin_.size()) - 1;
  for (int y = 0; y < yarns; ++y) {
    const std::vector<ContactPoint> fresh = linearised(particles, y);
    std::copy(fresh.begin(), fresh.end(), points_.begin() + model_->yarn_begin_[y]);
  }
  points_changed();
  if (!(min_distance(t, x) > spec_.core)) {
    for (int y = 0; y < yarns; ++y) remake(y);
    points_changed();
    return false;
  }
  check_points(points_, net_);
  renewed_at_ = particles;
  const auto at = std::make_shared<const std::vector<Vec3>>(std::move(particles));
  for (int y = 0; y < yarns; ++y) made_at_[y] = at, std::vector<Vec3>().swap(cut_offsets_[y]);
  return true;
}

namespace {

Vec3 rotate(double c, double s, Vec3 u) { return {c * u.x - s * u.y, s * u.x + c * u.y, u.z}; }

// W (3 x 2 row-major) times the 2-vector (x, y).
Vec3 times(const std::array<double, 6>& W, double x, double y) {
  return {W[0] * x + W[1] * y, W[2] * x + W[3] * y, W[4] * x + W[5] * y};
}

PointTurn turned(const ContactPoint& point, const std::vector<Vec3>& particles) {
  PointTurn t;
  t.u = point.offset;
  if (point.turn[0] >= 0) {
    const Vec3& xi = particles[point.particles[point.turn[0]]];
    const Vec3& xj = particles[point.particles[point.turn[1]]];
    t.vx = xj.x - xi.x, t.vy = xj.y - xi.y;
    t.v2 = t.vx * t.vx + t.vy * t.vy;
    const double len = std::sqrt(t.v2);
    t.c = (point.axis[0] * t.vx + point.axis[1] * t.vy) / len;
    t.s = (point.axis[0] * t.vy - point.axis[1] * t.vx) / len;
    t.gx = -t.vy / t.v2, t.gy = t.vx / t.v2;
    t.turns = true;
  }
  Vec3 wg2q{};  // sum_i W_i G2 q_i
  for (int i = 0; i < kContactParticles && point.particles[i] >= 0; ++i) {
    const Vec3 q = rotate(t.c, -t.s, particles[point.particles[i]]);  // R^T x_i
    t.u = t.u + times(point.weights[i], q.x, q.y);
    if (t.turns) wg2q = wg2q + times(point.weights[i], -q.y, q.x);
  }
  if (t.turns) t.a = Vec3{-t.u.y, t.u.x, 0.0} - wg2q;
  return t;
}

// grad_k(phi) of the point's particle k (zero unless it is one of the turning pair).
void turn_gradient(const ContactPoint& point, const PointTurn& t, int k, double& gx, double& gy) {
  const double sign = k == point.turn[1] ? 1.0 : (k == point.turn[0] ? -1.0 : 0.0);
  gx = t.turns ? sign * t.gx : 0.0;
  gy = t.turns ? sign * t.gy : 0.0;
}

// dp/dx_k = R (W_k R2^T + a grad_k^T), 3 x 2 row-major.
std::array<double, 6> jacobian(const ContactPoint& point, const PointTurn& t, int k) {
  const std::array<double, 6>& W = point.weights[k];
  double gx, gy;
  turn_gradient(point, t, k, gx, gy);
  // Columns of W R2^T + a grad^T (R2^T = [c s; -s c]), then rotated by R.
  const Vec3 col0 =
      Vec3{W[0] * t.c - W[1] * t.s, W[2] * t.c - W[3] * t.s, W[4] * t.c - W[5] * t.s} + gx * t.a;
  const Vec3 col1 =
      Vec3{W[0] * t.s + W[1] * t.c, W[2] * t.s + W[3] * t.c, W[4] * t.s + W[5] * t.c} + gy * t.a;
  const Vec3 r0 = rotate(t.c, t.s, col0), r1 = rotate(t.c, t.s, col1);
  return {r0.x, r1.x, r0.y, r1.y, r0.z, r1.z};
}

}  // namespace

Vec3 position_of(const ContactPoint& point, const std::vector<Vec3>& particles) {
  const PointTurn t = turned(point, particles);
  return rotate(t.c, t.s, t.u);
}

void ContactNetwork::points_changed() {
  listed_at_.clear();
  cached_ = false;
  yarn_of_.resize(points_.size());
  arc_of_.resize(points_.size());
  for (std::size_t k = 0; k < points_.size(); ++k)
    yarn_of_[k] = points_[k].yarn, arc_of_[k] = points_[k].arc;
}

void ContactNetwork::positions(double t, const double* x) const {
  if (cached_ && t == cached_t_ && std::equal(cached_x_.begin(), cached_x_.end(), x)) return;
  net_.all_positions(t, x, pos_);
  pts_.resize(points_.size());
  turns_.resize(points_.size());
  for (std::size_t k = 0; k < points_.size(); ++k) {
    const PointTurn tk = turned(points_[k], pos_);
    turns_[k] = {tk.c, tk.s, tk.a, tk.gx, tk.gy};
    pts_[k] = rotate(tk.c, tk.s, tk.u);
  }
  cached_x_.assign(x, x + dof());
  cached_t_ = t;
  cached_ = true;
}

void ContactNetwork::refresh_pairs() const {
  if (listed_at_.size() == pts_.size()) {
    double moved = 0.0;
    for (std::size_t k = 0; k < pts_.size(); ++k)
      moved = std::max(moved, norm(pts_[k] - listed_at_[k]));
    if (2.0 * moved <= spec_.skin) return;  // no two points came skin closer
  }
  listed_at_ = pts_;
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

// Adds (dp/dx_i)^T F (F a force on point p) to p's free particles' x and y, divided by their mass
// if `mass` is given.
void spread(const ContactPoint& p, const PointTurn& t, const SpringNetwork& net, Vec3 F,
            double* out, const std::vector<double>* mass) {
  for (int i = 0; i < kContactParticles && p.particles[i] >= 0; ++i) {
    const int f = net.free_index(p.particles[i]);
    if (f < 0) continue;
    const std::array<double, 6> W = jacobian(p, t, i);
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
    spread(points_[pr.a], turn_of(pr.a), net_, F, out, mass);
    spread(points_[pr.b], turn_of(pr.b), net_, -1.0 * F, out, mass);
  });
}

void ContactNetwork::set_held_positions(const std::vector<Vec3>& p) {
  net_.set_held_positions(p);
  cached_ = false;  // the particles' positions at a given (t, x) changed
}

void ContactNetwork::held_reactions(double t, const double* x, std::vector<Vec3>& out) const {
  net_.held_reactions(t, x, out);
  // The contact's forces on held particles (spread() keeps the free ones'): -(dp/dx_i)^T F.
  const bool finite = for_each_contact(t, x, [&](const Pair& pr, Vec3 d, double D, double de,
                                                 double) {
    const Vec3 F = (-de / D) * d;  // on point a; b gets the opposite
    for (int side = 0; side < 2; ++side) {
      const ContactPoint& p = points_[side == 0 ? pr.a : pr.b];
      const PointTurn turn = turn_of(side == 0 ? pr.a : pr.b);
      const Vec3 G = side == 0 ? F : -1.0 * F;
      for (int i = 0; i < kContactParticles && p.particles[i] >= 0; ++i) {
        const int h = net_.held_index(p.particles[i]);
        if (h < 0) continue;
        const std::array<double, 6> W = jacobian(p, turn, i);
        out[h].x -= W[0] * G.x + W[2] * G.y + W[4] * G.z;
        out[h].y -= W[1] * G.x + W[3] * G.y + W[5] * G.z;
      }
    }
  });
  if (!finite)
    for (Vec3& r : out) r = Vec3{std::nan(""), std::nan(""), std::nan("")};
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
  std::fill(values, values + model_->pattern_.nnz(), 0.0);
  for (std::size_t k = 0; k < net_values_.size(); ++k)
    values[model_->net_entry_[k]] = net_values_[k];
  const std::vector<double>& m = net_.mass();
  // Per point, dE/dp summed over its pairs (a local: 24 bytes a point not held between calls).
  std::vector<Vec3> grad(points_.size(), Vec3{0.0, 0.0, 0.0});
  bool missed = false;
  // Adds -block / m_r (2 x 2, row-major) to particle block (fr, fc): da/dx = -K / m.
  auto add_block = [&](int particle_r, int particle_c, const double block[4]) {
    const int fr = net_.free_index(particle_r), fc = net_.free_index(particle_c);
    if (fr < 0 || fc < 0) return;
    const int e_node = model_->nodes_.find(fr, fc);
    if (e_node < 0) {
      missed = true;
      return;
    }
    for (int p = 0; p < 2; ++p)
      for (int q = 0; q < 2; ++q)
        values[node_block_entry(model_->nodes_, e_node, fc, p, q)] -= block[2 * p + q] / m[3 * fr];
  };
  std::array<std::array<double, 6>, kContactParticles> J[2];
  const bool finite =
      for_each_contact(t, x, [&](const Pair& pr, Vec3 d, double D, double de, double d2e) {
        const double u[3] = {d.x / D, d.y / D, d.z / D}, s = de / D;
        // H = d2e u u^T + (de / D)(I - u u^T), in p_a - p_b; the gradient in p_a is de u.
        double H[3][3];
        for (int p = 0; p < 3; ++p)
          for (int q = 0; q < 3; ++q) H[p][q] = (d2e - s) * u[p] * u[q] + (p == q ? s : 0.0);
        grad[pr.a] = grad[pr.a] + s * d;
        grad[pr.b] = grad[pr.b] - s * d;
        missed = false;
        const ContactPoint* pt[2] = {&points_[pr.a], &points_[pr.b]};
        const int index[2] = {pr.a, pr.b};
        for (int A = 0; A < 2; ++A) {
          const PointTurn tA = turn_of(index[A]);
          for (int i = 0; i < kContactParticles && pt[A]->particles[i] >= 0; ++i)
            J[A][i] = jacobian(*pt[A], tA, i);
        }
        for (int A = 0; A < 2; ++A)
          for (int i = 0; i < kContactParticles && pt[A]->particles[i] >= 0; ++i) {
            const std::array<double, 6>& Ji = J[A][i];
            // G = Ji^T H, 2 x 3 (Ji row-major 3 x 2: Ji[2 k + p] is row k, column p)
            double G[2][3];
            for (int p = 0; p < 2; ++p)
              for (int q = 0; q < 3; ++q)
                G[p][q] = Ji[p] * H[0][q] + Ji[2 + p] * H[1][q] + Ji[4 + p] * H[2][q];
            for (int B = 0; B < 2; ++B)
              for (int j = 0; j < kContactParticles && pt[B]->particles[j] >= 0; ++j) {
                const std::array<double, 6>& Jj = J[B][j];
                const double sign = A == B ? 1.0 : -1.0;  // d^2E/dx_r dx_c = s_r s_c Ji^T H Jj
                double block[4];
                for (int p = 0; p < 2; ++p)
                  for (int q = 0; q < 2; ++q)
                    block[2 * p + q] =
                        sign * (G[p][0] * Jj[q] + G[p][1] * Jj[2 + q] + G[p][2] * Jj[4 + q]);
                add_block(pt[A]->particles[i], pt[B]->particles[j], block);
              }
          }
        pattern_misses_ += missed;
      });
  if (!finite) {
    std::fill(values, values + model_->pattern_.nnz(), std::nan(""));
    return;
  }
  // The maps' curvature (header, "Co-rotated points"): per turning point with a gradient g.
  for (std::size_t k = 0; k < points_.size(); ++k) {
    const ContactPoint& pt = points_[k];
    const Vec3 g = grad[k];
    if (pt.turn[0] < 0 || (g.x == 0.0 && g.y == 0.0 && g.z == 0.0)) continue;
    const PointTurn tk = turn_of(static_cast<int>(k));
    const Vec3 gt = rotate(tk.c, -tk.s, g);  // R^T g
    int count = 0;
    while (count < kContactParticles && pt.particles[count] >= 0) ++count;
    double n[kContactParticles][2], gr[kContactParticles][2];
    double c = gt.y * tk.a.x - gt.x * tk.a.y;  // g~ . G a
    for (int i = 0; i < count; ++i) {
      const std::array<double, 6>& W = pt.weights[i];
      // m = (G W - W G2)^T g~: G W has rows (-W_y, W_x, 0), W G2 columns (W_col1, -W_col0).
      const double m0 = -W[2] * gt.x + W[0] * gt.y - (W[1] * gt.x + W[3] * gt.y + W[5] * gt.z);
      const double m1 = -W[3] * gt.x + W[1] * gt.y + (W[0] * gt.x + W[2] * gt.y + W[4] * gt.z);
      const Vec3 q = rotate(tk.c, -tk.s, pos_[pt.particles[i]]);  // R^T x_i
      c -= m0 * -q.y + m1 * q.x;                                  // m . G2 q
      n[i][0] = tk.c * m0 - tk.s * m1;
      n[i][1] = tk.s * m0 + tk.c * m1;
      turn_gradient(pt, tk, i, gr[i][0], gr[i][1]);
    }
    const double ga = dot(gt, tk.a);
    // d^2 phi / dv^2 = [2 vx vy, vy^2 - vx^2; vy^2 - vx^2, -2 vx vy] / |v|^4
    const double v4 = tk.v2 * tk.v2;
    const double P[4] = {2.0 * tk.vx * tk.vy / v4, (tk.vy * tk.vy - tk.vx * tk.vx) / v4,
                         (tk.vy * tk.vy - tk.vx * tk.vx) / v4, -2.0 * tk.vx * tk.vy / v4};
    missed = false;
    for (int i = 0; i < count; ++i)
      for (int j = 0; j < count; ++j) {
        const bool ti = i == pt.turn[0] || i == pt.turn[1], tj = j == pt.turn[0] || j == pt.turn[1];
        if (!ti && !tj) continue;
        // d^2 phi / dx_i dx_j: +P on each turning particle's own block, -P between the two
        const double sign = (ti && tj) ? (i == j ? 1.0 : -1.0) : 0.0;
        double block[4];
        for (int p = 0; p < 2; ++p)
          for (int q = 0; q < 2; ++q)
            block[2 * p + q] = n[i][p] * gr[j][q] + gr[i][p] * n[j][q] + c * gr[i][p] * gr[j][q] +
                               ga * sign * P[2 * p + q];
        add_block(pt.particles[i], pt.particles[j], block);
      }
    pattern_misses_ += missed;
  }
}

double ContactNetwork::admissible_step(double t, const double* x, const double* dx) const {
  if (!pairs_of(t, x)) return 1.0;
  // pos_, pts_ and turns_ describe x throughout: the step's points go into buffers of their own
  // (the points, and each point's (c, s) for its turn; not a copy of the caches).
  const std::size_t n = points_.size();
  std::vector<Vec3> particles, at(n);  // the particles and points at fraction `done`
  std::vector<double> y(x, x + dof());
  double cap = 1.0, done = -1.0;
  // The points at fraction s of the (capped) step, into `at`; with `turn`, the largest turn of a
  // point from x there (and `turning`: whether any point turns).
  double turn = 0.0;
  bool turning = false;
  auto points_at = [&](double s, bool measure_turn) {
    if (s == done && !measure_turn) return;
    for (int i = 0; i < dof(); ++i) y[i] = x[i] + s * cap * dx[i];
    net_.all_positions(t, y.data(), particles);
    turn = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const PointTurn tk = turned(points_[k], particles);
      at[k] = rotate(tk.c, tk.s, tk.u);
      if (!measure_turn || points_[k].turn[0] < 0) continue;
      turning = true;
      turn = std::max(
          turn, std::abs(std::remainder(std::atan2(tk.s, tk.c) - turn_angle(static_cast<int>(k)),
                                        2.0 * 3.14159265358979323846)));
    }
    done = s;
  };
  points_at(1.0, true);
  double longest = 0.0;
  for (std::size_t k = 0; k < n; ++k) longest = std::max(longest, norm(at[k] - pts_[k]));
  if (!(longest < std::numeric_limits<double>::infinity())) return 0.0;
  // A step that moves a point by more than step_cap is cut to that first (a yarn jumping several
  // diameters in one Newton step is not trusted, the swept boxes stay small, and renewable
  // points stray less from their exact positions within one step).
  if (longest > spec_.step_cap) {
    cap = spec_.step_cap / longest;
    points_at(1.0, true);
  }
  // Co-rotated points move on curves: the step is swept as chords between exact states, each
  // turning no point more than kChordTurn (its path's sagitta ~ kChordTurn^2 / 8 of its reach).
  const int chords =
      std::min(kMaxChords, std::max(1, static_cast<int>(std::ceil(turn / kChordTurn))));
  double fraction = 1.0;
  std::vector<Vec3> from = pts_;
  for (int c = 0; c < chords; ++c) {
    points_at(double(c + 1) / chords, false);
    const double f = sweep_fraction(
        from, [&](std::size_t k) { return at[k] - from[k]; }, spec_.filter_keep);
    if (f < 1.0) {
      fraction = (c + f) / chords;
      break;
    }
    from = at;
  }
  // The end of a bent path is checked exactly on x's near pairs (a pair further apart would have
  // had to move more than the skin, which the chords see): halved while a pair is inside a core.
  if (turning)
    for (int halve = 0; fraction > 0.0; ++halve) {
      points_at(fraction, false);
      bool clear = true;
      for (const Pair& pr : pairs_) clear = clear && norm(at[pr.a] - at[pr.b]) > spec_.core;
      if (clear) break;
      fraction = halve < 40 ? 0.5 * fraction : 0.0;
    }
  return cap * fraction;
}

double ContactNetwork::turn_angle(int k) const { return std::atan2(turns_[k].s, turns_[k].c); }

PointTurn ContactNetwork::turn_of(int k) const {
  const TurnCache& q = turns_[k];
  const ContactPoint& point = points_[k];
  PointTurn t;
  t.c = q.c, t.s = q.s, t.a = q.a, t.gx = q.gx, t.gy = q.gy;
  if (point.turn[0] >= 0) {  // v as turned() makes it, from the particles at the same state
    const Vec3& xi = pos_[point.particles[point.turn[0]]];
    const Vec3& xj = pos_[point.particles[point.turn[1]]];
    t.vx = xj.x - xi.x, t.vy = xj.y - xi.y;
    t.v2 = t.vx * t.vx + t.vy * t.vy;
    t.turns = true;
  }
  return t;
}

template <class MoveOf>
double ContactNetwork::sweep_fraction(const std::vector<Vec3>& start, MoveOf move,
                                      double keep) const {
  double fraction = 1.0;
  auto sweep_pair = [&](int a, int b) {
    const Vec3 d0 = start[a] - start[b];
    const Vec3 dd = move(a) - move(b);
    const double D0 = norm(d0);
    const double floor = spec_.core + keep * (std::min(D0, spec_.touching) - spec_.core);
    const double A = dot(dd, dd), B = dot(d0, dd), C = D0 * D0 - floor * floor;
    if (!(A > 0.0) || B >= 0.0 || C <= 0.0) return;
    const double disc = B * B - A * C;
    if (disc < 0.0) return;
    const double tau = (-B - std::sqrt(disc)) / A;  // first time the distance reaches floor
    fraction = std::min(fraction, std::max(0.0, tau));
  };
  // The near-pair list holds every pair that can come within d on the way when no point is
  // further than skin / 2 from where the list was made, start to end: a pair not listed was
  // d + skin apart there. Such a pair never comes below its floor (< d), so the fraction is the
  // one the swept boxes give (a minimum, whatever the order).
  if (listed_at_.size() == start.size()) {
    double furthest = 0.0;
    for (std::size_t k = 0; k < start.size(); ++k)
      furthest = std::max(furthest, norm(start[k] - listed_at_[k]) + norm(move(k)));
    if (2.0 * furthest <= spec_.skin) {
      for (const Pair& pr : pairs_) sweep_pair(pr.a, pr.b);
      ++list_sweeps_;
      return fraction;
    }
  }
  std::vector<Box> boxes(start.size());
  for (std::size_t k = 0; k < start.size(); ++k) {
    const Vec3 e = start[k] + move(k);
    boxes[k] = {std::min(start[k].x, e.x) - 0.5 * spec_.touching,
                std::max(start[k].x, e.x) + 0.5 * spec_.touching,
                std::min(start[k].y, e.y) - 0.5 * spec_.touching,
                std::max(start[k].y, e.y) + 0.5 * spec_.touching};
  }
  overlapping_boxes(boxes, spec_.touching, [&](int a, int b) {
    if (may_pair(a, b)) sweep_pair(a, b);
  });
  return fraction;
}

std::string ContactNetwork::describe() const {
  std::ostringstream o;
  o << net_.describe() << "; yarn contact: " << points_.size() << " points, barrier from "
    << spec_.touching << " m to its core " << spec_.core << " m, kappa " << spec_.stiffness
    << " N/m";
  return o.str();
}

}  // namespace knitsim
