// The yarn-level knit model's front end (models/yarn_knit.hpp) and its run
// (src/scene/yarn_knit_run.hpp): a chart becomes one yarn with the right vertex counts, continuous
// at the selvedges and clear at d at the start; a small relaxed run keeps each course's yarn
// length within 1 %; single_tuck with knit.model = yarn ends with a status and its measures.
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "models/yarn_knit.hpp"
#include "src/scene/knit_run.hpp"
#include "src/scene/knit_scene.hpp"
#include "src/scene/scene.hpp"
#include "src/scene/yarn_knit_run.hpp"

using namespace knitsim;

namespace {

const char* kSmall = "KKKK\nKKKK\nKKKK\n";    // 4 wales x 3 courses
const char* kTuck = "KKKKK\nKKTKK\nKKKKK\n";  // one tuck mid-chart

YarnKnitParams yarn_params(int per_cell, double stitch_length) {
  YarnKnitParams p;
  p.model = KnitModelKind::Yarn;
  p.vertices_per_loop = per_cell;
  p.stitch_length = stitch_length;
  return p;
}

}  // namespace

TEST_CASE("chart to yarn: vertex counts, one yarn continuous at the selvedges, held ends",
          "[yarn_knit]") {
  for (const char* text : {kSmall, kTuck}) {
    const KnitChart chart = parse_knit_chart(text);
    for (int per_cell : {8, 12}) {
      const YarnKnit y = build_yarn_knit(chart, KnitParams{}, yarn_params(per_cell, 0.0));
      REQUIRE(static_cast<int>(y.course_vertices.size()) == chart.courses);
      std::vector<int> seen(y.start.size(), 0);
      for (int j = 0; j < chart.courses; ++j) {
        const std::vector<int>& idx = y.course_vertices[j];
        // per_cell edges per chart cell, sampled along the course's centreline.
        CHECK(static_cast<int>(idx.size()) == per_cell * chart.wales + 1);
        // Knitting order: even courses left to right, odd ones back, each course contiguous.
        for (std::size_t k = 1; k < idx.size(); ++k)
          CHECK(idx[k] - idx[k - 1] == (j % 2 == 0 ? 1 : -1));
        for (int v : idx) ++seen[v];
        // Left to right in space.
        CHECK(y.start[idx.back()].x > y.start[idx.front()].x);
      }
      // Every vertex once; those in no course are the selvedge turns, between consecutive courses
      // on the side where the next course begins.
      for (std::size_t v = 0; v < seen.size(); ++v) CHECK(seen[v] <= 1);
      for (int j = 0; j + 1 < chart.courses; ++j) {
        const int end_j = j % 2 == 0 ? y.course_vertices[j].back() : y.course_vertices[j].front();
        const int begin_next =
            j % 2 == 0 ? y.course_vertices[j + 1].back() : y.course_vertices[j + 1].front();
        REQUIRE(begin_next > end_j + 1);  // a turn of at least one vertex
        for (int v = end_j + 1; v < begin_next; ++v) CHECK(seen[v] == 0);
      }
      // Continuity: no edge is a jump (longest under twice the mean).
      double sum = 0.0, longest = 0.0;
      for (std::size_t e = 0; e + 1 < y.start.size(); ++e) {
        const double l = norm(y.start[e + 1] - y.start[e]);
        sum += l;
        longest = std::max(longest, l);
      }
      CHECK(longest < 2.0 * sum / static_cast<double>(y.start.size() - 1));
      // Held: both yarn ends and the head arc (T3..T5) of every loop of the first and the last
      // course, nothing of the courses between.
      CHECK(y.pins.front() == 0);
      CHECK(y.pins.back() == static_cast<int>(y.start.size()) - 1);
      for (int held : {0, chart.courses - 1})
        for (int i = 0; i < chart.wales; ++i) {
          const int l = y.structure.loop(i, held);
          for (int e = 2; e < 4; ++e) {
            const int v = y.course_vertices[held][std::lround(y.loop_points[l][e])];
            CHECK(std::binary_search(y.pins.begin(), y.pins.end(), v));
          }
        }
      for (int j = 1; j + 1 < chart.courses; ++j)
        for (int v : y.course_vertices[j])
          CHECK(!std::binary_search(y.pins.begin(), y.pins.end(), v));
    }
  }
}

