// equilibrium: the state the damped dynamics reach from rest, found without integrating the
// transient (user's view and measurements: docs/equilibrium.md).
//
//   1. While pins move (t < equilibrium_start_time()) the dynamics run: cvode-bdf with the run's
//      options. The soft modes relax far slower than the pins move (docs/equilibrium.md), so the
//      path through the motion is not quasi-static and must be integrated.
//   2. Then continuation along the overdamped flow C dx/ds = F(x) -- the gradient flow of the
//      potential energy E, since F = -dE/dx and C = M Gamma is the (diagonal, positive) damping
//      matrix -- by linearly implicit steps
//          (C / h + K) dx = F(x),   K = -M Ax = d^2E/dx^2 (symmetric),
//      globalised by a trust region on E: a step is accepted if E falls; rho = actual / predicted
//      fall (quadratic model F.dx - dx.K dx / 2) above 0.75 grows h x4, below 0.25 halves it; a
//      rejected step (E rises, or C/h + K has a negative pivot) divides h by 4. As h grows the
//      step becomes Newton's with the exact Hessian, so the end converges quadratically. A step
//      the model does not admit whole (MechanicalSystem::admissible_step: a contact barrier it
//      would jump through) is cut to the admitted fraction before the energy test. Near
//      the minimum E's change drowns in round-off; there a step is accepted if it lowers
//      ||F||_inf. The first h moves the sheet kFirstMove at most (h F_i / C_i).
//   3. A converged step (||dx||_inf <= position_tol) at a state where K has negative pivots is a
//      saddle (a sheet held flat in compression, an exactly symmetric start): the state is moved
//      kEscape along K's most negative mode, its largest component positive (a fixed sign, so
//      runs are reproducible), and the flow goes on; RunStats.saddle_escapes counts it.
// The stop and the certificate are the driver's, as for every integrator
// (equilibrium_check.hpp). Where a dof has no damping its mass per second stands in for C (the
// flow's end does not depend on C's scale).
//
// Fallback: kMaxRejected tries in a row that the step control rejects, kMaxStalled converged
// steps in a row where K is not positive definite and no negative mode is found, or
// kMaxFlowSteps flow steps without the driver's stop hand the run to the dynamics (cvode-bdf,
// from the current state at rest) to its end; RunStats.fallbacks counts it and the status
// message says so. t then advances again.
//
// Time: the flow's h is a continuation parameter, not time. The solver's t stays at the end of
// the pins' motion (or the start), so t_final says when the pins stopped and --continue from
// its state restarts the flow at once; velocities are 0 after the motion.
//
// Counters: steps = flow steps (one accepted step each, or the one that gave up) plus the
// dynamics' steps; nonlin_fails = rejected tries of a flow step plus the dynamics' own;
// factorisations include the dynamics' and the saddle probes'.
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include "solvers/equilibrium_check.hpp"
#include "solvers/factories.hpp"
#include "solvers/schur_matrix.hpp"
#include "solvers/symmetric_factor.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim::detail {

namespace {

constexpr double kFirstMove = 1e-3;  // m: the largest displacement of the first flow step
constexpr double kEscape = 1e-3;     // m: the largest displacement of a saddle escape
constexpr double kMaxH = 1e15;       // s: beyond this C / h is below round-off of K
constexpr int kMaxRejected = 60;     // rejected tries in a row before the fallback
constexpr long kMaxFlowSteps = 5000;  // before the fallback (drapes: experiments/equilibrium)
constexpr int kMaxStalled = 20;       // converged steps in a row, K not definite, no mode to leave
constexpr double kRoundoffFall = 1e-12;  // relative energy change read as round-off

class EquilibriumSolver final : public Integrator {
 public:
  const IntegratorInfo& info() const override { return info_; }

  void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
             const IntegratorOptions& opt) override {
    opt.validate();
    sys_ = &sys;
    opt_ = opt;
    n_ = sys.dof();
    t_ = t0;
    x_.assign(x0, x0 + n_);
    v_.assign(v0, v0 + n_);
    steps_ = rhs_ = factorisations_ = rejected_ = escapes_ = fallbacks_ = flow_steps_ = 0;
    stalled_ = 0;
    fallback_ = false;
    motion_ = RunStats{};
    h_ = 0.0;
    fresh_ = true;
    A_ = schur_matrix(sys);
    factor_ = std::make_unique<SymmetricFactor>(opt.factorization);
    factor_->analyze(A_);
    probe_.reset();
    c_.resize(n_);
    const auto& m = sys.mass();
    const auto& g = sys.damping_rate();
    for (int i = 0; i < n_; ++i) c_[i] = m[i] * g[i] > 0.0 ? m[i] * g[i] : m[i];
    ax_.resize(sys.stiffness_pattern().nnz());
    a_.resize(n_);
    F_.resize(n_);
    dx_.resize(n_);
    kdx_.resize(n_);
    trial_.resize(n_);
    inner_.reset();
    if (t0 < sys.equilibrium_start_time()) {
      inner_ = make_cvode_bdf();
      inner_->start(sys, t0, x0, v0, opt);
    }
  }

