#include "src/measure/yarn_measures.hpp"

#include <algorithm>
#include <ctime>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "src/geometry/nurbs.hpp"
#include "src/geometry/segment_distance.hpp"

namespace knitsim {

namespace {

struct FlatSegment {
  int course, segment;
  Vec3 p0, p1;
};

std::vector<FlatSegment> flatten(const YarnPolylines& lines) {
  std::vector<FlatSegment> out;
  for (size_t j = 0; j < lines.vertices.size(); ++j) {
    const std::vector<Vec3>& v = lines.vertices[j];
    for (size_t k = 0; k + 1 < v.size(); ++k)
      out.push_back({static_cast<int>(j), static_cast<int>(k), v[k], v[k + 1]});
  }
  return out;
}

// Two segments count (see the header): different courses, or one course at least `gap` m
// apart along the yarn.
bool counted(const YarnPolylines& lines, const FlatSegment& a, const FlatSegment& b, double gap) {
  if (a.course != b.course) return true;
  const int i = std::min(a.segment, b.segment), k = std::max(a.segment, b.segment);
  const std::vector<double>& arc = lines.arc[a.course];
  return arc[k] - arc[i + 1] >= gap;
}

// Calls f(a, b) for every counted pair of segments whose midpoints lie in neighbouring cells of
// a grid in the front view (x, y) of cell size >= radius + longest segment: every pair closer
// than `radius` is among them. The fabric is a few r thick, so z is not binned. Cells are a dense
// array filled by a counting sort, the segments copied in cell order (each cell contiguous).
template <class F>
void for_each_near_pair(const YarnPolylines& lines, const std::vector<FlatSegment>& segs,
                        double radius, double gap, F&& f) {
  if (segs.empty()) return;
  double longest = 0.0, x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const FlatSegment& s : segs) {
    longest = std::max(longest, norm(s.p1 - s.p0));
    const Vec3 c = 0.5 * (s.p0 + s.p1);
    x0 = std::min(x0, c.x), y0 = std::min(y0, c.y), x1 = std::max(x1, c.x), y1 = std::max(y1, c.y);
  }
  double cell = radius + longest;
  if (!(cell > 0.0) || !std::isfinite(cell) || !std::isfinite(x1 - x0) || !std::isfinite(y1 - y0))
    return;
  // At most ~4 cells per segment (a coarser grid is still complete, only slower).
  cell = std::max(cell, std::sqrt((x1 - x0) * (y1 - y0) / (4.0 * segs.size())));
  const int64_t nx = static_cast<int64_t>((x1 - x0) / cell) + 1;
  const int64_t ny = static_cast<int64_t>((y1 - y0) / cell) + 1;
  auto cell_of = [&](const FlatSegment& s) {
    const Vec3 c = 0.5 * (s.p0 + s.p1);
    const int64_t ix = std::min(nx - 1, static_cast<int64_t>((c.x - x0) / cell));
    const int64_t iy = std::min(ny - 1, static_cast<int64_t>((c.y - y0) / cell));
    return ix * ny + iy;
  };
  std::vector<size_t> begin(static_cast<size_t>(nx * ny) + 1, 0);
  for (const FlatSegment& s : segs) ++begin[cell_of(s) + 1];
  for (size_t c = 1; c < begin.size(); ++c) begin[c] += begin[c - 1];
  std::vector<FlatSegment> sorted(segs.size());
  {
    std::vector<size_t> next(begin.begin(), begin.end() - 1);
    for (const FlatSegment& s : segs) sorted[next[cell_of(s)]++] = s;
  }
  // Each unordered pair of neighbouring cells once: the cell itself and its four neighbours
  // (ix + 1, iy - 1..iy + 1), (ix, iy + 1).
  constexpr int kNeighbours[4][2] = {{1, -1}, {1, 0}, {1, 1}, {0, 1}};
  for (int64_t ix = 0; ix < nx; ++ix)
    for (int64_t iy = 0; iy < ny; ++iy) {
      const size_t c = static_cast<size_t>(ix * ny + iy);
      for (size_t p = begin[c]; p < begin[c + 1]; ++p)
        for (size_t q = p + 1; q < begin[c + 1]; ++q)
          if (counted(lines, sorted[p], sorted[q], gap)) f(sorted[p], sorted[q]);
      for (const auto& d : kNeighbours) {
        const int64_t jx = ix + d[0], jy = iy + d[1];
        if (jx >= nx || jy < 0 || jy >= ny) continue;
        const size_t o = static_cast<size_t>(jx * ny + jy);
        for (size_t p = begin[c]; p < begin[c + 1]; ++p)
          for (size_t q = begin[o]; q < begin[o + 1]; ++q)
            if (counted(lines, sorted[p], sorted[q], gap)) f(sorted[p], sorted[q]);
      }
    }
}

FlatSegment segment_of(const YarnPolylines& lines, int course, int segment) {
  const std::vector<Vec3>& v = lines.vertices[course];
  return {course, segment, v[segment], v[segment + 1]};
}

// Front-view (x, y) crossing of two segments: true, with the depth of each segment at the
// crossing point (linear along the segment), or false. Ties are broken by a fixed perturbation:
// a point within 1e-10 of a segment's length of that segment's line (on it, to round-off) is
// on the side it would be on if the segment of the higher (course, segment) were moved by an
// infinitesimal (e, e^2) in the plane. Two yarns crossing at a vertex, of one or of both (the
// knit's rest centrelines share points), then cross at exactly one pair of their segments,
// whatever the vertices' round-off; with strict signs such a crossing counted none, one or two
// pairs, and which depended on the order of the arithmetic that placed the vertices.
bool cross_in_front_view(const FlatSegment& first, const FlatSegment& second,
                         double* z_first = nullptr, double* z_second = nullptr) {
  const bool swap = std::tie(second.course, second.segment) < std::tie(first.course, first.segment);
  const FlatSegment& a = swap ? second : first;
  const FlatSegment& b = swap ? first : second;  // the one moved
  // Which side of the line p -> q the point r is on (true: left), with its orientation o (0 on
  // a tie); `move` +1 if r is on the moved segment, -1 if the line is: o(r + move (e, e^2)) =
  // o + move (-dy e + dx e^2).
  auto left = [](Vec3 p, Vec3 q, Vec3 r, double move, double& o) {
    const double dx = q.x - p.x, dy = q.y - p.y;
    o = dx * (r.y - p.y) - dy * (r.x - p.x);
    if (std::abs(o) > 1e-10 * (dx * dx + dy * dy)) return o > 0.0;
    o = 0.0;
    return dy != 0.0 ? -move * dy > 0.0 : move * dx > 0.0;
  };
  double o1, o2, o3, o4;
  if (left(a.p0, a.p1, b.p0, 1.0, o1) == left(a.p0, a.p1, b.p1, 1.0, o2)) return false;
  if (left(b.p0, b.p1, a.p0, -1.0, o3) == left(b.p0, b.p1, a.p1, -1.0, o4)) return false;
  // Opposite sides: o1 - o2 and o3 - o4 are not 0 (at most one of each pair is a tie).
  const double za = a.p0.z + (o3 / (o3 - o4)) * (a.p1.z - a.p0.z);
  const double zb = b.p0.z + (o1 / (o1 - o2)) * (b.p1.z - b.p0.z);
  if (z_first != nullptr) *z_first = swap ? zb : za;
  if (z_second != nullptr) *z_second = swap ? za : zb;
  return true;
}

// sigma of a crossing in `lines`: which piece is in front (+1: a, -1: b) where the two cross in
// the front view, taken at the segment pair nearest the given one (rings of growing index
// distance, at most two intervals along each yarn) whose front views cross. If none do there
// (the pieces' projections came to touch or parted), where their front views come closest
// within that reach. 0 only if the depths are equal there.
int crossing_sign(const YarnPolylines& lines, YarnSegment a, YarnSegment b) {
  const int reach = 2 * lines.samples_per_interval;
  const int na = static_cast<int>(lines.vertices[a.course].size()) - 1;
  const int nb = static_cast<int>(lines.vertices[b.course].size()) - 1;
  auto order = [](double za, double zb) { return za > zb ? 1 : za < zb ? -1 : 0; };
  auto flat = [](Vec3 p) { return Vec3{p.x, p.y, 0.0}; };
  double nearest = std::numeric_limits<double>::infinity();
  int nearest_order = 0;
  for (int ring = 0; ring <= reach; ++ring)
    for (int di = -ring; di <= ring; ++di)  // the ring's perimeter only
      for (int dk = -ring; dk <= ring; dk += (std::abs(di) == ring ? 1 : std::max(1, 2 * ring))) {
        const int i = a.segment + di, k = b.segment + dk;
        if (i < 0 || k < 0 || i >= na || k >= nb) continue;
        const FlatSegment sa = segment_of(lines, a.course, i), sb = segment_of(lines, b.course, k);
        // Not a segment against itself or its neighbour on one course (they touch).
        if (!counted(lines, sa, sb, std::numeric_limits<double>::min())) continue;
        double za, zb;
        if (cross_in_front_view(sa, sb, &za, &zb)) return order(za, zb);
        const SegmentClosest c = closest_points(flat(sa.p0), flat(sa.p1), flat(sb.p0), flat(sb.p1));
        if (c.distance < nearest) {
          nearest = c.distance;
          nearest_order =
              order(sa.p0.z + c.s * (sa.p1.z - sa.p0.z), sb.p0.z + c.t * (sb.p1.z - sb.p0.z));
        }
      }
  return nearest_order;
}

}  // namespace

