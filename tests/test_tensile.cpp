// Knit under load (docs/knit.md, "Under load"): clamps' reactions against the weight they hold,
// the tensile test's energy balance W = dE, springs in series, plain jersey's small-strain
// stiffness against a hand count of its springs, and bad clamp and test inputs.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "models/knit_loops.hpp"
#include "solvers/equilibrium_check.hpp"
#include "solvers/integrator.hpp"
#include "src/scene/knit_run.hpp"
#include "src/scene/tensile_run.hpp"
#include "tests/cli_runner.hpp"
#include "tests/knit_test_scenes.hpp"

using namespace knitsim;
using namespace knitsim::test;

namespace {

// Settles `start` with the equilibrium solver.
RunStats settle(KnitStart& s, const IntegratorOptions& opt = {}) {
  return run_to_equilibrium(s.model.system(), "equilibrium", opt, s.x, s.v);
}

}  // namespace

// A swatch hung from its top edge under gravity: the top clamp's reaction holds the whole
// weight (the free points' through the springs and the held points' own). At an equilibrium the
// free points' net forces, each at most residual x F_ref, sum to reactions + weight, so the
// balance is bounded by n_free x residual x F_ref. Dropping the held points' own weight (5 of 35
// points) would miss by 14 % of it.
TEST_CASE("a swatch hung from its top edge: its clamp's reaction is its weight", "[tensile]") {
  for (double contact : {0.0, 10.0}) {
    KnitParams p;
    p.pins = KnitPins::Top;
    p.gravity = true;
    p.contact_ratio = contact;
    KnitStart s = start_knit(scene_of(plain(5, 6), p));
    const RunStats stats = settle(s);
    INFO("contact " << contact << ": " << stats.message);
    REQUIRE(stats.status == RunStatus::Equilibrium);
    const std::vector<ClampReaction> r = knit_clamp_reactions(s.model, stats.t_final, s.x);
    REQUIRE(r.size() == 1);
    CHECK(r[0].name == "top");
    CHECK(r[0].points == 5);
    const Vec3 weight = knit_weight(s.model);
    REQUIRE(weight.y < 0.0);
    const double bound =
        (s.model.network.dof() / 3) * stats.residual * s.model.network.residual_force_scale();
    CHECK(std::abs(r[0].reaction.y + weight.y) <= bound);
    CHECK(std::abs(r[0].reaction.x) <= bound);
    CHECK(bound < 1e-3 * std::abs(weight.y));  // the check is sharp
  }
}

// Springs in series: a single wale of C loops without the stabiliser (paper 2's network: wale
// springs only, k_w each, rest h), its bottom held and its top pulled by u: the top clamp's
// reaction is (k_w / C) u along the pull and the bottom's its opposite.
TEST_CASE("a single wale pulled: the series stiffness k_w / C", "[tensile]") {
  const int C = 6;
  const double u = 2e-5;  // m, ~ 0.22 r: 3.6 % strain
  KnitParams p;
  p.network = KnitNetwork::Paper;
  p.wale_stiffness = 120.0;
  p.clamps = parse_knit_clamps("bottom; top move 0," + std::to_string(u));
  KnitStart s = start_knit(scene_of(plain(1, C), p));
  const RunStats stats = settle(s);
  REQUIRE(stats.status == RunStatus::Equilibrium);
  const std::vector<ClampReaction> r = knit_clamp_reactions(s.model, stats.t_final, s.x);
  REQUIRE(r.size() == 2);
  CHECK(r[1].displacement.y == Approx(u).epsilon(1e-12));
  // Each free point's net force is at most residual x F_ref at the stop (the residual decides
  // here: the chain's sideways motion has no stiffness at rest), and a clamp's reaction differs
  // from the springs' k_w/C u by at most the free points' sum.
  const double bound =
      (s.model.network.dof() / 3) * stats.residual * s.model.network.residual_force_scale();
  const double F = p.wale_stiffness / C * u;
  INFO("top " << r[1].reaction.y << " N, bottom " << r[0].reaction.y << " N, k_w u / C " << F
              << " N, bound " << bound << " N");
  CHECK(std::abs(r[1].reaction.y - F) <= bound);
  CHECK(std::abs(r[0].reaction.y + F) <= bound);
  CHECK(bound < 1e-4 * F);  // the check is sharp: a wale spring more or less is 17 % of F
}

