#include "src/measure/knit_measures.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace knitsim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const Vec3 kNoPoint{kNaN, kNaN, kNaN};

[[noreturn]] void bad_cell(const char* what, int wale, int course, const std::string& why) {
  std::ostringstream os;
  os << what << ": cell (wale " << wale << ", course " << course << "): " << why;
  throw std::invalid_argument(os.str());
}

// The point at arc length s along a polyline (linear within a segment; s inside the arc).
Vec3 point_at(const std::vector<Vec3>& v, const std::vector<double>& arc, double s) {
  const size_t k = std::upper_bound(arc.begin(), arc.end(), s) - arc.begin();
  if (k == 0) return v.front();
  if (k >= arc.size()) return v.back();
  const double len = arc[k] - arc[k - 1];
  const double t = len > 0.0 ? (s - arc[k - 1]) / len : 0.0;
  return v[k - 1] + t * (v[k] - v[k - 1]);
}

// The polyline between arc lengths s0 <= s1: the cut ends and the vertices strictly between.
std::vector<Vec3> piece(const std::vector<Vec3>& v, const std::vector<double>& arc, double s0,
                        double s1) {
  std::vector<Vec3> out{point_at(v, arc, s0)};
  for (size_t k = std::upper_bound(arc.begin(), arc.end(), s0) - arc.begin();
       k < arc.size() && arc[k] < s1; ++k)
    out.push_back(v[k]);
  out.push_back(point_at(v, arc, s1));
  return out;
}

struct ArcShape {
  Vec3 centre = kNoPoint;
  double height = kNaN, width = kNaN;
};

// Centroid (arc-length weighted) and x, y extents of a piece of polyline.
ArcShape shape_of(const std::vector<Vec3>& p) {
  ArcShape s;
  double length = 0.0, x0 = p[0].x, x1 = p[0].x, y0 = p[0].y, y1 = p[0].y;
  Vec3 moment{0.0, 0.0, 0.0};
  for (size_t k = 1; k < p.size(); ++k) {
    const double l = norm(p[k] - p[k - 1]);
    length += l;
    moment = moment + (0.5 * l) * (p[k] + p[k - 1]);
    x0 = std::min(x0, p[k].x), x1 = std::max(x1, p[k].x);
    y0 = std::min(y0, p[k].y), y1 = std::max(y1, p[k].y);
  }
  s.centre = length > 0.0 ? (1.0 / length) * moment : p[0];
  s.height = y1 - y0;
  s.width = x1 - x0;
  return s;
}

double min_z(const std::vector<Vec3>& p) {
  double z = p[0].z;
  for (const Vec3& q : p) z = std::min(z, q.z);
  return z;
}

void check(const KnitYarns& y, const char* what) {
  const KnitChart& c = y.chart;
  if (y.lines.vertices.size() != static_cast<size_t>(c.courses) ||
      y.lines.arc.size() != static_cast<size_t>(c.courses) ||
      y.marks.size() != static_cast<size_t>(c.wales) * c.courses) {
    std::ostringstream os;
    os << what << ": " << y.lines.vertices.size() << " polylines, " << y.lines.arc.size()
       << " arcs and " << y.marks.size() << " marks for a chart of " << c.wales << " wales x "
       << c.courses << " courses";
    throw std::invalid_argument(os.str());
  }
  for (int j = 0; j < c.courses; ++j) {
    const std::vector<double>& arc = y.lines.arc[j];
    if (arc.size() != y.lines.vertices[j].size() || arc.size() < 2)
      bad_cell(what, 0, j, "a course's polyline needs >= 2 vertices, one arc length each");
    for (int i = 0; i < c.wales; ++i) {
      const StitchMarks& m = y.marks[j * c.wales + i];
      // Not written as a < b: NaN must fail too.
      auto ordered = [](double a, double b) { return a <= b; };
      const bool loop = c.at(i, j) != Stitch::Miss;
      if (!(ordered(arc.front(), m.begin) && ordered(m.begin, m.end) && ordered(m.end, arc.back())))
        bad_cell(what, i, j, "needs arc marks 0 <= begin <= end <= the course's length");
      if (loop && !(ordered(m.begin, m.loop_begin) && ordered(m.loop_begin, m.loop_end) &&
                    ordered(m.loop_end, m.end)))
        bad_cell(what, i, j, "a loop needs begin <= loop_begin <= loop_end <= end");
    }
  }
}

