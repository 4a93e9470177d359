// ARKODE integrators (SUNDIALS 6.4 / ARKODE 5.4) on the 2n first-order system y = [x; v],
// y' = f(t, y) = [v; a_c(t, x) - Gamma v] (src/core/first_order.hpp), J = [[0, I], [Ax, -Gamma]].
//
//   arkode-erk    ERKStep, the default adaptive embedded table of order 4
//                 (Zonneveld 5-3-4; IntegratorOptions::max_order picks the default table of
//                 another order, 2..8; 7 selects the order-8 table). Explicit: its step is bounded
//                 by stability, ~2.8/max|lambda| with max|lambda| ~ c/m ~ 1e5 /s on the drape --
//                 the stiffness penalty the comparison is to show.
//   arkode-dirk   ARKStep, fully implicit y' = f_I = f with an ESDIRK table (default
//                 ESDIRK4(3)6L[2]SA, order 4, L-stable, stiffly accurate; max_order 3 / 4 / 5
//                 select ESDIRK3(2)4L[2]SA / ESDIRK4(3)6L[2]SA / ESDIRK5(4)7L[2]SA). Newton
//                 with A = I - gamma J assembled into J's fixed CSC pattern (NewtonMatrix via
//                 ARKStepSetLinSysFn) and factored by KLU.
//   arkode-imex   ARKStep IMEX (default ARK4(3)6L[2]SA pair; max_order 3..5 picks the ARK
//                 pair of that order): explicit f_E = [0; g(t)] with g = constant_acceleration
//                 (gravity), implicit f_I = [v; a_c - g - Gamma v] (springs and damping).
//                 g does not depend on y, so J_I = J and the same KLU Newton matrix serves.
//
// Each step() is one *StepEvolve(..., ARK_ONE_STEP) call with the stop time t_stop, so the
// integrator never steps past t_stop. ARKODE's per-call step cap is set to
// IntegratorOptions::max_steps (run_to_equilibrium enforces the run's cap); scalar rtol,
// atol, or per component (atol on x, velocity_atol on v) when velocity_atol > 0
// (sun::absolute_tolerances). The Jacobian refresh interval is set explicitly
// (kJacobianEvalFrequency, equal to CVODE's default so cvode-bdf and the ARKODE methods are
// compared on equal terms) and, as ARKODE requires, only after the linear solver is attached.
// max_order_used reports the order of the Butcher table in use. rhs_evals counts f_E plus f_I
// calls.
//
// Implicit stage derivatives are deduced from the stage equations (ARKStepSetDeduceImplicitRhs)
// instead of re-evaluating f_I at the Newton solution: otherwise the Newton error of a stiff
// component (|lambda| up to ~5e5 /s here) is amplified by h |lambda| >> 1 into the stage
// derivatives and the embedded error estimate (docs/numerics.md, "Integrators", has the
// measurement).
#include <arkode/arkode_ls.h>

#include <algorithm>
#include <limits>
#include <sstream>

#include "solvers/factories.hpp"
#include "solvers/sundials_common.hpp"
#include "src/core/invalid_field.hpp"

