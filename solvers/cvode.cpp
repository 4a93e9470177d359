// CVODE integrators (SUNDIALS 6.4, linked as libsundials_cvode, never cvodes) on the 2n
// first-order system y = [x; v], y' = [v; a_c(t, x) - Gamma v] (src/core/first_order.hpp), with
// Jacobian J = [[0, I], [Ax, -Gamma]], Ax = da_c/dx.
//
//   cvode-bdf        BDF orders 1..5, Newton iteration; A = I - gamma J assembled into J's
//                    fixed CSC pattern (NewtonMatrix, via CVodeSetLinSysFn: values only, the
//                    pattern is written once), solved by the symmetric Schur-complement LDL^T
//                    (default) or KLU (IntegratorOptions::newton_solver); both keep their
//                    symbolic analysis across set-ups and refactor numerically per set-up.
//   cvode-bdf-dense  the same with a dense matrix and dense LU: O((2n)^3) per set-up, for
//                    comparison on small meshes only (refused above 2n = 3000).
//   cvode-bdf-gmres  the same BDF/Newton, matrix-free SPGMR: analytic products
//                    J w = [w_v; Ax w_x - Gamma w_v] (Ax refreshed in jtsetup at the Newton
//                    iterate), a left preconditioner (below; default the lagged Schur
//                    LDL^T), Krylov dimension IntegratorOptions::krylov_dim (0 = SUNDIALS'
//                    5), linear tolerance factor krylov_eps_lin (with block-Jacobi it sets
//                    the residual floor).
//   cvode-adams      Adams-Moulton orders 1..12 solved by fixed-point iteration (no Jacobian,
//                    no linear solver): its step is bounded by stability, ~1/max|lambda|, so
//                    on the drape (c/m ~ 1e5 /s) it costs like an explicit method.
//
// Each step() is one CVode(..., CV_ONE_STEP) call with CVodeSetStopTime(t_stop), so the
// integrator never steps past t_stop. CVODE's per-call step cap (default 500) is set to
// IntegratorOptions::max_steps; run_to_equilibrium enforces the run's cap. Tolerances:
// scalar rtol, atol, or per component (atol on x, velocity_atol on v) when velocity_atol > 0
// (sun::absolute_tolerances). max_order caps the BDF (<= 5) or Adams (<= 12) order; the
// largest order used is tracked with CVodeGetLastOrder after each step.
//
// BDF stability limit detection (CVodeSetStabLimDet) is on: BDF orders 3-5 are not A-stable,
// and at tight tolerances (rtol 1e-8, atol 1e-10) the order-5 steps go unstable on two_corner
// without it (CV_ERR_FAILURE); at the default tolerances it changes nothing noticeable.
//
// The BDF Newton iteration is converged 10x tighter than CVODE's default (nonlinear
// convergence coefficient kNewtonConvCoef = 0.01 instead of 0.1): the stop rule tests the
// static residual, i.e. the stiff spring forces, which a loosely converged corrector leaves
// noisy (at 0.1 small grids stall above equilibrium_tol until t_max, and the drapes take more
// steps). Why 0.01 and not 0.001: docs/numerics.md, "Linear algebra".
//
// Restarts (Integrator::restart, used by the driver up to IntegratorOptions::max_restarts):
// CV_ERR_FAILURE and CV_CONV_FAILURE are reported as recoverable; restart() re-initialises
// CVODE at the last accepted state (CVodeReInit: order 1, a new initial step from cvHin, the
// linear solver and every option kept) and carries CVODE's counters, which ReInit zeroes.
//
// Preconditioners of cvode-bdf-gmres (IntegratorOptions::gmres_preconditioner), all of the
// form P = [[I, -gamma I], [-gamma B, D]], D = I + gamma Gamma, with B the Jacobian block Ax
// (or part of it) at the latest Jacobian refresh (psetup with jok false); P^-1 through the
// Schur complement S = D - gamma^2 B:
//     z_v = S^-1 (r_v + gamma B r_x),  z_x = r_x + gamma z_v.
//   block-jacobi  B = Ax's 3 x 3 diagonal block per particle p: S_p^-1 inverted exactly
//                 (needs every particle's x, y, z as unknowns: not on a mirror reduction);
//   schur-ic      B = Ax, S scaled by M to the symmetric M D - gamma^2 K and approximated by
//                 Eigen's incomplete Cholesky (which shifts the diagonal until the pivots
//                 are positive: S is indefinite where springs are compressed);
//   schur-ldl     the same S by sparse LDL^T (analysed once): exact at the set-up, lagged
//                 until the next one, where GMRES corrects the lag.
// S (or S_p^-1) is rebuilt at every psetup (gamma changes), the Jacobian only when jok is false.
//
// Counters (fill_stats): rhs_evals include the linear solver's difference-quotient RHS
// calls; jac_evals are Jacobian evaluations (gmres: Ax refreshes for products plus
// preconditioner refreshes).
#include <cvode/cvode_ls.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "solvers/factories.hpp"
#include "solvers/schur_matrix.hpp"
#include "solvers/sundials_common.hpp"
#include "solvers/symmetric_factor.hpp"
#include "src/core/invalid_field.hpp"

