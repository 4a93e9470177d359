// The one contract between physics (models/) and integrators (solvers/).
//
// A MechanicalSystem is a second-order ODE over n degrees of freedom (3 per free particle; a
// mirror reduction ties some of them and has fewer, models/mirror_reduced.hpp):
//
//     x'' = a(t, x, v) = a_c(t, x) - Gamma v
//
//   a_c   conservative + external acceleration, M^-1 (F_spring(x, t) + F_ext)    [m/s^2]
//   Gamma per-dof linear damping rate gamma_i = c_i / m_i (absolute damping)     [1/s]
//   M     diagonal mass, one value per dof                                        [kg]
//
// Its Jacobian blocks are da/dx = da_c/dx (sparse, the "stiffness" pattern, built once, every
// diagonal present) and da/dv = -Gamma (diagonal). Pinned particles are not degrees of freedom;
// their (possibly time-dependent) positions enter a_c through t. a_c derives from the potential:
// M a_c = -dE/dx with E = potential_energy (gravity included), so M da_c/dx is symmetric; the
// equilibrium solver's energy test and the certificate rely on both.
//
// Model and run (Drake's System and Context). The const functions are functions of (t, x) and of
// the object's state, and change no state: they may refill caches that are functions of what
// they are evaluated at (documented as caches where they are declared). A model without run
// state (has_run_state() false) is const in fact; a SpringNetwork (the drape grid's, the knit's)
// may be evaluated from several threads at once, a mirror reduction (models/mirror_reduced.hpp)
// keeps scratch buffers and serves one thread at a time. A model whose functions
// change over a run (the yarn contact's renewed points, which change E(x) itself) is split: a
// const model, shareable by any number of runs and threads, and a per-run object that
// implements MechanicalSystem over it and owns the state that changes (ContactModel and
// ContactNetwork, models/yarn_contact.hpp). That state changes only in update(), called by the
// run driver between steps through a non-const reference; a per-run object serves one thread.
#pragma once

#include <string>
#include <vector>

#include "src/core/sparse.hpp"

namespace knitsim {

class HeldPoints;  // src/core/held_points.hpp

class MechanicalSystem {
 public:
  virtual ~MechanicalSystem() = default;

  // Number of degrees of freedom n.
  virtual int dof() const = 0;

  // Initial state at t = 0 (arrays of length n).
  virtual void initial_state(double* x, double* v) const = 0;

  // a_c(t, x) into a (length n).
  virtual void conservative_acceleration(double t, const double* x, double* a) const = 0;

  // The state-independent part of a_c (e.g. gravity) into a (length n): what an IMEX split
  // treats explicitly. Default: zero.
  virtual void constant_acceleration(double t, double* a) const;

  // gamma_i (1/s), length n; a = a_c - gamma .* v.
  virtual const std::vector<double>& damping_rate() const = 0;

  // m_i (kg), length n: a particle's mass on each of its coordinates (a reduction's are
  // weighted, models/mirror_reduced.hpp).
  virtual const std::vector<double>& mass() const = 0;

  // CSC pattern of da_c/dx (n x n), every diagonal entry present; fixed for the lifetime.
  virtual const CscPattern& stiffness_pattern() const = 0;

  // Values of da_c/dx = M^-1 dF/dx in stiffness_pattern() order (nnz doubles).
  virtual void stiffness_values(double t, const double* x, double* values) const = 0;

  // Static residual used by the equilibrium criterion (docs/equilibrium.md): a dimensionless
  // measure of the net force at rest, e.g. max_i |F_i(x)| / (mean mass x g).
  virtual double static_residual(double t, const double* x) const = 0;

  // Round-off floor of static_residual at (t, x): an upper estimate of the residual that
  // rounding alone leaves at an exact equilibrium, in the same units. run_to_equilibrium solves
  // K against it (as forces) for the floor of the stop in positions and, where K is singular
  // and the residual decides, accepts r below it (up to 1e3 x equilibrium_tol;
  // equilibrium_threshold, solvers/integrator.hpp), so a stiff model is not integrated to
  // t_max chasing what its arithmetic cannot reach. Default 0: no floor known.
  virtual double residual_roundoff(double /*t*/, const double* /*x*/) const { return 0.0; }

  // True when the forces do not see rigid motions of the whole state (no pins, no external
  // field: a free-floating body, e.g. a knit chart without pins or gravity). Its stiffness then
  // has the 6 rigid-body modes (3 translations, 3 rotations of the particles, 3 dofs each) in
  // its null space; the equilibrium certificate factors them out. Default: false (a model whose
  // other zero-stiffness modes would then read as a saddle must not declare it).
  virtual bool free_floating() const { return false; }
  // True when the model holds its particles in the plane z = 0 by an out-of-plane stiffness of
  // its own (SpringNetwork's planar mode): a free-floating planar model has 3 rigid-body modes
  // (the translations in the plane and the turn about z), not 6.
  virtual bool planar() const { return false; }

  // Equilibrium may only be declared from this time on (e.g. after prescribed pin motion).
  virtual double equilibrium_start_time() const { return 0.0; }

  // The largest fraction in [0, 1] of the step from x to x + dx that the model admits: less
  // than 1 where the step would jump through a barrier the model keeps (yarn contact,
  // models/yarn_contact.hpp). The solvers that take whole Newton steps (equilibrium,
  // implicit-euler) shorten theirs by it. Default 1.
  virtual double admissible_step(double /*t*/, const double* /*x*/, const double* /*dx*/) const {
    return 1.0;
  }

  // The explicit update of the run's state between steps: lets a per-run object that
  // approximates part of its model about a state (the yarn contact's points, linearised about
  // where the yarn was) renew that approximation at an accepted state x; returns true if its
  // functions changed there, so integrators must forget what they computed from them
  // (Integrator::model_changed). The run driver calls it at each stop check. Default: no run
  // state, nothing to update.
  virtual bool update(double /*t*/, const double* /*x*/) { return false; }
  // True for a per-run object whose update() may change its functions (see the top): the run
  // driver then needs it non-const.
  virtual bool has_run_state() const { return false; }

  // Position constraint projection for the explicit reference paths (Provot 1995): called
  // after each step; returns true if anything moved. Implicit paths never call it.
  virtual bool project(double /*t*/, double* /*x*/, double* /*v*/) const { return false; }

  // Energies (J): potential at (t, x) (every force of a_c: springs, stencils, contact, gravity;
  // see the header comment) and kinetic 1/2 sum m v^2.
  virtual double potential_energy(double t, const double* x) const = 0;
  double kinetic_energy(const double* v) const;

  // Human-readable description for summaries.
  virtual std::string describe() const = 0;

  // The points the model holds (pins, clamps) as run state a driver may move, and the forces
  // that hold them (src/core/held_points.hpp); null for a model that offers none. Default: null.
  virtual HeldPoints* held_points() { return nullptr; }
  virtual const HeldPoints* held_points() const { return nullptr; }
};

}  // namespace knitsim