// Courses above cell (i, j) on its needle that tuck or miss before the next knit.
int held_over(const KnitChart& c, int i, int j) {
  if (c.at(i, j) == Stitch::Miss) return 0;
  int n = 0;
  for (int k = j + 1; k < c.courses && c.at(i, k) != Stitch::Knit; ++k) ++n;
  return n;
}

// One state's per-cell measures into the fields selected by `rest`.
void measure_state(const KnitYarns& y, bool rest, std::vector<StitchMeasure>& out) {
  const KnitChart& c = y.chart;
  const int W = c.wales;
  for (int j = 0; j < c.courses; ++j) {
    const std::vector<Vec3>& v = y.lines.vertices[j];
    const std::vector<double>& arc = y.lines.arc[j];
    for (int i = 0; i < W; ++i) {
      const StitchMarks& mk = y.marks[j * W + i];
      StitchMeasure& s = out[j * W + i];
      ArcShape shape;
      double float_length = kNaN, float_depth = kNaN;
      if (c.at(i, j) != Stitch::Miss) {
        shape = shape_of(piece(v, arc, mk.loop_begin, mk.loop_end));
      } else {
        int i0 = i, i1 = i;
        while (i0 > 0 && c.at(i0 - 1, j) == Stitch::Miss) --i0;
        while (i1 + 1 < W && c.at(i1 + 1, j) == Stitch::Miss) ++i1;
        float_length = y.marks[j * W + i1].end - y.marks[j * W + i0].begin;
        int left = i - 1, right = i + 1;
        while (left >= 0 && c.at(left, j) != Stitch::Knit) --left;
        while (right < W && c.at(right, j) != Stitch::Knit) ++right;
        if (left >= 0 && right < W) {
          const double zl = point_at(v, arc, y.marks[j * W + left].loop_end).z;
          const double zr = point_at(v, arc, y.marks[j * W + right].loop_begin).z;
          const double face = zl + (zr - zl) * double(i - left) / double(right - left);
          float_depth = face - min_z(piece(v, arc, mk.begin, mk.end));
        }
      }
      const double yarn = mk.end - mk.begin;
      (rest ? s.centre_rest : s.centre) = shape.centre;
      (rest ? s.loop_height_rest : s.loop_height) = shape.height;
      (rest ? s.loop_width_rest : s.loop_width) = shape.width;
      (rest ? s.yarn_length_rest : s.yarn_length) = yarn;
      (rest ? s.float_length_rest : s.float_length) = float_length;
      (rest ? s.float_depth_rest : s.float_depth) = float_depth;
    }
  }
}

// Pooled spacing (sum of distances / sum of index steps) between the first and last plain knit
// loops of each interior line (a course for wales, a wale for courses).
struct PooledSpacing {
  double now = 0.0, rest = 0.0;
  int steps = 0;
};

PooledSpacing pooled_spacing(const KnitChart& c, const std::vector<StitchMeasure>& s,
                             bool along_course) {
  PooledSpacing sp;
  const int W = c.wales, C = c.courses;
  auto plain = [&](int i, int j) {
    const StitchMeasure& m = s[j * W + i];
    return m.stitch == Stitch::Knit && m.held_over == 0;
  };
  const int lines = along_course ? C : W, cells = along_course ? W : C;
  for (int line = 2; line <= lines - 3; ++line) {
    int first = -1, last = -1;
    for (int k = 2; k <= cells - 3; ++k) {
      const int i = along_course ? k : line, j = along_course ? line : k;
      if (!plain(i, j)) continue;
      if (first < 0) first = k;
      last = k;
    }
    if (first < 0 || last == first) continue;
    auto at = [&](int k) -> const StitchMeasure& {
      return along_course ? s[line * W + k] : s[k * W + line];
    };
    sp.now += norm(at(last).centre - at(first).centre);
    sp.rest += norm(at(last).centre_rest - at(first).centre_rest);
    sp.steps += last - first;
  }
  return sp;
}

}  // namespace

std::vector<StitchPoints> knit_stitch_points(const KnitModel& m) {
  const KnitChart& c = m.chart;
  const std::vector<LoopTypeValues> tv = type_value_points(m, m.rest_positions());
  std::vector<StitchPoints> out(static_cast<size_t>(c.wales) * c.courses);
  // The layout of course_yarn_points: sinker 0, then per wale a loop's type-value points
  // without its sinkers (or a miss's float point) and the sinker on its right.
  for (int j = 0; j < c.courses; ++j) {
    int at = 0;
    for (int i = 0; i < c.wales; ++i) {
      StitchPoints& p = out[j * c.wales + i];
      const int l = m.loop(i, j);
      const int n = l >= 0 ? static_cast<int>(tv[l].k.size()) : 3;
      p.begin = at;
      p.end = at + n - 1;
      if (l >= 0 && m.loops[l].kind == Stitch::Knit) {
        p.loop_begin = at + 1;   // T1
        p.loop_end = p.end - 1;  // T7
      } else if (l >= 0) {
        p.loop_begin = p.begin, p.loop_end = p.end;
      }
      at = p.end;
    }
  }
  return out;
}

