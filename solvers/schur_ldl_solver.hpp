// A SUNDIALS linear solver for the Newton systems of implicit integrators on a
// FirstOrderSystem: it eliminates the velocity block and factors a symmetric 3n x 3n matrix
// instead of the unsymmetric 6n x 6n one (docs/numerics.md, "Linear algebra").
//
// CVODE and ARKODE (identity mass) build A = I - gamma J in the FirstOrderSystem's CSC pattern
// (src/core/first_order.hpp), so
//     A = [ I       -gamma I ]      A_vx = -gamma Ax,   A_vv = I + gamma Gamma (diagonal).
//         [ A_vx     A_vv    ]
// gamma is read back from A itself (A(0, n) = -gamma). Solving A [x1; x2] = [b1; b2]:
//     x1 = b1 + gamma x2,
//     M (A_vv + gamma A_vx) x2 = M (b2 - A_vx b1),
// where M (A_vv + gamma A_vx) = M (I + gamma Gamma) - gamma^2 K, K = M Ax = dF/dx symmetric.
// This reduced matrix has the model's stiffness pattern; it is analysed once and factorised
// numerically at each setup by a SymmetricFactor (symmetric_factor.hpp: a 3 x 3 block or scalar
// LDL^T, or CHOLMOD's supernodal LL^T on large grids with LDL^T where S is not positive
// definite -- K is indefinite when springs are compressed).
//
// Small steps: Jacobi-preconditioned CG instead of the factorisation. When gamma is small
// the reduced matrix S = M (I + gamma Gamma) - gamma^2 K is close to its diagonal (S ~ M
// for gamma^2 omega_max^2 << 1), and a few conjugate-gradient iterations solve it for a
// fraction of one LDL^T factorisation. At each setup the Gershgorin radius rho of D^-1 S
// (D = diag S) is computed; if every S_jj > 0 and rho <= SchurOptions::cg_max_radius < 1, the
// spectrum of D^-1 S lies in [1 - rho, 1 + rho] (condition number <= (1 + rho) / (1 - rho)),
// the factorisation is deferred, and each solve runs CG from zero until the relative error in
// the D norm is provably <= cg_rel_tol (from the residual and that spectrum bound). If CG
// breaks down or needs more than cg_max_iterations, S is factorised there and then, and LDL^T
// serves this setup's remaining solves. Every solve is exact to cg_rel_tol = 1e-6 in that
// norm; the Newton iteration it serves converges with far less (inexact Newton needs ~1e-2),
// and random two_corner drapes at rtol 1e-8 stop at equilibrium as often as with LDL^T
// (experiments/benchmark/stops.sh). The bound is on the error, not the residual: at large
// steps S is stiffness-dominated and ill-conditioned, and a small residual can hide a large
// error (experiments/benchmark/README.md, "Stops inside the fit box"). The steps taken match
// the LDL^T path's on four_corner (tests/test_schur_ldl.cpp); where CVODE's step control sits
// on a knife edge they can drift by a few steps (tests/test_knit.cpp).
// It pays on the knit model's ringing phase, where CVODE takes hundreds of microsecond steps
// (experiments/benchmark/README.md, "Newton solver `cg-ldl`"). On drapes most steps are large,
// the radius test fails, and the added cost is one pass over S per setup.
//
// Requirements: A is the SUNMatrix that CVODE/ARKODE hold, a CSC sparse matrix with exactly
// FirstOrderSystem::jacobian_pattern() (SUNMatScaleAddI keeps it since every diagonal entry is
// present). Setup returns SUNLS_PACKAGE_FAIL_REC (recoverable) if the factorisation fails, so
// the integrator retries with a smaller step.
#pragma once

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#include "solvers/integrator.hpp"
#include "solvers/symmetric_factor.hpp"
#include "src/core/first_order.hpp"

namespace knitsim::detail {

struct SchurOptions {
  // CG is tried when max_j sum_{i != j} |S_ij| / S_jj <= cg_max_radius (in [0, 1); 0 = LDL^T
  // only); at 0.8 the condition number of D^-1 S is <= 9 and CG gains ~1 digit per 3 steps.
  double cg_max_radius = 0.8;
  int cg_max_iterations = 40;  // per solve, then LDL^T
  double cg_rel_tol = 1e-6;    // bound on |x - x_cg|_D / |x|_D
  IntegratorOptions::Factorization factorization = IntegratorOptions::Factorization::Automatic;
  // The right-hand side's product A_vx b1 particle by particle where each particle's three
  // columns share one row list (spring networks), else column by column: the same sums bit for
  // bit, one pass over the rows instead of three (false: always column by column; for tests).
  bool node_columns = true;
};

// Work done since creation.
struct SchurCounts {
  long setups = 0;
  long factorisations = 0;  // numeric factorisations of S
  // The back end, its LDL^T fallbacks and its cost: schur_factor(LS).
  long cg_solves = 0;      // solves finished by CG
  long cg_iterations = 0;  // CG iterations, including those of solves CG gave up on
  bool node_columns = false;  // the right-hand side's product is taken particle by particle
};

// The returned solver owns its workspace; free it with SUNLinSolFree. `sys` must outlive it.
SUNLinearSolver make_schur_ldl_solver(SUNContext ctx, const FirstOrderSystem& sys,
                                      const SchurOptions& options = {});

// True if LS was made by make_schur_ldl_solver (it is SUNLINEARSOLVER_CUSTOM, like any
// user-supplied solver, so the ID alone cannot tell).
bool is_schur_ldl_solver(SUNLinearSolver LS);

// Counts of a solver made by make_schur_ldl_solver.
SchurCounts schur_counts(SUNLinearSolver LS);

// The factorisation of S inside a solver made by make_schur_ldl_solver.
const SymmetricFactor& schur_factor(SUNLinearSolver LS);

}  // namespace knitsim::detail
