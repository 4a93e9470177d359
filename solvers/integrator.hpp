// One interface for every integrator, one driver that runs any of them to equilibrium.
//
//   auto integ = make_integrator("cvode-bdf");         // by name, see integrator_catalog()
//   IntegratorOptions opt;  opt.rtol = 1e-6;  opt.validate();
//   std::vector<double> x, v;                          // in: initial state (empty: the model's)
//   RunStats s = run_to_equilibrium(model, *integ, opt, x, v);   // out: final state
//
// Integrators see only a MechanicalSystem (src/core/mechanical_system.hpp); they never know which
// model they run. Every run stops by the same test (docs/equilibrium.md;
// solvers/equilibrium_check.hpp), made every `check_every` steps from the model's
// equilibrium_start_time() on: the Newton correction ||K^-1 F||_inf below position_tol where the
// stiffness K is positive definite, or the static residual below equilibrium_threshold() where K is
// singular; the state that passes is certified and checked in energy (RunStatus). Otherwise a run
// ends at t_max, the step cap, the wall-clock cap or an interrupt request, and RunStats.status says
// which. Numerical failure (a SUNDIALS error, a non-finite or runaway state) is a status, never an
// exception.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "src/core/mechanical_system.hpp"

namespace knitsim {

struct IntegratorOptions {
  // Each field: meaning, units, default. Why a default is what it is: docs/numerics.md,
  // "Options and why their defaults".
  double rtol = 1e-6;             // relative tolerance of the adaptive methods (knitsim fit: 1e-8)
  double atol = 1e-9;             // absolute tolerance: m for positions (and m/s for velocities)
  double velocity_atol = 0.0;     // m/s, absolute tolerance of the velocities; 0 = atol
  double dt = 0.0;                // s, fixed step of euler, verlet, implicit-euler; 0 = automatic
  double dt_safety = 0.5;         // fraction of the predicted stability limit when dt = 0
  int max_order = 0;              // cap on the method order (BDF <= 5, Adams <= 12); 0 = default
  long max_steps = 500'000'000;   // steps per run at most
  double t_max = 1e7;             // s, physical end time if no equilibrium first, [1e-9, 1e15]
  // The stop, tested once the static residual (max_i |F_i| / mean particle weight, dimensionless)
  // is below max(1e-4, equilibrium_tol): where K is positive definite, ||K^-1 F||_inf below
  // max(position_tol, its round-off floor) m; where K is singular, the residual below
  // equilibrium_threshold() (below: equilibrium_tol, or a round-off floor up to 1e3 x it).
  double equilibrium_tol = 1e-8;  // static residual, dimensionless: the stop where K is singular
  double position_tol = 1e-10;    // m, the stop in positions where K is positive definite
  double max_wall_seconds = 0.0;  // s, wall-clock cap per run; 0 = none
  // Set from outside (the CLI's signal handler) to end the run as Interrupted; read at each
  // residual check. nullptr = none.
  const std::atomic<bool>* interrupt = nullptr;
  long check_every = 0;           // steps between residual checks; 0 = 1000 (euler, verlet), else 1
  double runaway_position = 1e3;  // m: |x_i| above it counts as a blow-up (Diverged)
  int max_restarts = 10;          // most fresh starts per run after recoverable step failures
  int krylov_dim = 30;            // cvode-bdf-gmres: Krylov dimension (0 = SUNDIALS' 5)
  double krylov_eps_lin = 5e-7;   // cvode-bdf-gmres: GMRES over Newton tolerance (SUNDIALS': 0.05)
  // Newton systems of cvode-bdf, arkode-dirk, arkode-imex: Klu = sparse LU of I - gamma J;
  // SchurLdl = velocities eliminated, symmetric LDL^T; SchurCgLdl = the same, by CG where the
  // reduced matrix is provably well conditioned (solvers/schur_ldl_solver.hpp). Same systems.
  enum class NewtonSolver { Klu, SchurLdl, SchurCgLdl };
  NewtonSolver newton_solver = NewtonSolver::SchurCgLdl;  // names: to_string below
  // cvode-bdf-gmres's left preconditioner of I - gamma J: none; per-particle 6 x 6 blocks
  // inverted; the Schur matrix S by incomplete Cholesky; or S by LDL^T, lagged between set-ups.
  enum class GmresPreconditioner { None, BlockJacobi, SchurIc, SchurLdl };
  GmresPreconditioner gmres_preconditioner = GmresPreconditioner::SchurLdl;
  // Factorisation of the symmetric S (solvers/symmetric_factor.hpp): Eigen's simplicial LDL^T,
  // the same in 3 x 3 node blocks (block_ldlt.hpp), CHOLMOD's supernodal LL^T, or Automatic:
  // Block below SymmetricFactor::supernodal_min_dof unknowns, Supernodal from there.
  enum class Factorization { Automatic, Simplicial, Block, Supernodal };
  Factorization factorization = Factorization::Automatic;

