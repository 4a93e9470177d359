// static: an accelerator that reaches the equilibrium the damped dynamics reach
// (docs/equilibrium.md) faster than integrating until the residual is tiny.
//
// Why not plain Newton: F(x) = 0 has many solutions (saddles, buckled shapes, other fold
// branches), and Newton from the flat state often lands on one of those (docs/numerics.md,
// "Integrators"). The physically reached state is the end of the damped dynamics from the
// initial state, so `static` follows the dynamics until close to that end, then polishes:
//
//   1. Relaxation: cvode-bdf (the same integrator, options and stop rule) from the initial
//      state, one CVODE step per step(), until the static residual r(x) (docs/equilibrium.md) falls
//      below the polish threshold (initially kPolishThreshold = 1e-3) -- and only once
//      t >= equilibrium_start_time() (pins no longer moving).
//   2. Polish: KINSOL Newton with line search (KIN_LINESEARCH, a fresh Jacobian every
//      iteration) on the static residual in newtons,
//          F(x) = M a_c(t, x) = F_spring(x) + M g = 0,   dF/dx = K = M Ax
//      (symmetric; sparse KLU on the model's stiffness pattern), from the relaxed x.
//      KINSOL stops at ||F||_inf / F_ref <= target / 2, where F_ref is inferred from r(x) at
//      the relaxed state (F_ref = max_i |F_i| / r) and target = equilibrium_threshold()
//      (solvers/integrator.hpp): equilibrium_tol, or the round-off floor where that is larger
//      -- aiming below the floor would reject every attempt. The Newton solution is
//      accepted only if r(x*) <= target AND max_i |x*_i - x_i| <=
//      kMaxNewtonCorrection (1e-3 m): a larger correction means Newton left the basin of
//      the state the dynamics are heading to (another branch), whatever its residual.
//      Accepted: the state becomes (x*, v = 0) at the same t, so run_to_equilibrium sees an
//      equilibrium at once (further steps, if any, continue the relaxation from there).
//      Failed or rejected: the relaxation goes on from where it was and the threshold drops
//      x 0.1, so the next attempt starts closer; once it is below the target no further
//      attempt is made and the dynamics alone finish the run. How a run ended shows in its
//      final state: velocities are exactly zero only if a polish was accepted (and the run
//      stopped there); RunStats.nonlin_fails includes the rejected attempts.
//   Each step() is one relaxation step or one polish attempt. What it saves, and where it
//   does not: docs/numerics.md, "Integrators".
//
// Counters (fill_stats): those of cvode-bdf summed over the relaxation, plus: steps +=
// polish attempts; nonlin_iters += Newton iterations; nonlin_fails += rejected or failed
// polish attempts; rhs_evals += residual evaluations; jac_evals and lin_setups += KINSOL
// Jacobian evaluations (= KLU factorisations, one per Newton iteration).
#include <kinsol/kinsol_ls.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "solvers/factories.hpp"
#include "solvers/sundials_common.hpp"

namespace knitsim::detail {

namespace {

using namespace knitsim::sun;

constexpr double kPolishThreshold = 1e-3;      // first residual at which Newton is tried
constexpr double kThresholdFactor = 0.1;       // threshold x this after a failed attempt
constexpr double kMaxNewtonCorrection = 1e-3;  // m, largest accepted |x* - x_relaxed|
constexpr long kMaxNewtonIters = 20;           // KINSOL iterations per attempt (quadratic near x*)

// user_data of the KINSOL callbacks: F(x) = M a_c(t, x) at the polish time t.
struct StaticProblem {
  const MechanicalSystem* sys = nullptr;
  double t = 0.0;
};

int static_force(N_Vector x, N_Vector f, void* user_data) {
  return guarded([&] {
    const auto* p = static_cast<const StaticProblem*>(user_data);
    const int n = p->sys->dof();
    double* out = vec_data(f);
    p->sys->conservative_acceleration(p->t, vec_data(x), out);
    const auto& m = p->sys->mass();
    for (int i = 0; i < n; ++i) out[i] *= m[i];
    return finite_or_recoverable(out, n);
  });
}

// K = M Ax. KINSOL zeroes the matrix (index arrays included) before calling this, so the
// pattern is written again (O(nnz)) before the values.
int static_jacobian(N_Vector x, N_Vector /*f*/, SUNMatrix K, void* user_data, N_Vector, N_Vector) {
  return guarded([&] {
    const auto* p = static_cast<const StaticProblem*>(user_data);
    const CscPattern& pattern = p->sys->stiffness_pattern();
    write_csc_pattern(pattern, K);
    double* k = SUNSparseMatrix_Data(K);
    p->sys->stiffness_values(p->t, vec_data(x), k);
    const auto& m = p->sys->mass();
    for (int e = 0; e < pattern.nnz(); ++e) k[e] *= m[pattern.rowind[e]];
    return finite_or_recoverable(k, pattern.nnz());
  });
}

class StaticRelaxNewton final : public Integrator {
 public:
  const IntegratorInfo& info() const override { return info_; }

