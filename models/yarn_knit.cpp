#include "models/yarn_knit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <stdexcept>
#include <utility>

#include "src/core/invalid_field.hpp"

namespace knitsim {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

void check_whole(const char* key, double value, double lo, double hi) {
  if (!(std::isfinite(value) && value >= lo && value <= hi && value == std::floor(value))) {
    std::ostringstream range;
    range << "must be a whole number in [" << lo << ", " << hi << "]";
    bad_field(key, value, range.str());
  }
}

void check_length(const char* key, double value, const char* zero) {
  if (!(std::isfinite(value) && value >= 0.0 && value <= 0.1))
    bad_field(key, value, std::string("must be in [0, 0.1] m (0: ") + zero + ")");
}

// Where each chart cell's yarn points lie in its course's list of yarn points
// (course_yarn_points: sinker 0, then per wale a loop's type-value points without its sinkers,
// or a miss's float point, and the sinker on its right), and each loop's T1, T7, T3, T5.
struct CellPoints {
  int begin = -1, end = -1, loop_begin = -1, loop_end = -1;
};

int position_of(const LoopTypeValues& tv, int k) {
  for (std::size_t i = 0; i < tv.k.size(); ++i)
    if (tv.k[i] == k) return static_cast<int>(i);
  return -1;
}

// A half-ellipse from a to b (exclusive) bulging `bulge` along `out`, with edges about `edge`.
std::vector<Vec3> turn(const Vec3& a, const Vec3& b, const Vec3& out, double bulge, double edge) {
  const Vec3 c = 0.5 * (a + b), half = 0.5 * (b - a);
  const double semi = norm(half);
  const double arc = kPi * std::sqrt(0.5 * (semi * semi + bulge * bulge));
  const int n = std::max(2, static_cast<int>(std::ceil(arc / edge)));
  std::vector<Vec3> p;
  for (int k = 1; k < n; ++k) {
    const double th = kPi * k / n;
    p.push_back(c - std::cos(th) * half + std::sin(th) * bulge * out);
  }
  return p;
}

}  // namespace

const char* to_string(KnitModelKind kind) {
  return kind == KnitModelKind::Yarn ? "yarn" : "network";
}

void YarnKnitParams::validate() const {
  yarn.validate();
  check_length("knit.stitch_length", stitch_length, "the start's own length");
  check_length("knit.tuck_length", tuck_length, "the knit's ratio");
  check_length("knit.miss_length", miss_length, "the knit's ratio");
  check_whole("knit.yarn_vertices", vertices_per_loop, 4, 256);
  check_whole("knit.yarn_ramp", ramp_stages, 1, 100);
}