  Step step(double t_stop) override {
    if (inner_ && fallback_) return inner_step(t_stop);
    if (inner_) return motion_step(t_stop);
    if (fresh_) {
      std::fill(v_.begin(), v_.end(), 0.0);
      evaluate(x_.data());
      if (!(E_ == E_)) return {false, "non-finite potential energy", false};
      h_ = first_h();
      fresh_ = false;
    }
    ++steps_;
    if (++flow_steps_ > kMaxFlowSteps) return fall_back();
    for (int rejected = 0; rejected < kMaxRejected; ++rejected) {
      // A factorisation cut short by a stop request reads as a rejected try: end the step at
      // once (the driver reports interrupted) rather than shrink h and fall back.
      if (stop_requested()) return {false, "stopped on request", false};
      const Trial trial = try_step();
      if (trial.accepted) {
        rejected_ += rejected;
        if (trial.move > opt_.position_tol) {
          stalled_ = 0;
        } else if (!escape_saddle() && ++stalled_ >= kMaxStalled) {
          return fall_back();  // converged where K is not positive definite, no mode to leave
        }
        return {};
      }
      h_ /= 4.0;
    }
    rejected_ += kMaxRejected;
    return fall_back();
  }

  void model_changed() override {
    if (inner_) return inner_->model_changed();  // the pins' motion, or the fallback
    if (!fresh_) evaluate(x_.data());  // E, F and Ax of the changed model at the flow's state
  }

  // The flow is stuck, or stays on a state the driver's stop cannot certify (K singular or with
  // a negative pivot no mode is found for; its t never advances, so t_max would never end it):
  // the dynamics (cvode-bdf) take over from here, at rest.
  Step fall_back() {
    ++fallbacks_;
    fallback_ = true;
    std::fill(v_.begin(), v_.end(), 0.0);
    inner_ = make_cvode_bdf();
    inner_->start(*sys_, t_, x_.data(), v_.data(), opt_);
    return {};
  }

  double time() const override { return t_; }
  const double* positions() const override { return x_.data(); }
  const double* velocities() const override { return v_.data(); }

  std::string run_note() const override {
    std::string note;
    if (escapes_ > 0)
      note += "; left " + std::to_string(escapes_) +
              " saddle(s) along a negative mode (the symmetry broke)";
    if (fallbacks_ > 0) note += "; the flow stalled: fell back to the dynamics";
    return note;
  }

  void fill_stats(RunStats& s) const override {
    s.steps = steps_;
    s.rhs_evals = rhs_;
    s.jac_evals = rhs_;
    s.lin_setups = factorisations_;
    s.factorisations = factorisations_ + (probe_ ? probe_->factorisations() : 0);
    s.nonlin_iters = 0;
    s.nonlin_fails = rejected_;
    s.saddle_escapes = escapes_;
    s.fallbacks = fallbacks_;
    s.lin_iters = s.err_test_fails = 0;
    s.max_order_used = 0;
    factor_->fill_stats(s);
    RunStats motion = motion_;
    if (inner_) inner_->fill_stats(motion);
    add_counters(s, motion);
    if (fallback_) s.t_final = t_;
  }

 private:
  struct Trial {
    bool accepted = false;
    double move = 0.0;  // m, ||dx||_inf of an accepted step
  };

  // One step of the dynamics (the pins' motion, or a fallback), its state taken over.
  Step inner_step(double t_stop) {
    const Step st = inner_->step(t_stop);
    t_ = inner_->time();
    std::copy_n(inner_->positions(), n_, x_.begin());
    std::copy_n(inner_->velocities(), n_, v_.begin());
    return st;
  }

  Step motion_step(double t_stop) {
    const double t_end = sys_->equilibrium_start_time();
    const Step st = inner_step(std::min(t_stop, t_end));
    if (st.ok && t_ >= t_end) {
      inner_->fill_stats(motion_);
      inner_.reset();
    }
    return st;
  }

  // E, F = M a_c and Ax at x (the flow's current state).
  void evaluate(const double* x) {
    const auto& m = sys_->mass();
    sys_->conservative_acceleration(t_, x, a_.data());
    for (int i = 0; i < n_; ++i) F_[i] = m[i] * a_[i];
    sys_->stiffness_values(t_, x, ax_.data());
    E_ = sys_->potential_energy(t_, x);
    force_norm_ = F_.cwiseAbs().maxCoeff();
    ++rhs_;
  }

  double first_h() const {
    double rate = 0.0;  // the fastest |F_i| / C_i, m/s
    for (int i = 0; i < n_; ++i) rate = std::max(rate, std::abs(F_[i]) / c_[i]);
    return rate > 0.0 ? std::min(kMaxH, kFirstMove / rate) : 1.0;
  }