namespace knitsim::detail {

namespace {

using namespace knitsim::sun;

enum class CvodeMethod { BdfSparse, BdfDense, BdfGmres, AdamsFixedPoint };

constexpr long kDenseLimit = 3000;        // largest 2n cvode-bdf-dense accepts
constexpr double kNewtonConvCoef = 0.01;  // BDF Newton tolerance factor (CVODE default 0.1)

// ---- cvode-bdf / cvode-bdf-dense: the linear system A = I - gamma J -----------------------

int cvode_linsys(double t, N_Vector y, N_Vector /*fy*/, SUNMatrix /*A*/, sunbooleantype jok,
                 sunbooleantype* jcur, double gamma, void* user_data, N_Vector, N_Vector,
                 N_Vector) {
  return guarded([&] {
    auto* problem = static_cast<OdeProblem*>(user_data);
    bool current = false;
    const int r = problem->newton->assemble(t, vec_data(y), jok != SUNFALSE, gamma, &current);
    *jcur = current ? SUNTRUE : SUNFALSE;
    return r;
  });
}

// ---- cvode-bdf-gmres: Jacobian-vector products and the preconditioners -----------------

using GmresPreconditioner = IntegratorOptions::GmresPreconditioner;

struct KrylovProblem final : OdeProblem {
  KrylovProblem(const FirstOrderSystem& system, GmresPreconditioner which,
                IntegratorOptions::Factorization factorization)
      : OdeProblem(system), preconditioner(which), ldl(factorization) {
    const MechanicalSystem& sys = system.mechanical();
    const CscPattern& p = sys.stiffness_pattern();
    const int n = sys.dof();
    ax_product.assign(p.nnz(), 0.0);
    ax_scratch.assign(p.nnz(), 0.0);
    if (which == GmresPreconditioner::BlockJacobi) {
      const int particles = n / 3;
      block_pos.assign(9 * particles, -1);
      for (int q = 0; q < particles; ++q)
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r) block_pos[9 * q + 3 * c + r] = p.find(3 * q + r, 3 * q + c);
      block_ax.assign(9 * particles, 0.0);
      block_inv.assign(9 * particles, 0.0);
    } else if (which != GmresPreconditioner::None) {
      schur = schur_matrix(sys);
      ax_rx.assign(n, 0.0);
      rhs = Eigen::VectorXd::Zero(n);
      z_v = Eigen::VectorXd::Zero(n);
    }
  }
  GmresPreconditioner preconditioner;
  std::vector<double> ax_product;  // Ax at the latest jtsetup (stiffness pattern order)
  std::vector<double> ax_scratch;  // Ax at the latest preconditioner refresh
  // BlockJacobi
  std::vector<int> block_pos;     // per particle, column-major 3 x 3: position in Ax, -1 absent
  std::vector<double> block_ax;   // per particle: B_p, column-major
  std::vector<double> block_inv;  // per particle: S_p^-1, column-major
  // SchurIc, SchurLdl
  Eigen::SparseMatrix<double> schur;  // S = M (I + gamma Gamma) - gamma^2 K at the latest psetup
  Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>> ic;
  SymmetricFactor ldl;
  bool analysed = false;
  std::vector<double> ax_rx;
  Eigen::VectorXd rhs, z_v;
};

KrylovProblem& krylov(void* user_data) {
  return static_cast<KrylovProblem&>(*static_cast<OdeProblem*>(user_data));
}

int cvode_jtsetup(double t, N_Vector y, N_Vector /*fy*/, void* user_data) {
  return guarded([&] {
    KrylovProblem& k = krylov(user_data);
    k.fo.mechanical().stiffness_values(t, vec_data(y), k.ax_product.data());
    return finite_or_recoverable(k.ax_product.data(), static_cast<long>(k.ax_product.size()));
  });
}

int cvode_jtimes(N_Vector w, N_Vector jw, double /*t*/, N_Vector /*y*/, N_Vector /*fy*/,
                 void* user_data, N_Vector /*tmp*/) {
  return guarded([&] {
    KrylovProblem& k = krylov(user_data);
    const MechanicalSystem& sys = k.fo.mechanical();
    const int n = sys.dof();
    const double* wx = vec_data(w);
    const double* wv = wx + n;
    double* out = vec_data(jw);
    std::copy_n(wv, n, out);
    csc_multiply(sys.stiffness_pattern(), k.ax_product.data(), wx, out + n);
    const auto& g = sys.damping_rate();
    for (int i = 0; i < n; ++i) out[n + i] -= g[i] * wv[i];
    return 0;
  });
}

// Inverse of a column-major 3 x 3 matrix; false if (nearly) singular.
bool invert3(const double* a, double* inv) {
  const double c00 = a[4] * a[8] - a[7] * a[5], c01 = a[7] * a[2] - a[1] * a[8],
               c02 = a[1] * a[5] - a[4] * a[2];
  const double det = a[0] * c00 + a[3] * c01 + a[6] * c02;
  double scale = 0.0;
  for (int i = 0; i < 9; ++i) scale = std::max(scale, std::abs(a[i]));
  if (!(std::abs(det) > 1e-14 * scale * scale * scale)) return false;
  const double d = 1.0 / det;
  inv[0] = c00 * d;
  inv[1] = c01 * d;
  inv[2] = c02 * d;
  inv[3] = (a[6] * a[5] - a[3] * a[8]) * d;
  inv[4] = (a[0] * a[8] - a[6] * a[2]) * d;
  inv[5] = (a[3] * a[2] - a[0] * a[5]) * d;
  inv[6] = (a[3] * a[7] - a[6] * a[4]) * d;
  inv[7] = (a[6] * a[1] - a[0] * a[7]) * d;
  inv[8] = (a[0] * a[4] - a[3] * a[1]) * d;
  return true;
}

// Block-Jacobi set-up: S_p^-1 per particle.
int block_jacobi_setup(KrylovProblem& k, double gamma) {
  const MechanicalSystem& sys = k.fo.mechanical();
  const auto& g = sys.damping_rate();
  for (std::size_t i = 0; i < k.block_pos.size(); ++i)
    k.block_ax[i] = k.block_pos[i] < 0 ? 0.0 : k.ax_scratch[k.block_pos[i]];
  for (int q = 0; q < sys.dof() / 3; ++q) {
    double s[9];
    const double* b = &k.block_ax[9 * q];
    for (int i = 0; i < 9; ++i) s[i] = -gamma * gamma * b[i];
    for (int r = 0; r < 3; ++r) s[4 * r] += 1.0 + gamma * g[3 * q + r];
    if (!invert3(s, &k.block_inv[9 * q])) return 1;
  }
  return 0;
}

// Schur set-up: S = M (I + gamma Gamma) - gamma^2 K with K = M Ax, then its incomplete
// Cholesky (Eigen's, with its diagonal shift where S is not positive definite) or its LDL^T.
int schur_setup(KrylovProblem& k, double gamma) {
  fill_schur_values(k.fo.mechanical(), gamma, k.ax_scratch.data(), k.schur);
  if (k.preconditioner == GmresPreconditioner::SchurIc) {
    if (!k.analysed) k.ic.analyzePattern(k.schur);
    k.analysed = true;
    k.ic.factorize(k.schur);
    return k.ic.info() == Eigen::Success ? 0 : 1;
  }
  if (!k.analysed) k.ldl.analyze(k.schur);
  k.analysed = true;
  return k.ldl.factorize(k.schur) ? 0 : 1;
}

int cvode_psetup(double t, N_Vector y, N_Vector /*fy*/, sunbooleantype jok, sunbooleantype* jcur,
                 double gamma, void* user_data) {
  return guarded([&] {
    KrylovProblem& k = krylov(user_data);
    if (jok == SUNFALSE) {
      k.fo.mechanical().stiffness_values(t, vec_data(y), k.ax_scratch.data());
      if (finite_or_recoverable(k.ax_scratch.data(), static_cast<long>(k.ax_scratch.size())) != 0)
        return 1;
    }
    *jcur = jok == SUNFALSE ? SUNTRUE : SUNFALSE;
    return k.preconditioner == GmresPreconditioner::BlockJacobi ? block_jacobi_setup(k, gamma)
                                                                : schur_setup(k, gamma);
  });
}

// z = P^-1 r for P = [[I, -gamma I], [-gamma B, D]] (B = Ax or its diagonal blocks at the
// latest refresh, D = I + gamma Gamma): z_v = (D - gamma^2 B)^-1 (r_v + gamma B r_x),
// z_x = r_x + gamma z_v.
int cvode_psolve(double /*t*/, N_Vector /*y*/, N_Vector /*fy*/, N_Vector r, N_Vector z,
                 double gamma, double /*delta*/, int /*lr*/, void* user_data) {
  return guarded([&] {
    KrylovProblem& k = krylov(user_data);
    const MechanicalSystem& sys = k.fo.mechanical();
    const int n = sys.dof();
    const double* rx = vec_data(r);
    const double* rv = rx + n;
    double* zx = vec_data(z);
    double* zv = zx + n;
    if (k.preconditioner == GmresPreconditioner::BlockJacobi) {
      for (int q = 0; q < n / 3; ++q) {
        const double* b = &k.block_ax[9 * q];
        const double* inv = &k.block_inv[9 * q];
        double rhs[3];
        for (int i = 0; i < 3; ++i)
          rhs[i] = rv[3 * q + i] +
                   gamma * (b[i] * rx[3 * q] + b[3 + i] * rx[3 * q + 1] + b[6 + i] * rx[3 * q + 2]);
        for (int i = 0; i < 3; ++i)
          zv[3 * q + i] = inv[i] * rhs[0] + inv[3 + i] * rhs[1] + inv[6 + i] * rhs[2];
      }
    } else {  // the same with the whole Ax, scaled by M to the symmetric S
      csc_multiply(sys.stiffness_pattern(), k.ax_scratch.data(), rx, k.ax_rx.data());
      const auto& m = sys.mass();
      for (int i = 0; i < n; ++i) k.rhs[i] = m[i] * (rv[i] + gamma * k.ax_rx[i]);
      if (k.preconditioner == GmresPreconditioner::SchurIc)
        k.z_v = k.ic.solve(k.rhs);
      else
        k.ldl.solve(k.rhs, k.z_v);
      std::copy_n(k.z_v.data(), n, zv);
    }
    for (int i = 0; i < n; ++i) zx[i] = rx[i] + gamma * zv[i];
    return 0;
  });
}

// ---- the integrator -------------------------------------------------------------------

class Cvode final : public Integrator {
 public:
  Cvode(CvodeMethod method, IntegratorInfo info) : method_(method), info_(std::move(info)) {}
  const IntegratorInfo& info() const override { return info_; }

