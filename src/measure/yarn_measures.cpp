#include "src/measure/yarn_measures.hpp"

#include <algorithm>
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
// a grid of cell size radius + longest segment: every pair closer than `radius` is among them.
template <class F>
void for_each_near_pair(const YarnPolylines& lines, const std::vector<FlatSegment>& segs,
                        double radius, double gap, F&& f) {
  if (segs.empty()) return;
  double longest = 0.0;
  Vec3 lo{1e300, 1e300, 1e300};
  for (const FlatSegment& s : segs) {
    longest = std::max(longest, norm(s.p1 - s.p0));
    const Vec3 c = 0.5 * (s.p0 + s.p1);
    lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
  }
  const double cell = radius + longest;
  if (!(cell > 0.0) || !std::isfinite(cell)) return;
  auto coord = [&](double v, double v0) { return static_cast<int64_t>((v - v0) / cell); };
  constexpr int64_t kBits = 21, kMask = (int64_t{1} << kBits) - 1;
  auto key = [&](int64_t ix, int64_t iy, int64_t iz) {
    return ((ix & kMask) << (2 * kBits)) | ((iy & kMask) << kBits) | (iz & kMask);
  };
  // Segments sorted by cell key; the occupied cells with their ranges in that order. Keys are
  // lexicographic in (ix, iy, iz) >= 0, so each pair of neighbouring cells is visited once, from
  // the cell with the smaller key.
  std::vector<std::pair<int64_t, int>> sorted(segs.size());
  for (size_t n = 0; n < segs.size(); ++n) {
    const Vec3 c = 0.5 * (segs[n].p0 + segs[n].p1);
    sorted[n] = {key(coord(c.x, lo.x), coord(c.y, lo.y), coord(c.z, lo.z)), static_cast<int>(n)};
  }
  std::sort(sorted.begin(), sorted.end());
  std::vector<int64_t> cell_key;
  std::vector<size_t> cell_begin;
  for (size_t n = 0; n < sorted.size(); ++n)
    if (n == 0 || sorted[n].first != sorted[n - 1].first) {
      cell_key.push_back(sorted[n].first);
      cell_begin.push_back(n);
    }
  cell_begin.push_back(sorted.size());
  for (size_t c = 0; c < cell_key.size(); ++c) {
    const int64_t ix = cell_key[c] >> (2 * kBits), iy = (cell_key[c] >> kBits) & kMask,
                  iz = cell_key[c] & kMask;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (ix + dx < 0 || iy + dy < 0 || iz + dz < 0) continue;
          const int64_t k = key(ix + dx, iy + dy, iz + dz);
          if (k < cell_key[c]) continue;
          const auto it = std::lower_bound(cell_key.begin(), cell_key.end(), k);
          if (it == cell_key.end() || *it != k) continue;
          const size_t o = static_cast<size_t>(it - cell_key.begin());
          for (size_t p = cell_begin[c]; p < cell_begin[c + 1]; ++p)
            for (size_t q = o == c ? p + 1 : cell_begin[o]; q < cell_begin[o + 1]; ++q) {
              const FlatSegment& a = segs[sorted[p].second];
              const FlatSegment& b = segs[sorted[q].second];
              if (counted(lines, a, b, gap)) f(a, b);
            }
        }
  }
}

int triple_sign(const FlatSegment& a, const FlatSegment& b, const SegmentClosest& c) {
  const double v = dot(c.a - c.b, cross(a.p1 - a.p0, b.p1 - b.p0));
  return v > 0.0 ? 1 : v < 0.0 ? -1 : 0;
}

FlatSegment segment_of(const YarnPolylines& lines, int course, int segment) {
  const std::vector<Vec3>& v = lines.vertices[course];
  return {course, segment, v[segment], v[segment + 1]};
}

// Front-view (x, y) proper intersection of two segments.
bool cross_in_front_view(const FlatSegment& a, const FlatSegment& b) {
  auto orient = [](Vec3 p, Vec3 q, Vec3 r) {
    return (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
  };
  const double o1 = orient(a.p0, a.p1, b.p0), o2 = orient(a.p0, a.p1, b.p1);
  const double o3 = orient(b.p0, b.p1, a.p0), o4 = orient(b.p0, b.p1, a.p1);
  return ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0)) &&
         ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0));
}