namespace {

// The yarn through the structure's rest centrelines at its current scale: fills start,
// course_vertices, marks, loop_points, start_length, target_length and pins of y.
void lay_yarn(YarnKnit& y, std::vector<std::array<double, 4>>& loop_points) {
  const KnitModel& m = y.structure;
  const KnitChart& c = m.chart;
  const double r = m.params.loop_radius;
  const int per_cell = static_cast<int>(y.params.vertices_per_loop);
  const std::vector<Vec3> rest = m.rest_positions();
  const std::vector<LoopTypeValues> tv = type_value_points(m, rest);
  const std::vector<std::vector<Vec3>> points = course_yarn_points(m, rest);

  y.start.clear();
  y.course_vertices.assign(c.courses, {});
  y.marks.assign(static_cast<std::size_t>(c.wales) * c.courses, {});
  loop_points.assign(m.loops.size(), {kNaN, kNaN, kNaN, kNaN});
  std::vector<std::vector<Vec3>> samples(c.courses);
  for (int j = 0; j < c.courses; ++j) {
    const NurbsCurve curve = interpolate_cubic(points[j], kYarnParametrization);
    const std::vector<double> ubar = interpolation_parameters(points[j], kYarnParametrization);
    const int edges = per_cell * c.wales;
    const CurveSamples cs = sample_curve(curve, edges + 1, Spacing::ArcLength);
    samples[j] = cs.points;
    // Fractional vertex index of yarn point k: between the samples bracketing its parameter,
    // linear in the parameter (the samples are uniform in arc length; the speed varies little
    // across one edge).
    std::vector<double> index(ubar.size(), 0.0);
    for (std::size_t k = 0; k < ubar.size(); ++k) {
      const double u = curve.u_min() + ubar[k] * (curve.u_max() - curve.u_min());
      const std::size_t hi = std::clamp<std::size_t>(
          std::upper_bound(cs.u.begin(), cs.u.end(), u) - cs.u.begin(), 1, cs.u.size() - 1);
      const double u0 = cs.u[hi - 1], u1 = cs.u[hi];
      index[k] = static_cast<double>(hi - 1) + (u1 > u0 ? (u - u0) / (u1 - u0) : 0.0);
    }
    auto at = [&](int k) { return k < 0 ? kNaN : index[k]; };
    int pos = 0;
    for (int i = 0; i < c.wales; ++i) {
      const int l = m.loop(i, j);
      CellPoints p;
      const int n = l >= 0 ? static_cast<int>(tv[l].k.size()) : 3;
      p.begin = pos, p.end = pos + n - 1;
      if (l >= 0 && m.loops[l].kind == Stitch::Knit)
        p.loop_begin = pos + 1, p.loop_end = p.end - 1;
      else if (l >= 0)
        p.loop_begin = p.begin, p.loop_end = p.end;
      y.marks[j * c.wales + i] = {at(p.begin), at(p.end), at(p.loop_begin), at(p.loop_end)};
      if (l >= 0) {
        const int t1 = position_of(tv[l], 1), t7 = position_of(tv[l], 7);
        const int t3 = position_of(tv[l], 3), t5 = position_of(tv[l], 5);
        loop_points[l] = {at(t1 < 0 ? -1 : pos + t1), at(t7 < 0 ? -1 : pos + t7),
                          at(t3 < 0 ? -1 : pos + t3), at(t5 < 0 ? -1 : pos + t5)};
      }
      pos = p.end;
    }
  }

  // One yarn: even courses left to right, odd ones back, joined by turns at the selvedges.
  double edge_sum = 0.0;
  long edge_count = 0;
  for (const auto& s : samples)
    for (std::size_t k = 1; k < s.size(); ++k) edge_sum += norm(s[k] - s[k - 1]), ++edge_count;
  const double edge = edge_sum / static_cast<double>(edge_count);
  std::vector<char> turn_edge;  // per edge: 1 in a selvedge turn
  for (int j = 0; j < c.courses; ++j) {
    const std::vector<Vec3>& s = samples[j];
    const int n = static_cast<int>(s.size());
    const bool forward = j % 2 == 0;
    const Vec3 first = forward ? s.front() : s.back();
    if (j > 0) {
      const Vec3 last = y.start.back();
      const Vec3 out{forward ? -1.0 : 1.0, 0.0, 0.0};  // the turn is on the side course j starts
      for (const Vec3& p : turn(last, first, out, 2.0 * r, edge)) {
        y.start.push_back(p);
        turn_edge.push_back(1);
      }
      turn_edge.push_back(1);  // the edge into the course's first vertex
    }
    std::vector<int>& idx = y.course_vertices[j];
    idx.assign(n, -1);
    for (int k = 0; k < n; ++k) {
      const int local = forward ? k : n - 1 - k;
      if (k > 0) turn_edge.push_back(0);
      idx[local] = static_cast<int>(y.start.size());
      y.start.push_back(s[local]);
    }
  }

  // Held: both ends of the yarn and the heads of the first and last courses' loops. Measured:
  // with only the last course held, a frictionless yarn unravels from the bottom (bending
  // straightens the first courses: their loops shrink and slip, the yarn kept at its length).
  const int ne = static_cast<int>(y.start.size()) - 1;
  y.held_groups = {{0}, {ne}};
  for (int held : {0, c.courses - 1}) {
    for (int i = 0; i < c.wales; ++i) {
      const int l = m.loop(i, held);
      if (l < 0) continue;
      // The head arc T3..T5, as a needle through the loop holds it (one vertex at T4 let the
      // loop it holds slip over it).
      const double a = loop_points[l][2], b = loop_points[l][3];
      if (!std::isfinite(a) || !std::isfinite(b)) continue;
      std::vector<int> group;
      for (long k = std::lround(std::min(a, b)); k <= std::lround(std::max(a, b)); ++k) {
        const int v = y.course_vertices[held][static_cast<int>(k)];
        bool seen = false;
        for (const auto& g : y.held_groups) seen = seen || std::find(g.begin(), g.end(), v) != g.end();
        if (!seen) group.push_back(v);
      }
      if (!group.empty()) y.held_groups.push_back(std::move(group));
    }
  }
  y.pins.clear();
  std::vector<int> group_of(y.start.size(), -1);
  for (std::size_t g = 0; g < y.held_groups.size(); ++g)
    for (int v : y.held_groups[g]) {
      y.pins.push_back(v);
      group_of[v] = static_cast<int>(g);
    }
  std::sort(y.pins.begin(), y.pins.end());
  y.centre = Vec3{0.0, 0.0, 0.0};
  for (const Vec3& p : y.start) y.centre = y.centre + p;
  y.centre = (1.0 / static_cast<double>(y.start.size())) * y.centre;

  // Rest lengths: the start's, and the knitted lengths per cell (by the stitch's type). A held
  // group's edges keep their start length (the needle holds the loop at its size); the cell's
  // other edges take up the difference, so every cell of a type knits the same yarn.
  y.start_length.resize(ne);
  for (int e = 0; e < ne; ++e) y.start_length[e] = norm(y.start[e + 1] - y.start[e]);
  auto held_edge = [&](int e) { return group_of[e] >= 0 && group_of[e] == group_of[e + 1]; };
  std::vector<char> cell_kind(ne, 'K');  // per edge, the stitch of the cell it lies in
  std::vector<int> cell_of(ne, -1);      // per edge, its cell (course * wales + wale), -1: a turn
  std::vector<double> cell_start(y.marks.size(), 0.0), cell_held(y.marks.size(), 0.0);
  double sum[3] = {0, 0, 0};
  int count[3] = {0, 0, 0};
  auto slot = [](Stitch s) { return s == Stitch::Knit ? 0 : s == Stitch::Tuck ? 1 : 2; };
  for (int j = 0; j < c.courses; ++j) {
    const std::vector<int>& idx = y.course_vertices[j];
    for (int i = 0; i < c.wales; ++i) {
      const int cell = j * c.wales + i;
      const YarnCellMarks& mk = y.marks[cell];
      for (int k = 0; k + 1 < static_cast<int>(idx.size()); ++k) {
        const double mid = k + 0.5;
        if (mid < mk.begin || mid >= mk.end) continue;
        const int e = std::min(idx[k], idx[k + 1]);
        cell_kind[e] = static_cast<char>(c.at(i, j));
        cell_of[e] = cell;
        cell_start[cell] += y.start_length[e];
        if (held_edge(e)) cell_held[cell] += y.start_length[e];
      }
      sum[slot(c.at(i, j))] += cell_start[cell];
      ++count[slot(c.at(i, j))];
    }
  }
  const double wanted[3] = {y.params.stitch_length, y.params.tuck_length, y.params.miss_length};
  double ratio[3] = {1.0, 1.0, 1.0};
  if (wanted[0] > 0.0 && count[0] > 0) ratio[0] = wanted[0] / (sum[0] / count[0]);
  for (int t = 1; t < 3; ++t)
    ratio[t] = wanted[t] > 0.0 && count[t] > 0 ? wanted[t] / (sum[t] / count[t]) : ratio[0];
  y.knit_ratio = ratio[0];
  y.target_length.resize(ne);
  for (int e = 0; e < ne; ++e) {
    const int t = cell_of[e] < 0 ? 0 : slot(static_cast<Stitch>(cell_kind[e]));
    double q = ratio[t];
    if (held_edge(e)) {
      q = 1.0;
    } else if (q != 1.0 && cell_of[e] >= 0 && cell_held[cell_of[e]] > 0.0) {
      const double s = cell_start[cell_of[e]], h = cell_held[cell_of[e]];
      q = std::max(0.1, (ratio[t] * s - h) / (s - h));
    }
    y.target_length[e] = y.start_length[e] * q;
  }
}

}  // namespace