namespace knitsim::detail {

namespace {

using namespace knitsim::sun;

enum class ArkMethod { Erk, Dirk, Imex };

constexpr long kJacobianEvalFrequency = 51;  // steps between Jacobian refreshes

// IMEX: the constant acceleration g(t) of the split, in a buffer allocated once.
struct ImexProblem final : OdeProblem {
  explicit ImexProblem(const FirstOrderSystem& system)
      : OdeProblem(system), constant(system.mechanical().dof(), 0.0) {}
  std::vector<double> constant;
};

ImexProblem& imex(void* user_data) {
  return static_cast<ImexProblem&>(*static_cast<OdeProblem*>(user_data));
}

// f_E = [0; g(t)]
int imex_explicit(double t, N_Vector /*y*/, N_Vector ydot, void* user_data) {
  return guarded([&] {
    ImexProblem& p = imex(user_data);
    const int n = p.fo.mechanical().dof();
    double* out = vec_data(ydot);
    std::fill_n(out, n, 0.0);
    p.fo.mechanical().constant_acceleration(t, out + n);
    return finite_or_recoverable(out + n, n);
  });
}

// f_I = f - f_E = [v; a_c - g - Gamma v]
int imex_implicit(double t, N_Vector y, N_Vector ydot, void* user_data) {
  return guarded([&] {
    ImexProblem& p = imex(user_data);
    const int n = p.fo.mechanical().dof();
    double* out = vec_data(ydot);
    p.fo.rhs(t, vec_data(y), out);
    p.fo.mechanical().constant_acceleration(t, p.constant.data());
    for (int i = 0; i < n; ++i) out[n + i] -= p.constant[i];
    return finite_or_recoverable(out, 2L * n);
  });
}

int arkode_linsys(double t, N_Vector y, N_Vector /*fy*/, SUNMatrix /*A*/, SUNMatrix /*M*/,
                  sunbooleantype jok, sunbooleantype* jcur, double gamma, void* user_data, N_Vector,
                  N_Vector, N_Vector) {
  return guarded([&] {
    auto* problem = static_cast<OdeProblem*>(user_data);
    bool current = false;
    const int r = problem->newton->assemble(t, vec_data(y), jok != SUNFALSE, gamma, &current);
    *jcur = current ? SUNTRUE : SUNFALSE;
    return r;
  });
}

ARKODE_DIRKTableID esdirk_table(int order) {
  switch (order) {
    case 3:
      return ARKODE_ESDIRK324L2SA_4_2_3;
    case 5:
      return ARKODE_ESDIRK547L2SA_7_4_5;
    default:
      return ARKODE_ESDIRK436L2SA_6_3_4;
  }
}

class Arkode final : public Integrator {
 public:
  Arkode(ArkMethod method, IntegratorInfo info) : method_(method), info_(std::move(info)) {}
  const IntegratorInfo& info() const override { return info_; }

  void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
             const IntegratorOptions& opt) override {
    opt.validate();
    const bool erk = method_ == ArkMethod::Erk;
    const int lo = erk ? 2 : 3, hi = erk ? 8 : 5;
    if (opt.max_order != 0 && (opt.max_order < lo || opt.max_order > hi)) {
      bad_field("max_order", opt.max_order,
                "must be 0 (default 4) or in " + std::to_string(lo) + ".." + std::to_string(hi) +
                    " for " + info_.name);
    }
    const int n = sys.dof();
    s_.reset();  // free the previous run's SUNDIALS objects before making new ones
    auto s = std::make_unique<Session>();
    s->ctx = make_context();
    SUNContext ctx = s->ctx.get();
    s->fo = std::make_unique<FirstOrderSystem>(sys);
    if (method_ == ArkMethod::Imex)
      s->problem = std::make_unique<ImexProblem>(*s->fo);
    else
      s->problem = std::make_unique<OdeProblem>(*s->fo);
    s->y = make_state(x0, v0, n, ctx);
    N_Vector y = s->y.get();
    const ErrorLog* log = &s->log;

    if (erk) {
      s->erk = ErkStepMemPtr(check_created(ERKStepCreate(ode_rhs, t0, y, ctx), "ERKStepCreate"));
      void* mem = s->erk.get();
      check(ERKStepSetErrHandlerFn(mem, record_error, &s->log), "ERKStepSetErrHandlerFn", kErk);
      check(ERKStepSetUserData(mem, s->problem.get()), "ERKStepSetUserData", kErk, log);
      if (const VectorPtr abstol = absolute_tolerances(opt, n, ctx))
        check(ERKStepSVtolerances(mem, opt.rtol, abstol.get()), "ERKStepSVtolerances", kErk, log);
      else
        check(ERKStepSStolerances(mem, opt.rtol, opt.atol), "ERKStepSStolerances", kErk, log);
      check(ERKStepSetMaxNumSteps(mem, opt.max_steps), "ERKStepSetMaxNumSteps", kErk, log);
      if (opt.max_order > 0)
        check(ERKStepSetOrder(mem, opt.max_order), "ERKStepSetOrder", kErk, log);
    } else {
      const bool split = method_ == ArkMethod::Imex;
      s->ark = ArkStepMemPtr(
          check_created(split ? ARKStepCreate(imex_explicit, imex_implicit, t0, y, ctx)
                              : ARKStepCreate(nullptr, ode_rhs, t0, y, ctx),
                        "ARKStepCreate"));
      void* mem = s->ark.get();
      check(ARKStepSetErrHandlerFn(mem, record_error, &s->log), "ARKStepSetErrHandlerFn", kArk);
      check(ARKStepSetUserData(mem, s->problem.get()), "ARKStepSetUserData", kArk, log);
      if (const VectorPtr abstol = absolute_tolerances(opt, n, ctx))
        check(ARKStepSVtolerances(mem, opt.rtol, abstol.get()), "ARKStepSVtolerances", kArk, log);
      else
        check(ARKStepSStolerances(mem, opt.rtol, opt.atol), "ARKStepSStolerances", kArk, log);
      check(ARKStepSetMaxNumSteps(mem, opt.max_steps), "ARKStepSetMaxNumSteps", kArk, log);
      check(ARKStepSetDeduceImplicitRhs(mem, SUNTRUE), "ARKStepSetDeduceImplicitRhs", kArk, log);
      if (split) {
        if (opt.max_order > 0)
          check(ARKStepSetOrder(mem, opt.max_order), "ARKStepSetOrder", kArk, log);
      } else {
        check(ARKStepSetTableNum(mem, esdirk_table(opt.max_order), ARKODE_ERK_NONE),
              "ARKStepSetTableNum", kArk, log);
      }
      s->newton = std::make_unique<NewtonMatrix>(*s->fo, MatrixKind::SparseCsc, ctx);
      s->problem->newton = s->newton.get();
      SUNMatrix A = s->newton->get();
      s->ls = make_newton_solver(opt, *s->fo, y, A, ctx);
      check(ARKStepSetLinearSolver(mem, s->ls.get(), A), "ARKStepSetLinearSolver", kArkLs, log);
      check(ARKStepSetLinSysFn(mem, arkode_linsys), "ARKStepSetLinSysFn", kArkLs, log);
      // Only valid once the linear solver is attached (ARKLS memory exists).
      check(ARKStepSetJacEvalFrequency(mem, kJacobianEvalFrequency), "ARKStepSetJacEvalFrequency",
            kArkLs, log);
    }
    s_ = std::move(s);
    t_ = t0;
    stop_time_ = std::numeric_limits<double>::quiet_NaN();
  }