// sigma of a crossing in `lines`: from the segment pair (a, b), descend to the pair of least
// distance among neighbouring pairs (index steps of -1, 0, +1 on each yarn, at most one
// interval from the start), i.e. to the local closest approach of the two yarn pieces, and
// take the triple-product sign there.
int crossing_sign(const YarnPolylines& lines, YarnSegment a, YarnSegment b) {
  const int w = lines.samples_per_interval;
  const int na = static_cast<int>(lines.vertices[a.course].size()) - 1;
  const int nb = static_cast<int>(lines.vertices[b.course].size()) - 1;
  auto distance_at = [&](int i, int k, SegmentClosest& c) {
    if (i < 0 || k < 0 || i >= na || k >= nb || std::abs(i - a.segment) > w ||
        std::abs(k - b.segment) > w)
      return std::numeric_limits<double>::infinity();
    const FlatSegment sa = segment_of(lines, a.course, i), sb = segment_of(lines, b.course, k);
    // Not a segment against itself or its neighbour on one course (they touch).
    if (!counted(lines, sa, sb, std::numeric_limits<double>::min()))
      return std::numeric_limits<double>::infinity();
    c = closest_points(sa.p0, sa.p1, sb.p0, sb.p1);
    return c.distance;
  };
  int i = a.segment, k = b.segment;
  SegmentClosest best;
  double d = distance_at(i, k, best);
  for (bool moved = true; moved;) {
    moved = false;
    int bi = i, bk = k;
    SegmentClosest c;
    for (int di = -1; di <= 1; ++di)
      for (int dk = -1; dk <= 1; ++dk) {
        const double e = distance_at(i + di, k + dk, c);
        if (e < d) d = e, bi = i + di, bk = k + dk, best = c, moved = true;
      }
    i = bi, k = bk;
  }
  if (!std::isfinite(d)) return 0;
  return triple_sign(segment_of(lines, a.course, i), segment_of(lines, b.course, k), best);
}

}  // namespace

YarnPolylines yarn_polylines(const KnitModel& m, const std::vector<Vec3>& positions,
                             int samples_per_interval) {
  if (samples_per_interval < 1)
    throw std::invalid_argument("yarn_polylines: samples_per_interval must be >= 1");
  YarnPolylines out;
  out.samples_per_interval = samples_per_interval;
  for (const std::vector<Vec3>& yarn : course_yarn_points(m, positions)) {
    const NurbsCurve curve = interpolate_cubic(yarn, kYarnParametrization);
    const std::vector<double> ubar = interpolation_parameters(yarn, kYarnParametrization);
    std::vector<Vec3> v;
    v.reserve(samples_per_interval * (yarn.size() - 1) + 1);
    for (size_t k = 0; k + 1 < yarn.size(); ++k)
      for (int s = 0; s < samples_per_interval; ++s)
        v.push_back(
            evaluate(curve, ubar[k] + (ubar[k + 1] - ubar[k]) * s / samples_per_interval).point);
    v.push_back(evaluate(curve, ubar.back()).point);
    std::vector<double> arc(v.size(), 0.0);
    for (size_t k = 1; k < v.size(); ++k) arc[k] = arc[k - 1] + norm(v[k] - v[k - 1]);
    out.vertices.push_back(std::move(v));
    out.arc.push_back(std::move(arc));
  }
  return out;
}

YarnClearance yarn_clearance(const KnitModel& m, const YarnPolylines& lines,
                             double search_radius_over_r) {
  const double r = m.params.loop_radius;
  YarnClearance best;
  best.over_r = search_radius_over_r;
  for (const std::vector<Vec3>& v : lines.vertices)
    if (!std::all_of(v.begin(), v.end(), is_finite)) {
      best.over_r = std::nan("");
      return best;
    }
  const std::vector<FlatSegment> segs = flatten(lines);
  double d_best = search_radius_over_r * r;
  for_each_near_pair(lines, segs, search_radius_over_r * r, kSameYarnGap * r,
                     [&](const FlatSegment& a, const FlatSegment& b) {
                       // Lower bound: midpoint distance less the half lengths.
                       const double bound = norm(0.5 * (a.p0 + a.p1 - b.p0 - b.p1)) -
                                            0.5 * (norm(a.p1 - a.p0) + norm(b.p1 - b.p0));
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

ClearanceOverRun::ClearanceOverRun(const KnitModel& m, RunObserver* next, double resample_over_r,
                                   double resample_fraction)
    : m_(m),
      next_(next),
      resample_(resample_over_r * m.params.loop_radius),
      fraction_(resample_fraction) {}

void ClearanceOverRun::observe(double t, const double* x, bool force) {
  m_.network.all_positions(t, x, pos_);
  if (!force && !last_.empty()) {
    double moved = 0.0;
    for (size_t k = 0; k < pos_.size(); ++k) moved = std::max(moved, norm(pos_[k] - last_[k]));
    if (moved < std::max(resample_, fraction_ * last_clearance_)) return;
  }
  last_ = pos_;
  ++measured_;
  YarnClearance c;
  if (std::all_of(pos_.begin(), pos_.end(), is_finite))
    c = yarn_clearance(m_, yarn_polylines(m_, pos_));
  else
    c.over_r = std::nan("");
  last_clearance_ = std::isfinite(c.over_r) ? c.over_r * m_.params.loop_radius : 0.0;
  if (measured_ > 1 && std::isnan(min_.over_r)) return;  // a non-finite state stays the verdict
  if (measured_ == 1 || std::isnan(c.over_r) || c.over_r < min_.over_r) {
    min_ = c;
    t_min_ = t;
  }
}

void ClearanceOverRun::on_step(double t, double h, int order) {
  if (next_) next_->on_step(t, h, order);
}

void ClearanceOverRun::on_check(double t, const double* x, const double* v, double residual) {
  observe(t, x, false);
  if (next_) next_->on_check(t, x, v, residual);
}

}  // namespace knitsim
