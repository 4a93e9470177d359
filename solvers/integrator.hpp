// One interface for every integrator, one driver that runs any of them to equilibrium.
//
//   auto integ = make_integrator("cvode-bdf");         // by name, see integrator_catalog()
//   IntegratorOptions opt;  opt.rtol = 1e-6;  opt.validate();
//   std::vector<double> x, v;                          // in: initial state (empty: the model's)
//   RunStats s = run_to_equilibrium(model, *integ, opt, x, v);   // out: final state
//
// Integrators see only a MechanicalSystem (src/core/mechanical_system.hpp); they never know which
// model they run. Every run stops by the same test (docs/equilibrium.md; solvers/equilibrium_check.hpp),
// made every `check_every` steps from the model's equilibrium_start_time() on: the Newton
// correction ||K^-1 F||_inf below position_tol where the stiffness K is positive definite, or
// the static residual below equilibrium_threshold() where K is singular; the state that passes
// is certified and checked in energy (RunStatus). Otherwise a run ends at t_max, the step cap,
// the wall-clock cap or an interrupt request, and RunStats.status says which. Numerical failure
// (a SUNDIALS error, a non-finite or runaway state) is a status, never an exception.
//
// One concept per header, all included here: the options (integrator_options.hpp), what a run
// reports (run_stats.hpp), the integrator interface (integrator_interface.hpp) and the observer
// (run_observer.hpp); this header keeps the registry, the run driver and the stable-step
// estimates.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "solvers/integrator_interface.hpp"
#include "solvers/integrator_options.hpp"
#include "solvers/run_observer.hpp"
#include "solvers/run_stats.hpp"
#include "src/core/mechanical_system.hpp"

namespace knitsim {

// Registry: every integrator by name (docs/numerics.md).
const std::vector<IntegratorInfo>& integrator_catalog();
std::unique_ptr<Integrator> make_integrator(const std::string& name);  // throws invalid_argument
// The SuiteSparse release (CHOLMOD, KLU) the solvers were compiled against, e.g. "5.12.0",
// for manifests.
std::string suitesparse_version();

// The one run-to-equilibrium driver. x, v: in the initial state at time t0 (empty = the model's
// initial_state), out the final state. t0 > 0 continues a run that stopped there (knitsim drape
// --continue); it must be below opt.t_max (std::invalid_argument otherwise). The counters in the
// result are this call's only. Between steps, at each check, it updates the system's run state
// (MechanicalSystem::update); a system with run state must therefore be passed non-const (the
// const overload throws std::logic_error for one).
RunStats run_to_equilibrium(MechanicalSystem& sys, Integrator& integ, const IntegratorOptions& opt,
                            std::vector<double>& x, std::vector<double>& v,
                            RunObserver* observer = nullptr, double t0 = 0.0);
RunStats run_to_equilibrium(const MechanicalSystem& sys, Integrator& integ,
                            const IntegratorOptions& opt, std::vector<double>& x,
                            std::vector<double>& v, RunObserver* observer = nullptr,
                            double t0 = 0.0);

// The static residual below which run_to_equilibrium accepts a state (t, x) where K is singular:
// equilibrium_tol, or the residual's round-off floor there (MechanicalSystem::residual_roundoff)
// where that is larger, but never more than 1e3 x equilibrium_tol (a tolerance is not loosened
// further: a run asked for the impossible ends at t_max). Costs one pass over the model's
// springs. Integrators that solve for the equilibrium themselves (static) aim at this.
double equilibrium_threshold(const MechanicalSystem& sys, double t, const double* x,
                             double equilibrium_tol);

// Convenience: make_integrator(name) + run_to_equilibrium.
RunStats run_to_equilibrium(MechanicalSystem& sys, const std::string& integrator,
                            const IntegratorOptions& opt, std::vector<double>& x,
                            std::vector<double>& v, RunObserver* observer = nullptr,
                            double t0 = 0.0);
RunStats run_to_equilibrium(const MechanicalSystem& sys, const std::string& integrator,
                            const IntegratorOptions& opt, std::vector<double>& x,
                            std::vector<double>& v, RunObserver* observer = nullptr,
                            double t0 = 0.0);

// Linear stability prediction for the explicit fixed-step methods (docs/numerics.md), per dof i from
// a Gershgorin bound on da_c/dx at (t, x): omega_i^2 <= sum_j |Ax_ij|, gamma_i = c_i/m_i.
//   euler:  |1 + h lambda| < 1 for lambda = -gamma/2 +- sqrt(gamma^2/4 - omega^2)
//           (overdamped: h < 2 / |lambda_fast|; underdamped: h < gamma / omega^2)
//   verlet: velocity Verlet with the damping integrated exactly over each half step
//           (e = exp(-gamma h/2), phi = (1 - e)/gamma): h phi omega^2 < 2 (1 + e^2)/(1 + e);
//           gamma -> 0 gives the classical h omega < 2.
// Returns the smallest limit over all dof (s); +inf if no dof constrains it, 0 if none is
// stable (undamped Euler).
double predict_stable_dt(const std::string& method, const MechanicalSystem& sys, double t,
                         const double* x);

// The same limits, sharper: each dof's omega_i^2 is also capped by the fastest undamped mode,
// lambda_max(M^-1/2 (-K) M^-1/2), and, where every c_i = gamma_i m_i > 0, by gamma_i times the
// fastest overdamped relaxation rate, lambda_max(C^-1/2 (-K) C^-1/2) (K = M Ax symmetrised; both
// by 40 Lanczos steps, top Ritz value plus its residual). The Gershgorin row sum overestimates
// both on a coupled grid. This is an estimate, not a bound (it can come out slightly above the
// exact limit), so the automatic dt keeps predict_stable_dt; explicit runs report both
// (summary.json). How close each comes to the exact limits: experiments/stability.
double estimate_stable_dt(const std::string& method, const MechanicalSystem& sys, double t,
                          const double* x);

}  // namespace knitsim