  void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
             const IntegratorOptions& opt) override {
    opt.validate();
    sys_ = &sys;
    opt_ = opt;
    relax_ = make_cvode_bdf();
    relax_->start(sys, t0, x0, v0, opt);
    finished_ = RunStats{};
    threshold_ = kPolishThreshold;
    polished_ = false;
    attempts_ = rejected_ = newton_iters_ = newton_fevals_ = newton_jevals_ = 0;

    const int n = sys.dof();
    k_.reset();
    auto k = std::make_unique<Kinsol>();
    k->ctx = make_context();
    SUNContext ctx = k->ctx.get();
    k->problem.sys = &sys;
    k->x = make_vector(n, ctx);
    k->x_scale = make_vector(n, ctx);
    N_VConst(1.0, k->x_scale.get());  // positions in metres
    k->f_scale = make_vector(n, ctx);
    k->force = make_vector(n, ctx);
    k->K = make_csc_matrix(sys.stiffness_pattern(), ctx);
    k->ls = make_klu(k->x.get(), k->K.get(), ctx);
    k->mem = KinsolMemPtr(check_created(KINCreate(ctx), "KINCreate"));
    void* mem = k->mem.get();
    const ErrorLog* log = &k->log;
    check(KINSetErrHandlerFn(mem, record_error, &k->log), "KINSetErrHandlerFn", kName);
    check(KINInit(mem, static_force, k->x.get()), "KINInit", kName, log);
    check(KINSetUserData(mem, &k->problem), "KINSetUserData", kName, log);
    check(KINSetLinearSolver(mem, k->ls.get(), k->K.get()), "KINSetLinearSolver", kLsName, log);
    check(KINSetJacFn(mem, static_jacobian), "KINSetJacFn", kLsName, log);
    check(KINSetMaxSetupCalls(mem, 1), "KINSetMaxSetupCalls", kName, log);  // exact Newton
    check(KINSetNumMaxIters(mem, kMaxNewtonIters), "KINSetNumMaxIters", kName, log);
    k_ = std::move(k);
    zeros_.assign(n, 0.0);
  }

  Step step(double t_stop) override {
    const double t = relax_->time();
    if (!polished_ && threshold_ > opt_.equilibrium_tol && t >= sys_->equilibrium_start_time()) {
      const double r = sys_->static_residual(t, relax_->positions());
      const double target = r <= threshold_ ? equilibrium_threshold(*sys_, t, relax_->positions(),
                                                                    opt_.equilibrium_tol)
                                            : 0.0;
      if (r <= threshold_ && r > target && threshold_ > target) {
        try {
          return polish(t, r, target);
        } catch (const std::exception& e) {  // a broken SUNDIALS invariant, reported as a status
          return {false, std::string("static polish: ") + e.what()};
        }
      }
    }
    return relax_->step(t_stop);
  }

  bool restart() override { return relax_->restart(); }
  int last_order() const override { return relax_->last_order(); }  // polish attempts: unchanged
  double time() const override { return relax_->time(); }
  const double* positions() const override { return relax_->positions(); }
  const double* velocities() const override { return relax_->velocities(); }

