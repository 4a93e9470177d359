#include "src/core/jacobian_check.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace knitsim {

JacobianCheck check_stiffness_jacobian(const MechanicalSystem& sys, double t, const double* x,
                                       double step) {
  const int n = sys.dof();
  const CscPattern& p = sys.stiffness_pattern();
  std::vector<double> analytic(p.nnz());
  sys.stiffness_values(t, x, analytic.data());

  std::vector<double> xp(x, x + n), ap(n), am(n);
  std::vector<double> fd(static_cast<size_t>(n) * n);  // column-major dense
  std::vector<double> col_scale(n, 0.0);
  for (int j = 0; j < n; ++j) {
    const double h = step * std::max(1.0, std::abs(x[j]));
    xp[j] = x[j] + h;
    sys.conservative_acceleration(t, xp.data(), ap.data());
    xp[j] = x[j] - h;
    sys.conservative_acceleration(t, xp.data(), am.data());
    xp[j] = x[j];
    for (int i = 0; i < n; ++i) {
      const double d = (ap[i] - am[i]) / (2.0 * h);
      fd[static_cast<size_t>(j) * n + i] = d;
      col_scale[j] = std::max(col_scale[j], std::abs(d));
    }
  }
  JacobianCheck r;
  auto consider = [&](int i, int j, double a, bool in_pattern) {
    const double f = fd[static_cast<size_t>(j) * n + i];
    const double scale = std::max({col_scale[j], std::abs(a), 1e-300});
    const double err = std::abs(a - f) / scale;
    if (err > r.max_relative_error || r.worst_row < 0) {
      r = {err, i, j, a, f, !in_pattern};
    }
  };
  for (int j = 0; j < n; ++j) {
    int k = p.colptr[j];
    for (int i = 0; i < n; ++i) {
      if (k < p.colptr[j + 1] && p.rowind[k] == i) {
        consider(i, j, analytic[k], true);
        ++k;
      } else {
        consider(i, j, 0.0, false);
      }
    }
  }
  return r;
}

}  // namespace knitsim