YarnRodsSpec YarnKnit::spec_at(double f, const std::vector<Vec3>& initial) const {
  YarnRodsSpec out;
  out.yarn = params.yarn;
  // The rest lengths as a straight polyline (only its lengths matter: the yarn is straight at
  // rest, kappa0 = 0).
  std::vector<Vec3> straight{Vec3{0.0, 0.0, 0.0}};
  double x = 0.0;
  for (std::size_t e = 0; e < start_length.size(); ++e) {
    x += start_length[e] + f * (target_length[e] - start_length[e]);
    straight.push_back({x, 0.0, 0.0});
  }
  out.rest = {std::move(straight)};
  out.initial = {initial.empty() ? start : initial};
  for (int p : pins) out.pins.push_back({0, p});
  // F_ref: the bending force of a loop, B / l^2 with l the knitted stitch length.
  double l = 0.0;
  for (double t : target_length) l += t;
  l /= std::max<std::size_t>(1, marks.size());
  out.residual_force_scale = params.yarn.bending_rigidity / (l * l);
  out.contact = true;
  // The Jacobian pattern's radius (kYarnPatternRadius): the run makes the rods afresh every few
  // steps (src/scene/yarn_knit_run.cpp), so the pattern follows the yarn.
  out.yarn.pattern_radius = std::max(out.yarn.pattern_radius, kYarnPatternRadius);
  return out;
}

std::vector<Vec3> YarnKnit::carried(const std::vector<Vec3>& pos, double from,
                                    double to) const {
  const double s = to / from;
  std::vector<Vec3> out(pos.size());
  for (std::size_t v = 0; v < pos.size(); ++v) out[v] = centre + s * (pos[v] - centre);
  for (const std::vector<int>& g : held_groups) {
    Vec3 c0{0.0, 0.0, 0.0}, c{0.0, 0.0, 0.0};
    for (int v : g) c0 = c0 + start[v], c = c + pos[v];
    c0 = (1.0 / g.size()) * c0, c = (1.0 / g.size()) * c;
    const Vec3 shift = (centre + to * (c0 - centre)) - c;
    for (int v : g) out[v] = pos[v] + shift;
  }
  return out;
}