  // K dx, with K = -M Ax in the stiffness pattern's order.
  void multiply_k(const Eigen::VectorXd& dx, Eigen::VectorXd& out) const {
    const CscPattern& p = sys_->stiffness_pattern();
    const auto& m = sys_->mass();
    out.setZero();
    for (int c = 0; c < p.cols; ++c)
      for (int k = p.colptr[c]; k < p.colptr[c + 1]; ++k)
        out[p.rowind[k]] -= m[p.rowind[k]] * ax_[k] * dx[c];
  }

  Trial try_step() {
    // A(h) = C / h + K; fill_flow_values takes C = M Gamma, so undamped dofs are added here.
    fill_flow_values(*sys_, 1.0 / h_, ax_.data(), A_);
    const auto& m = sys_->mass();
    const auto& g = sys_->damping_rate();
    for (int i = 0; i < n_; ++i)
      if (!(m[i] * g[i] > 0.0)) A_.coeffRef(i, i) += c_[i] / h_;
    ++factorisations_;
    if (!factor_->factorize(A_) || factor_->negative_pivots() > 0) return {};
    factor_->solve(F_, dx_);
    if (!dx_.allFinite()) return {};
    // A step the model does not admit whole (it would jump through a contact barrier) is cut to
    // the admitted fraction; the energy test below then judges the shorter step.
    const double admit = sys_->admissible_step(t_, x_.data(), dx_.data());
    if (!(admit > 0.0)) return {};
    if (admit < 1.0) dx_ *= admit;
    multiply_k(dx_, kdx_);
    const double predicted = F_.dot(dx_) - 0.5 * dx_.dot(kdx_);
    for (int i = 0; i < n_; ++i) trial_[i] = x_[i] + dx_[i];
    const double e_new = sys_->potential_energy(t_, trial_.data());
    const double fall = E_ - e_new;
    const bool roundoff = std::abs(predicted) <= kRoundoffFall * (std::abs(E_) + std::abs(e_new));
    double grow = 1.0;
    if (roundoff) {
      // E cannot tell: accept if the force falls (Newton's end game).
      const double f_old = force_norm_;
      const std::vector<double> x_old = x_;
      const Eigen::VectorXd F_old = F_;
      const double e_old = E_;
      std::copy(trial_.begin(), trial_.end(), x_.begin());
      evaluate(x_.data());
      if (!(force_norm_ <= f_old)) {
        x_ = x_old;
        F_ = F_old;
        E_ = e_old;
        force_norm_ = f_old;
        sys_->stiffness_values(t_, x_.data(), ax_.data());
        return {};
      }
      grow = 4.0;
    } else {
      if (!(fall > 0.0)) return {};
      const double rho = fall / predicted;
      grow = rho > 0.75 ? 4.0 : (rho < 0.25 ? 0.5 : 1.0);
      std::copy(trial_.begin(), trial_.end(), x_.begin());
      evaluate(x_.data());
    }
    h_ = std::min(kMaxH, h_ * grow);
    return {true, dx_.cwiseAbs().maxCoeff()};
  }

  // At a converged state: a saddle (negative pivots of K) is left along its negative mode.
  // Returns whether K is positive definite here or the state left a saddle.
  bool escape_saddle() {
    if (!probe_) probe_ = std::make_unique<StiffnessProbe>(*sys_, opt_.factorization);
    const StiffnessProbe::Result r = probe_->probe(t_, x_.data());
    if (r.factored && !r.singular && r.negative_pivots == 0) return true;
    if (!r.factored || r.negative_pivots == 0) return false;
    if (!probe_->leave_saddle(t_, x_.data(), kEscape)) return false;
    ++escapes_;
    evaluate(x_.data());
    h_ = first_h();
    return true;
  }

  IntegratorInfo info_{"equilibrium",
                       "the equilibrium the damped dynamics reach: cvode-bdf while pins move, "
                       "then the overdamped flow by implicit steps with a trust region on the "
                       "energy, Newton at the end",
                       0, true, false, true, false};
  const MechanicalSystem* sys_ = nullptr;
  IntegratorOptions opt_;
  int n_ = 0;
  double t_ = 0.0;
  std::vector<double> x_, v_, a_, ax_, trial_;
  Eigen::VectorXd c_, F_, dx_, kdx_;
  double E_ = 0.0, force_norm_ = 0.0, h_ = 0.0;
  bool fresh_ = true;
  bool fallback_ = false;
  Eigen::SparseMatrix<double> A_;
  std::unique_ptr<SymmetricFactor> factor_;
  std::unique_ptr<StiffnessProbe> probe_;
  std::unique_ptr<Integrator> inner_;
  RunStats motion_;
  long steps_ = 0, rhs_ = 0, factorisations_ = 0, rejected_ = 0, escapes_ = 0, fallbacks_ = 0;
  long flow_steps_ = 0;
  int stalled_ = 0;
};

}  // namespace

std::unique_ptr<Integrator> make_equilibrium() { return std::make_unique<EquilibriumSolver>(); }

}  // namespace knitsim::detail
