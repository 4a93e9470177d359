// Equilibrium sensitivities (src/fit/sensitivity.hpp): the model's dF/dp against finite differences
// of the force, the measurement chain's tangent against finite differences of measure_edges,
// and d(coefficients)/dp against central differences of full re-runs to a polished equilibrium;
// the exact k-L0 scaling law; damping and an inactive elongation limit exactly zero.
//
// Speed: a 30 cm sheet with L0 = 5 cm (a 7 x 7 grid); each full run is a few ms.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "src/fit/sensitivity.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

using namespace knitsim;

namespace {

Scene small_scene(const char* name, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> sets = {"fabric.width=0.3", "model.natural_length=0.05"};
  sets.insert(sets.end(), extra.begin(), extra.end());
  Scene s = load_scene(name, sets);
  s.options.rtol = 1e-10;
  s.options.atol = 1e-12;
  return s;
}

DrapeParams with(DrapeParams p, DrapeParameter which, double value) {
  switch (which) {
    case DrapeParameter::Stiffness:
      p.stiffness = value;
      break;
    case DrapeParameter::Damping:
      p.damping = value;
      break;
    case DrapeParameter::ElongationLimit:
      p.elongation_limit = value;
      break;
    case DrapeParameter::NaturalLength:
      p.natural_length = value;
      break;
  }
  return p;
}

double value_of(const DrapeParams& p, DrapeParameter which) {
  switch (which) {
    case DrapeParameter::Stiffness:
      return p.stiffness;
    case DrapeParameter::Damping:
      return p.damping;
    case DrapeParameter::ElongationLimit:
      return p.elongation_limit;
    case DrapeParameter::NaturalLength:
      return p.natural_length;
  }
  return 0.0;
}

// The polished equilibrium of a scene and its sensitivities to all four parameters.
DrapeSensitivity solve(const Scene& scene, const PolishOptions& polish) {
  const DrapeResult run = run_drape(scene, "cvode-bdf");
  REQUIRE(run.stats.status == RunStatus::Equilibrium);
  return drape_sensitivity(run.grid, run.stats.t_final, free_state(run.grid.network, run.positions),
                           {DrapeParameter::Stiffness, DrapeParameter::Damping,
                            DrapeParameter::ElongationLimit, DrapeParameter::NaturalLength},
                           polish);
}

// max |a - b| / max |b| over all edges and coefficients.
double relative_difference(const std::vector<EdgeCoefficients>& a,
                           const std::vector<EdgeCoefficients>& b) {
  double diff = 0.0, scale = 0.0;
  for (size_t e = 0; e < a.size(); ++e)
    for (size_t i = 0; i < a[e].size(); ++i) {
      diff = std::max(diff, std::abs(a[e][i] - b[e][i]));
      scale = std::max(scale, std::abs(b[e][i]));
    }
  return diff / scale;
}

}  // namespace