std::vector<std::vector<Vec3>> YarnKnit::course_polylines(const std::vector<Vec3>& all) const {
  std::vector<std::vector<Vec3>> out(course_vertices.size());
  for (std::size_t j = 0; j < course_vertices.size(); ++j)
    for (int v : course_vertices[j]) out[j].push_back(all[v]);
  return out;
}

double YarnKnit::course_length(int course, const std::vector<Vec3>& all) const {
  const std::vector<int>& idx = course_vertices[course];
  double len = 0.0;
  for (std::size_t k = 1; k < idx.size(); ++k) len += norm(all[idx[k]] - all[idx[k - 1]]);
  return len;
}

std::vector<Vec3> YarnKnit::interlacing_points(const std::vector<Vec3>& all) const {
  const KnitModel& m = structure;
  auto material = [&](int j, double q) {
    const std::vector<int>& idx = course_vertices[j];
    const int last = static_cast<int>(idx.size()) - 1;
    const int k = std::clamp(static_cast<int>(std::floor(q)), 0, last - 1);
    const double s = q - k;
    return (1.0 - s) * all[idx[k]] + s * all[idx[k + 1]];
  };
  std::vector<Vec3> sum(m.points.size(), Vec3{0.0, 0.0, 0.0});
  std::vector<int> n(m.points.size(), 0);
  for (std::size_t l = 0; l < m.loops.size(); ++l) {
    const KnitLoop& loop = m.loops[l];
    const std::array<double, 4>& q = loop_points[l];
    if (loop.lower >= 0 && std::isfinite(q[0]) && std::isfinite(q[1])) {
      sum[loop.lower] =
          sum[loop.lower] + 0.5 * (material(loop.course, q[0]) + material(loop.course, q[1]));
      ++n[loop.lower];
    }
    if (loop.upper >= 0 && std::isfinite(q[2]) && std::isfinite(q[3])) {
      sum[loop.upper] =
          sum[loop.upper] + 0.5 * (material(loop.course, q[2]) + material(loop.course, q[3]));
      ++n[loop.upper];
    }
  }
  std::vector<Vec3> out(m.points.size());
  Vec3 shift{0.0, 0.0, 0.0};
  int found = 0;
  for (std::size_t p = 0; p < out.size(); ++p)
    if (n[p] > 0) {
      out[p] = (1.0 / n[p]) * sum[p];
      shift = shift + (out[p] - m.points[p].rest);
      ++found;
    }
  if (found > 0) shift = (1.0 / found) * shift;
  for (std::size_t p = 0; p < out.size(); ++p)
    if (n[p] == 0) out[p] = m.points[p].rest + shift;
  return out;
}

YarnKnit build_yarn_knit(const KnitChart& chart, const KnitParams& structure_params,
                         const YarnKnitParams& params) {
  params.validate();
  const double d = params.yarn.diameter();
  KnitParams kp = structure_params;
  kp.contact_ratio = 0.0;  // the structure's own contact points are not used
  kp.bending_ratio = 0.0;
  kp.pins = KnitPins::None;
  kp.gravity = false;
  // Scale until the closest pair the contact sees is between kYarnStartClearance d and
  // kYarnStartClearanceMax d; the clearance scales with r but for the same-yarn window (2 d of
  // arc), so a few passes.
  double r = d;
  double clearance = 0.0;
  std::optional<YarnKnit> made;
  for (int pass = 0; pass < 12; ++pass) {
    kp.loop_radius = r;
    made.emplace(build_knit(chart, kp));
    YarnKnit& y = *made;
    y.params = params;
    y.d = d;
    lay_yarn(y, y.loop_points);
    YarnRodsSpec s = y.spec(0, 1);
    s.contact = false;
    const YarnRods rods(s);
    std::vector<double> x(rods.dof()), v(rods.dof());
    rods.initial_state(x.data(), v.data());
    clearance = rods.min_clearance(x.data());
    if (clearance >= kYarnStartClearance * d && clearance <= kYarnStartClearanceMax * d) break;
    r *= std::isfinite(clearance)
             ? 0.5 * (kYarnStartClearance + kYarnStartClearanceMax) * d / clearance
             : 0.8;
  }
  if (!(clearance >= d))
    throw std::invalid_argument(
        "knit.model = yarn: the chart's start could not be made intersection-free at the yarn "
        "diameter (closest pair " +
        std::to_string(clearance / d) + " d)");
  YarnKnit y = std::move(*made);
  y.r = r;
  y.start_clearance = clearance;
  return y;
}

}  // namespace knitsim