// Energy balance: with the contact off every step is an equilibrium of one potential, so the
// moving clamp's work from step 0 to N equals the stored energy's change. The work is the
// trapezoid rule on (u, F), whose error on a step is h^3 |F''| / 12, F'' estimated from the
// force's second differences: bound sum_k h |F_k+1 - 2 F_k + F_k-1| / 12 x 2 (twice, for the
// estimate), plus what the stop leaves: each state within newton_step of its equilibrium, where
// the energy is stationary, so |dE| <= |F_residual| x newton_step summed over the free points.
TEST_CASE("tensile with the contact off: the clamp's work is the stored energy's change",
          "[tensile]") {
  for (const char* direction : {"wale", "course"}) {
    KnitParams p;
    p.contact_ratio = 0.0;
    TensileOptions o;
    o.direction = direction;
    o.steps = 8;
    o.strain = 0.12;
    o.outputs = 0;
    const TensileResult r = run_tensile(scene_of(plain(8, 12), p), o);
    INFO(direction);
    REQUIRE(r.complete);
    REQUIRE(r.steps.size() == 9u);
    double bound = 0.0;
    const double h = r.steps[1].displacement - r.steps[0].displacement;
    for (std::size_t k = 0; k < r.steps.size(); ++k) {
      const TensileStep& s = r.steps[k];
      CHECK(s.stats.certificate == "stable_minimum");
      bound += (r.model.network.dof() / 3) * s.stats.residual *
               r.model.network.residual_force_scale() * s.stats.newton_step;
      if (k > 0 && k + 1 < r.steps.size())
        bound += 2.0 * h *
                 std::abs(r.steps[k + 1].force - 2.0 * s.force + r.steps[k - 1].force) / 12.0;
    }
    const double work = tensile_work(r.steps, 0, r.steps.size() - 1);
    const double dE = r.steps.back().energy - r.steps.front().energy;
    INFO("work " << work << " J, dE " << dE << " J, bound " << bound << " J");
    CHECK(work > 0.0);
    CHECK(std::abs(work - dE) <= bound);
    CHECK(bound < 1e-3 * dE);  // the check is sharp
  }
}