TEST_CASE("drape_tangent + net_force_tangent match finite differences of the force",
          "[sensitivity]") {
  // A stretched state (every free particle moved outward by 10 % and down) so that springs
  // exceed eps_max = 5 %: the elongation-limit term is active and has a derivative.
  const DrapeParams base = small_scene("four_corner").params;
  const DrapeGrid grid = build_drape_grid(base);
  std::vector<double> x(grid.network.dof()), v(grid.network.dof());
  grid.network.initial_state(x.data(), v.data());
  for (size_t i = 0; i < x.size(); i += 3) {
    x[i] = 0.15 + 1.1 * (x[i] - 0.15);
    x[i + 2] = -0.02 * std::sin(x[i] * 10.0);
  }
  REQUIRE(grid.network.max_strain(0.0, x.data()) > 0.06);
  for (DrapeParameter p : {DrapeParameter::Stiffness, DrapeParameter::ElongationLimit,
                           DrapeParameter::NaturalLength}) {
    const double p0 = value_of(base, p), h = 1e-6 * p0;
    const DrapeGrid plus = build_drape_grid(with(base, p, p0 + h));
    const DrapeGrid minus = build_drape_grid(with(base, p, p0 - h));
    REQUIRE(plus.n == grid.n);
    REQUIRE(minus.n == grid.n);
    std::vector<double> fp(x.size()), fm(x.size()), analytic(x.size());
    plus.network.net_force(0.0, x.data(), fp.data());
    minus.network.net_force(0.0, x.data(), fm.data());
    grid.network.net_force_tangent(0.0, x.data(), drape_tangent(grid, p, 0.0), analytic.data());
    double diff = 0.0, scale = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
      const double fd = (fp[i] - fm[i]) / (2.0 * h);
      diff = std::max(diff, std::abs(analytic[i] - fd));
      scale = std::max(scale, std::abs(fd));
    }
    INFO(to_string(p) << ": max |analytic - fd| = " << diff << ", scale " << scale);
    CHECK(scale > 0.0);
    CHECK(diff <= 1e-6 * scale);
  }
  // Damping never enters the static force.
  std::vector<double> zero(x.size(), 1.0);
  grid.network.net_force_tangent(0.0, x.data(), drape_tangent(grid, DrapeParameter::Damping, 0.0),
                                 zero.data());
  for (double z : zero) CHECK(z == 0.0);
}

TEST_CASE("measure_edges_tangent matches finite differences of measure_edges", "[sensitivity]") {
  for (const char* name : {"four_corner", "two_corner"}) {
    const Scene scene = small_scene(name);
    const DrapeResult run = run_drape(scene, "cvode-bdf");
    REQUIRE(run.stats.status == RunStatus::Equilibrium);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Vec3> dX(run.positions.size());
    for (Vec3& d : dX) d = {u(rng), u(rng), u(rng)};
    const double h = 1e-7;
    std::vector<Vec3> plus = run.positions, minus = run.positions;
    for (size_t k = 0; k < dX.size(); ++k) {
      plus[k] = plus[k] + h * dX[k];
      minus[k] = minus[k] - h * dX[k];
    }
    const auto fp = measure_edges(run.grid, plus), fm = measure_edges(run.grid, minus);
    std::vector<EdgeCoefficients> fd(fp.size());
    for (size_t e = 0; e < fp.size(); ++e)
      for (size_t i = 0; i < fd[e].size(); ++i)
        fd[e][i] = (fp[e].coefficients[i] - fm[e].coefficients[i]) / (2.0 * h);
    const double rel = relative_difference(measure_edges_tangent(run.grid, run.positions, dX), fd);
    INFO(name << ": relative difference " << rel);
    CHECK(rel < 1e-6);
  }
}

TEST_CASE("Newton polish reaches the arithmetic floor on the same equilibrium", "[sensitivity]") {
  const Scene scene = small_scene("four_corner");
  const DrapeResult run = run_drape(scene, "cvode-bdf");
  REQUIRE(run.stats.status == RunStatus::Equilibrium);
  const SpringNetwork& net = run.grid.network;
  std::vector<double> x = free_state(net, run.positions);
  const PolishSummary s = polish_equilibrium(net, run.stats.t_final, x);
  INFO(s.message);
  CHECK(run.stats.certificate == "stable_minimum");
  CHECK(s.residual <= 1e-9);
  CHECK(s.residual < 0.1 * s.residual_before);
  CHECK(s.correction < 1e-6);  // the same state, not another branch
  CHECK(s.status == PolishStatus::Converged);
  // Moved 0.2 mm off the equilibrium, Newton returns to it; a 0.1 mm cap rejects the same
  // correction and leaves the state as it was.
  std::vector<double> moved = x;
  for (size_t i = 2; i < moved.size(); i += 3) moved[i] += 2e-4;
  std::vector<double> back = moved;
  const PolishSummary ok = polish_equilibrium(net, run.stats.t_final, back);
  CHECK(ok.status == PolishStatus::Converged);
  double far = 0.0;
  for (size_t i = 0; i < x.size(); ++i) far = std::max(far, std::abs(back[i] - x[i]));
  CHECK(far < 1e-9);
  PolishOptions tight;
  tight.max_correction = 1e-4;
  std::vector<double> kept = moved;
  const PolishSummary r = polish_equilibrium(net, run.stats.t_final, kept, tight);
  CHECK(r.status == PolishStatus::Rejected);
  CHECK(kept == moved);
}