  Step step(double t_stop) override {
    const bool erk = method_ == ArkMethod::Erk;
    void* mem = erk ? s_->erk.get() : s_->ark.get();
    const FlagNameFn name = erk ? kErk : kArk;
    if (!(t_stop > t_)) {
      std::ostringstream os;
      os << info_.name << ": stop time " << t_stop << " s is not ahead of t = " << t_ << " s";
      return {false, os.str()};
    }
    if (t_stop != stop_time_) {
      const int flag = erk ? ERKStepSetStopTime(mem, t_stop) : ARKStepSetStopTime(mem, t_stop);
      if (flag < 0) return {false, step_failure("SetStopTime", flag, name, t_, s_->log)};
      stop_time_ = t_stop;
    }
    s_->log.clear();  // a failure message names only this step's SUNDIALS messages
    const int flag = erk ? ERKStepEvolve(mem, t_stop, s_->y.get(), &t_, ARK_ONE_STEP)
                         : ARKStepEvolve(mem, t_stop, s_->y.get(), &t_, ARK_ONE_STEP);
    if (flag < 0)  // y and t_ are the last accepted state
      return {false, step_failure(erk ? "ERKStepEvolve" : "ARKStepEvolve", flag, name, t_, s_->log),
              flag == ARK_ERR_FAILURE || flag == ARK_CONV_FAILURE};
    return {};
  }

  // *StepReset at (t_, y) with the initial step re-estimated (SetInitStep 0; Reset alone keeps
  // the last step size). Counters and options are kept.
  bool restart() override {
    if (!s_) return false;
    const bool erk = method_ == ArkMethod::Erk;
    void* mem = erk ? s_->erk.get() : s_->ark.get();
    const int init = erk ? ERKStepSetInitStep(mem, 0.0) : ARKStepSetInitStep(mem, 0.0);
    if (init < 0) return false;
    const int reset = erk ? ERKStepReset(mem, t_, s_->y.get()) : ARKStepReset(mem, t_, s_->y.get());
    if (reset < 0) return false;
    stop_time_ = std::numeric_limits<double>::quiet_NaN();  // set again by the next step()
    return true;
  }

  double time() const override { return t_; }
  const double* positions() const override { return vec_data(s_->y.get()); }
  const double* velocities() const override {
    return vec_data(s_->y.get()) + s_->fo->mechanical().dof();
  }

