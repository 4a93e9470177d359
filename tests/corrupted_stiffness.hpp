// A deliberately wrong Jacobian for the tests of the finite-difference check (Ceres tests its
// gradient checker the same way): a system that forwards everything to `s` but multiplies some
// of its stiffness values by `factor`. The check must catch it.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "src/core/mechanical_system.hpp"
#include "src/core/sparse.hpp"

namespace knitsim::test {

class CorruptedStiffness final : public MechanicalSystem {
 public:
  // `entries`: indices into stiffness_values' array (positions in the CSC pattern).
  CorruptedStiffness(const MechanicalSystem& s, std::vector<int> entries, double factor = 1.01)
      : s_(s), entries_(std::move(entries)), factor_(factor) {}
  int dof() const override { return s_.dof(); }
  void initial_state(double* x, double* v) const override { s_.initial_state(x, v); }
  void conservative_acceleration(double t, const double* x, double* a) const override {
    s_.conservative_acceleration(t, x, a);
  }
  const std::vector<double>& damping_rate() const override { return s_.damping_rate(); }
  const std::vector<double>& mass() const override { return s_.mass(); }
  const CscPattern& stiffness_pattern() const override { return s_.stiffness_pattern(); }
  void stiffness_values(double t, const double* x, double* values) const override {
    s_.stiffness_values(t, x, values);
    for (int k : entries_) values[k] *= factor_;
  }
  double static_residual(double t, const double* x) const override {
    return s_.static_residual(t, x);
  }
  double potential_energy(double t, const double* x) const override {
    return s_.potential_energy(t, x);
  }
  std::string describe() const override { return "corrupted: " + s_.describe(); }

 private:
  const MechanicalSystem& s_;
  std::vector<int> entries_;
  double factor_;
};

// The entries of the 3 x 3 block of free particles (r, c) in `pattern`.
inline std::vector<int> block_entries(const CscPattern& pattern, int r, int c) {
  std::vector<int> e;
  for (int p = 0; p < 3; ++p)
    for (int q = 0; q < 3; ++q) e.push_back(pattern.find(3 * r + p, 3 * c + q));
  return e;
}

}  // namespace knitsim::test