  void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
             const IntegratorOptions& opt) override {
    opt.validate();
    const int n = sys.dof();
    const bool bdf = method_ != CvodeMethod::AdamsFixedPoint;
    const int order_cap = bdf ? 5 : 12;
    if (opt.max_order > order_cap) {
      bad_field("max_order", opt.max_order,
                "must be in 0.." + std::to_string(order_cap) + " for " + info_.name +
                    " (0 = " + std::to_string(order_cap) + ")");
    }
    if (method_ == CvodeMethod::BdfDense && 2L * n > kDenseLimit) {
      std::ostringstream os;
      os << info_.name << ": first-order system size 2n = " << 2L * n << " exceeds " << kDenseLimit
         << " (dense LU is for small meshes; use cvode-bdf)";
      throw std::invalid_argument(os.str());
    }
    if (method_ == CvodeMethod::BdfGmres &&
        opt.gmres_preconditioner == GmresPreconditioner::BlockJacobi &&
        !has_node_triples(sys.stiffness_pattern()))
      throw std::invalid_argument(
          "--gmres-preconditioner block-jacobi: needs every particle's x, y, z as unknowns (a "
          "whole sheet or a knit chart); this model has " +
          std::to_string(n) + " unknowns (a mirror reduction?): use schur-ldl");

    s_.reset();  // free the previous run's SUNDIALS objects before making new ones
    auto s = std::make_unique<Session>();
    s->ctx = make_context();
    SUNContext ctx = s->ctx.get();
    s->fo = std::make_unique<FirstOrderSystem>(sys);
    if (method_ == CvodeMethod::BdfGmres)
      s->problem =
          std::make_unique<KrylovProblem>(*s->fo, opt.gmres_preconditioner, opt.factorization);
    else
      s->problem = std::make_unique<OdeProblem>(*s->fo);
    s->y = make_state(x0, v0, n, ctx);
    N_Vector y = s->y.get();

    s->mem = CvodeMemPtr(check_created(CVodeCreate(bdf ? CV_BDF : CV_ADAMS, ctx), "CVodeCreate"));
    void* mem = s->mem.get();
    const ErrorLog* log = &s->log;
    check(CVodeSetErrHandlerFn(mem, record_error, &s->log), "CVodeSetErrHandlerFn", kName);
    check(CVodeInit(mem, ode_rhs, t0, y), "CVodeInit", kName, log);
    check(CVodeSetUserData(mem, s->problem.get()), "CVodeSetUserData", kName, log);
    if (const VectorPtr abstol = absolute_tolerances(opt, n, ctx))
      check(CVodeSVtolerances(mem, opt.rtol, abstol.get()), "CVodeSVtolerances", kName, log);
    else
      check(CVodeSStolerances(mem, opt.rtol, opt.atol), "CVodeSStolerances", kName, log);
    check(CVodeSetMaxNumSteps(mem, opt.max_steps), "CVodeSetMaxNumSteps", kName, log);
    if (opt.max_order > 0) check(CVodeSetMaxOrd(mem, opt.max_order), "CVodeSetMaxOrd", kName, log);
    if (bdf) {
      check(CVodeSetStabLimDet(mem, SUNTRUE), "CVodeSetStabLimDet", kName, log);
      check(CVodeSetNonlinConvCoef(mem, kNewtonConvCoef), "CVodeSetNonlinConvCoef", kName, log);
    }

    switch (method_) {
      case CvodeMethod::BdfSparse:
      case CvodeMethod::BdfDense: {
        const bool sparse = method_ == CvodeMethod::BdfSparse;
        s->newton = std::make_unique<NewtonMatrix>(
            *s->fo, sparse ? MatrixKind::SparseCsc : MatrixKind::Dense, ctx);
        s->problem->newton = s->newton.get();
        SUNMatrix A = s->newton->get();
        s->ls = sparse
                    ? make_newton_solver(opt, *s->fo, y, A, ctx)
                    : LinearSolverPtr(check_created(SUNLinSol_Dense(y, A, ctx), "SUNLinSol_Dense"));
        check(CVodeSetLinearSolver(mem, s->ls.get(), A), "CVodeSetLinearSolver", kLsName, log);
        check(CVodeSetLinSysFn(mem, cvode_linsys), "CVodeSetLinSysFn", kLsName, log);
        break;
      }
      case CvodeMethod::BdfGmres: {
        const bool pre = opt.gmres_preconditioner != GmresPreconditioner::None;
        const int pretype = pre ? SUN_PREC_LEFT : SUN_PREC_NONE;
        s->ls = LinearSolverPtr(
            check_created(SUNLinSol_SPGMR(y, pretype, opt.krylov_dim, ctx), "SUNLinSol_SPGMR"));
        check(CVodeSetLinearSolver(mem, s->ls.get(), nullptr), "CVodeSetLinearSolver", kLsName,
              log);
        check(CVodeSetJacTimes(mem, cvode_jtsetup, cvode_jtimes), "CVodeSetJacTimes", kLsName, log);
        check(CVodeSetEpsLin(mem, opt.krylov_eps_lin), "CVodeSetEpsLin", kLsName, log);
        if (pre)
          check(CVodeSetPreconditioner(mem, cvode_psetup, cvode_psolve), "CVodeSetPreconditioner",
                kLsName, log);
        break;
      }
      case CvodeMethod::AdamsFixedPoint:
        s->nls = NonlinearSolverPtr(
            check_created(SUNNonlinSol_FixedPoint(y, 0, ctx), "SUNNonlinSol_FixedPoint"));
        check(CVodeSetNonlinearSolver(mem, s->nls.get()), "CVodeSetNonlinearSolver", kName, log);
        break;
    }
    s_ = std::move(s);
    carried_ = RunStats{};
    t_ = t0;
    stop_time_ = std::numeric_limits<double>::quiet_NaN();
    max_order_used_ = last_order_ = 0;
  }

