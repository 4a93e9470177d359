// Yarn measures (src/measure/yarn_measures.hpp): the segment-to-segment
// distance, the clearance of knit states, the designed crossings and their check, and the
// clearance over a run.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "models/knit_loops.hpp"
#include "src/geometry/segment_distance.hpp"
#include "src/measure/yarn_measures.hpp"
#include "tests/test_files.hpp"

using namespace knitsim;
using knitsim::test::chart_file;

namespace {

// Rotation about a unit axis by angle a (Rodrigues), applied to p.
Vec3 rotate(Vec3 p, Vec3 axis, double a) {
  return std::cos(a) * p + std::sin(a) * cross(axis, p) + (1.0 - std::cos(a)) * dot(axis, p) * axis;
}

}  // namespace

TEST_CASE("segment distance: closed forms and a brute-force search") {
  // Perpendicular skew segments 2 apart, crossing at their middles.
  SegmentClosest c = closest_points({-1, 0, 0}, {1, 0, 0}, {0, -1, 2}, {0, 1, 2});
  CHECK(c.distance == Approx(2.0));
  CHECK(c.s == Approx(0.5));
  CHECK(c.t == Approx(0.5));
  // Parallel, overlapping: distance 1 wherever the witnesses are.
  c = closest_points({0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {3, 1, 0});
  CHECK(c.distance == Approx(1.0));
  // End to end: (1,0,0) to (2,0,0).
  c = closest_points({0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 5, 0});
  CHECK(c.distance == Approx(1.0));
  CHECK(c.s == 1.0);
  CHECK(c.t == 0.0);
  // Degenerate: a point against a segment, two points.
  CHECK(closest_points({0, 3, 0}, {0, 3, 0}, {-1, 0, 0}, {1, 0, 0}).distance == Approx(3.0));
  CHECK(closest_points({0, 0, 0}, {0, 0, 0}, {0, 0, 4}, {0, 0, 4}).distance == Approx(4.0));

  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto rnd = [&] { return Vec3{u(rng), u(rng), u(rng)}; };
  for (int n = 0; n < 200; ++n) {
    const Vec3 a0 = rnd(), a1 = rnd(), b0 = rnd(), b1 = rnd();
    const SegmentClosest got = closest_points(a0, a1, b0, b1);
    double brute = 1e300;
    for (int i = 0; i <= 200; ++i)
      for (int k = 0; k <= 200; ++k)
        brute = std::min(brute, norm(a0 + (i / 200.0) * (a1 - a0) - b0 - (k / 200.0) * (b1 - b0)));
    INFO("case " << n);
    CHECK(got.distance <= brute + 1e-12);
    // The grid's resolution: the true minimum lies within half a grid step of a grid point.
    CHECK(got.distance >= brute - (norm(a1 - a0) + norm(b1 - b0)) / 400.0);
    CHECK(norm(got.a - got.b) == Approx(got.distance));
  }
}

TEST_CASE("plain jersey at rest: clearance 1.212 r, crossings invariant under rigid motions") {
  const KnitModel m = build_knit(parse_knit_chart(chart_file("plain_jersey.chart")), KnitParams{});
  const double r = m.params.loop_radius;
  const std::vector<Vec3> rest = m.rest_positions();
  const YarnPolylines lines = yarn_polylines(m, rest);
  REQUIRE(lines.vertices.size() == static_cast<size_t>(m.chart.courses));
  const YarnClearance c = yarn_clearance(m, lines);
  // The closest pieces belong to neighbouring courses (the head of a loop behind the feet of
  // the loop above), not one yarn with itself.
  CHECK(c.over_r == Approx(1.2116).epsilon(1e-4));
  CHECK(c.b.course == c.a.course + 1);
  const std::vector<YarnCrossing> crossings = designed_crossings(m, lines);
  // 8 wales x 6 courses (measured; about 3.3 per loop, fewer along the edges).
  CHECK(crossings.size() == 160);
  CHECK(check_crossings(crossings, lines).changed == 0);

  // A rigid motion changes no clearance: one in the plane for the default (planar) model, one in
  // space with the out-of-plane bending (whose loop frames follow the points out of the plane);
  // one in the plane, or a slight tilt of the yarns, no crossing's order.
  const Vec3 shift{3e-3, -1e-3, 2e-3};
  std::vector<Vec3> moved = rest;
  for (Vec3& p : moved) p = rotate(p, Vec3{0, 0, 1}, 0.7) + Vec3{shift.x, shift.y, 0.0};
  CHECK(yarn_clearance(m, yarn_polylines(m, moved)).over_r == Approx(c.over_r).epsilon(1e-9));
  KnitParams bent;
  bent.bending_ratio = 1.0;
  bent.contact_ratio = 0.0;
  const KnitModel mb = build_knit(parse_knit_chart(chart_file("plain_jersey.chart")), bent);
  const Vec3 axis = (1.0 / std::sqrt(3.0)) * Vec3{1, 1, 1};
  moved = rest;
  for (Vec3& p : moved) p = rotate(p, axis, 0.7) + shift;
  CHECK(yarn_clearance(mb, yarn_polylines(mb, moved)).over_r == Approx(c.over_r).epsilon(1e-9));
  YarnPolylines in_plane = lines;
  for (auto& course : in_plane.vertices)
    for (Vec3& p : course) p = rotate(rotate(p, Vec3{0, 0, 1}, 0.7), Vec3{1, 0, 0}, 0.05) + shift;
  CHECK(check_crossings(crossings, in_plane).changed == 0);

  // A mirror image of the yarns (z -> -z) swaps over and under at every crossing.
  YarnPolylines mirrored = lines;
  for (auto& course : mirrored.vertices)
    for (Vec3& p : course) p.z = -p.z;
  CHECK(check_crossings(crossings, mirrored).changed == 160);

  // Course 3's yarn pushed back through its neighbours in 20 steps of 0.15 r: the clearance
  // over the steps falls to within half a step of 0, and the crossings with courses 2 and 4
  // have changed at the end (the yarn now lies wholly behind them).
  double smallest = 1e300;
  YarnPolylines pushed = lines;
  for (int step = 1; step <= 20; ++step) {
    pushed = lines;
    for (Vec3& p : pushed.vertices[3]) p.z -= 0.15 * r * step;
    smallest = std::min(smallest, yarn_clearance(m, pushed).over_r);
  }
  CHECK(smallest < 0.08);
  const CrossingCheck after = check_crossings(crossings, pushed);
  CHECK(after.changed > 0);
  for (int n : after.changed_index) {
    const YarnCrossing& x = crossings[n];
    CHECK((x.a.course == 3 || x.b.course == 3));
  }
}

TEST_CASE("a crossing at a vertex counts once whatever the vertex's round-off") {
  const KnitModel m = build_knit(parse_knit_chart(chart_file("plain_jersey.chart")), KnitParams{});
  const double r = m.params.loop_radius;
  // Three yarns (courses 0, 1, 2), 9 vertices each, 0.5 r apart along them, through one shared
  // vertex P (their 5th): course 1 level, course 0 rising across it and across course 2, which
  // comes down to P and back up (it touches course 1 from above there: 0 or 2 crossings, by
  // the side the tie-break puts it on). Depths: course 1 at the back, 0, then 2 in front.
  const Vec3 P{0.0257, 0.0032, 0.0};  // far from the origin, as the knit's vertices are
  auto unit = [](Vec3 v) { return (1.0 / norm(v)) * v; };
  auto yarn = [&](Vec3 left, Vec3 right, double z) {
    std::vector<Vec3> v;
    for (int k = -4; k <= 4; ++k) {
      const Vec3 side = k < 0 ? left : right;
      v.push_back(P + (0.5 * r * std::abs(k)) * side + Vec3{0, 0, z});
    }
    return v;
  };
  auto lines_with = [&](Vec3 shift0, Vec3 shift2) {
    YarnPolylines lines;
    lines.vertices = {yarn(unit(Vec3{-1, -0.3, 0}), unit(Vec3{1, 0.3, 0}), r),
                      yarn(Vec3{-1, 0, 0}, Vec3{1, 0, 0}, -r),
                      yarn(unit(Vec3{-1, 0.2, 0}), unit(Vec3{1, 0.2, 0}), 3 * r)};
    lines.vertices[0][4] = lines.vertices[0][4] + shift0;
    lines.vertices[2][4] = lines.vertices[2][4] + shift2;
    for (auto& v : lines.vertices) {
      lines.arc.emplace_back();
      double s = 0.0;
      for (std::size_t k = 0; k < v.size(); ++k) {
        if (k > 0) s += norm(v[k] - v[k - 1]);
        lines.arc.back().push_back(s);
      }
    }
    return lines;
  };
  const YarnPolylines exact = lines_with({}, {});
  const std::vector<YarnCrossing> designed = designed_crossings(m, exact);
  auto between = [](const std::vector<YarnCrossing>& xs, int ca, int cb) {
    return std::count_if(xs.begin(), xs.end(), [&](const YarnCrossing& x) {
      return x.a.course == ca && x.b.course == cb;
    });
  };
  CHECK(between(designed, 0, 1) == 1);  // strict signs: 0 (every orientation exactly 0)
  const auto touches = between(designed, 1, 2);
  CHECK((touches == 0 || touches == 2));
  CHECK(between(designed, 0, 2) == 1);
  for (const YarnCrossing& x : designed) CHECK(x.sign == (x.b.course == 1 ? 1 : -1));
  // The shared vertex moved by round-off (a few ulps of its coordinates, either way): the same
  // count, so two models placing the same vertices by different arithmetic agree.
  const double ulp = 4e-18;  // m: ~ the spacing of doubles near 0.03 m
  for (const Vec3 d : {Vec3{ulp, 0, 0}, Vec3{-ulp, 0, 0}, Vec3{0, ulp, 0}, Vec3{0, -ulp, 0},
                       Vec3{ulp, -ulp, 0}, Vec3{-ulp, ulp, 0}}) {
    const std::vector<YarnCrossing> moved = designed_crossings(m, lines_with(d, -1.0 * d));
    CHECK(between(moved, 0, 1) == 1);
    CHECK(between(moved, 0, 2) == 1);
    CHECK(between(moved, 1, 2) == touches);
  }
  // And the check at the end sees them: course 0 pushed behind course 1 changes that crossing
  // (it was behind course 2 already).
  YarnPolylines behind = exact;
  for (Vec3& p : behind.vertices[0]) p.z = -3 * r;
  CHECK(check_crossings(designed, behind).changed == 1);
}

TEST_CASE("rest clearance of the committed charts, and the clearance over a run") {
  // The tuck and held-loop rest geometry (models/knit_loops.hpp): a single tuck's yarns keep
  // plain jersey's clearance (1.212 r); the loops held over two courses by several_misses'
  // floats and several_tucks' stacked tucks keep their legs more than a diameter apart (1.150 r
  // and 1.199 r: one leg point per course). Every valid chart: the next test cases.
  for (const char* name : {"plain_jersey.chart", "single_tuck.chart", "tucks40.chart"}) {
    CAPTURE(name);
    const KnitModel m = build_knit(parse_knit_chart(chart_file(name)), KnitParams{});
    CHECK(yarn_clearance(m, yarn_polylines(m, m.rest_positions())).over_r >= 1.2);
  }
  for (const char* name : {"several_misses.chart", "several_tucks.chart"}) {
    CAPTURE(name);
    const KnitModel m = build_knit(parse_knit_chart(chart_file(name)), KnitParams{});
    CHECK(yarn_clearance(m, yarn_polylines(m, m.rest_positions())).over_r >= 1.1);
  }

  // The single tuck with paper 2's network: the clearance over the run dips below its end
  // value, so an end-only measure would miss the worst state (the yarns overlap: contact is
  // not in the model yet).
  KnitParams paper;
  paper.network = KnitNetwork::Paper;
  const KnitModel t = build_knit(parse_knit_chart(chart_file("single_tuck.chart")), paper);
  ClearanceOverRun over(t, nullptr);
  std::vector<double> x, v;
  IntegratorOptions opt;
  x.resize(t.network.dof()), v.resize(t.network.dof());
  t.network.initial_state(x.data(), v.data());
  over.observe(0.0, x.data(), true);
  const RunStats s = run_to_equilibrium(t.network, "cvode-bdf", opt, x, v, &over);
  REQUIRE(s.status == RunStatus::Equilibrium);
  over.observe(s.t_final, x.data(), true);
  std::vector<Vec3> end;
  t.network.all_positions(s.t_final, x.data(), end);
  const double at_end = yarn_clearance(t, yarn_polylines(t, end)).over_r;
  CHECK(over.measured_states() > 10);
  CHECK(over.minimum().over_r < at_end - 0.01);
  // Measured: 1.212 r at rest, 0.165 r at t = 2.3e-4 s, 0.188 r at the end.
  CHECK(over.minimum().over_r < 0.5);
  CHECK(over.t_of_minimum() > 0.0);
  CHECK(over.t_of_minimum() < s.t_final);
  // The guarantee (yarn_measures.hpp): a missed dip is shallower than 2 A 0.05 r; measured A ~1.6.
  CHECK(over.amplification() >= 1.0);
  CHECK(over.resolution_over_r() < 0.3);
  // A hint only narrows the search: the same clearance as without it, from any counted pair.
  const YarnPolylines end_lines = yarn_polylines(t, end);
  const YarnClearance plain = yarn_clearance(t, end_lines);
  YarnClearance far = plain;
  far.a = {0, 0};
  far.b = {t.chart.courses - 1, 5};
  for (const YarnClearance* hint : std::vector<const YarnClearance*>{&plain, &far, &over.minimum()})
    CHECK(yarn_clearance(t, end_lines, 2.0, hint).over_r == plain.over_r);
}

TEST_CASE("every valid committed chart starts with its yarns apart") {
  // models/charts/*.chart and the charts of the fuzz corpus that parse and validate (the others
  // are there to be refused): at t = 0 (the network's initial state, where every run starts) the
  // rest clearance is at least 0.99 r (one yarn diameter d = r, less the polyline's sampling)
  // and the crossing check against the rest state's designed crossings reports none changed.
  // Guards the tuck and held-loop rest geometry (models/knit_loops.hpp): stacked tucks' legs
  // cross within 0.05 r (stacked_tucks) and 0.10 r (several_tucks) if the lower tuck's head is
  // the shallower.
  std::vector<std::string> checked;
  for (const std::string& dir :
       {std::string(KNITSIM_CHARTS), std::string(KNITSIM_FUZZ_CORPUS) + "/chart"}) {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(dir))
      if (e.path().extension() == ".chart") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const std::filesystem::path& f : files) {
      CAPTURE(f.string());
      std::ifstream in(f);
      REQUIRE(in.good());
      std::stringstream text;
      text << in.rdbuf();
      KnitChart chart;
      try {
        chart = parse_knit_chart(text.str());
      } catch (const std::invalid_argument&) {
        continue;  // a chart the model refuses (bad_letter, ragged, tuck_edge, ...)
      }
      const KnitModel m = build_knit(chart, KnitParams{});
      std::vector<double> x(m.network.dof()), v(m.network.dof());
      m.network.initial_state(x.data(), v.data());
      std::vector<Vec3> start;
      m.network.all_positions(0.0, x.data(), start);
      const YarnPolylines rest = yarn_polylines(m, m.rest_positions());
      const YarnPolylines at_start = yarn_polylines(m, start);
      const YarnClearance c = yarn_clearance(m, at_start);
      CAPTURE(c.over_r, c.a.course, c.b.course);
      CHECK(c.over_r >= 0.99);
      const std::vector<YarnCrossing> crossings = designed_crossings(m, rest);
      CHECK(!crossings.empty());
      CHECK(check_crossings(crossings, at_start).changed == 0);
      checked.push_back(f.parent_path().filename().string() + "/" + f.filename().string());
    }
  }
  // Every shipped chart, and the corpus's valid ones with stacked or neighbouring tucks.
  for (const char* name :
       {"charts/plain_jersey.chart", "charts/single_tuck.chart", "charts/tucks40.chart",
        "charts/several_misses.chart", "charts/several_tucks.chart", "chart/stacked_tucks.chart",
        "chart/crlf_mixed.chart"}) {
    CAPTURE(name);
    CHECK(std::find(checked.begin(), checked.end(), name) != checked.end());
  }
}