TEST_CASE("chart to yarn: the start is clear at d, the ramp's target is the stitch length",
          "[yarn_knit]") {
  const KnitChart chart = parse_knit_chart(kTuck);
  const YarnKnit y = build_yarn_knit(chart, KnitParams{}, yarn_params(12, 3.4e-3));
  INFO("start clearance " << y.start_clearance / y.d << " d, r = " << y.r / y.d << " d");
  CHECK(y.start_clearance >= kYarnStartClearance * y.d);
  CHECK(y.start_clearance <= kYarnStartClearanceMax * y.d);
  // Checked independently of min_clearance: segment distances of the start's pairs more than
  // 2 d apart along the yarn, sampled finely.
  std::vector<double> arc(y.start.size(), 0.0);
  for (std::size_t k = 1; k < arc.size(); ++k)
    arc[k] = arc[k - 1] + norm(y.start[k] - y.start[k - 1]);
  double closest = 1e9;
  for (std::size_t a = 0; a + 1 < y.start.size(); ++a)
    for (std::size_t b = a + 1; b + 1 < y.start.size(); ++b) {
      if (norm(y.start[a] - y.start[b]) > 4.0 * y.d) continue;
      for (int i = 0; i <= 8; ++i)
        for (int k = 0; k <= 8; ++k) {
          const double s = i / 8.0, t = k / 8.0;
          const double sa = arc[a] + s * (arc[a + 1] - arc[a]);
          const double sb = arc[b] + t * (arc[b + 1] - arc[b]);
          if (std::abs(sa - sb) < 2.0 * y.d) continue;
          const Vec3 p = (1 - s) * y.start[a] + s * y.start[a + 1];
          const Vec3 q = (1 - t) * y.start[b] + t * y.start[b + 1];
          closest = std::min(closest, norm(p - q));
        }
    }
  INFO("sampled clearance " << closest / y.d << " d");
  CHECK(closest >= y.d);
  // The knit cells' target yarn, sinker to sinker, is the stitch length on average.
  const KnitYarns target_yarns = yarn_knit_yarns(y, y.start);
  double knit_sum = 0.0;
  int knits = 0;
  for (int j = 0; j < chart.courses; ++j)
    for (int i = 0; i < chart.wales; ++i) {
      if (chart.at(i, j) != Stitch::Knit) continue;
      const YarnCellMarks& m = y.marks[j * chart.wales + i];
      const std::vector<int>& idx = y.course_vertices[j];
      for (std::size_t k = 0; k + 1 < idx.size(); ++k)
        if (k + 0.5 >= m.begin && k + 0.5 < m.end)
          knit_sum += y.target_length[std::min(idx[k], idx[k + 1])];
      ++knits;
    }
  CHECK(knit_sum / knits == Approx(3.4e-3).epsilon(1e-9));
  CHECK(target_yarns.lines.vertices.size() == static_cast<std::size_t>(chart.courses));
}

TEST_CASE("a relaxed yarn run keeps each course's length within 1 % and stays clear",
          "[yarn_knit][run]") {
  Scene input = knit_scene("small", {"knit.model=yarn", "knit.stitch_length=0",
                                     "knit.yarn_vertices=8", "run.t_max=1e3"});
  // Capped: on an idle machine this run reaches equilibrium; on a loaded one the cap may come
  // first (docs/yarn_model.md, "What is not met"), and the length must be kept either way.
  input.options.max_wall_seconds = 60.0;
  KnitScene scene = make_knit_scene(input, parse_knit_chart(kSmall), 2);
  const KnitResult r = run_knit(scene, "equilibrium");
  REQUIRE(r.yarn);
  INFO("status " << to_string(r.stats.status) << ", residual " << r.stats.residual);
  // At 8 edges a cell this chart loses its structure on the way (below): its stop then ends
  // outside the model's limits, and only so.
  CHECK((r.stats.status == RunStatus::Equilibrium || r.stats.status == RunStatus::WallLimit ||
         (r.stats.status == RunStatus::OutsideModelLimits && r.yarn->structure_end.lost())));
  CHECK(r.stats.steps > 0);
  for (std::size_t j = 0; j < r.yarn->course_end.size(); ++j) {
    INFO("course " << j);
    CHECK(std::abs(r.yarn->course_end[j] / r.yarn->course_knitted[j] - 1.0) < 0.01);
  }
  CHECK(r.yarn->clearance_min_over_d >= 0.45);  // the barrier's guaranteed floor (d0 - d/4)
  CHECK(r.yarn->clearance_end_over_d >= 0.9);
  // The structure check ran on the yarn's own crossings, and a lost structure is said in the
  // status (this chart at 8 edges a cell loses it on the way: docs/yarn_model.md, "The structure
  // check").
  INFO("interlock gap max " << r.yarn->structure_end.interlock_gap_max_over_d << " d, "
                            << r.measures.crossings.changed << " crossings changed");
  CHECK(r.measures.crossings.designed > 0);
  const bool said = r.stats.message.find("lost its knitted structure") != std::string::npos;
  CHECK(r.yarn->structure_end.lost() == said);
  CHECK((r.stats.status != RunStatus::Equilibrium || r.yarn->structure_end.withdrawn == 0));
  // The structure's points read off the yarn: finite, one per point.
  CHECK(r.positions.size() == r.model.points.size());
  CHECK(std::all_of(r.positions.begin(), r.positions.end(), is_finite));
  for (const StitchMeasure& m : r.yarn->textile.stitches) CHECK(std::isfinite(m.yarn_length));
}