  Step step(double t_stop) override {
    void* mem = s_->mem.get();
    if (!(t_stop > t_)) {
      std::ostringstream os;
      os << info_.name << ": stop time " << t_stop << " s is not ahead of t = " << t_ << " s";
      return {false, os.str()};
    }
    if (t_stop != stop_time_) {
      const int flag = CVodeSetStopTime(mem, t_stop);
      if (flag < 0) return {false, step_failure("CVodeSetStopTime", flag, kName, t_, s_->log)};
      stop_time_ = t_stop;
    }
    s_->log.clear();  // a failure message names only this step's SUNDIALS messages
    const int flag = CVode(mem, t_stop, s_->y.get(), &t_, CV_ONE_STEP);
    if (flag < 0)  // CVODE has left y at its last accepted state, t_ at that time
      return {false, step_failure("CVode", flag, kName, t_, s_->log),
              flag == CV_ERR_FAILURE || flag == CV_CONV_FAILURE};
    int order = 0;
    const int got = CVodeGetLastOrder(mem, &order);
    if (got < 0) return {false, step_failure("CVodeGetLastOrder", got, kName, t_, s_->log)};
    last_order_ = order;
    max_order_used_ = std::max(max_order_used_, order);
    return {};
  }

  // CVodeReInit at (t_, y): order 1 and a fresh initial step, the linear solver and all options
  // kept. ReInit zeroes CVODE's counters, so they are carried over first.
  bool restart() override {
    if (!s_) return false;
    RunStats now;
    cvode_counters(now);
    add_counters(carried_, now);
    if (CVodeReInit(s_->mem.get(), t_, s_->y.get()) < 0) return false;
    stop_time_ = std::numeric_limits<double>::quiet_NaN();  // set again by the next step()
    return true;
  }