  void fill_stats(RunStats& st) const override {
    if (!s_) return;
    if (method_ == ArkMethod::Erk) {
      void* mem = s_->erk.get();
      check(ERKStepGetNumSteps(mem, &st.steps), "ERKStepGetNumSteps", kErk);
      check(ERKStepGetNumRhsEvals(mem, &st.rhs_evals), "ERKStepGetNumRhsEvals", kErk);
      check(ERKStepGetNumErrTestFails(mem, &st.err_test_fails), "ERKStepGetNumErrTestFails", kErk);
      if (st.steps > 0) st.max_order_used = last_order();
      return;
    }
    void* mem = s_->ark.get();
    long nfe = 0, nfi = 0, nfe_ls = 0;
    check(ARKStepGetNumSteps(mem, &st.steps), "ARKStepGetNumSteps", kArk);
    check(ARKStepGetNumRhsEvals(mem, &nfe, &nfi), "ARKStepGetNumRhsEvals", kArk);
    check(ARKStepGetNumLinSolvSetups(mem, &st.lin_setups), "ARKStepGetNumLinSolvSetups", kArk);
    check(ARKStepGetNumErrTestFails(mem, &st.err_test_fails), "ARKStepGetNumErrTestFails", kArk);
    check(ARKStepGetNonlinSolvStats(mem, &st.nonlin_iters, &st.nonlin_fails),
          "ARKStepGetNonlinSolvStats", kArk);
    check(ARKStepGetNumJacEvals(mem, &st.jac_evals), "ARKStepGetNumJacEvals", kArkLs);
    check(ARKStepGetNumLinIters(mem, &st.lin_iters), "ARKStepGetNumLinIters", kArkLs);
    check(ARKStepGetNumLinRhsEvals(mem, &nfe_ls), "ARKStepGetNumLinRhsEvals", kArkLs);
    st.rhs_evals = nfe + nfi + nfe_ls;
    add_newton_solver_counts(s_->ls.get(), st);
    if (st.steps > 0) st.max_order_used = last_order();
  }

  // The order of the Butcher table in use (implicit table for ARK IMEX).
  int last_order() const override {
    if (!s_) return 0;
    if (method_ == ArkMethod::Erk) {
      ARKodeButcherTable B = nullptr;
      check(ERKStepGetCurrentButcherTable(s_->erk.get(), &B), "ERKStepGetCurrentButcherTable",
            kErk);
      return B ? B->q : 0;
    }
    ARKodeButcherTable Bi = nullptr, Be = nullptr;
    check(ARKStepGetCurrentButcherTables(s_->ark.get(), &Bi, &Be), "ARKStepGetCurrentButcherTables",
          kArk);
    return Bi ? Bi->q : (Be ? Be->q : 0);
  }

 private:
  static constexpr FlagNameFn kErk = ERKStepGetReturnFlagName;
  static constexpr FlagNameFn kArk = ARKStepGetReturnFlagName;
  static constexpr FlagNameFn kArkLs = ARKStepGetLinReturnFlagName;

  // Everything SUNDIALS of one run, declared in creation order (destroyed in reverse).
  struct Session {
    ContextPtr ctx;
    std::unique_ptr<FirstOrderSystem> fo;
    std::unique_ptr<OdeProblem> problem;
    VectorPtr y;
    std::unique_ptr<NewtonMatrix> newton;
    LinearSolverPtr ls;
    ErrorLog log;
    ErkStepMemPtr erk;  // arkode-erk
    ArkStepMemPtr ark;  // arkode-dirk, arkode-imex
  };

  ArkMethod method_;
  IntegratorInfo info_;
  std::unique_ptr<Session> s_;
  double t_ = 0.0;
  double stop_time_ = 0.0;
};

}  // namespace

std::unique_ptr<Integrator> make_arkode_erk() {
  return std::make_unique<Arkode>(
      ArkMethod::Erk,
      IntegratorInfo{"arkode-erk", "ARKODE ERKStep, adaptive explicit RK (order 4 default)", 4,
                     true, true});
}

std::unique_ptr<Integrator> make_arkode_dirk() {
  return std::make_unique<Arkode>(
      ArkMethod::Dirk,
      IntegratorInfo{"arkode-dirk",
                     "ARKODE ARKStep ESDIRK (order 4 default), Newton, sparse direct (Schur "
                     "LDL^T or KLU)",
                     4, true, false});
}

std::unique_ptr<Integrator> make_arkode_imex() {
  return std::make_unique<Arkode>(
      ArkMethod::Imex,
      IntegratorInfo{
          "arkode-imex",
          "ARKODE ARKStep IMEX (ARK 4 default): springs + damping implicit (sparse direct), "
          "gravity explicit",
          4, true, false});
}

}  // namespace knitsim::detail
