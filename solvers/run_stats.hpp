// What a run reports: why it stopped (RunStatus) and its counters, timings and end-state checks
// (RunStats), printable as text and JSON (src/io/).
#pragma once

#include <string>

namespace knitsim {

enum class RunStatus {
  Equilibrium,    // the stop in positions (or the residual where K is singular), energy checked
  // A state the stop accepts but the damped dynamics cannot reach: its potential energy is
  // above the total energy the run had once the pins stopped (e.g. implicit-euler at a very
  // large dt landing on a crumpled equilibrium).
  SpuriousEquilibrium,
  // The stop passed, but the state breaks the model's own limits (a drape strained far past its
  // elongation limit, a sag larger than the sheet: docs/reliability.md, "Results against the
  // model's limits"). Set by the command that checks them, never by run_to_equilibrium.
  OutsideModelLimits,
  TimeLimit,      // reached t_max first
  StepLimit,      // reached max_steps first
  WallLimit,      // reached max_wall_seconds first
  Interrupted,    // IntegratorOptions::interrupt was set (e.g. Ctrl-C) before the end
  // No progress: IntegratorOptions::stall_checks checks in a row with t standing still and the
  // static residual never below its lowest value (docs/equilibrium.md, "The stall rule").
  Stalled,
  SolverFailure,  // the integrator reported an error (e.g. a SUNDIALS flag)
  Diverged,       // non-finite or runaway state
};
const char* to_string(RunStatus s);

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

}  // namespace knitsim