// Plain jersey's small-strain stiffness against a hand count of the network's springs
// (docs/knit.md, "The model as built"; w = 8 r, h = 7 r, d^2 = w^2 + h^2, k_s = s (k_w + k_c)/2):
// the affine stretch u = eps y (x) of the lattice stores, per unit of eps^2 / 2, the sum over
// springs of k (dy^2 / L)^2 (dx for the courses). By the principle of minimum potential energy
// the clamped strip's true stiffness is at most that (Voigt's bound, exact), and in a strip
// 2:1 long the lateral contraction the bound ignores is weak here (nu ~ 0.06) and the free
// edges' missing bending springs little: measured 0.5-0.7 % below the count (checked to 2 %).
//   wale:   W C k_w h^2 + 2 (W-1) C k_s h^4/d^2 + W (C-1) s k_w (2h)^2, over G^2 = (C h)^2
//   course: (W-1) C k_c w^2 + 2 (W-1) C k_s w^4/d^2 + (W-2)(C+1) s k_c (2w)^2, over ((W-1) w)^2
TEST_CASE("plain jersey's small-strain stiffness against a hand count of its springs",
          "[tensile]") {
  KnitParams p;
  p.contact_ratio = 0.0;
  p.wale_stiffness = 100.0;
  p.course_stiffness = 80.0;
  const double r0 = p.loop_radius, w = 8 * r0, h = 7 * r0, d2 = w * w + h * h;
  const double s = p.stabiliser_ratio, ks = s * 0.5 * (p.wale_stiffness + p.course_stiffness);
  for (const char* direction : {"wale", "course"}) {
    TensileOptions o;
    o.direction = direction;
    o.steps = 1;
    o.strain = 1e-4;
    o.outputs = 0;
    const bool wale = o.direction == "wale";
    const TensileResult r = run_tensile(scene_of(plain(24, 24), p), o);
    REQUIRE(r.complete);
    const int W = r.specimen.wales, C = r.specimen.courses;
    const double count =
        wale ? (W * C * p.wale_stiffness * h * h + 2.0 * (W - 1) * C * ks * h * h * h * h / d2 +
                W * (C - 1) * s * p.wale_stiffness * 4 * h * h) /
                   (C * h * C * h)
             : ((W - 1) * C * p.course_stiffness * w * w + 2.0 * (W - 1) * C * ks * w * w * w * w / d2 +
                (W - 2) * (C + 1) * s * p.course_stiffness * 4 * w * w) /
                   ((W - 1) * w * (W - 1) * w);  // N/m: force per unit displacement
    const double measured = (r.steps[1].force - r.steps[0].force) / r.steps[1].displacement;
    INFO(direction << ": " << W << " x " << C << ", measured " << measured << " N/m, count "
                   << count << " N/m");
    CHECK(measured <= count * (1.0 + 1e-6));
    CHECK(measured >= 0.98 * count);
  }
}

// Bad clamp and test inputs: one line naming the key or flag and the accepted range, exit 2,
// nothing written.
TEST_CASE("bad clamps and tensile options: one line, exit 2, nothing written", "[tensile]") {
  TempDir tmp("tensile-bad");
  const fs::path chart = tmp.path / "plain.chart";
  const fs::path one = tmp.path / "one.chart";
  std::ofstream(chart) << plain(5, 4);
  std::ofstream(one) << plain(5, 1);
  struct Case {
    std::string command, expect;
  };
  const std::vector<Case> cases = {
      {"knit --chart '" + chart.string() + "' --set 'knit.clamps=bottom; bottom'",
       "knit.clamps = bottom: selects no point that an earlier clamp does not hold already"},
      {"knit --chart '" + one.string() + "' --set knit.clamps=top",
       "knit.clamps = top: a chart of one course has no edge"},
      {"knit --chart '" + chart.string() + "' --set 'knit.clamps=top path 0.5:0,1e-5 1.5:0,2e-5'",
       "knit.clamps = top path 0.5:0,1e-5 1.5:0,2e-5: a path's load fractions S must increase "
       "within (0, 1]"},
      {"knit --chart '" + chart.string() + "' --set 'knit.clamps=wales 3-7'",
       "knit.clamps = wales 3-7: wales must be in 0 to 4"},
      {"knit --chart '" + chart.string() + "' --set 'knit.clamps=courses 4'",
       "knit.clamps = courses 4: courses must be in 0 to 3"},
      {"knit --chart '" + chart.string() + "' --set 'knit.clamps=middle'",
       "knit.clamps = middle: each clamp"},
      {"knit --chart '" + chart.string() + "' --set 'knit.clamps=top move 1e-5'",
       "knit.clamps = top move 1e-5: a displacement is DX,DY"},
      {"tensile --chart '" + chart.string() + "' --strain 2", "--strain = 2: must be in (0, 1]"},
      {"tensile --chart '" + chart.string() + "' --steps 0", "--steps = 0: must be an integer"},
      {"tensile --chart '" + chart.string() + "' --direction diagonal",
       "--direction = diagonal: must be wale or course"},
      {"tensile --chart '" + chart.string() + "' --gauge-ratio -1",
       "--gauge-ratio = -1: must be in (0, 100]"},
      {"tensile --chart '" + chart.string() + "' --set knit.pins=top",
       "knit.pins: tensile clamps the specimen itself"},
  };
  for (const Case& c : cases) {
    const fs::path out = tmp.path / "out";
    const Run run = run_knitsim(c.command + " --quiet --out '" + out.string() + "'", tmp);
    INFO(c.command << "\n" << run.err);
    CHECK(run.status == 2);
    CHECK(run.err.find(c.expect) != std::string::npos);
    CHECK(std::count(run.err.begin(), run.err.end(), '\n') == 1);
    CHECK(!fs::exists(out));
  }
}

