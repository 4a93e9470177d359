// The options of every integrator and of the run driver (solvers/integrator.hpp): tolerances,
// steps, caps, the stop and the linear algebra. A plain struct with defaults and units, checked by
// validate(); the user sets them through the rows of the key table (src/scene/scene.hpp).
#pragma once

#include <atomic>

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
  // Set from outside (the CLI's signal handler) to end the run as Interrupted; read after every
  // step, with the process-wide stop request (src/core/stop_request.hpp) that also cuts a step's
  // factorisations and SUNDIALS iterations short. nullptr = none.
  const std::atomic<bool>* interrupt = nullptr;
  long check_every = 0;           // steps between residual checks; 0 = 1000 (euler, verlet), else 1
  double runaway_position = 1e3;  // m: |x_i| above it counts as a blow-up (Diverged)
  int max_restarts = 10;          // most fresh starts per run after recoverable step failures
  // The stall rule (run_to_equilibrium): the run ends as Stalled after this many checks in a
  // row at which t has not advanced (the equilibrium solver's flow, whose t stands still) and
  // the static residual is not below its lowest value since t last advanced, for a model of up
  // to 2500 unknowns, x sqrt(n / 2500) above (a fine grid's flow needs more); 0 = never.
  long stall_checks = 1000;
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

// "klu", "ldl", "cg-ldl": the names of --newton-solver and of summary.json's options.
const char* to_string(IntegratorOptions::NewtonSolver s);
const char* to_string(IntegratorOptions::GmresPreconditioner p);
// "auto", "simplicial", "block", "supernodal": the names of --factorization and of summary.json.
const char* to_string(IntegratorOptions::Factorization f);

}  // namespace knitsim
