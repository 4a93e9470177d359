// Finite-difference check of a MechanicalSystem's analytic Jacobian da_c/dx (Ceres'
// GradientChecker idea): every column j is compared with the central difference
//   (a_c(x + h_j e_j) - a_c(x - h_j e_j)) / (2 h_j),   h_j = step x max(1, |x_j|),
// entry by entry, with error |analytic - fd| / max(column scale, |analytic|), the column
// scale being max |fd| over the column (the diagonal block dominates each column). Entries
// outside the pattern must be ~0 in the finite differences. O(n) RHS calls: for tests and
// diagnostics, not hot loops.
#pragma once

#include "src/core/mechanical_system.hpp"

namespace knitsim {

struct JacobianCheck {
  double max_relative_error = 0.0;  // over all entries (pattern and outside it)
  int worst_row = -1, worst_col = -1;
  double worst_analytic = 0.0, worst_fd = 0.0;
  bool outside_pattern = false;  // the worst entry is missing from the pattern
};

JacobianCheck check_stiffness_jacobian(const MechanicalSystem& sys, double t, const double* x,
                                       double step = 1e-6);

}  // namespace knitsim