KnitYarns knit_yarns(const KnitChart& chart, YarnPolylines lines,
                     const std::vector<StitchPoints>& points) {
  if (points.size() != static_cast<size_t>(chart.wales) * chart.courses ||
      lines.arc.size() != static_cast<size_t>(chart.courses))
    throw std::invalid_argument("knit_yarns: stitch points or polylines do not fit the chart");
  const int S = lines.samples_per_interval;
  KnitYarns y;
  y.chart = chart;
  y.marks.resize(points.size());
  for (int j = 0; j < chart.courses; ++j)
    for (int i = 0; i < chart.wales; ++i) {
      const StitchPoints& p = points[j * chart.wales + i];
      const std::vector<double>& arc = lines.arc[j];
      auto mark = [&](int k) {
        if (k < 0) return kNaN;
        if (static_cast<size_t>(k) * S >= arc.size())
          bad_cell("knit_yarns", i, j, "a yarn point past the course's polyline");
        return arc[static_cast<size_t>(k) * S];
      };
      y.marks[j * chart.wales + i] = {mark(p.begin), mark(p.end), mark(p.loop_begin),
                                      mark(p.loop_end)};
    }
  y.lines = std::move(lines);
  return y;
}

KnitYarns knit_yarns(const KnitModel& m, const std::vector<Vec3>& positions,
                     int samples_per_interval) {
  return knit_yarns(m.chart, yarn_polylines(m, positions, samples_per_interval),
                    knit_stitch_points(m));
}

TextileMeasures textile_measures(const KnitYarns& now, const KnitYarns& rest) {
  check(now, "textile_measures (state)");
  check(rest, "textile_measures (rest)");
  const KnitChart& c = now.chart;
  if (rest.chart.wales != c.wales || rest.chart.courses != c.courses ||
      rest.chart.stitches != c.stitches)
    throw std::invalid_argument("textile_measures: the state and the rest have different charts");
  TextileMeasures out;
  out.stitches.resize(c.stitches.size());
  for (int j = 0; j < c.courses; ++j)
    for (int i = 0; i < c.wales; ++i) {
      StitchMeasure& s = out.stitches[j * c.wales + i];
      s.wale = i, s.course = j, s.stitch = c.at(i, j), s.held_over = held_over(c, i, j);
    }
  measure_state(now, false, out.stitches);
  measure_state(rest, true, out.stitches);

  FabricMeasure& f = out.fabric;
  const PooledSpacing wales = pooled_spacing(c, out.stitches, true);
  const PooledSpacing courses = pooled_spacing(c, out.stitches, false);
  f.wale_steps = wales.steps, f.course_steps = courses.steps;
  auto per_cm = [](double distance, int steps) {
    return steps > 0 ? 0.01 * steps / distance : kNaN;
  };
  f.wales_per_cm = per_cm(wales.now, wales.steps);
  f.wales_per_cm_rest = per_cm(wales.rest, wales.steps);
  f.courses_per_cm = per_cm(courses.now, courses.steps);
  f.courses_per_cm_rest = per_cm(courses.rest, courses.steps);
  f.width_change = wales.steps > 0 ? wales.now / wales.rest - 1.0 : kNaN;
  f.length_change = courses.steps > 0 ? courses.now / courses.rest - 1.0 : kNaN;
  double yarn = 0.0, yarn_rest = 0.0;
  for (int j = 2; j <= c.courses - 3; ++j)
    for (int i = 2; i <= c.wales - 3; ++i) {
      yarn += out.stitches[j * c.wales + i].yarn_length;
      yarn_rest += out.stitches[j * c.wales + i].yarn_length_rest;
      ++f.interior_cells;
    }
  f.stitch_length = f.interior_cells > 0 ? yarn / f.interior_cells : kNaN;
  f.stitch_length_rest = f.interior_cells > 0 ? yarn_rest / f.interior_cells : kNaN;
  return out;
}

TextileMeasures textile_measures(const KnitModel& m, const std::vector<Vec3>& positions) {
  return textile_measures(knit_yarns(m, positions), knit_yarns(m, m.rest_positions()));
}

}  // namespace knitsim