YarnClearance yarn_clearance(const KnitModel& m, const YarnPolylines& lines,
                             double search_radius_over_r, const YarnClearance* hint) {
  const double r = m.params.loop_radius;
  YarnClearance best;
  best.over_r = search_radius_over_r;
  for (const std::vector<Vec3>& v : lines.vertices)
    if (!std::all_of(v.begin(), v.end(), is_finite)) {
      best.over_r = std::nan("");
      return best;
    }
  double d_best = search_radius_over_r * r;
  const double gap = kSameYarnGap * r;
  auto valid = [&](YarnSegment s) {
    return s.course >= 0 && s.course < static_cast<int>(lines.vertices.size()) && s.segment >= 0 &&
           s.segment + 1 < static_cast<int>(lines.vertices[s.course].size());
  };
  // The hinted pair's distance in these lines is an upper bound of the clearance: only pairs
  // closer than it need the grid (a smaller search radius, fewer cells and pairs). Exact.
  if (hint != nullptr && valid(hint->a) && valid(hint->b)) {
    const FlatSegment a = segment_of(lines, hint->a.course, hint->a.segment);
    const FlatSegment b = segment_of(lines, hint->b.course, hint->b.segment);
    if (counted(lines, a, b, gap)) {
      const SegmentClosest c = closest_points(a.p0, a.p1, b.p0, b.p1);
      if (c.distance < d_best) {
        d_best = c.distance;
        best.a = hint->a;
        best.b = hint->b;
        best.where = 0.5 * (c.a + c.b);
      }
    }
  }
  const std::vector<FlatSegment> segs = flatten(lines);
  for_each_near_pair(lines, segs, d_best, gap, [&](const FlatSegment& a, const FlatSegment& b) {
    // Lower bounds: the gap between the bounding boxes along each axis, then the midpoint
    // distance less the half lengths.
    auto apart = [&](double a0, double a1, double b0, double b1) {
      return std::min(b0, b1) - std::max(a0, a1) >= d_best ||
             std::min(a0, a1) - std::max(b0, b1) >= d_best;
    };
    if (apart(a.p0.x, a.p1.x, b.p0.x, b.p1.x) || apart(a.p0.y, a.p1.y, b.p0.y, b.p1.y) ||
        apart(a.p0.z, a.p1.z, b.p0.z, b.p1.z))
      return;
    const double bound =
        norm(0.5 * (a.p0 + a.p1 - b.p0 - b.p1)) - 0.5 * (norm(a.p1 - a.p0) + norm(b.p1 - b.p0));
    if (bound >= d_best) return;
    const SegmentClosest c = closest_points(a.p0, a.p1, b.p0, b.p1);
    if (c.distance < d_best) {
      d_best = c.distance;
      best.a = {a.course, a.segment};
      best.b = {b.course, b.segment};
      best.where = 0.5 * (c.a + c.b);
    }
  });
  best.over_r = d_best / r;
  return best;
}