  void fill_stats(RunStats& st) const override {
    relax_->fill_stats(st);
    add_counters(st, finished_);
    st.steps += attempts_;
    st.rhs_evals += newton_fevals_;
    st.jac_evals += newton_jevals_;
    st.lin_setups += newton_jevals_;
    st.factorisations += newton_jevals_;
    st.nonlin_iters += newton_iters_;
    st.nonlin_fails += rejected_;
  }

 private:
  // One Newton polish from the relaxed state at time t (residual r0 > target, the
  // equilibrium_threshold: equilibrium_tol, or the round-off floor where that is larger).
  Step polish(double t, double r0, double target) {
    ++attempts_;
    const int n = sys_->dof();
    void* mem = k_->mem.get();
    const double* x_relaxed = relax_->positions();
    double* x = vec_data(k_->x.get());
    std::copy_n(x_relaxed, n, x);
    k_->problem.t = t;
    // F_ref from the relaxed state: fscale = r0 / max_i |F_i(x_relaxed)| (1/N).
    const double* f = vec_data(k_->force.get());
    double f_max = 0.0;
    if (static_force(k_->x.get(), k_->force.get(), &k_->problem) == 0)
      for (int i = 0; i < n; ++i) f_max = std::max(f_max, std::abs(f[i]));
    ++newton_fevals_;
    bool accepted = false;
    if (f_max > 0.0) {
      N_VConst(r0 / f_max, k_->f_scale.get());
      k_->log.clear();
      check(KINSetFuncNormTol(mem, 0.5 * target), "KINSetFuncNormTol", kName);
      // KINSOL counters restart with every KINSol call.
      const int flag =
          KINSol(mem, k_->x.get(), KIN_LINESEARCH, k_->x_scale.get(), k_->f_scale.get());
      long nni = 0, nfe = 0, nje = 0;
      check(KINGetNumNonlinSolvIters(mem, &nni), "KINGetNumNonlinSolvIters", kName);
      check(KINGetNumFuncEvals(mem, &nfe), "KINGetNumFuncEvals", kName);
      check(KINGetNumJacEvals(mem, &nje), "KINGetNumJacEvals", kLsName);
      newton_iters_ += nni;
      newton_fevals_ += nfe;
      newton_jevals_ += nje;
      if (flag >= 0) {
        double correction = 0.0;
        for (int i = 0; i < n; ++i)
          correction = std::max(correction, std::abs(x[i] - x_relaxed[i]));
        accepted = correction <= kMaxNewtonCorrection && sys_->static_residual(t, x) <= target;
      }
    }
    if (!accepted) {
      ++rejected_;
      threshold_ *= kThresholdFactor;
      return {};
    }
    // The state becomes (x*, 0) at t: restart the relaxation integrator there.
    RunStats done;
    relax_->fill_stats(done);
    add_counters(finished_, done);
    relax_->start(*sys_, t, x, zeros_.data(), opt_);
    polished_ = true;
    return {};
  }

  static constexpr FlagNameFn kName = KINGetReturnFlagName;
  static constexpr FlagNameFn kLsName = KINGetLinReturnFlagName;

  // KINSOL objects, declared in creation order (destroyed in reverse).
  struct Kinsol {
    ContextPtr ctx;
    StaticProblem problem;
    VectorPtr x, x_scale, f_scale, force;
    MatrixPtr K;
    LinearSolverPtr ls;
    ErrorLog log;
    KinsolMemPtr mem;
  };

  IntegratorInfo info_{"static",
                       "accelerator: cvode-bdf relaxation, then KINSOL Newton (line search, KLU) "
                       "polish accepted only near the relaxed state",
                       0, true, false};
  const MechanicalSystem* sys_ = nullptr;
  IntegratorOptions opt_;
  std::unique_ptr<Integrator> relax_;
  std::unique_ptr<Kinsol> k_;
  std::vector<double> zeros_;
  RunStats finished_;  // counters of relaxation segments already ended by a polish
  double threshold_ = kPolishThreshold;
  bool polished_ = false;
  long attempts_ = 0, rejected_ = 0, newton_iters_ = 0, newton_fevals_ = 0, newton_jevals_ = 0;
};

}  // namespace

std::unique_ptr<Integrator> make_static() { return std::make_unique<StaticRelaxNewton>(); }

}  // namespace knitsim::detail
