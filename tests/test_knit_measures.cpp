// Textile measures (src/measure/knit_measures.hpp; docs/knit.md, "Textile measures"): plain
// jersey at rest against the closed forms of its geometry and against the centreline's length
// computed independently (Gauss-Legendre on the NURBS), the edge exclusion rule, the rows of a
// tuck and a miss chart, the network's marks landing on its type-value points, measures that
// follow the centrelines, not the interlacing points, and `knitsim knit`'s stitches.csv and
// summary.json `fabric` block.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "models/knit_loops.hpp"
#include "solvers/integrator.hpp"
#include "src/geometry/nurbs.hpp"
#include "src/measure/knit_measures.hpp"
#include "tests/cli_runner.hpp"
#include "tests/test_files.hpp"

using namespace knitsim;
using knitsim::test::chart_file;

namespace {

KnitModel chart_model(const std::string& file, KnitParams p = KnitParams{}) {
  return build_knit(parse_knit_chart(chart_file(file)), p);
}

KnitModel plain_model(int wales, int courses) {
  std::string text;
  for (int j = 0; j < courses; ++j) text += std::string(wales, 'K') + "\n";
  return build_knit(parse_knit_chart(text), KnitParams{});
}

TextileMeasures at_rest(const KnitModel& m) {
  const KnitYarns rest = knit_yarns(m, m.rest_positions());
  return textile_measures(rest, rest);
}

bool same(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

const StitchMeasure& cell(const TextileMeasures& t, const KnitModel& m, int wale, int course) {
  return t.stitches[course * m.chart.wales + wale];
}

// The length of course j's centreline between yarn points k0 and k1, by the curve's own
// arc-length quadrature (not the measuring polyline).
double curve_length(const KnitModel& m, const std::vector<Vec3>& pos, int j, int k0, int k1) {
  const std::vector<Vec3> yarn = course_yarn_points(m, pos)[j];
  const NurbsCurve c = interpolate_cubic(yarn, kYarnParametrization);
  const std::vector<double> u = interpolation_parameters(yarn, kYarnParametrization);
  return arc_length(c, u[k0], u[k1]);
}

// x and y extents of course j's centreline between yarn points k0 and k1, densely sampled.
std::pair<double, double> curve_extents(const KnitModel& m, const std::vector<Vec3>& pos, int j,
                                        int k0, int k1) {
  const std::vector<Vec3> yarn = course_yarn_points(m, pos)[j];
  const NurbsCurve c = interpolate_cubic(yarn, kYarnParametrization);
  const std::vector<double> u = interpolation_parameters(yarn, kYarnParametrization);
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (int s = 0; s <= 20000; ++s) {
    const Vec3 p = evaluate(c, u[k0] + (u[k1] - u[k0]) * s / 20000.0).point;
    x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
  }
  return {x1 - x0, y1 - y0};
}

// Polylines through given yarn points, sampled as yarn_polylines samples them (uniform in the
// curve parameter, S per interval): the test's own, to feed the measures yarns that no network
// state has.
YarnPolylines polylines_through(const std::vector<std::vector<Vec3>>& yarns, int S) {
  YarnPolylines out;
  out.samples_per_interval = S;
  for (const std::vector<Vec3>& yarn : yarns) {
    const NurbsCurve c = interpolate_cubic(yarn, kYarnParametrization);
    const std::vector<double> u = interpolation_parameters(yarn, kYarnParametrization);
    std::vector<Vec3> v;
    for (size_t k = 0; k + 1 < yarn.size(); ++k)
      for (int s = 0; s < S; ++s) v.push_back(evaluate(c, u[k] + (u[k + 1] - u[k]) * s / S).point);
    v.push_back(evaluate(c, u.back()).point);
    std::vector<double> arc(v.size(), 0.0);
    for (size_t k = 1; k < v.size(); ++k) arc[k] = arc[k - 1] + norm(v[k] - v[k - 1]);
    out.vertices.push_back(v);
    out.arc.push_back(arc);
  }
  return out;
}

}  // namespace

TEST_CASE("plain jersey at rest: the measures are the closed forms of the rest geometry",
          "[knit_measures]") {
  const KnitModel m = chart_model("plain_jersey.chart");  // 8 wales x 6 courses
  const double r = m.params.loop_radius, w = 8.0 * r, h = 7.0 * r;
  const std::vector<Vec3> rest = m.rest_positions();
  const TextileMeasures t = at_rest(m);
  const FabricMeasure& f = t.fabric;
  // Wale spacing w = 8r, course spacing h = 7r: wales/cm = 1 / (100 w), courses/cm = 1 / (100 h).
  CHECK(f.wales_per_cm_rest == Approx(0.01 / w).epsilon(1e-9));
  CHECK(f.courses_per_cm_rest == Approx(0.01 / h).epsilon(1e-12));
  CHECK(f.wales_per_cm == f.wales_per_cm_rest);
  CHECK(f.courses_per_cm == f.courses_per_cm_rest);
  CHECK(f.width_change == 0.0);
  CHECK(f.length_change == 0.0);
  CHECK(f.interior_cells == 4 * 2);  // wales 2..5, courses 2..3
  // Stitch length: the centreline from sinker to sinker, T0 to T8 (yarn points 8i, 8i + 8 of a
  // plain course), by the curve's own quadrature; the measure's polyline (32 samples per
  // interval) is within its chord deficit, ~5e-5.
  double interior = 0.0;
  for (int j = 2; j <= 3; ++j)
    for (int i = 2; i <= 5; ++i) {
      const double l = curve_length(m, rest, j, 8 * i, 8 * i + 8);
      interior += l / 8.0;
      CHECK(cell(t, m, i, j).yarn_length_rest == Approx(l).epsilon(1e-4));
      CHECK(cell(t, m, i, j).yarn_length_rest < l);  // a chord never exceeds its arc
    }
  CHECK(f.stitch_length_rest == Approx(interior).epsilon(1e-4));
  CHECK(f.stitch_length == f.stitch_length_rest);
  WARN("plain jersey at rest: wales/cm "
       << f.wales_per_cm_rest << " (1/(100 w) = " << 0.01 / w << "), courses/cm "
       << f.courses_per_cm_rest << " (" << 0.01 / h << "), stitch length "
       << f.stitch_length_rest / r << " r (curve " << interior / r << " r)");
  for (int j = 0; j < m.chart.courses; ++j)
    for (int i = 0; i < m.chart.wales; ++i) {
      const StitchMeasure& s = cell(t, m, i, j);
      CAPTURE(i, j);
      CHECK(s.stitch == Stitch::Knit);
      CHECK(s.held_over == 0);
      CHECK(same(s.centre, s.centre_rest));
      // The loop, foot to foot (T1 to T7, yarn points 8i + 1, 8i + 7): its extents.
      const auto [width, height] = curve_extents(m, rest, j, 8 * i + 1, 8 * i + 7);
      CHECK(s.loop_height_rest == Approx(height).margin(2e-3 * r));
      CHECK(s.loop_width_rest == Approx(width).margin(2e-3 * r));
      // Feet at the course's base, the head r above the upper point: 8r.
      CHECK(s.loop_height_rest == Approx(8.0 * r).margin(0.01 * r));
      // Neighbouring centres w apart along a course, h apart along a wale (away from the
      // yarn's ends, where the cubic's end conditions shift the edge loops).
      if (i >= 3 && i <= m.chart.wales - 3)
        CHECK(s.centre_rest.x - cell(t, m, i - 1, j).centre_rest.x == Approx(w).epsilon(1e-8));
      if (j >= 1) {
        CHECK(s.centre_rest.y - cell(t, m, i, j - 1).centre_rest.y == Approx(h).epsilon(1e-12));
        CHECK(s.centre_rest.x == Approx(cell(t, m, i, j - 1).centre_rest.x).margin(1e-9 * r));
      }
      CHECK(std::isnan(s.float_length_rest));
      CHECK(std::isnan(s.float_depth_rest));
    }
  WARN("plain loop at rest: height " << cell(t, m, 3, 2).loop_height_rest / r << " r, width "
                                     << cell(t, m, 3, 2).loop_width_rest / r << " r, centre "
                                     << (cell(t, m, 3, 2).centre_rest.y - 2 * h) / r
                                     << " r above its course's base");
}

TEST_CASE("the network's marks land on its type-value points", "[knit_measures]") {
  for (const char* name :
       {"plain_jersey.chart", "single_tuck.chart", "several_tucks.chart", "several_misses.chart"}) {
    CAPTURE(name);
    const KnitModel m = chart_model(name);
    const std::vector<Vec3> rest = m.rest_positions();
    const std::vector<StitchPoints> sp = knit_stitch_points(m);
    const std::vector<std::vector<Vec3>> yarns = course_yarn_points(m, rest);
    const std::vector<LoopTypeValues> tv = type_value_points(m, rest);
    for (size_t l = 0; l < m.loops.size(); ++l) {
      const KnitLoop& loop = m.loops[l];
      const StitchPoints& p = sp[loop.course * m.chart.wales + loop.wale];
      const std::vector<Vec3>& yarn = yarns[loop.course];
      CHECK(same(yarn[p.begin], tv[l].t.front()));  // T0
      CHECK(same(yarn[p.end], tv[l].t.back()));     // T8
      if (loop.kind == Stitch::Knit) {
        CHECK(tv[l].k[1] == 1);
        CHECK(same(yarn[p.loop_begin], tv[l].t[1]));                 // T1
        CHECK(same(yarn[p.loop_end], tv[l].t[tv[l].t.size() - 2]));  // T7
      }
    }
    // And the polylines pass through the yarn points at vertex k S.
    const KnitYarns y = knit_yarns(m, rest);
    for (int j = 0; j < m.chart.courses; ++j) {
      const StitchPoints& last = sp[j * m.chart.wales + m.chart.wales - 1];
      CHECK(static_cast<size_t>(last.end) + 1 == yarns[j].size());
      CHECK(y.marks[j * m.chart.wales + m.chart.wales - 1].end == y.lines.arc[j].back());
      CHECK(norm(y.lines.vertices[j][last.end * kStitchSamplesPerInterval] - yarns[j].back()) <
            1e-12 * m.params.loop_radius);
    }
  }
}

TEST_CASE("courses and wales per cm count only loops two or more from every edge",
          "[knit_measures]") {
  const KnitModel m = plain_model(10, 9);
  const double r = m.params.loop_radius;
  const KnitYarns rest = knit_yarns(m, m.rest_positions());
  // The edge loops differ at rest (the cubic's end conditions at the yarn's ends): the rule is
  // what makes the closed form exact.
  const TextileMeasures t = textile_measures(rest, rest);
  CHECK(std::abs(cell(t, m, 0, 4).yarn_length_rest / cell(t, m, 4, 4).yarn_length_rest - 1.0) >
        1e-3);
  WARN("plain 10 x 9 at rest: edge stitch / interior stitch - 1 = "
       << cell(t, m, 0, 4).yarn_length_rest / cell(t, m, 4, 4).yarn_length_rest - 1.0
       << ", wale 2 / wale 5 - 1 = "
       << cell(t, m, 2, 4).yarn_length_rest / cell(t, m, 5, 4).yarn_length_rest - 1.0);
  CHECK(cell(t, m, 2, 4).yarn_length_rest ==
        Approx(cell(t, m, 5, 4).yarn_length_rest).epsilon(1e-9));
  // Move every vertex of one cell's yarn (a whole wale, or a whole course) and see which moves
  // change the fabric's counts: a wale or course one from the edge must not, two from it must.
  auto moved = [&](int wale, int course, Vec3 by) {
    KnitYarns y = rest;
    for (int j = 0; j < m.chart.courses; ++j) {
      if (course >= 0 && j != course) continue;
      for (int i = 0; i < m.chart.wales; ++i) {
        if (wale >= 0 && i != wale) continue;
        const StitchMarks& mk = y.marks[j * m.chart.wales + i];
        for (size_t k = 0; k < y.lines.vertices[j].size(); ++k)
          if (y.lines.arc[j][k] >= mk.begin && y.lines.arc[j][k] <= mk.end)
            y.lines.vertices[j][k] = y.lines.vertices[j][k] + by;
      }
    }
    return textile_measures(y, rest).fabric;
  };
  const Vec3 dx{r, 0.0, 0.0}, dy{0.0, r, 0.0};
  for (int wale : {1, m.chart.wales - 2}) {
    CAPTURE(wale);
    CHECK(moved(wale, -1, dx).wales_per_cm == t.fabric.wales_per_cm);
    CHECK(moved(wale, -1, dx).width_change == 0.0);
  }
  for (int wale : {2, m.chart.wales - 3}) {
    CAPTURE(wale);
    CHECK(moved(wale, -1, dx).wales_per_cm != Approx(t.fabric.wales_per_cm).epsilon(1e-3));
    CHECK(std::abs(moved(wale, -1, dx).width_change) > 1e-3);
  }
  for (int course : {1, m.chart.courses - 2}) {
    CAPTURE(course);
    CHECK(moved(-1, course, dy).courses_per_cm == t.fabric.courses_per_cm);
    CHECK(moved(-1, course, dy).length_change == 0.0);
  }
  for (int course : {2, m.chart.courses - 3}) {
    CAPTURE(course);
    CHECK(moved(-1, course, dy).courses_per_cm != Approx(t.fabric.courses_per_cm).epsilon(1e-3));
    CHECK(std::abs(moved(-1, course, dy).length_change) > 1e-3);
  }

  // Charts too small: 6 x 6 has two interior wales and courses (2 and 3); 5 x 5 one (no
  // spacing, NaN) but one interior cell (a stitch length); 4 x 4 none.
  const TextileMeasures six = at_rest(plain_model(6, 6));
  CHECK(six.fabric.wales_per_cm_rest == Approx(0.01 / (8.0 * r)).epsilon(1e-6));
  CHECK(six.fabric.courses_per_cm_rest == Approx(0.01 / (7.0 * r)).epsilon(1e-12));
  const TextileMeasures five = at_rest(plain_model(5, 7));
  CHECK(std::isnan(five.fabric.wales_per_cm));
  CHECK(std::isnan(five.fabric.wales_per_cm_rest));
  CHECK(std::isnan(five.fabric.width_change));
  CHECK(five.fabric.courses_per_cm_rest == Approx(0.01 / (7.0 * r)).epsilon(1e-12));
  CHECK(five.fabric.interior_cells == 3);
  CHECK(std::isfinite(five.fabric.stitch_length));
  const TextileMeasures four = at_rest(plain_model(4, 4));
  CHECK(four.fabric.interior_cells == 0);
  CHECK(std::isnan(four.fabric.stitch_length));
  CHECK(std::isnan(four.fabric.courses_per_cm));
}

TEST_CASE("a tuck chart's rows: the tuck loop and the loop it holds", "[knit_measures]") {
  const KnitModel m = chart_model("single_tuck.chart");  // the tuck at wale 3, course 2
  const double r = m.params.loop_radius, h = 7.0 * r;
  const std::vector<Vec3> rest = m.rest_positions();
  const TextileMeasures t = at_rest(m);
  const StitchMeasure& tuck = cell(t, m, 3, 2);
  const StitchMeasure& held = cell(t, m, 3, 1);
  CHECK(tuck.stitch == Stitch::Tuck);
  CHECK(tuck.held_over == 0);
  CHECK(held.stitch == Stitch::Knit);
  CHECK(held.held_over == 1);
  // The tuck's loop is its cell, sinker to sinker: yarn points 24 to 30 of course 2 (three
  // plain knits of 8 intervals, then the tuck's T0 T2 T3 T4 T5 T6 T8).
  const double tuck_length = curve_length(m, rest, 2, 24, 30);
  CHECK(tuck.yarn_length_rest == Approx(tuck_length).epsilon(1e-4));
  // The held loop: 2 points per leg, 8 + 2 intervals, yarn points 24 to 34 of course 1.
  const double held_length = curve_length(m, rest, 1, 24, 34);
  CHECK(held.yarn_length_rest == Approx(held_length).epsilon(1e-4));
  const double plain = cell(t, m, 5, 1).yarn_length_rest;
  CHECK(held.yarn_length_rest > plain + h);  // held over one more course
  // Heights: the held loop from its feet (course 1's base) to its head, r above level 3: 2h + r;
  // the tuck's open arc from its sinkers (r below course 2's base) to its head (r above level 3,
  // 3r further back): h + 2r.
  CHECK(held.loop_height_rest == Approx(2.0 * h + r).margin(0.05 * r));
  CHECK(tuck.loop_height_rest == Approx(h + 2.0 * r).margin(0.1 * r));
  CHECK(std::isnan(tuck.float_length_rest));
  WARN("single_tuck at rest: tuck loop length "
       << tuck.yarn_length_rest / r << " r (curve " << tuck_length / r << " r), height "
       << tuck.loop_height_rest / r << " r; held loop " << held.yarn_length_rest / r
       << " r, height " << held.loop_height_rest / r << " r; plain stitch " << plain / r << " r");

  // At a relaxed state (the stabilised network without contact, cvode-bdf): the measures read
  // that state's centrelines; the held loop pulls the tuck's head down, the tuck loop shortens.
  KnitParams p;
  p.contact_ratio = 0.0;
  const KnitModel n = chart_model("single_tuck.chart", p);
  std::vector<double> x, v;
  IntegratorOptions opt;
  const RunStats s = run_to_equilibrium(n.network, "cvode-bdf", opt, x, v);
  REQUIRE(s.status == RunStatus::Equilibrium);
  std::vector<Vec3> end;
  n.network.all_positions(s.t_final, x.data(), end);
  const TextileMeasures e = textile_measures(knit_yarns(n, end), knit_yarns(n, n.rest_positions()));
  const StitchMeasure& tuck_end = cell(e, n, 3, 2);
  const StitchMeasure& held_end = cell(e, n, 3, 1);
  CHECK(tuck_end.yarn_length == Approx(curve_length(n, end, 2, 24, 30)).epsilon(1e-4));
  CHECK(held_end.yarn_length == Approx(curve_length(n, end, 1, 24, 34)).epsilon(1e-4));
  CHECK(tuck_end.loop_height < tuck_end.loop_height_rest - r);
  CHECK(held_end.loop_height < held_end.loop_height_rest - 3.0 * r);
  CHECK(tuck_end.yarn_length_rest == tuck.yarn_length_rest);
  CHECK(std::isfinite(e.fabric.wales_per_cm));
  WARN("single_tuck relaxed (no contact): tuck loop "
       << tuck_end.yarn_length / r << " r, height " << tuck_end.loop_height / r
       << " r; held loop height " << held_end.loop_height / r << " r; wales/cm "
       << e.fabric.wales_per_cm << " (rest " << e.fabric.wales_per_cm_rest << "), courses/cm "
       << e.fabric.courses_per_cm << " (rest " << e.fabric.courses_per_cm_rest << ")");
}

TEST_CASE("a miss chart's rows: floats, their lengths and depths", "[knit_measures]") {
  // several_misses: single floats at (2,1), (8,4), (8,5), (2,5); a float over two wales at
  // (5,3)-(6,3); wale 8 misses at courses 4 and 5, so the loop (8,3) is held over two courses.
  const KnitModel m = chart_model("several_misses.chart");
  const double r = m.params.loop_radius, w = 8.0 * r, h = 7.0 * r;
  const TextileMeasures t = at_rest(m);
  for (auto [i, j] : {std::pair{2, 1}, {5, 3}, {6, 3}, {8, 4}, {8, 5}, {2, 5}}) {
    CAPTURE(i, j);
    const StitchMeasure& s = cell(t, m, i, j);
    CHECK(s.stitch == Stitch::Miss);
    CHECK(s.held_over == 0);
    // No loop: centre and loop extents NaN; its yarn (the float's piece under this wale) is.
    CHECK(std::isnan(s.centre_rest.x));
    CHECK(std::isnan(s.loop_height_rest));
    CHECK(std::isnan(s.loop_width_rest));
    CHECK(s.yarn_length_rest == Approx(w).epsilon(0.05));
    // The float r behind the feet of the loops either side.
    CHECK(s.float_depth_rest == Approx(r).epsilon(0.1));
  }
  // Float lengths ~ the wales they span.
  CHECK(cell(t, m, 2, 1).float_length_rest == Approx(w).epsilon(0.05));
  CHECK(cell(t, m, 5, 3).float_length_rest == Approx(2.0 * w).epsilon(0.05));
  CHECK(cell(t, m, 6, 3).float_length_rest == cell(t, m, 5, 3).float_length_rest);
  CHECK(cell(t, m, 5, 3).float_length_rest ==
        Approx(cell(t, m, 5, 3).yarn_length_rest + cell(t, m, 6, 3).yarn_length_rest));
  // The loop under the two misses of wale 8.
  const StitchMeasure& held = cell(t, m, 8, 3);
  CHECK(held.held_over == 2);
  CHECK(held.loop_height_rest == Approx(3.0 * h + r).margin(0.05 * r));
  CHECK(cell(t, m, 2, 0).held_over == 1);
  WARN("several_misses at rest: float (2,1) "
       << cell(t, m, 2, 1).float_length_rest / r << " r, depth "
       << cell(t, m, 2, 1).float_depth_rest / r << " r; float (5..6,3) "
       << cell(t, m, 5, 3).float_length_rest / r << " r; loop (8,3) held over 2: height "
       << held.loop_height_rest / r << " r, length " << held.yarn_length_rest / r << " r");
}

TEST_CASE("the measures follow the centrelines, not the interlacing points", "[knit_measures]") {
  // Move one type-value point, the head T4 of loop (4, 3) of plain jersey, up by r in the yarn
  // points only: the network's points do not move, so a measure read off them would not change.
  const KnitModel m = chart_model("plain_jersey.chart");
  const double r = m.params.loop_radius;
  const std::vector<Vec3> rest = m.rest_positions();
  const std::vector<StitchPoints> sp = knit_stitch_points(m);
  std::vector<std::vector<Vec3>> yarns = course_yarn_points(m, rest);
  // The test's polylines are yarn_polylines' at rest (to round-off).
  const KnitYarns base =
      knit_yarns(m.chart, polylines_through(yarns, kStitchSamplesPerInterval), sp);
  const KnitYarns network = knit_yarns(m, rest);
  REQUIRE(base.lines.vertices[3].size() == network.lines.vertices[3].size());
  for (size_t k = 0; k < base.lines.vertices[3].size(); ++k)
    REQUIRE(norm(base.lines.vertices[3][k] - network.lines.vertices[3][k]) < 1e-12 * r);
  const int head = sp[3 * m.chart.wales + 4].begin + 4;  // T0 T1 T2 T3 T4
  yarns[3][head].y += r;
  const KnitYarns moved =
      knit_yarns(m.chart, polylines_through(yarns, kStitchSamplesPerInterval), sp);
  const TextileMeasures before = textile_measures(base, base);
  const TextileMeasures after = textile_measures(moved, base);
  const StitchMeasure& s0 = cell(before, m, 4, 3);
  const StitchMeasure& s1 = cell(after, m, 4, 3);
  CHECK(s1.loop_height - s0.loop_height == Approx(r).margin(0.1 * r));
  CHECK(s1.yarn_length > s0.yarn_length + 0.5 * r);
  CHECK(s1.centre.y > s0.centre.y + 0.1 * r);
  CHECK(s1.loop_height_rest == s0.loop_height_rest);
  // The interior's counts follow too: the moved loop is an interior loop of course 3.
  CHECK(after.fabric.stitch_length > before.fabric.stitch_length);
  CHECK(after.fabric.length_change != 0.0);
  // The neighbours' loops keep their heights to within the cubic's spread of the change.
  CHECK(std::abs(cell(after, m, 3, 3).loop_height - cell(before, m, 3, 3).loop_height) < 0.05 * r);
}

TEST_CASE("inconsistent input is refused, naming the cell", "[knit_measures]") {
  const KnitModel m = chart_model("single_tuck.chart");
  KnitYarns y = knit_yarns(m, m.rest_positions());
  KnitYarns bad = y;
  std::swap(bad.marks[2 * m.chart.wales + 3].loop_begin, bad.marks[2 * m.chart.wales + 3].end);
  CHECK_THROWS_WITH(textile_measures(bad, y),
                    Catch::Contains("wale 3, course 2") && Catch::Contains("loop_begin"));
  bad = y;
  bad.marks[5].end = y.lines.arc[0].back() * 2.0;
  CHECK_THROWS_WITH(textile_measures(bad, y), Catch::Contains("wale 5, course 0"));
  bad = y;
  bad.marks.pop_back();
  CHECK_THROWS_AS(textile_measures(bad, y), std::invalid_argument);
  const KnitModel plain = chart_model("plain_jersey.chart");
  const KnitYarns other = knit_yarns(plain, plain.rest_positions());
  CHECK_THROWS_WITH(textile_measures(other, y), Catch::Contains("different charts"));
}

namespace {

// The cells of stitches.csv, by their header's names (an empty field is NaN).
std::vector<std::map<std::string, std::string>> read_csv(const std::string& text) {
  std::vector<std::map<std::string, std::string>> rows;
  std::vector<std::string> names;
  for (const std::string& line : knitsim::test::lines(text)) {
    std::vector<std::string> fields;
    std::stringstream in(line);
    for (std::string f; std::getline(in, f, ',');) fields.push_back(f);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    if (names.empty()) {
      names = fields;
      continue;
    }
    REQUIRE(fields.size() == names.size());
    std::map<std::string, std::string> row;
    for (size_t k = 0; k < names.size(); ++k) row[names[k]] = fields[k];
    rows.push_back(row);
  }
  return rows;
}

double number(const std::string& field) { return field.empty() ? std::nan("") : std::stod(field); }

bool same_number(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

}  // namespace

TEST_CASE("knitsim knit writes stitches.csv and summary.json's fabric block", "[knit_measures]") {
  using knitsim::test::run_knitsim;
  using knitsim::test::slurp;
  using knitsim::test::TempDir;
  TempDir tmp("knit-measures");
  const std::string chart = std::string(KNITSIM_CHARTS) + "/single_tuck.chart";
  const knitsim::test::Run r = run_knitsim(
      "knit --chart '" + chart + "' --set knit.contact=0 --no-pictures --quiet --out '" +
          (tmp.path / "out").string() + "'",
      tmp);
  INFO(r.err);
  REQUIRE(r.status == 0);
  // The run's end positions from points.csv (shortest exact text), measured here: the files
  // hold the same numbers.
  KnitParams p;
  p.contact_ratio = 0.0;
  const KnitModel m = chart_model("single_tuck.chart", p);
  std::vector<Vec3> end(m.points.size());
  for (const auto& row : read_csv(slurp(tmp.path / "out" / "points.csv")))
    end[std::stoi(row.at("id"))] = {number(row.at("x")), number(row.at("y")), number(row.at("z"))};
  const TextileMeasures t = textile_measures(m, end);
  const auto rows = read_csv(slurp(tmp.path / "out" / "stitches.csv"));
  REQUIRE(rows.size() == t.stitches.size());
  for (size_t k = 0; k < rows.size(); ++k) {
    const StitchMeasure& s = t.stitches[k];
    const auto& row = rows[k];
    CAPTURE(k);
    CHECK(std::stoi(row.at("wale")) == s.wale);
    CHECK(std::stoi(row.at("course")) == s.course);
    CHECK(row.at("stitch") == std::string(1, static_cast<char>(s.stitch)));
    CHECK(std::stoi(row.at("held_over")) == s.held_over);
    CHECK(same_number(number(row.at("y_m")), s.centre.y));
    CHECK(same_number(number(row.at("x0_m")), s.centre_rest.x));
    CHECK(same_number(number(row.at("loop_height_m")), s.loop_height));
    CHECK(same_number(number(row.at("loop_width0_m")), s.loop_width_rest));
    CHECK(same_number(number(row.at("yarn_length_m")), s.yarn_length));
    CHECK(same_number(number(row.at("float_depth_m")), s.float_depth));
  }
  CHECK(rows[2 * 8 + 3].at("stitch") == "T");
  CHECK(rows[2 * 8 + 3].at("float_length_m").empty());
  const auto summary = nlohmann::json::parse(slurp(tmp.path / "out" / "summary.json"));
  const auto& f = summary.at("fabric");
  CHECK(f.at("courses_per_cm").get<double>() == t.fabric.courses_per_cm);
  CHECK(f.at("wales_per_cm").get<double>() == t.fabric.wales_per_cm);
  CHECK(f.at("courses_per_cm_rest").get<double>() == t.fabric.courses_per_cm_rest);
  CHECK(f.at("wales_per_cm_rest").get<double>() == t.fabric.wales_per_cm_rest);
  CHECK(f.at("width_change").get<double>() == t.fabric.width_change);
  CHECK(f.at("length_change").get<double>() == t.fabric.length_change);
  CHECK(f.at("stitch_length_m").get<double>() == t.fabric.stitch_length);
  CHECK(f.at("interior_cells") == 8);
  CHECK(summary.at("units").at("fabric").get<std::string>().find("1/cm") != std::string::npos);

  // A chart too small for the interior: null counts, one row per cell all the same.
  std::ofstream(tmp.path / "small.chart") << "KKKK\nKKKK\nKKKK\nKKKK\n";
  const knitsim::test::Run s =
      run_knitsim("knit --chart '" + (tmp.path / "small.chart").string() +
                      "' --no-pictures --quiet --out '" + (tmp.path / "small").string() + "'",
                  tmp);
  REQUIRE(s.status == 0);
  const auto small = nlohmann::json::parse(slurp(tmp.path / "small" / "summary.json"));
  for (const char* key : {"courses_per_cm", "wales_per_cm", "courses_per_cm_rest",
                          "wales_per_cm_rest", "width_change", "length_change", "stitch_length_m"})
    CHECK(small.at("fabric").at(key).is_null());
  CHECK(small.at("fabric").at("interior_cells") == 0);
  CHECK(read_csv(slurp(tmp.path / "small" / "stitches.csv")).size() == 16);
}