// knitsim tensile's files: tensile.csv with the columns, one row per step; a step that
// does not reach equilibrium (here cut by --max-steps) is its last row's status, exit 3, with
// the curve so far and the summary written.
TEST_CASE("knitsim tensile writes the curve, and the curve so far when a step fails",
          "[tensile]") {
  TempDir tmp("tensile-cli");
  const fs::path chart = tmp.path / "plain.chart";
  std::ofstream(chart) << plain(6, 8);
  const fs::path out = tmp.path / "out";
  Run run = run_knitsim("tensile --chart '" + chart.string() +
                            "' --steps 3 --strain 0.06 --unload --set knit.contact=0 --quiet "
                            "--no-pictures --out '" + out.string() + "'",
                        tmp);
  INFO(run.err);
  REQUIRE(run.status == 0);
  std::vector<std::string> rows = lines(slurp(out / "tensile.csv"));
  REQUIRE(rows.size() == 8u);  // header, step 0, 3 up, 3 down
  CHECK(rows[0].rfind("step,strain,displacement_m,force_N,force_per_width_N_per_m,"
                      "lateral_strain,energy_J,status,",
                      0) == 0);
  CHECK(rows[4].rfind("3,0.0", 0) == 0);
  CHECK(rows[7].find(",equilibrium,") != std::string::npos);
  CHECK(fs::exists(out / "step_006" / "points.csv"));  // --outputs 3 of 6: steps 2, 4, 6
  CHECK(fs::exists(out / "manifest.json"));

  // A flow step cap of 1: step 1 along the courses (with the contact on it needs more than the
  // warm start's Newton step and one flow step) ends step_limit.
  const fs::path cut = tmp.path / "cut";
  run = run_knitsim("tensile --chart '" + chart.string() +
                        "' --steps 3 --strain 0.06 --direction course --max-steps 1 --quiet "
                        "--no-pictures --out '" + cut.string() + "'",
                    tmp);
  CHECK(run.status == 3);
  CHECK(run.err.find("ended step_limit") != std::string::npos);
  rows = lines(slurp(cut / "tensile.csv"));
  REQUIRE(rows.size() >= 2u);
  CHECK(rows.back().find(",step_limit,") != std::string::npos);
  const nlohmann::json summary = nlohmann::json::parse(slurp(cut / "summary.json"));
  CHECK(summary["status"] == "step_limit");
  CHECK(fs::exists(cut / "manifest.json"));
}

namespace {

// Every check's state and static residual, and where each kept step's solve ended in that list.
struct CheckRecorder final : RunObserver {
  std::vector<std::vector<double>> states;
  std::vector<double> residuals;
  std::vector<std::size_t> step_end;  // per kept step k (1, 2, ...), states.size() after it
  int dof = 0;
  void on_check(double, const double* x, const double*, double residual) override {
    states.emplace_back(x, x + dof);
    residuals.push_back(residual);
  }
};

}  // namespace

