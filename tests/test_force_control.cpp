// Force control (docs/knit.md, "Under load"): a clamp under a force as a rigid bar whose
// position along the loaded components is an unknown (models/force_control.hpp), forces on
// points, load steps. The balance of reactions, applied loads and weight; the force and the
// displacement controls agreeing on the same state; the bar's Jacobian against finite
// differences; bad load keys refused with one line.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "models/force_control.hpp"
#include "models/knit_loads.hpp"
#include "models/knit_loops.hpp"
#include "src/core/jacobian_check.hpp"
#include "src/scene/knit_run.hpp"
#include "tests/cli_runner.hpp"
#include "tests/knit_test_scenes.hpp"

using namespace knitsim;
using namespace knitsim::test;

namespace {

// The free points' count: each free point's net force is at most residual x F_ref at an
// equilibrium, and so is each bar's (models/force_control.hpp, static residual).
double balance_bound(const KnitResult& r, const RunStats& s, int bars) {
  const double free_points = r.model.network.dof() / 3;
  return (free_points + bars) * s.residual * r.model.network.residual_force_scale();
}

const ClampReaction& clamp_named(const std::vector<ClampReaction>& c, const std::string& name) {
  const auto it =
      std::find_if(c.begin(), c.end(), [&](const ClampReaction& r) { return r.name == name; });
  REQUIRE(it != c.end());
  return *it;
}

}  // namespace

// A 5 x 6 swatch hung from its top edge under gravity, a force F on its bottom bar in 2 load
// steps: at each step's end the top reaction, the bar's force and the weight sum to zero within
// the bound above, and the bar carries load x F. Then the same swatch with its bottom clamp
// moved (displacement control) to where the bar ended: its reaction is F and every point stands
// where the force-controlled run put it. A wrong sign or scale of the applied force, a bar that
// does not move its points, or a reaction read at the wrong state breaks one of these.
TEST_CASE(
    "a swatch hung from its top edge with a force on its bottom bar: the balance, and "
    "force and displacement control agree",
    "[force]") {
  const double F = 5e-3;  // N, ~1 r of stretch on this swatch
  for (double contact : {0.0, 10.0}) {
    KnitParams p;
    p.pins = KnitPins::Top;
    p.gravity = true;
    p.contact_ratio = contact;
    p.clamps = parse_knit_clamps("bottom force 0,-5e-3");
    p.load_steps = 2;
    const KnitResult r = run_knit(scene_of(plain(5, 6), p), "equilibrium");
    INFO("contact " << contact << ": " << r.stats.message);
    REQUIRE(r.stats.status == RunStatus::Equilibrium);
    REQUIRE(r.load_steps.size() == 2);
    for (const KnitLoadStep& step : r.load_steps) {
      INFO("step " << step.step);
      CHECK(step.load == Approx(0.5 * step.step));
      const double bound = balance_bound(r, step.stats, 1);
      const KnitBalance& b = step.balance;
      CHECK(b.applied.y == Approx(-step.load * F));
      CHECK(b.weight.y < 0.0);
      CHECK(std::abs(b.sum.x) <= bound);
      CHECK(std::abs(b.sum.y) <= bound);
      CHECK(bound < 1e-4 * F);  // the check is sharp
      const ClampReaction& top = clamp_named(step.clamps, "top");
      const ClampReaction& bar = clamp_named(step.clamps, "bottom force 0,-5e-3");
      CHECK(std::abs(top.reaction.y - (step.load * F - b.weight.y)) <= bound);
      CHECK(std::abs(bar.reaction.y + step.load * F) <= bound);  // the bar holds load x F
      CHECK(bar.displacement.x == 0.0);                          // held along x
      CHECK(bar.displacement.y < 0.0);                           // pulled down
    }
    const double u = r.load_steps.back().clamps[1].displacement.y;
    INFO("bar displacement " << u << " m = " << u / p.loop_radius << " r");
    CHECK(-u > 0.3 * p.loop_radius);  // a stretch the agreement below can resolve

    // Displacement control at that displacement.
    KnitParams q = p;
    std::ostringstream clamp;
    clamp.precision(17);
    clamp << "bottom move 0," << u;
    q.clamps = parse_knit_clamps(clamp.str());
    q.load_steps = 0;
    const KnitResult d = run_knit(scene_of(plain(5, 6), q), "equilibrium");
    REQUIRE(d.stats.status == RunStatus::Equilibrium);
    const std::vector<ClampReaction> rd = knit_clamp_reactions(d.model, d.stats.t_final, d.x);
    const ClampReaction& moved = clamp_named(rd, clamp.str());
    INFO("displacement control's reaction " << moved.reaction.y << " N against " << -F);
    CHECK(std::abs(moved.reaction.y + F) <= 1e-4 * F);
    double worst = 0.0;
    for (std::size_t k = 0; k < r.positions.size(); ++k)
      worst = std::max(worst, norm(r.positions[k] - d.positions[k]));
    INFO("largest difference of a point between the controls " << worst / p.loop_radius << " r");
    CHECK(worst <= 1e-4 * p.loop_radius);
  }
}

