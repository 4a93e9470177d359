#include "src/core/first_order.hpp"

#include <algorithm>

namespace knitsim {

double MechanicalSystem::kinetic_energy(const double* v) const {
  const auto& m = mass();
  double e = 0.0;
  for (int i = 0; i < dof(); ++i) e += 0.5 * m[i] * v[i] * v[i];
  return e;
}

void MechanicalSystem::constant_acceleration(double /*t*/, double* a) const {
  std::fill(a, a + dof(), 0.0);
}

FirstOrderSystem::FirstOrderSystem(const MechanicalSystem& sys) : sys_(sys), n_(sys.dof()) {
  const CscPattern& ax = sys_.stiffness_pattern();
  const int n = n_;
  pattern_.rows = pattern_.cols = 2 * n;
  pattern_.colptr.assign(2 * n + 1, 0);
  pattern_.rowind.reserve(n + ax.nnz() + 2 * n);
  ax_offset_.resize(n);
  for (int j = 0; j < n; ++j) {
    pattern_.rowind.push_back(j);  // explicit zero diagonal of the top-left block
    ax_offset_[j] = static_cast<int>(pattern_.rowind.size());
    for (int k = ax.colptr[j]; k < ax.colptr[j + 1]; ++k) pattern_.rowind.push_back(n + ax.rowind[k]);
    pattern_.colptr[j + 1] = static_cast<int>(pattern_.rowind.size());
  }
  for (int j = 0; j < n; ++j) {
    pattern_.rowind.push_back(j);      // identity block
    pattern_.rowind.push_back(n + j);  // -gamma diagonal
    pattern_.colptr[n + j + 1] = static_cast<int>(pattern_.rowind.size());
  }
  ax_values_.resize(ax.nnz());
}

void FirstOrderSystem::rhs(double t, const double* y, double* ydot) const {
  const int n = n_;
  const double* x = y;
  const double* v = y + n;
  std::copy(v, v + n, ydot);
  double* a = ydot + n;
  sys_.conservative_acceleration(t, x, a);
  const auto& gamma = sys_.damping_rate();
  for (int i = 0; i < n; ++i) a[i] -= gamma[i] * v[i];
}

void FirstOrderSystem::jacobian_values(double t, const double* y, double* values) const {
  const int n = n_;
  const CscPattern& ax = sys_.stiffness_pattern();
  sys_.stiffness_values(t, y, ax_values_.data());
  const auto& gamma = sys_.damping_rate();
  for (int j = 0; j < n; ++j) {
    int k = pattern_.colptr[j];
    values[k] = 0.0;
    const int len = ax.colptr[j + 1] - ax.colptr[j];
    std::copy_n(ax_values_.data() + ax.colptr[j], len, values + ax_offset_[j]);
  }
  for (int j = 0; j < n; ++j) {
    const int k = pattern_.colptr[n + j];
    values[k] = 1.0;
    values[k + 1] = -gamma[j];
  }
}

}  // namespace knitsim
