// The reduced (Schur-complement) Newton matrix of a MechanicalSystem, in its stiffness pattern:
//     S = M (I + h Gamma) - h^2 K,   K = M Ax  (Ax = stiffness_values: row i of K over m_i),
// symmetric since K is. implicit-euler factors it with h = dt, and cvode-bdf-gmres's Schur
// preconditioners with h = CVODE's gamma (solvers/cvode.cpp).
#pragma once

#include <Eigen/SparseCore>

#include "src/core/mechanical_system.hpp"

namespace knitsim::detail {

// An n x n matrix with exactly sys.stiffness_pattern() (Eigen's compressed columns hold the
// same sorted rows, so its value array is in the pattern's order); values zero.
Eigen::SparseMatrix<double> schur_matrix(const MechanicalSystem& sys);

// Writes S's values for step factor h, from `ax` (stiffness_values, the pattern's order).
void fill_schur_values(const MechanicalSystem& sys, double h, const double* ax,
                       Eigen::SparseMatrix<double>& S);

}  // namespace knitsim::detail