TEST_CASE("tucks and misses on one needle start with their yarns a diameter apart") {
  // The tuck and held-loop rest geometry (models/knit_loops.hpp) on the combinations of
  // experiments/random_charts and beyond, each on the middle needle of a small chart: at the
  // network's initial state the clearance is at least 0.99 r (one yarn diameter d = r, less the
  // polyline's sampling), and the designed crossings keep their over/under order when every
  // interlacing point moves by up to 0.02 r (the geometry is a function of the points; yarns a
  // diameter apart cannot pass through each other on such a move).
  const struct {
    const char* name;
    const char* chart;
  } cases[] = {
      {"miss above a tuck", "KKKKKKK\nKKKKKKK\nKKKMKKK\nKKKTKKK\nKKKKKKK\n"},
      {"miss above a miss above a tuck", "KKKKKKK\nKKKMKKK\nKKKMKKK\nKKKTKKK\nKKKKKKK\n"},
      {"tuck above a miss", "KKKKKKK\nKKKTKKK\nKKKMKKK\nKKKKKKK\n"},
      {"float over three wales above a tuck", "KKKKKKKK\nKKKKKKKK\nKKMMMKKK\nKKKTKKKK\nKKKKKKKK\n"},
      {"float over two tucks", "KKKKKKKK\nKKKKKKKK\nKKMMKKKK\nKKTTKKKK\nKKKKKKKK\n"},
      {"miss above two stacked tucks", "KKKKKKK\nKKKKKKK\nKKKMKKK\nKKKTKKK\nKKKTKKK\nKKKKKKK\n"},
      {"loop held over three courses", "KKKKKKK\nKKKMKKK\nKKKMKKK\nKKKMKKK\nKKKKKKK\n"},
      {"two loops side by side held over three",
       "KKKKKKKK\nKKKMMKKK\nKKKMMKKK\nKKKMMKKK\nKKKKKKKK\n"},
      {"loop held over four tucks", "KKKKKKK\nKKKTKKK\nKKKTKKK\nKKKTKKK\nKKKTKKK\nKKKKKKK\n"},
      {"loop held over tucks and misses by turns",
       "KKKKKKK\nKKKTKKK\nKKKMKKK\nKKKTKKK\nKKKMKKK\nKKKTKKK\nKKKKKKK\n"},
      {"tucks and misses in a checkerboard",
       "KKKKKKKK\nKMTMTMTK\nKTMTMTMK\nKMTMTMTK\nKTMTMTMK\nKKKKKKKK\n"},
  };
  for (const auto& c : cases) {
    CAPTURE(c.name);
    const KnitModel m = build_knit(parse_knit_chart(c.chart), KnitParams{});
    std::vector<double> x(m.network.dof()), v(m.network.dof());
    m.network.initial_state(x.data(), v.data());
    std::vector<Vec3> start;
    m.network.all_positions(0.0, x.data(), start);
    const YarnPolylines lines = yarn_polylines(m, start);
    const YarnClearance clear = yarn_clearance(m, lines);
    CAPTURE(clear.over_r, clear.a.course, clear.b.course);
    CHECK(clear.over_r >= 0.99);
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(-0.02 * m.params.loop_radius,
                                             0.02 * m.params.loop_radius);
    std::vector<Vec3> moved = start;
    for (Vec3& p : moved) p = p + Vec3{u(rng), u(rng), u(rng)};
    const std::vector<YarnCrossing> crossings = designed_crossings(m, lines);
    CHECK(!crossings.empty());
    CHECK(check_crossings(crossings, yarn_polylines(m, moved)).changed == 0);
  }

  // The designed order where a float passes a tuck on its needle: in front of the tuck's legs
  // (as a stacked tuck's legs are), behind the legs of the loop held under both (a float lies
  // on the back of the fabric). Depths at the closest points of the crossing pieces, whose
  // midpoints lie within the middle wale (|x - 3 w| < 4 r).
  const KnitModel m =
      build_knit(parse_knit_chart("KKKKKKK\nKKKKKKK\nKKKMKKK\nKKKTKKK\nKKKKKKK\n"), KnitParams{});
  const double r = m.params.loop_radius, w = m.params.wale_spacing();
  const YarnPolylines rest = yarn_polylines(m, m.rest_positions());
  auto piece = [&](const YarnSegment& s, int k) { return rest.vertices[s.course][s.segment + k]; };
  int over_tuck = 0, under_held = 0;
  for (const YarnCrossing& x : designed_crossings(m, rest)) {
    if (x.b.course != 2 && x.a.course != 2) continue;
    const YarnSegment fl = x.a.course == 2 ? x.a : x.b, other = x.a.course == 2 ? x.b : x.a;
    const Vec3 mid_float = 0.5 * (piece(fl, 0) + piece(fl, 1));
    const Vec3 mid_other = 0.5 * (piece(other, 0) + piece(other, 1));
    if (std::abs(mid_float.x - 3 * w) >= 4 * r || std::abs(mid_other.x - 3 * w) >= 4 * r) continue;
    const SegmentClosest c =
        closest_points(piece(fl, 0), piece(fl, 1), piece(other, 0), piece(other, 1));
    CAPTURE(other.course, c.a.z / r, c.b.z / r);
    if (other.course == 1) {
      CHECK(c.a.z > c.b.z);  // the float in front of the tuck's legs
      ++over_tuck;
    } else if (other.course == 0) {
      CHECK(c.a.z < c.b.z);  // behind the held loop's legs
      ++under_held;
    }
  }
  CHECK(over_tuck >= 2);   // both legs of the tuck
  CHECK(under_held >= 2);  // both legs of the held loop
}