  int last_order() const override { return last_order_; }
  double time() const override { return t_; }
  const double* positions() const override { return vec_data(s_->y.get()); }
  const double* velocities() const override {
    return vec_data(s_->y.get()) + s_->fo->mechanical().dof();
  }

  void fill_stats(RunStats& st) const override {
    if (!s_) return;
    cvode_counters(st);
    add_counters(st, carried_);
    add_newton_solver_counts(s_->ls.get(), st);  // the solver's own counts survive a restart
    if (method_ == CvodeMethod::BdfGmres) {
      const auto& k = static_cast<const KrylovProblem&>(*s_->problem);
      if (k.preconditioner == GmresPreconditioner::SchurLdl) k.ldl.fill_stats(st);
    }
    st.max_order_used = max_order_used_;
  }

 private:
  static constexpr FlagNameFn kName = CVodeGetReturnFlagName;
  static constexpr FlagNameFn kLsName = CVodeGetLinReturnFlagName;

  // CVODE's counters since the last (Re)Init into st (rhs_evals include the linear solver's
  // difference-quotient RHS calls; gmres jac_evals = J v set-ups + preconditioner set-ups).
  void cvode_counters(RunStats& st) const {
    void* mem = s_->mem.get();
    long nfe = 0, nfe_ls = 0;
    check(CVodeGetNumSteps(mem, &st.steps), "CVodeGetNumSteps", kName);
    check(CVodeGetNumRhsEvals(mem, &nfe), "CVodeGetNumRhsEvals", kName);
    check(CVodeGetNumLinSolvSetups(mem, &st.lin_setups), "CVodeGetNumLinSolvSetups", kName);
    check(CVodeGetNumErrTestFails(mem, &st.err_test_fails), "CVodeGetNumErrTestFails", kName);
    check(CVodeGetNonlinSolvStats(mem, &st.nonlin_iters, &st.nonlin_fails),
          "CVodeGetNonlinSolvStats", kName);
    st.jac_evals = st.lin_iters = 0;
    if (s_->ls) {
      check(CVodeGetNumLinRhsEvals(mem, &nfe_ls), "CVodeGetNumLinRhsEvals", kLsName);
      check(CVodeGetNumLinIters(mem, &st.lin_iters), "CVodeGetNumLinIters", kLsName);
      if (method_ == CvodeMethod::BdfGmres) {
        long njt = 0, npe = 0;
        check(CVodeGetNumJTSetupEvals(mem, &njt), "CVodeGetNumJTSetupEvals", kLsName);
        check(CVodeGetNumPrecEvals(mem, &npe), "CVodeGetNumPrecEvals", kLsName);
        st.jac_evals = njt + npe;
      } else {
        check(CVodeGetNumJacEvals(mem, &st.jac_evals), "CVodeGetNumJacEvals", kLsName);
      }
    }
    st.rhs_evals = nfe + nfe_ls;
  }

