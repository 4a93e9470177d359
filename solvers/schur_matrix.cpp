#include "solvers/schur_matrix.hpp"

#include <algorithm>

namespace knitsim::detail {

Eigen::SparseMatrix<double> schur_matrix(const MechanicalSystem& sys) {
  // The pattern's arrays are Eigen's compressed ColMajor storage as they are (rows sorted).
  const CscPattern& p = sys.stiffness_pattern();
  Eigen::SparseMatrix<double> S(p.rows, p.cols);
  S.resizeNonZeros(p.nnz());
  std::copy(p.colptr.begin(), p.colptr.end(), S.outerIndexPtr());
  std::copy(p.rowind.begin(), p.rowind.end(), S.innerIndexPtr());
  std::fill(S.valuePtr(), S.valuePtr() + p.nnz(), 0.0);
  return S;
}

void fill_schur_values(const MechanicalSystem& sys, double h, const double* ax,
                       Eigen::SparseMatrix<double>& S) {
  const CscPattern& p = sys.stiffness_pattern();
  const auto& m = sys.mass();
  const auto& g = sys.damping_rate();
  double* s = S.valuePtr();
  for (int c = 0; c < p.cols; ++c)
    for (int k = p.colptr[c]; k < p.colptr[c + 1]; ++k) {
      const int i = p.rowind[k];
      s[k] = -h * h * m[i] * ax[k];
      if (i == c) s[k] += m[i] * (1.0 + h * g[i]);
    }
}

}  // namespace knitsim::detail