TEST_CASE("edge sensitivities agree with central differences of full re-runs", "[sensitivity]") {
  const PolishOptions polish;  // Newton to the arithmetic floor
  for (const char* name : {"four_corner", "two_corner"}) {
    const Scene scene = small_scene(name);
    const DrapeSensitivity s = solve(scene, polish);
    REQUIRE(s.status == SensitivityStatus::Ok);
    CHECK(s.positive_pivots == 0);  // a stable equilibrium: K negative definite
    for (const ParameterSensitivity& ps : s.parameters) {
      if (ps.parameter == DrapeParameter::Damping) {
        CHECK(ps.structural_zero);
        continue;
      }
      if (ps.parameter == DrapeParameter::ElongationLimit) {  // strains << 5 %: inactive
        CHECK(ps.structural_zero);
        for (const EdgeCoefficients& c : ps.dcoefficients)
          for (double v : c) CHECK(v == 0.0);
        continue;
      }
      const double p0 = value_of(scene.params, ps.parameter), h = 1e-4 * p0;
      Scene plus = scene, minus = scene;
      plus.params = with(scene.params, ps.parameter, p0 + h);
      minus.params = with(scene.params, ps.parameter, p0 - h);
      const DrapeSensitivity sp = solve(plus, polish), sm = solve(minus, polish);
      REQUIRE(sp.status == SensitivityStatus::Ok);
      REQUIRE(sm.status == SensitivityStatus::Ok);
      std::vector<EdgeCoefficients> fd(s.edges.size());
      for (size_t e = 0; e < fd.size(); ++e)
        for (size_t i = 0; i < fd[e].size(); ++i)
          fd[e][i] = (sp.edges[e].coefficients[i] - sm.edges[e].coefficients[i]) / (2.0 * h);
      const double rel = relative_difference(ps.dcoefficients, fd);
      INFO(name << " " << to_string(ps.parameter) << ": relative difference " << rel);
      CHECK(rel < 1e-4);
      // Positions too (dx*/dp itself), pins included for L0.
      double diff = 0.0, scale = 0.0;
      for (size_t q = 0; q < s.positions.size(); ++q) {
        const Vec3 fdq = (1.0 / (2.0 * h)) * (sp.positions[q] - sm.positions[q]);
        diff = std::max(diff, norm(ps.dpositions[q] - fdq));
        scale = std::max(scale, norm(fdq));
      }
      INFO("positions: max |analytic - fd| " << diff << ", scale " << scale);
      CHECK(diff < 1e-4 * scale);
    }
  }
}

TEST_CASE("at fixed n the edges depend on k and L0 only through k / L0", "[sensitivity]") {
  // dc/dL0 = -(k / L0) dc/dk exactly (src/fit/sensitivity.hpp): the data cannot tell k from L0.
  for (const char* name : {"four_corner", "two_corner"}) {
    const Scene scene = small_scene(name);
    const DrapeSensitivity s = solve(scene, PolishOptions{});
    REQUIRE(s.status == SensitivityStatus::Ok);
    const double ratio = scene.params.stiffness / scene.params.natural_length;
    std::vector<EdgeCoefficients> predicted = s.parameters[0].dcoefficients;  // dc/dk
    for (auto& c : predicted)
      for (double& v : c) v *= -ratio;
    const double rel = relative_difference(s.parameters[3].dcoefficients, predicted);
    INFO(name << ": relative difference " << rel);
    CHECK(rel < 1e-8);
  }
}
