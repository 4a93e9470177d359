// Equilibrium sensitivities of a drape: how the measured edge coefficients move with the model
// parameters, from one sparse factorisation at the reached equilibrium.
//
// The equilibrium x*(p) of the free particles satisfies F(x*, p) = F_spring + M g = 0 (N), so
//     K dx*/dp = -dF/dp,      K = dF/dx (symmetric 3n x 3n, the model's stiffness pattern with
//                             rows scaled back by the mass: K = M da_c/dx)
// dF/dp comes from the model (SpringNetwork::net_force_tangent, drape_tangent); K is factored
// once by the integrators' symmetric factorisation (solvers/symmetric_factor.hpp: 3 x 3 block
// LDL^T, supernodal LL^T on large grids with an LDL^T fallback). K need not be definite (a
// compressed spring's geometric term is negative), so the factor is LDL^T, not Cholesky; by
// Sylvester's law the signs of D give K's inertia: a stable equilibrium has no positive pivot
// (K negative definite), and the count is reported.
//
// Chain to the measurement (src/measure/measurement.hpp): positions X (all particles; free ones
// dx*/dp, pins from the pin tangent) -> normalised edge points (s, d) (span or hanging rule)
// -> least-squares quartic c = argmin |V(s) c - d| -> coefficients. The fit's derivative is
//     dc = (V^T V)^-1 [ dV^T (d - V c) + V^T (dd - dV c) ],   dV_kj = j s_k^(j-1) ds_k
// applied with the column-pivoted QR of V (never forming V^T V).
//
// Parameters are those of DrapeParameter (drape_grid.hpp), derivatives AT FIXED n: the natural
// length L0 sets n = round(W/L0), which jumps at L0 = W/(n + 1/2); the sensitivity to L0 is the
// derivative inside the current bracket (the whole grid scaled, n held). Consequences, exact at
// fixed n: every length scales with L0, every force with k L0 (springs) or rho_A L0^2 (weight),
// so the normalised edges depend on k and L0 only through k / (rho_A g L0):
//     dc/dL0 = -(k / L0) dc/dk                          (tests/test_sensitivity.cpp checks it)
// and the drape data can determine k / L0, never k and L0 apart (besides the discrete n).
// Damping does not enter F and an inactive elongation limit contributes nothing: their dF/dp is
// exactly zero, so are their sensitivities, and they are reported as `structural_zero`
// (computed, not estimated by finite differences).
//
// Accuracy: dx*/dp is exact at an exact equilibrium; at a static residual r it is off by
// O(r). polish_equilibrium() first takes Newton steps x <- x - K^-1 F to the floor, so the
// sensitivities are as accurate as the factorisation.
//
// Failure modes: a singular K (zero pivot: a mechanism without gravity to hold it) or a Newton
// polish that does not converge is a status, not an exception; wrong sizes throw
// std::invalid_argument.
#pragma once

#include <string>
#include <vector>

#include "models/drape_grid.hpp"
#include "src/measure/measurement.hpp"

namespace knitsim {

// K = dF/dx of the free dofs at (t, x), factored once (LDL^T). Solves K y = b.
class StiffnessFactor {
 public:
  StiffnessFactor(const SpringNetwork& network, double t, const double* x);
  ~StiffnessFactor();
  StiffnessFactor(const StiffnessFactor&) = delete;
  StiffnessFactor& operator=(const StiffnessFactor&) = delete;

  bool ok() const;              // false if the factorisation met a zero pivot
  int positive_pivots() const;  // number of positive eigenvalues of K (0: stable equilibrium)
  int dof() const;
  void solve(const double* b, double* y) const;  // K y = b (b, y of length dof())

 private:
  struct Impl;
  Impl* impl_;
};

struct PolishOptions {
  // Newton steps continue until one makes no progress (the arithmetic floor, 1e-10 .. 1e-12 on
  // the drapes) or max_iterations; Converged if the static residual (docs/equilibrium.md) is then
  // <= tol.
  double tol = 1e-9;             // > 0
  int max_iterations = 8;        // Newton steps; >= 1
  double max_correction = 1e-3;  // m; a larger total |x* - x| means Newton left the branch the
                                 // dynamics reached: rejected (x unchanged); > 0
  void validate() const;         // std::invalid_argument "field = value: range"
};

enum class PolishStatus { Converged, NotConverged, Rejected, SingularStiffness };
const char* to_string(PolishStatus s);

struct PolishSummary {
  PolishStatus status = PolishStatus::NotConverged;
  std::string message;
  int iterations = 0;
  double residual_before = 0.0;  // static residual at the input x
  double residual = 0.0;         // at the output x
  double correction = 0.0;       // max_i |x_out - x_in|, m
};

// Newton on F(x) = 0 from x (free dofs, in/out) at time t. On Rejected or SingularStiffness x
// is left unchanged; NotConverged keeps the best iterate.
PolishSummary polish_equilibrium(const SpringNetwork& network, double t, std::vector<double>& x,
                                 const PolishOptions& options = {});

// The free dofs x (3 per free particle) from all particles' positions.
std::vector<double> free_state(const SpringNetwork& network, const std::vector<Vec3>& positions);

// d(coefficients)/dp of measure_edges(grid, positions) along the position tangent dpositions
// (all particles, pins included), in grid.edges order.
std::vector<EdgeCoefficients> measure_edges_tangent(const DrapeGrid& grid,
                                                    const std::vector<Vec3>& positions,
                                                    const std::vector<Vec3>& dpositions);

enum class SensitivityStatus { Ok, PolishFailed, SingularStiffness };
const char* to_string(SensitivityStatus s);

struct ParameterSensitivity {
  DrapeParameter parameter = DrapeParameter::Stiffness;
  bool structural_zero = false;                 // dF/dp == 0 exactly (damping; inactive limit)
  std::vector<double> dx;                       // dx*/dp, free dofs (m per unit of p)
  std::vector<Vec3> dpositions;                 // all particles, pins included
  std::vector<EdgeCoefficients> dcoefficients;  // per edge (grid.edges order), per unit of p
};

struct DrapeSensitivity {
  SensitivityStatus status = SensitivityStatus::Ok;
  std::string message;
  PolishSummary polish;
  int positive_pivots = 0;                       // K's positive eigenvalues at x* (0 = stable)
  std::vector<double> x;                         // the polished equilibrium (free dofs)
  std::vector<Vec3> positions;                   // all particles at x*
  std::vector<EdgeFit> edges;                    // measure_edges at x*
  std::vector<ParameterSensitivity> parameters;  // in the order asked
};

// Polishes the equilibrium x (free dofs, e.g. free_state of a run's positions at t) of grid,
// measures its edges and computes the sensitivities of the listed parameters.
DrapeSensitivity drape_sensitivity(const DrapeGrid& grid, double t, std::vector<double> x,
                                   const std::vector<DrapeParameter>& parameters,
                                   const PolishOptions& polish = {});

}  // namespace knitsim
