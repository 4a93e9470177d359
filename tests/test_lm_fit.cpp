// Levenberg-Marquardt (src/fit/lm_fit.hpp): the bounded solver on closed-form problems, the
// identifiability formulas on hand-made Jacobians, and the drape fit on a noise-free twin.
//
// Speed: the drape twin is a 30 cm sheet with L0 = 5 cm (7 x 7 grid), a few ms per evaluation.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <vector>

#include "src/fit/lm_fit.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

using namespace knitsim;

namespace {

// y_k = a exp(-b t_k) at t_k = 0, 0.25, ..., 2: residuals r = y - model, J = dr/d(a, b).
LmProblem exponential_problem(double a, double b, std::vector<double> lower,
                              std::vector<double> upper) {
  LmProblem p;
  p.lower = std::move(lower);
  p.upper = std::move(upper);
  p.evaluate = [a, b](const std::vector<double>& x, Eigen::VectorXd& r, Eigen::MatrixXd& J) {
    const int m = 9;
    r.resize(m);
    J.resize(m, 3);
    for (int k = 0; k < m; ++k) {
      const double t = 0.25 * k, e = std::exp(-x[1] * t);
      r(k) = a * std::exp(-b * t) - x[0] * e;
      J(k, 0) = -e;
      J(k, 1) = x[0] * t * e;
      J(k, 2) = 0.0;  // a parameter the data do not see (like damping)
    }
    return true;
  };
  return p;
}

}  // namespace

TEST_CASE("run_lm recovers a zero-residual exponential and leaves a blind parameter alone",
          "[lm]") {
  const LmProblem p = exponential_problem(2.0, 1.5, {0.1, 0.1, 0.0}, {5.0, 5.0, 1.0});
  LmOptions o;
  o.max_evaluations = 40;
  o.step_tol = 1e-12;
  o.cost_tol = 0.0;
  const LmResult r = run_lm(p, {1.0, 0.5, 0.3}, o);
  INFO(r.message << ", " << r.evaluations << " evaluations");
  CHECK(std::abs(r.x[0] - 2.0) < 1e-9);
  CHECK(std::abs(r.x[1] - 1.5) < 1e-9);
  CHECK(r.x[2] == 0.3);  // zero column: zero step
  // A coordinate with lower == upper is held, the others still converge.
  const LmProblem fixed = exponential_problem(2.0, 1.5, {0.1, 1.5, 0.0}, {5.0, 1.5, 1.0});
  const LmResult f = run_lm(fixed, {1.0, 0.5, 0.3}, o);
  CHECK(f.x[1] == 1.5);
  CHECK(std::abs(f.x[0] - 2.0) < 1e-9);
  CHECK(r.evaluations < 25);
  CHECK(r.failed_evaluations == 0);
}

TEST_CASE("run_lm stops on the bound when the optimum lies outside the box", "[lm]") {
  // True b = 1.5 but b <= 1: the constrained optimum has b = 1 and a the best a for b = 1.
  const LmProblem p = exponential_problem(2.0, 1.5, {0.1, 0.1, 0.0}, {5.0, 1.0, 1.0});
  LmOptions o;
  o.max_evaluations = 40;
  const LmResult r = run_lm(p, {1.0, 0.5, 0.5}, o);
  CHECK(r.x[1] == 1.0);
  // a minimises sum (y_k - a e_k)^2 at b = 1: a = sum y e / sum e^2.
  double num = 0.0, den = 0.0;
  for (int k = 0; k < 9; ++k) {
    const double t = 0.25 * k, e = std::exp(-t);
    num += 2.0 * std::exp(-1.5 * t) * e;
    den += e * e;
  }
  CHECK(std::abs(r.x[0] - num / den) < 1e-6);
  // KKT: the gradient in b points out of the box (decreasing cost for larger b).
  const Eigen::VectorXd g = r.J.transpose() * r.r;
  CHECK(g(1) < 0.0);
}

TEST_CASE("run_lm counts a failed evaluation as a rejected step", "[lm]") {
  LmProblem p = exponential_problem(2.0, 1.5, {0.1, 0.1, 0.0}, {5.0, 5.0, 1.0});
  const auto inner = p.evaluate;
  int calls = 0;
  p.evaluate = [&](const std::vector<double>& x, Eigen::VectorXd& r, Eigen::MatrixXd& J) {
    return ++calls != 2 && inner(x, r, J);  // the first trial point fails
  };
  LmOptions o;
  o.max_evaluations = 40;
  const LmResult r = run_lm(p, {1.0, 0.5, 0.3}, o);
  CHECK(r.failed_evaluations == 1);
  CHECK(std::abs(r.x[1] - 1.5) < 1e-5);
}