TEST_CASE("single_tuck with knit.model = yarn ends with a status and its measures",
          "[yarn_knit][run]") {
  Scene input = knit_scene("single_tuck", {"knit.model=yarn"});
  input.options.max_wall_seconds = 5.0;
  const std::string chart_text =
      "KKKKKKKK\nKKKKKKKK\nKKKKKKKK\nKKKTKKKK\nKKKKKKKK\nKKKKKKKK\n";  // as the committed chart
  KnitScene scene = make_knit_scene(input, parse_knit_chart(chart_text), 2);
  const KnitResult r = run_knit(scene, "cvode-bdf");
  REQUIRE(r.yarn);
  INFO("status " << to_string(r.stats.status));
  CHECK((r.stats.status == RunStatus::Equilibrium || r.stats.status == RunStatus::WallLimit));
  CHECK(r.yarn->clearance_min_over_d >= 0.45);
  CHECK(r.yarn->stages.size() >= 1);
  CHECK(r.frames.size() >= 1);
  for (const FrameRecorder::Frame& f : r.frames)
    CHECK(f.x.size() == static_cast<std::size_t>(r.model.network.dof()));
}

TEST_CASE("an explicit method on the yarn model keeps the wall cap and its checks",
          "[yarn_knit][run]") {
  // Its checks come every 1000 steps; the run must not be cut into 50-step rounds that never
  // reach one (verlet ran 633 s past a 5 s cap so).
  Scene input = knit_scene("small", {"knit.model=yarn", "knit.yarn_vertices=8"});
  input.options.max_wall_seconds = 1.0;
  KnitScene scene = make_knit_scene(input, parse_knit_chart(kSmall), 2);
  const auto w0 = std::chrono::steady_clock::now();
  const KnitResult r = run_knit(scene, "verlet");
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  INFO("status " << to_string(r.stats.status) << ", " << r.stats.steps << " steps, " << wall
                 << " s");
  CHECK(r.stats.status == RunStatus::WallLimit);
  CHECK(r.stats.steps >= 1000);  // the first check, at step 1000, may already see the cap
  CHECK(wall < 30.0);  // the cap plus the set-up and the outputs' measures, on a loaded machine
}

TEST_CASE("the structure check: kept at the start, lost when a course is pulled out",
          "[yarn_knit][structure]") {
  const KnitChart chart = parse_knit_chart(kSmall);
  const YarnKnit y = build_yarn_knit(chart, KnitParams{}, yarn_params(8, 0.0));
  const std::vector<YarnCrossing> designed = yarn_designed_crossings(y);
  REQUIRE(!designed.empty());
  const YarnStructure start = check_yarn_structure(y, designed, y.start);
  INFO("start: " << start.crossings.designed << " crossings, " << start.interlocks
                 << " interlocks, gap max " << start.interlock_gap_max_over_d << " d");
  CHECK(start.crossings.changed == 0);
  CHECK(start.interlocks == chart.wales * (chart.courses - 1));  // every knit loop holds one
  CHECK(start.withdrawn == 0);
  CHECK(start.interlock_gap_max_over_d < kYarnWithdrawn);
  CHECK(!start.lost());
  CHECK(yarn_structure_message(start).empty());

  // The middle course pulled out of the fabric, 6 d in front of it: its loops leave the heads
  // of the course below, and every crossing with its neighbours now has it in front.
  std::vector<Vec3> pulled = y.start;
  for (int v : y.course_vertices[1]) pulled[v].z += 6.0 * y.d;
  const YarnStructure lost = check_yarn_structure(y, designed, pulled);
  INFO("pulled: " << lost.crossings.changed << " crossings changed, " << lost.withdrawn
                  << " withdrawn, gap max " << lost.interlock_gap_max_over_d << " d");
  CHECK(lost.crossings.changed > 0);
  CHECK(lost.withdrawn == chart.wales * 2);  // its feet from course 0, course 2's from its heads
  CHECK(lost.lost());

  // Withdrawn without any crossing changed (as a frictionless yarn may): only the interlocks
  // see it.
  YarnStructure only_withdrawn = start;
  only_withdrawn.withdrawn = 1;
  CHECK(only_withdrawn.lost());

  // Reported: an equilibrium becomes outside_model_limits with the message; another status
  // keeps its name and gains it.
  RunStats eq;
  eq.status = RunStatus::Equilibrium;
  report_yarn_structure(lost, eq);
  CHECK(eq.status == RunStatus::OutsideModelLimits);
  CHECK(eq.message.find("lost its knitted structure") != std::string::npos);
  RunStats wall;
  wall.status = RunStatus::WallLimit;
  wall.message = "wall";
  report_yarn_structure(lost, wall);
  CHECK(wall.status == RunStatus::WallLimit);
  CHECK(wall.message.find("wall; the yarn lost") == 0);
  YarnStructure crossed = start;  // a crossing changed, every loop still held
  crossed.crossings.changed = 2;
  RunStats turned;
  turned.status = RunStatus::Equilibrium;
  turned.message = "Newton";
  report_yarn_structure(crossed, turned);
  CHECK(turned.status == RunStatus::Equilibrium);
  CHECK(turned.message.find("Newton; the yarn lost its knitted structure: 2 of") == 0);
  RunStats kept;
  kept.status = RunStatus::Equilibrium;
  report_yarn_structure(start, kept);
  CHECK(kept.status == RunStatus::Equilibrium);
  CHECK(kept.message.empty());
}
