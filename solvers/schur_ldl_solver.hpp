// A SUNDIALS linear solver for the Newton systems of implicit integrators on a
// FirstOrderSystem: it eliminates the velocity block and factors a symmetric 3n x 3n matrix
// instead of the unsymmetric 6n x 6n one (SPEC 2.12, "levers").
//
// CVODE and ARKODE (identity mass) build A = I - gamma J in the FirstOrderSystem's CSC pattern
// (src/first_order.hpp), so
//     A = [ I       -gamma I ]      A_vx = -gamma Ax,   A_vv = I + gamma Gamma (diagonal).
//         [ A_vx     A_vv    ]
// gamma is read back from A itself (A(0, n) = -gamma). Solving A [x1; x2] = [b1; b2]:
//     x1 = b1 + gamma x2,
//     M (A_vv + gamma A_vx) x2 = M (b2 - A_vx b1),
// where M (A_vv + gamma A_vx) = M (I + gamma Gamma) - gamma^2 K, K = M Ax = dF/dx symmetric.
// This reduced matrix has the model's stiffness pattern; it is analysed once (AMD ordering,
// Eigen SimplicialLDLT) and factorised numerically at each setup. LDL^T, not LL^T: K is
// indefinite when springs are compressed.
//
// Requirements: A is the SUNMatrix that CVODE/ARKODE hold, a CSC sparse matrix with exactly
// FirstOrderSystem::jacobian_pattern() (SUNMatScaleAddI keeps it since every diagonal entry is
// present). Setup returns SUNLS_PACKAGE_FAIL_REC (recoverable) if the factorisation fails, so
// the integrator retries with a smaller step.
#pragma once

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#include "src/first_order.hpp"

namespace knitsim::detail {

// The returned solver owns its workspace; free it with SUNLinSolFree. `sys` must outlive it.
SUNLinearSolver make_schur_ldl_solver(SUNContext ctx, const FirstOrderSystem& sys);

}  // namespace knitsim::detail