  // Everything SUNDIALS of one run, declared in creation order (destroyed in reverse).
  struct Session {
    ContextPtr ctx;
    std::unique_ptr<FirstOrderSystem> fo;
    std::unique_ptr<OdeProblem> problem;
    VectorPtr y;
    std::unique_ptr<NewtonMatrix> newton;
    LinearSolverPtr ls;
    NonlinearSolverPtr nls;
    ErrorLog log;
    CvodeMemPtr mem;
  };

  CvodeMethod method_;
  IntegratorInfo info_;
  std::unique_ptr<Session> s_;
  RunStats carried_;  // CVODE's counts of this run before its latest restart
  double t_ = 0.0;
  double stop_time_ = 0.0;
  int max_order_used_ = 0;
  int last_order_ = 0;  // order of the last step (CVodeGetLastOrder)
};

}  // namespace

std::unique_ptr<Integrator> make_cvode_bdf() {
  return std::make_unique<Cvode>(
      CvodeMethod::BdfSparse,
      IntegratorInfo{"cvode-bdf",
                     "CVODE BDF (orders 1-5), Newton, sparse direct (Schur LDL^T or KLU), "
                     "analytic Jacobian",
                     0, true, false});
}

std::unique_ptr<Integrator> make_cvode_bdf_dense() {
  return std::make_unique<Cvode>(
      CvodeMethod::BdfDense,
      IntegratorInfo{"cvode-bdf-dense", "CVODE BDF, Newton, dense LU (comparison only, 2n <= 3000)",
                     0, true, false});
}

std::unique_ptr<Integrator> make_cvode_bdf_gmres() {
  return std::make_unique<Cvode>(
      CvodeMethod::BdfGmres, IntegratorInfo{"cvode-bdf-gmres",
                                            "CVODE BDF, Newton-Krylov SPGMR, analytic J v, Schur "
                                            "LDL^T preconditioner (--gmres-preconditioner)",
                                            0, true, false});
}

std::unique_ptr<Integrator> make_cvode_adams() {
  return std::make_unique<Cvode>(
      CvodeMethod::AdamsFixedPoint,
      IntegratorInfo{"cvode-adams",
                     "CVODE Adams-Moulton (orders 1-12), fixed-point iteration, no Jacobian "
                     "(explicit-like: stability-bound steps)",
                     0, true, true});
}

}  // namespace knitsim::detail
