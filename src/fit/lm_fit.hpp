// Levenberg-Marquardt fit of the drape model with analytic equilibrium sensitivities, and the
// Gauss-Newton identifiability analysis at its optimum.
//
// Residuals (paper 1 Eq. 5, docs/fitting.md): r = P_measured - P_simulated over the measured edges
// (in the target's edge order) x the 5 coefficients p0..p4, so the error is E = 100 rms(r) (the
// value objective() returns). Jacobian J = -dP_simulated/dp from src/fit/sensitivity.hpp (one
// LDL^T of K per evaluation, negligible next to the drape run).
//
// Parameters: the four continuous genes of src/fit/drape_fit.hpp, x = [k, c, eps, L0] (DrapeGene
// order and units) in the box of DrapeFitBounds. The data see k and L0 only through k / L0 at
// a fixed grid size n = round(W / L0) (src/fit/sensitivity.hpp), and n jumps inside the box (n = 8
// .. 12 for W = 50 cm and L0 4-6 cm), so the search is over the categorical topology x the n
// bracket, and a smooth 1-D valley inside each:
//   1. Screening: one evaluation per (topology in the bounds, n bracket in the box) at the box
//      centre for k, c, eps and the bracket's middle L0 (plus starts_per_bracket - 1 seeded
//      random k); each is ranked by its Gauss-Newton prediction of the minimum, 100 rms(r + J
//      delta) with the (lambda -> 0, box-clipped) step delta from that point.
//   2. Refinement: LM from the `refine` best screened starts, L0 bounded to the start's n
//      bracket (the objective is smooth there), re-using the screening evaluation.
//   Drape evaluations = screened starts + the refinements' further trial points.
// Algorithm (hand-written, dense: 4 parameters and 20 residuals do not need Ceres): in
// unit-box coordinates u = (x - lower)/(upper - lower), the step solves
//     (J_u^T J_u + lambda I) delta = -J_u^T r     over the free coordinates
// (a coordinate at a bound whose gradient points outward is held); the trial point is clipped
// to the box. Gain ratio rho = actual / predicted decrease of |r|^2/2; accepted if rho > 1e-3;
// lambda updated as Nielsen (1999): x max(1/3, 1 - (2 rho - 1)^3) on success, x nu (nu doubling)
// on failure. Levenberg's lambda I (not Marquardt's diag(J^T J)) in the unit box, because
// columns that are exactly zero (damping; an inactive elongation limit: src/fit/sensitivity.hpp)
// must simply receive a zero step. Stops on a small step (|delta|_inf <= step_tol), a small
// relative decrease of |r|^2 (<= cost_tol), or the evaluation cap. Each trial point is one
// drape evaluation (a full run from the flat state, DrapeFitProblem's integrator and options;
// then a Newton polish, the residuals and J); a failed run (not Equilibrium, polish rejected)
// counts as a rejected step.
//
// Identifiability (Gauss-Newton, at the optimum): with relative columns Jr_i = x_i dr/dx_i,
// A = Jr^T Jr over the parameters with a non-zero column, s^2 = |r|^2 / (m - rank):
//   standard error of x_i  = x_i s sqrt((A^+)_ii), infinite when x_i has a component in a
//                            numerically null direction (eigenvalue <= 1e-10 lambda_max);
//   conditional SE         = x_i s / sqrt(A_ii) (x_i alone, the others known);
//   correlation(k, L0)     = -A_kL / sqrt(A_kk A_LL) (of the two estimates);
//   k / L0                 relative SE s sqrt(w^T A^+ w), w = e_k - e_L0 (in log coordinates).
// Structurally zero columns (damping; inactive limit) are reported as not identifiable.
//
// Failure modes: bad options throw std::invalid_argument naming the field; evaluation failures
// are counted, and a start whose first point fails is status StartFailed.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <cstdint>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "src/fit/drape_fit.hpp"
#include "src/fit/sensitivity.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/fit_options.hpp"

