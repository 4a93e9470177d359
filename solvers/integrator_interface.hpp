// The one interface every integrator implements (IntegratorInfo, Integrator); the run driver
// (solvers/integrator.hpp) drives any of them through it.
#pragma once

#include <string>

#include "solvers/integrator_options.hpp"
#include "solvers/run_stats.hpp"
#include "src/core/mechanical_system.hpp"

namespace knitsim {

struct IntegratorInfo {
  std::string name;
  std::string description;
  int order = 0;  // classical order (0 = variable / not applicable)
  bool adaptive = false;
  bool explicit_method = false;
  // Its numerical damping (a large fixed step of an L-stable method) brings even an undamped
  // system to rest, so damping = 0 is no cause for a warning.
  bool damps_numerically = false;
  // Its t is physical time throughout. False for `equilibrium`, whose t stops where the pins
  // stop: after that it follows the overdamped flow, whose step is not time.
  bool follows_time = true;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual const IntegratorInfo& info() const = 0;

  // Prepare a run of `sys` from (t0, x0, v0). Throws std::invalid_argument on bad options.
  // The system must outlive the run.
  virtual void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
                     const IntegratorOptions& opt) = 0;

  struct Step {
    bool ok = true;
    std::string message;       // on failure: what went wrong
    bool recoverable = false;  // on failure: restart() from the last accepted state may cure it
  };
  // Advance by one (internal) step, never beyond t_stop. On failure the state is the last
  // accepted one.
  virtual Step step(double t_stop) = 0;

  // Start the method afresh from its current state and time, forgetting its step-size and
  // order history, keeping its counters; false if the method cannot (the default).
  virtual bool restart() { return false; }

  // The system's functions changed at the current state (MechanicalSystem::update): forget
  // what was computed from the old ones (step history, cached forces). Default: restart().
  virtual void model_changed() { restart(); }

  // What the run's message adds about how the method got there (the equilibrium solver: the
  // saddles it left, a fall-back to the dynamics), starting "; ". Default: nothing.
  virtual std::string run_note() const { return {}; }

  // Method order of the step just taken: the controller's choice for variable-order methods
  // (cvode-bdf, cvode-adams), else info().order.
  virtual int last_order() const { return info().order; }

  virtual double time() const = 0;
  virtual const double* positions() const = 0;
  virtual const double* velocities() const = 0;
  // Counters so far (steps, evaluations, ...) and dt / dt_predicted where meaningful.
  virtual void fill_stats(RunStats& stats) const = 0;
};

}  // namespace knitsim