TEST_CASE("identifiability: closed-form standard errors and an exact k-L0 degeneracy", "[lm]") {
  const std::vector<double> x = {800.0, 15.0, 10.0, 0.05, 0.5};
  DrapeResiduals at;
  at.r = Eigen::VectorXd::LinSpaced(20, -1e-3, 1e-3);
  at.J = Eigen::MatrixXd::Zero(20, 4);
  for (int i = 0; i < 20; ++i) {
    at.J(i, 0) = std::sin(0.3 * i + 0.1) * 1e-4;
    at.J(i, 3) = std::cos(0.7 * i) * 2.0;
  }
  at.structural_zero = {false, true, true, false};
  DrapeIdentifiability id = identifiability(at, x);
  // Independent columns: SE_i = s sqrt(((J^T J)^-1)_ii) with s^2 = |r|^2 / (m - 2).
  Eigen::MatrixXd J2(20, 2);
  J2 << at.J.col(0), at.J.col(3);
  const Eigen::MatrixXd C = (J2.transpose() * J2).inverse();
  const double s = std::sqrt(at.r.squaredNorm() / 18.0);
  CHECK(id.rank == 2);
  CHECK(id.parameters[0].standard_error == Approx(s * std::sqrt(C(0, 0))).epsilon(1e-9));
  CHECK(id.parameters[3].standard_error == Approx(s * std::sqrt(C(1, 1))).epsilon(1e-9));
  CHECK(std::isinf(id.parameters[1].standard_error));
  CHECK(id.parameters[1].structural_zero);
  // Proportional columns, J_L0 = -(k / L0) J_k (the drape's exact law): rank 1, k and L0 each
  // undetermined, correlation +1, but k / L0 determined.
  at.J.col(3) = -(x[0] / x[3]) * at.J.col(0);
  id = identifiability(at, x);
  CHECK(id.rank == 1);
  CHECK(std::isinf(id.parameters[0].standard_error));
  CHECK(std::isinf(id.parameters[3].standard_error));
  CHECK(std::isfinite(id.parameters[0].conditional_standard_error));
  CHECK(id.correlation_stiffness_length == Approx(1.0).epsilon(1e-12));
  // k / L0 in log coordinates: the column is x_k J_k, so SE = s / |x_k J_k| (s with m - 1).
  const double s1 = std::sqrt(at.r.squaredNorm() / 19.0);
  CHECK(id.ratio_relative_error == Approx(s1 / (x[0] * at.J.col(0).norm())).epsilon(1e-6));
}

TEST_CASE("length_brackets splits the L0 box where n = round(W / L0) jumps", "[lm]") {
  const std::vector<LengthBracket> b = length_brackets(0.5, 0.04, 0.06);
  REQUIRE(b.size() >= 5);
  CHECK(b.back().cells == 8);
  CHECK(b.back().upper == 0.06);
  for (size_t i = 1; i < b.size(); ++i) CHECK(b[i].cells == b[i - 1].cells - 1);
  // Every L0 of the box lies in the bracket of its own n.
  for (int k = 0; k <= 1000; ++k) {
    DrapeParams p;
    p.width = 0.5;
    p.natural_length = 0.04 + 0.02 * k / 1000.0;
    int hits = 0;
    for (const LengthBracket& br : b)
      if (p.natural_length >= br.lower && p.natural_length <= br.upper) {
        ++hits;
        CHECK(br.cells == p.cells());
      }
    CHECK(hits == 1);
  }
}

TEST_CASE("drape LM: noise-free twin recovers k / L0 and the topology in few evaluations",
          "[lm][drape]") {
  // Twin at k = 852, L0 = 0.05 (n = 6 on a 30 cm sheet), topology a.
  std::vector<std::string> sets = {"fabric.width=0.3", "model.stiffness=852",
                                   "model.natural_length=0.05", "model.topology=a"};
  Scene twin = load_scene("four_corner", sets);
  twin.options.rtol = 1e-8;
  const DrapeResult run = run_drape(twin, "cvode-bdf");
  REQUIRE(run.stats.status == RunStatus::Equilibrium);
  TargetScene ts{"four_corner", {}, {}};
  for (const EdgeFit& e : measure_edges(run.grid, run.positions))
    ts.edges.push_back({e.name, TargetKind::Coefficients, {}, e.coefficients, {}, {}});
  DrapeFitOptions fo;
  // L0 within n = 6's bracket (0.3 / 6.5, 0.3 / 5.5] so that one n is in the box.
  fo.bounds.lower[kGeneNaturalLength] = 0.047;
  fo.bounds.upper[kGeneNaturalLength] = 0.054;
  Scene base = load_scene("four_corner", {"fabric.width=0.3"});
  base.options.rtol = 1e-8;
  const DrapeFitProblem problem(base, Target{{ts}}, fo);

  // The residual vector is Eq. 5's: 100 rms(r) = objective().
  const std::vector<double> x = {1000.0, 15.0, 10.0, 0.05, 0.5};
  const DrapeResiduals at = drape_residuals(problem, x);
  REQUIRE(!at.failed);
  CHECK(at.objective == Approx(problem.evaluate(x).objective).epsilon(1e-6));

  DrapeLmOptions o;
  const DrapeLmResult fit = fit_drape_lm(problem, o);
  INFO(fit.message << "; objective " << fit.objective << " %, k " << fit.params.stiffness << ", L0 "
                   << fit.params.natural_length);
  REQUIRE(fit.ok);
  CHECK(fit.params.topology == 'a');
  CHECK(fit.objective < 1e-4);
  const double ratio = fit.params.stiffness / fit.params.natural_length;
  CHECK(std::abs(ratio / (852.0 / 0.05) - 1.0) < 1e-4);
  CHECK(fit.evaluations <= 3 * o.lm.max_evaluations);
  // Damping and the elongation limit are blind (zero columns) and keep their start values.
  CHECK(fit.identifiability.parameters[kGeneDamping].structural_zero);
  CHECK(fit.identifiability.parameters[kGeneElongation].structural_zero);
  CHECK(fit.params.damping == 15.0);
  CHECK(fit.identifiability.correlation_stiffness_length == Approx(1.0).margin(1e-6));
}