// A step that lands on a saddle follows the negative mode (docs/knit.md, "Under load"): the
// several_tucks chart with out-of-plane bending (knit.bending = 0.1, the contact off: its points
// may leave the plane) pulled along the wales to 20 % in 4 steps and unloaded. Unloading to 5 %
// (step 7) the flow converges onto a saddle (K has a negative pivot: a tuck's compressed yarn
// would rather buckle out of the plane) and leaves it along the most negative mode; the step's
// status says so, and its end is a certified stable minimum whose energy lies below the
// saddle's (the step's check state of least residual where K is indefinite). With the escape
// disabled (EquilibriumSolver::escape_saddle returning false) the step does not end
// equilibrium_after_saddle: the run does not complete (step 0 already stands on a saddle).
TEST_CASE("a tensile step that lands on a saddle leaves it for a lower minimum", "[tensile]") {
  KnitParams p;
  p.contact_ratio = 0.0;
  p.bending_ratio = 0.1;
  const KnitScene scene = scene_of(
      "KKKKKKKKKKKK\nKKKKKKKKKKKK\nKKTKKKKKTKKK\nKKKKKKKKTKKK\nKKKKKTTKKKKK\nKKKKKKKKKKKK\n"
      "KKTKKKKKKKKK\nKKKKKKKKKKKK\n",
      p);
  TensileOptions o;
  o.steps = 4;
  o.strain = 0.2;
  o.unload = true;
  o.outputs = 8;  // every step kept: on_kept marks where each step's checks end
  CheckRecorder checks;
  const TensileResult r = run_tensile(
      scene, o, &checks, [&](const TensileResult& so_far, int step, const std::vector<double>&) {
        checks.dof = so_far.model.network.dof();
        checks.step_end.resize(static_cast<std::size_t>(step), checks.states.size());
      });
  REQUIRE(r.complete);
  REQUIRE(r.steps.size() == 9u);
  const TensileStep& s = r.steps[7];
  INFO(s.stats.message);
  CHECK(s.strain == Approx(0.05));
  REQUIRE(s.status == "equilibrium_after_saddle");
  CHECK(s.stats.saddle_escapes >= 1);
  CHECK(s.stats.certificate == "stable_minimum");
  CHECK(s.stats.negative_pivots == 0);
  // The saddle: step 7's check states (after step 6's), K probed at each with the clamps where
  // step 7 holds them.
  REQUIRE(checks.step_end.size() == 8u);
  KnitModel& m = const_cast<KnitModel&>(r.model);
  MechanicalSystem& sys = m.system();
  HeldPoints& held = *sys.held_points();
  std::vector<Vec3> held_rest(held.held_count());
  for (int k = 0; k < held.held_count(); ++k) held_rest[k] = m.points[held.held_particle(k)].rest;
  move_clamps(held, m.clamps, held_rest, 0.25);
  CHECK(sys.potential_energy(0.0, r.kept[6].x.data()) == Approx(s.energy).epsilon(1e-12));
  detail::StiffnessProbe probe(sys, scene.options.factorization);
  double saddle_residual = std::numeric_limits<double>::infinity(), saddle_energy = 0.0;
  for (std::size_t c = checks.step_end[5]; c < checks.step_end[6]; ++c) {
    const double* x = checks.states[c].data();
    if (checks.residuals[c] >= saddle_residual) continue;
    if (probe.probe(0.0, x, detail::StiffnessProbe::Measure::Spectrum).negative_pivots == 0)
      continue;
    saddle_residual = checks.residuals[c];
    saddle_energy = sys.potential_energy(0.0, x);
  }
  INFO("saddle residual " << saddle_residual << ", energy " << saddle_energy << " J; end "
                          << s.energy << " J");
  REQUIRE(saddle_residual < 1e-6);  // a critical point, to the flow's convergence
  CHECK(s.energy < saddle_energy - 1e-6 * saddle_energy);
  // Step 6 (10 %) ended flat, step 7 left the plane: the buckled tuck (1.7 r measured).
  auto depth = [](const std::vector<Vec3>& points) {
    double d = 0.0;
    for (const Vec3& q : points) d = std::max(d, std::abs(q.z));
    return d;
  };
  CHECK(depth(r.kept[5].positions) < 1e-6 * p.loop_radius);
  CHECK(depth(r.kept[6].positions) > 0.5 * p.loop_radius);
}
