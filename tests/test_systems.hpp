// Reusable test systems and helpers for the integrator tests (Drake's test-utilities idea):
// small spring networks with known answers, a system that fails on purpose, and a stepping
// loop over the Integrator interface.
//
// Chains (build_chain): `particles` free particles of mass m joined in a line by springs
// (k, L0) to a pin at the origin, the i-th (i = 1..N) starting at i (1 + stretch) L0 along the
// unit vector `direction`, at rest. Dof layout: particle i-1 owns x[3(i-1) .. 3(i-1)+2].
//   - hanging mass:   N = 1, direction -z, gravity on. Static stretch m g / k (closed form).
//   - hanging chain:  N > 1, gravity on; at rest the spring j (j = 1 at the pin) carries the
//                     weight (N - j + 1) m g below it, stretch (N - j + 1) m g / k.
//   - taut string:    far_pin = true adds a pin at (N + 1)(1 + stretch) L0 along `direction`
//                     joined to particle N; without gravity, a plucked string (pluck: the
//                     i-th particle is displaced by pluck sin(pi i / (N + 1)) along `pluck_axis`).
// Without gravity the static residual needs a force scale: residual_force_scale = 1 N.
//
// Isotropic oscillator (isotropic_oscillator): one free particle of mass m at rest at the
// origin, joined by six springs (k, L0) to pins at +-L0 on each axis, released at rest from
// `displacement` along x; no gravity. At rest da_c/dx = -(2k/m) I exactly, so every dof has
// omega^2 = 2k/m and gamma = c/m, and the Gershgorin bound of predict_stable_dt is exact. By
// symmetry the motion stays on the x axis, where the two x springs give the exactly linear
// force -2k x and the four others a cubic correction of relative size (x/L0)^2.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "models/spring_network.hpp"
#include "solvers/integrator.hpp"
#include "src/core/vec3.hpp"

namespace knitsim::test {

struct ChainParams {
  int particles = 1;         // N free particles, >= 1
  double mass = 0.1;         // m per particle, kg
  double stiffness = 100.0;  // k, N/m
  double rest = 0.1;         // L0, m
  double damping = 0.0;      // c per particle, N s/m (gamma = c/m)
  Vec3 direction{0, 0, -1};  // unit vector along which the chain starts from the pin
  double stretch = 0.0;      // initial strain of every spring (fraction)
  bool far_pin = false;      // pin the far end as well (taut string)
  double pluck = 0.0;        // transverse sine displacement amplitude, m
  Vec3 pluck_axis{0, 0, 1};  // its direction (unit, normal to `direction`)
  bool gravity = true;       // g = 9.81 m/s^2 along -z; off: residual_force_scale = 1 N
};

SpringNetworkSpec build_chain(const ChainParams& p);

SpringNetworkSpec isotropic_oscillator(double mass, double stiffness, double rest, double damping,
                                       double displacement);

// A wrapped system whose acceleration is NaN everywhere (everything else delegated): every
// integrator must report it as a status (Diverged / SolverFailure), never throw.
class NanAccelerationSystem final : public MechanicalSystem {
 public:
  explicit NanAccelerationSystem(const MechanicalSystem& base) : base_(base) {}
  int dof() const override { return base_.dof(); }
  void initial_state(double* x, double* v) const override { base_.initial_state(x, v); }
  void conservative_acceleration(double t, const double* x, double* a) const override;
  const std::vector<double>& damping_rate() const override { return base_.damping_rate(); }
  const std::vector<double>& mass() const override { return base_.mass(); }
  const CscPattern& stiffness_pattern() const override { return base_.stiffness_pattern(); }
  void stiffness_values(double t, const double* x, double* values) const override {
    base_.stiffness_values(t, x, values);
  }
  double static_residual(double t, const double* x) const override;
  double potential_energy(double t, const double* x) const override {
    return base_.potential_energy(t, x);
  }
  std::string describe() const override { return "NaN acceleration around " + base_.describe(); }

 private:
  const MechanicalSystem& base_;
};

// Steps a started integrator with step(t_end) until time() == t_end, calling after_step (if
// set) after each step; returns the failed step's message (or "step made no progress in
// time"), "" on success. The fixed-step methods take about t_end / dt steps, the last one
// possibly shortened (or an extra round-off-sized one).
std::string advance_to(Integrator& integ, double t_end,
                       const std::function<void()>& after_step = nullptr);

// max_i |a_i - b_i| (vectors of equal length).
double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b);

// Kinetic + potential energy (J) of sys at (t, x, v).
double total_energy(const MechanicalSystem& sys, double t, const double* x, const double* v);

// How far (m, max norm, to first order) a state of `net` whose static residual is at most
// `residual` can lie from the exact equilibrium at x: the net force on each of the p free
// particles is at most residual x F_ref (docs/equilibrium.md), so |F|_2 <= sqrt(p) residual F_ref, and
// the state is dx = K^-1 F away, K = -dF/dx the springs' tangent stiffness at x (symmetric
// positive definite at a stable equilibrium):
//   |dx|_inf <= |dx|_2 <= sqrt(p) residual F_ref / lambda_min(K).
// This is what the stop criterion guarantees, whatever the integrator: two runs that stopped
// at residuals r1 and r2 are within bound(r1) + bound(r2) of each other. Dense (Eigen), for
// test-sized networks; throws std::runtime_error if K is not positive definite at x.
double equilibrium_distance_bound(const SpringNetwork& net, double t, const std::vector<double>& x,
                                  double residual);

// The stop criterion's bound on how far apart (m, max norm) two settled runs of `net` can end,
// at (ta, xa) and (tb, xb): each stopped at its static residual (at most equilibrium_threshold,
// the tolerance or the round-off floor, unless the stop in positions came first), so each is within
// equilibrium_distance_bound of it from the exact equilibrium (K evaluated at xb).
double settled_distance_bound(const SpringNetwork& net, double ta, const std::vector<double>& xa,
                              double tb, const std::vector<double>& xb,
                              double equilibrium_tol = IntegratorOptions{}.equilibrium_tol);

}  // namespace knitsim::test