std::vector<YarnCrossing> designed_crossings(const KnitModel& m, const YarnPolylines& rest) {
  const double r = m.params.loop_radius;
  const std::vector<FlatSegment> segs = flatten(rest);
  std::vector<YarnCrossing> out;
  // At rest the fabric is at most ~4 r thick: crossing segments are within 8 r of each other.
  for_each_near_pair(rest, segs, 8.0 * r, kSameYarnGap * r,
                     [&](const FlatSegment& a, const FlatSegment& b) {
                       if (!cross_in_front_view(a, b)) return;
                       const YarnSegment sa{a.course, a.segment}, sb{b.course, b.segment};
                       out.push_back({sa, sb, crossing_sign(rest, sa, sb)});
                     });
  std::sort(out.begin(), out.end(), [](const YarnCrossing& p, const YarnCrossing& q) {
    return std::tie(p.a.course, p.a.segment, p.b.course, p.b.segment) <
           std::tie(q.a.course, q.a.segment, q.b.course, q.b.segment);
  });
  return out;
}

CrossingCheck check_crossings(const std::vector<YarnCrossing>& crossings,
                              const YarnPolylines& lines) {
  CrossingCheck out;
  out.designed = static_cast<int>(crossings.size());
  for (size_t n = 0; n < crossings.size(); ++n)
    if (crossing_sign(lines, crossings[n].a, crossings[n].b) != crossings[n].sign) {
      ++out.changed;
      out.changed_index.push_back(static_cast<int>(n));
    }
  return out;
}