// Forces on points: a swatch held at its top, two points of its bottom course pulled down and
// sideways: the top reaction balances the applied loads (no gravity), to the residual.
TEST_CASE("forces on points: the top reaction balances them", "[force]") {
  KnitParams p;
  p.pins = KnitPins::Top;
  p.contact_ratio = 0.0;
  p.point_forces =
      parse_knit_point_forces("wale 1 course 0 lower 1e-3,-2e-3; wale 3 course 1 upper 0,-1e-3");
  const KnitResult r = run_knit(scene_of(plain(5, 4), p), "equilibrium");
  INFO(r.stats.message);
  REQUIRE(r.stats.status == RunStatus::Equilibrium);
  REQUIRE(r.load_steps.size() == 1);
  const KnitLoadStep& step = r.load_steps.back();
  const double bound = balance_bound(r, step.stats, 0);
  CHECK(step.balance.applied.x == Approx(1e-3));
  CHECK(step.balance.applied.y == Approx(-3e-3));
  CHECK(std::abs(step.clamps[0].reaction.x + 1e-3) <= bound);
  CHECK(std::abs(step.clamps[0].reaction.y - 3e-3) <= bound);
  CHECK(bound < 1e-4 * 3e-3);
  // The loaded point moved the way it is pulled.
  const int pt = r.model.loops[r.model.loop(1, 0)].lower;
  CHECK(r.positions[pt].y < r.model.points[pt].rest.y - 0.1 * p.loop_radius);
}

// The bar's columns (central differences of the model's accelerations) and rows (from the
// Hessian's symmetry, not differenced) against the checker's own differences of every column.
TEST_CASE("force control's Jacobian against finite differences", "[force]") {
  for (double contact : {0.0, 10.0}) {
    KnitParams p;
    p.pins = KnitPins::Top;
    p.gravity = true;
    p.contact_ratio = contact;
    p.clamps = parse_knit_clamps("bottom force 2e-3,-5e-3");
    p.point_forces = parse_knit_point_forces("wale 2 course 1 lower 0,-1e-3");
    KnitModel m = build_knit(parse_knit_chart(plain(4, 4)), p);
    std::unique_ptr<ForceControl> fc = knit_force_control(m);
    REQUIRE(fc->unknowns() == 2);
    std::vector<double> x(fc->dof()), v(fc->dof());
    fc->initial_state(x.data(), v.data());
    const double r = p.loop_radius;
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] += 0.05 * r * std::sin(1.7 * static_cast<double>(i) + 0.3);
    x[fc->dof() - 2] = 0.2 * r, x[fc->dof() - 1] = -0.4 * r;  // the bar moved
    const JacobianCheck c = check_stiffness_jacobian(*fc, 0.0, x.data(), 1e-8);
    INFO("contact " << contact << ": worst (" << c.worst_row << ", " << c.worst_col << ") "
                    << c.worst_analytic << " vs " << c.worst_fd);
    CHECK(c.max_relative_error < 1e-4);
    CHECK(!c.outside_pattern);
  }
}

