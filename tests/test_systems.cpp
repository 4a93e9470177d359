#include "tests/test_systems.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace knitsim::test {

SpringNetworkSpec build_chain(const ChainParams& p) {
  if (p.particles < 1) throw std::invalid_argument("build_chain: particles must be >= 1");
  const int n = p.particles;
  const double spacing = (1.0 + p.stretch) * p.rest;
  const double pi = std::acos(-1.0);
  SpringNetworkSpec spec;
  // Particle 0 is the pin, 1..n are free, n+1 the far pin if any.
  const int total = n + 1 + (p.far_pin ? 1 : 0);
  for (int i = 0; i < total; ++i) {
    Vec3 pos = (i * spacing) * p.direction;
    if (i >= 1 && i <= n) pos = pos + (p.pluck * std::sin(pi * i / (n + 1))) * p.pluck_axis;
    spec.positions.push_back(pos);
    spec.masses.push_back(p.mass);
    if (i > 0) spec.springs.push_back({i - 1, i, p.rest, p.stiffness});
  }
  spec.pinned.push_back(0);
  spec.pin_paths.push_back({spec.positions[0], spec.positions[0], 0.0});
  if (p.far_pin) {
    spec.pinned.push_back(n + 1);
    spec.pin_paths.push_back({spec.positions[n + 1], spec.positions[n + 1], 0.0});
  }
  spec.damping = p.damping;
  if (!p.gravity) {
    spec.gravity = {0.0, 0.0, 0.0};
    spec.residual_force_scale = 1.0;
  }
  return spec;
}

SpringNetworkSpec isotropic_oscillator(double mass, double stiffness, double rest, double damping,
                                       double displacement) {
  SpringNetworkSpec spec;
  spec.positions = {{displacement, 0, 0}};
  spec.masses = {mass};
  for (const Vec3 pin : {Vec3{rest, 0, 0}, Vec3{-rest, 0, 0}, Vec3{0, rest, 0}, Vec3{0, -rest, 0},
                         Vec3{0, 0, rest}, Vec3{0, 0, -rest}}) {
    const int index = static_cast<int>(spec.positions.size());
    spec.positions.push_back(pin);
    spec.masses.push_back(mass);
    spec.springs.push_back({0, index, rest, stiffness});
    spec.pinned.push_back(index);
    spec.pin_paths.push_back({pin, pin, 0.0});
  }
  spec.damping = damping;
  spec.gravity = {0.0, 0.0, 0.0};
  spec.residual_force_scale = 1.0;
  return spec;
}

void NanAccelerationSystem::conservative_acceleration(double /*t*/, const double* /*x*/,
                                                      double* a) const {
  std::fill(a, a + dof(), std::numeric_limits<double>::quiet_NaN());
}

double NanAccelerationSystem::static_residual(double /*t*/, const double* /*x*/) const {
  return std::numeric_limits<double>::quiet_NaN();
}

std::string advance_to(Integrator& integ, double t_end, const std::function<void()>& after_step) {
  while (integ.time() < t_end) {
    const double t_before = integ.time();
    const Integrator::Step st = integ.step(t_end);
    if (!st.ok) return st.message.empty() ? "step failed" : st.message;
    if (!(integ.time() > t_before)) return "step made no progress in time";
    if (after_step) after_step();
  }
  return "";
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) throw std::invalid_argument("max_abs_difference: sizes differ");
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double d = std::abs(a[i] - b[i]);
    if (!(d <= worst)) worst = d;  // NaN propagates
  }
  return worst;
}

double total_energy(const MechanicalSystem& sys, double t, const double* x, const double* v) {
  return sys.kinetic_energy(v) + sys.potential_energy(t, x);
}

double equilibrium_distance_bound(const SpringNetwork& net, double t, const std::vector<double>& x,
                                  double residual) {
  const int n = net.dof();
  if (static_cast<int>(x.size()) != n)
    throw std::invalid_argument("equilibrium_distance_bound: state size does not match");
  // K = -M da_c/dx, symmetrised (the spring forces are conservative: it is symmetric up to
  // rounding).
  const CscPattern& p = net.stiffness_pattern();
  std::vector<double> values(p.nnz());
  net.stiffness_values(t, x.data(), values.data());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
  for (int c = 0; c < n; ++c)
    for (int k = p.colptr[c]; k < p.colptr[c + 1]; ++k)
      K(p.rowind[k], c) = -net.mass()[p.rowind[k]] * values[k];
  K = 0.5 * (K + K.transpose()).eval();
  const double lambda_min =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K, Eigen::EigenvaluesOnly)
          .eigenvalues()
          .minCoeff();
  if (!(lambda_min > 0.0))
    throw std::runtime_error("equilibrium_distance_bound: K is not positive definite (lambda_min " +
                             std::to_string(lambda_min) + " N/m)");
  const double particles = n / 3;
  return std::sqrt(particles) * residual * net.residual_force_scale() / lambda_min;
}

double settled_distance_bound(const SpringNetwork& net, double ta, const std::vector<double>& xa,
                              double tb, const std::vector<double>& xb, double equilibrium_tol) {
  // The residual each run stopped at: below the threshold, or above it where the stop in
  // positions ended the run first (solvers/equilibrium_check.hpp).
  const double ra = std::max(equilibrium_threshold(net, ta, xa.data(), equilibrium_tol),
                             net.static_residual(ta, xa.data()));
  const double rb = std::max(equilibrium_threshold(net, tb, xb.data(), equilibrium_tol),
                             net.static_residual(tb, xb.data()));
  return equilibrium_distance_bound(net, tb, xb, ra + rb);  // linear in the residual
}

}  // namespace knitsim::test
