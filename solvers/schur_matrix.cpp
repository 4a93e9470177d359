#include "solvers/schur_matrix.hpp"

#include <vector>

namespace knitsim::detail {

Eigen::SparseMatrix<double> schur_matrix(const MechanicalSystem& sys) {
  const CscPattern& p = sys.stiffness_pattern();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(p.nnz());
  for (int c = 0; c < p.cols; ++c)
    for (int k = p.colptr[c]; k < p.colptr[c + 1]; ++k) entries.emplace_back(p.rowind[k], c, 0.0);
  Eigen::SparseMatrix<double> S(p.rows, p.cols);
  S.setFromTriplets(entries.begin(), entries.end());
  S.makeCompressed();
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