ClearanceOverRun::ClearanceOverRun(const KnitModel& m, RunObserver* next, double resample_over_r)
    : m_(m), next_(next), tau_(resample_over_r) {}

void ClearanceOverRun::observe(double t, const double* x, bool force) {
  const double r = m_.params.loop_radius;
  m_.all_positions(t, x, pos_);
  double moved = 0.0;  // interlacing points, since the last measured state, m
  if (!last_.empty()) {
    for (size_t k = 0; k < pos_.size(); ++k) moved = std::max(moved, norm(pos_[k] - last_[k]));
    if (!force && moved < tau_ * r) return;
  }
  ++measured_;
  const std::clock_t cpu_start = std::clock();
  YarnClearance c;
  if (std::all_of(pos_.begin(), pos_.end(), is_finite)) {
    YarnPolylines lines = yarn_polylines(m_, pos_);
    c = yarn_clearance(m_, lines, 2.0, last_clearance_.a.course >= 0 ? &last_clearance_ : nullptr);
    if (moved > 0.0 && !last_lines_.vertices.empty()) {
      double vertex_moved = 0.0;
      for (size_t j = 0; j < lines.vertices.size(); ++j)
        for (size_t k = 0; k < lines.vertices[j].size(); ++k)
          vertex_moved =
              std::max(vertex_moved, norm(lines.vertices[j][k] - last_lines_.vertices[j][k]));
      amplification_ = std::max(amplification_, vertex_moved / moved);
    }
    last_lines_ = std::move(lines);
    last_clearance_ = c;
  } else {
    c.over_r = std::nan("");
  }
  last_ = pos_;
  cpu_seconds_ += static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  if (measured_ > 1 && std::isnan(min_.over_r)) return;  // a non-finite state stays the verdict
  if (measured_ == 1 || std::isnan(c.over_r) || c.over_r < min_.over_r) {
    min_ = c;
    t_min_ = t;
    check_min_ = checks_;
  }
}

void ClearanceOverRun::on_step(double t, double h, int order) {
  if (next_) next_->on_step(t, h, order);
}

void ClearanceOverRun::on_check(double t, const double* x, const double* v, double residual) {
  ++checks_;
  observe(t, x, false);
  if (next_) next_->on_check(t, x, v, residual);
}

}  // namespace knitsim