  // Throws std::invalid_argument naming the bad field and its accepted range.
  void validate() const;
};

enum class RunStatus {
  Equilibrium,    // the stop in positions (or the residual where K is singular), energy checked
  // A state the stop accepts but the damped dynamics cannot reach: its potential energy is
  // above the total energy the run had once the pins stopped (e.g. implicit-euler at a very
  // large dt landing on a crumpled equilibrium).
  SpuriousEquilibrium,
  TimeLimit,      // reached t_max first
  StepLimit,      // reached max_steps first
  WallLimit,      // reached max_wall_seconds first
  Interrupted,    // IntegratorOptions::interrupt was set (e.g. Ctrl-C) before the end
  SolverFailure,  // the integrator reported an error (e.g. a SUNDIALS flag)
  Diverged,       // non-finite or runaway state
};
const char* to_string(RunStatus s);
// "klu", "ldl", "cg-ldl": the names of --newton-solver and of summary.json's options.
const char* to_string(IntegratorOptions::NewtonSolver s);
const char* to_string(IntegratorOptions::GmresPreconditioner p);
// "auto", "simplicial", "block", "supernodal": the names of --factorization and of summary.json.
const char* to_string(IntegratorOptions::Factorization f);

struct RunStats {
  std::string integrator;
  RunStatus status = RunStatus::SolverFailure;
  std::string message;    // why it stopped, with the SUNDIALS flag name where relevant
  double t_final = 0.0;   // s
  double residual = 0.0;  // static residual at the end
  // Round-off floor of that residual (MechanicalSystem::residual_roundoff) at the end.
  double residual_floor = 0.0;
  double dt = 0.0;            // fixed step used (fixed-step methods), s
  double dt_predicted = 0.0;  // predicted stability limit (explicit methods), s
  double dt_estimated = 0.0;  // its sharper estimate (estimate_stable_dt; explicit methods), s
  long steps = 0;
  long rhs_evals = 0;
  long jac_evals = 0;
  long lin_setups = 0;
  long factorisations = 0;  // numeric factorisations of the Newton matrix (<= lin_setups)
  // The back end the run factorises S with ("simplicial", "block" or "supernodal"; empty if the
  // integrator has none) and its supernodal factorisations redone as LDL^T (S not positive
  // definite).
  std::string factorization;
  long ldl_fallbacks = 0;
  // One factorisation of S by that back end (SymmetricFactor::fill_stats): entries of L below
  // the diagonal, and floating-point operations in CHOLMOD's count, sum over L's columns of
  // (entries + 1)^2. 0 where the run factorises no S (explicit methods, KLU).
  double factor_nonzeros = 0.0;
  double factor_flops = 0.0;
  long lin_iters = 0;  // Krylov iterations (GMRES, or CG inside SchurCgLdl)
  long nonlin_iters = 0;
  long nonlin_fails = 0;
  long err_test_fails = 0;
  long restarts = 0;  // restarts after recoverable step failures (IntegratorOptions::max_restarts)
  int max_order_used = 0;
  // The end state's checks (solvers/equilibrium_check.hpp), where the stop was tested:
  //   certificate  "stable_minimum": K positive definite (no negative LDL^T pivot, smallest
  //                eigenvalue above n eps ||K||) and the energy check holds; "inconclusive":
  //                K singular (rigid-body or mechanism modes: the residual decided); "" where
  //                the stop did not pass (never tested, or at a saddle: negative pivots).
  std::string certificate;
  bool residual_decided = false;  // the stop was the static residual (K singular), not the
                                  // Newton correction
  int negative_pivots = 0;
  double min_eigenvalue = 0.0;        // N/m, K's eigenvalue nearest 0
  double eigenvalue_threshold = 0.0;  // N/m, n eps ||K||_inf
  double newton_step = 0.0;           // m, ||K^-1 F||_inf at the end
  double newton_floor = 0.0;          // m, its round-off floor
  // J: potential energy at the end, and the total (potential + kinetic) energy once the pins
  // had stopped, which damped motion can only lower; set where the stop passed, else 0.
  double energy = 0.0;
  double energy_reference = 0.0;
  long stop_factorisations = 0;  // factorisations of K by the stop's tests (not in factorisations)
  long saddle_escapes = 0;  // times the equilibrium solver left a saddle along its negative mode
  long fallbacks = 0;       // times the equilibrium solver handed the run to the dynamics
  double wall_seconds = 0.0;
  double cpu_seconds = 0.0;  // process CPU time during the run (robust on a loaded machine;
                             // counts all threads of the process)
};

// Adds part's work counters (steps ... err_test_fails, factorisations, ldl_fallbacks) to total's,
// takes the larger max_order_used and part's factorization if total has none: the counts of a
// run made of several parts (a restarted integrator, a reduction's run then the whole sheet's).
void add_counters(RunStats& total, const RunStats& part);

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

// Registry: every integrator by name (docs/numerics.md).
const std::vector<IntegratorInfo>& integrator_catalog();
std::unique_ptr<Integrator> make_integrator(const std::string& name);  // throws invalid_argument
// The SuiteSparse release (CHOLMOD, KLU) the solvers were compiled against, e.g. "5.12.0",
// for manifests.
std::string suitesparse_version();

// Observer of a run: on_step after every step (t after it, h = its size -- 0 for a step that did
// not advance time, e.g. a static polish attempt -- and the method order used), on_check at every
// residual check (for progress lines and time series); a check follows the step at the same t.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  virtual void on_step(double /*t*/, double /*h*/, int /*order*/) {}
  virtual void on_check(double t, const double* x, const double* v, double residual) = 0;
};

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
