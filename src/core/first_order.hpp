// First-order form y' = f(t, y) of a MechanicalSystem, with its sparse Jacobian.
//
// State layout: y = [x (n); v (n)], size 2n.
//     f(t, y) = [ v ; a_c(t, x) - Gamma v ]
//     J = df/dy = [ 0      I      ]
//                 [ Ax   -Gamma   ]      Ax = da_c/dx (stiffness pattern)
//
// The CSC pattern of J is built once. Column j < n (an x column) holds the explicit zero
// diagonal entry (j, j) followed by Ax's column j shifted down by n; column n + j (a v column)
// holds (j, n + j) = 1 and the diagonal (n + j, n + j) = -gamma_j. Every diagonal is present.
#pragma once

#include <vector>

#include "src/core/mechanical_system.hpp"
#include "src/core/sparse.hpp"

namespace knitsim {

class FirstOrderSystem {
 public:
  explicit FirstOrderSystem(const MechanicalSystem& sys);

  int size() const { return 2 * n_; }
  const MechanicalSystem& mechanical() const { return sys_; }

  void rhs(double t, const double* y, double* ydot) const;

  const CscPattern& jacobian_pattern() const { return pattern_; }
  // J values in jacobian_pattern() order.
  void jacobian_values(double t, const double* y, double* values) const;

 private:
  const MechanicalSystem& sys_;
  int n_;
  CscPattern pattern_;
  std::vector<int> ax_offset_;  // for column j < n: where Ax's column j starts in values
  mutable std::vector<double> ax_values_;
};

}  // namespace knitsim