namespace knitsim {

// A box-bounded least-squares problem: evaluate(x, r, J) fills the residuals (m) and the
// Jacobian dr/dx (m x p) and returns false for a failed evaluation.
struct LmProblem {
  std::vector<double> lower, upper;
  std::function<bool(const std::vector<double>& x, Eigen::VectorXd& r, Eigen::MatrixXd& J)>
      evaluate;
};

enum class LmStatus { StepTolerance, CostTolerance, EvaluationLimit, StartFailed };
const char* to_string(LmStatus s);

struct LmResult {
  LmStatus status = LmStatus::StartFailed;
  std::string message;
  std::vector<double> x;  // best point
  double cost = 0.0;      // |r|^2 / 2 at x
  Eigen::VectorXd r;      // at x
  Eigen::MatrixXd J;      // at x
  int accepted_steps = 0;
  int evaluations = 0;
  int failed_evaluations = 0;
};

// Runs LM from x0 (clipped to the box; a coordinate with lower == upper is held). Throws
// std::invalid_argument for lower > upper or mismatched sizes.
LmResult run_lm(const LmProblem& problem, std::vector<double> x0, const LmOptions& options);

// --- the drape fit ---------------------------------------------------------------------------

constexpr int kDrapeContinuous = 4;  // k, c, eps, L0 (DrapeGene order)

// Residuals and Jacobian of one parameter set (x: kDrapeGenes values, a country).
struct DrapeResiduals {
  bool failed = true;
  std::string message;
  double objective = 0.0;  // 100 rms(r), percent
  Eigen::VectorXd r;       // measured - simulated coefficients
  Eigen::MatrixXd J;       // dr/d[k, c, eps, L0], m x 4
  std::array<bool, kDrapeContinuous> structural_zero{};
  int positive_pivots = 0;                              // of K at the equilibrium (0 = stable)
  double residual_before_polish = 0.0, residual = 0.0;  // static residuals
  double cpu_seconds = 0.0;                             // drape run + sensitivities
};
DrapeResiduals drape_residuals(const DrapeFitProblem& problem, const std::vector<double>& x,
                               const PolishOptions& polish = {});

struct ParameterIdentifiability {
  bool structural_zero = false;
  double value = 0.0;
  double standard_error = 0.0;              // +inf: not determined by the data
  double conditional_standard_error = 0.0;  // +inf for a zero column
};

struct DrapeIdentifiability {
  std::array<ParameterIdentifiability, kDrapeContinuous> parameters;  // k, c, eps, L0
  double condition_number = 0.0;  // of A over the non-zero columns (+inf if singular)
  double correlation_stiffness_length = 0.0;
  double ratio_relative_error = 0.0;  // relative SE of k / L0
  double sigma = 0.0;                 // s, residual standard deviation
  int residuals = 0, rank = 0;
};
DrapeIdentifiability identifiability(const DrapeResiduals& at, const std::vector<double>& x);

// The starts' budget (starts_per_bracket, refine: LmStartOptions, src/scene/fit_options.hpp).
struct DrapeLmOptions : LmStartOptions {
  LmOptions lm;
  std::uint64_t seed = 1;
  PolishOptions polish;
  // Optional: called on the calling thread after every drape evaluation, in order, with the
  // country and its residuals (experiments/optimizers logs the search with it). An exception
  // it throws ends the fit and propagates.
  std::function<void(const std::vector<double>& x, const DrapeResiduals& e)> on_evaluation;
  void validate() const;
};

struct DrapeLmStart {
  char topology = 'a';
  int cells = 0;           // n of the start's bracket
  std::vector<double> x0;  // country (kDrapeGenes values)
  double screened = 0.0;   // objective at x0 (NaN if it failed)
  double predicted = 0.0;  // Gauss-Newton predicted minimum from x0
  bool refined = false;
  LmResult lm;             // refined: over the 4 continuous genes
  double objective = 0.0;  // refined: 100 rms(r) at lm.x; else = screened
  std::vector<double> x;   // refined: country at lm.x; else x0
};

struct DrapeLmResult {
  bool ok = false;  // at least one start evaluated
  std::string message;
  std::vector<double> best_x;  // country (kDrapeGenes values)
  DrapeParams params;
  double objective = 0.0;  // percent
  long evaluations = 0, failed_evaluations = 0;
  std::vector<DrapeLmStart> starts;
  DrapeIdentifiability identifiability;
  double wall_seconds = 0.0, cpu_seconds = 0.0;
};

// The L0 intervals of constant n = round(width / L0) inside [lower, upper], by decreasing n,
// closed, with cells() == n at both ends (a bracket may be one point, e.g. n = 13 at exactly
// L0 = 4 cm for W = 50 cm).
struct LengthBracket {
  int cells = 0;
  double lower = 0.0, upper = 0.0;  // m
};
std::vector<LengthBracket> length_brackets(double width, double lower, double upper);

// Screened multi-start LM (see above) over the topologies allowed by problem.options().bounds.
DrapeLmResult fit_drape_lm(const DrapeFitProblem& problem, const DrapeLmOptions& options);

// The options as the fit's manifest and checkpoint record them (field names as in
// DrapeLmOptions, the LM budget flattened).
nlohmann::json to_json(const DrapeLmOptions& o);

}  // namespace knitsim
