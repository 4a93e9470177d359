// The stall rule (docs/equilibrium.md, "The stall rule"): a run whose t stands still and whose
// static residual makes no new minimum for --stall-checks checks ends with status stalled, within
// that many checks; a chart that settles is not flagged, and the dynamics (t advancing) never are.
#include <catch2/catch.hpp>
#include <string>

#include "models/knit_loops.hpp"
#include "solvers/integrator.hpp"
#include "src/scene/knit_run.hpp"
#include "src/scene/knit_scene.hpp"

using namespace knitsim;

namespace {

// A knit scene of `chart` with the defaults of knitsim knit --chart (yarn contact on, its
// default integrator and velocity tolerance) and `sets` applied to it.
KnitScene chart_scene(const std::string& chart, long stall_checks, double contact = 10.0) {
  KnitScene scene;
  scene.name = "stall";
  scene.chart_file = "inline";
  scene.chart = parse_knit_chart(chart);
  scene.params.contact_ratio = contact;
  scene.options.stall_checks = stall_checks;
  scene.frames = 1;
  const std::string integrator = default_knit_integrator(scene.params.yarn_contact());
  set_default_knit_velocity_atol(scene.options, scene.params, make_integrator(integrator)->info());
  return scene;
}

KnitResult run(const KnitScene& scene) {
  return run_knit(scene, default_knit_integrator(scene.params.yarn_contact()));
}

// Floats over six wales in six courses between plain courses: valid, and its flow goes nowhere
// (issue 47: 5000 flow steps, then CVODE's error test at h = 2.8e-19 s, solver_failure after
// 60-245 s).
const std::string kFloats6 =
    "KKKKKKKK\nKKKKKKKK\nKMMMMMMK\nKMMMMMMK\nKMMMMMMK\nKMMMMMMK\nKMMMMMMK\nKMMMMMMK\n"
    "KKKKKKKK\nKKKKKKKK\n";

// models/charts/several_misses.chart: its longest stretch of flow steps without a new minimum
// of the residual is 9.
const std::string kSeveralMisses =
    "KKKKKKKKKKKK\nKKKKKKKKKKKK\nKKMKKKKKMKKK\nKKKKKKKKMKKK\nKKKKKMMKKKKK\nKKKKKKKKKKKK\n"
    "KKMKKKKKKKKK\nKKKKKKKKKKKK\n";

}  // namespace

TEST_CASE("a flow that makes no progress ends stalled within --stall-checks flow steps",
          "[stall]") {
  const KnitScene scene = chart_scene(kFloats6, IntegratorOptions{}.stall_checks);
  REQUIRE(scene.options.stall_checks == 1000);  // the documented default
  const KnitResult r = run(scene);
  CAPTURE(r.stats.message, r.stats.steps, r.stats.residual);
  CHECK(r.stats.status == RunStatus::Stalled);
  CHECK(std::string(to_string(r.stats.status)) == "stalled");
  CHECK(r.stats.message.find("stalled: the static residual stayed above its lowest value") == 0);
  CHECK(r.stats.message.find("for 1000 checks in a row (--stall-checks)") != std::string::npos);
  // Its lowest residual comes at flow step 20 (measured): the run ends 1000 flow steps later,
  // before the solver's own fallback to the dynamics at 5000.
  CHECK(r.stats.steps >= 1000);
  CHECK(r.stats.steps <= 1100);
  CHECK(r.stats.fallbacks == 0);
  CHECK(r.stats.t_final == 0.0);
}

TEST_CASE("a chart that settles is not flagged; the rule is live; the dynamics never stall",
          "[stall]") {
  SECTION("several_misses with the default rule ends as with the rule off, bit for bit") {
    const KnitResult on = run(chart_scene(kSeveralMisses, 1000));
    const KnitResult off = run(chart_scene(kSeveralMisses, 0));
    CHECK(on.stats.status == RunStatus::Equilibrium);
    CHECK(off.stats.status == RunStatus::Equilibrium);
    CHECK(on.stats.steps == off.stats.steps);
    CHECK(on.x == off.x);
  }
  SECTION("the same chart at --stall-checks 5, below its 9 checks without a new minimum, stalls") {
    const KnitResult r = run(chart_scene(kSeveralMisses, 5));
    CAPTURE(r.stats.message);
    CHECK(r.stats.status == RunStatus::Stalled);
    CHECK(r.stats.steps < 39);  // the whole settled run takes 39 flow steps
  }
  SECTION("cvode-bdf (knit.contact = 0) at --stall-checks 1: t advances, so no stall") {
    const KnitResult one = run(chart_scene(kSeveralMisses, 1, 0.0));
    const KnitResult off = run(chart_scene(kSeveralMisses, 0, 0.0));
    CHECK(one.stats.integrator == "cvode-bdf");
    CHECK(one.stats.status == RunStatus::Equilibrium);
    CHECK(one.stats.steps == off.stats.steps);
    CHECK(one.x == off.x);
  }
}