TEST_CASE("bad forces and load steps: one line, exit 2, nothing written", "[force]") {
  TempDir tmp("force-bad");
  const fs::path chart = tmp.path / "plain.chart";
  const fs::path one = tmp.path / "one.chart";
  const fs::path tuck = tmp.path / "tuck.chart";
  std::ofstream(chart) << plain(5, 4);
  std::ofstream(one) << plain(5, 1);
  std::ofstream(tuck) << "KKKKK\nKKMKK\nKKKKK\n";
  const std::string c = "knit --chart '" + chart.string() + "' --set ";
  struct Case {
    std::string command, expect;
  };
  const std::vector<Case> cases = {
      {c + "'knit.clamps=bottom; bottom force 0,-1e-3'",
       "knit.clamps = bottom force 0,-1e-3: selects no point that an earlier clamp does not hold"},
      {"knit --chart '" + one.string() + "' --set 'knit.clamps=top force 0,1e-3'",
       "knit.clamps = top force 0,1e-3: a chart of one course has no edge"},
      {c + "'knit.clamps=top force 0,-2000'",
       "knit.clamps = top force 0,-2000: a force's components must be in [-1000, 1000] N"},
      {c + "'knit.clamps=top force 0,0'", "knit.clamps = top force 0,0: a force needs a non-zero"},
      {c + "'knit.clamps=top force 1e-3'", "knit.clamps = top force 1e-3: a force is FX,FY"},
      {c + "'knit.forces=wale 9 course 0 lower 0,-1e-3'",
       "knit.forces = wale 9 course 0 lower 0,-1e-3: the cell must be in wales 0 to 4 and "
       "courses 0 to 3"},
      {c + "'knit.forces=wale 1 course 0 middle 0,-1e-3'",
       "knit.forces = wale 1 course 0 middle 0,-1e-3: each force"},
      {c + "'knit.forces=wale 1 course 0 lower nan,1'",
       "knit.forces = wale 1 course 0 lower nan,1: a force is FX,FY"},
      {c + "knit.pins=bottom --set 'knit.forces=wale 1 course 0 lower 0,-1e-3'",
       "the point is held by a clamp"},
      {"knit --chart '" + tuck.string() + "' --set 'knit.forces=wale 2 course 1 lower 0,1e-3'",
       "knit.forces = wale 2 course 1 lower 0,1e-3: the cell is a miss"},
      {c + "knit.load_steps=5000", "knit.load_steps = 5000: must be a whole number in [0, 1000]"},
      {c + "knit.load_steps=-1", "knit.load_steps"},
  };
  for (const Case& k : cases) {
    const fs::path out = tmp.path / "out";
    const Run run = run_knitsim(k.command + " --quiet --out '" + out.string() + "'", tmp);
    INFO(k.command << "\n" << run.err);
    CHECK(run.status == 2);
    CHECK(run.err.find(k.expect) != std::string::npos);
    CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
    CHECK(!fs::exists(out));
  }
}

// Through the command line, from a scene file: loads.csv one row per load step, summary.json's
// `loads` with the balance, the console's balance row; without load keys none of them.
TEST_CASE("a knit scene under load writes loads.csv and the balance", "[force]") {
  TempDir tmp("force-cli");
  const fs::path scene = tmp.path / "hung.toml";
  std::ofstream(scene) << "[knit]\nchart_text = \"\"\"\n"
                       << plain(5, 5)
                       << "\"\"\"\npins = \"top\"\ngravity = \"on\"\ncontact = 0\n"
                          "clamps = \"bottom force 0,-4e-3\"\n"
                          "forces = \"wale 2 course 2 lower 1e-3,0\"\nload_steps = 3\n";
  const fs::path out = tmp.path / "out";
  const Run run = run_knitsim(
      "knit --scene '" + scene.string() + "' --no-pictures --out '" + out.string() + "'", tmp);
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.out.find("balance           reactions (") != std::string::npos);
  std::ifstream csv(out / "loads.csv");
  std::string header, line;
  std::getline(csv, header);
  CHECK(header.rfind("step,load,status,newton_steps,residual,clamp_0_displacement_x_m", 0) == 0);
  CHECK(header.find(",clamp_1_reaction_y_N,") != std::string::npos);
  CHECK(header.find(",balance_z_N") == header.size() - 12);
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    CHECK(line.find(",equilibrium,") != std::string::npos);
  }
  CHECK(rows == 3);
  const nlohmann::json s = nlohmann::json::parse(slurp(out / "summary.json"));
  CHECK(s["loads"]["steps"] == 3);
  CHECK(s["loads"]["applied_N"][0].get<double>() == Approx(1e-3));
  CHECK(s["loads"]["applied_N"][1].get<double>() == Approx(-4e-3));
  CHECK(std::abs(s["loads"]["balance_N"][0].get<double>()) < 1e-8);
  CHECK(std::abs(s["loads"]["balance_N"][1].get<double>()) < 1e-8);
  CHECK(s["clamps"]["balance_N"] == s["loads"]["balance_N"]);

  // The same chart without load keys: no loads.csv (a stale one removed), no `loads`.
  std::ofstream(scene) << "[knit]\nchart_text = \"\"\"\n"
                       << plain(5, 5) << "\"\"\"\npins = \"top\"\ngravity = \"on\"\ncontact = 0\n";
  REQUIRE(run_knitsim("knit --scene '" + scene.string() + "' --no-pictures --quiet --out '" +
                          out.string() + "'",
                      tmp)
              .status == 0);
  CHECK(!fs::exists(out / "loads.csv"));
  CHECK(!nlohmann::json::parse(slurp(out / "summary.json")).contains("loads"));
}
