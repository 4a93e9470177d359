// The papers' explicit reference paths, fixed step h:
//
// euler (paper 1, Fig. 7): forward Euler on y = [x; v],
//     x_{k+1} = x_k + h v_k,   v_{k+1} = v_k + h (a_c(t_k, x_k) - Gamma v_k),
//   then the Provot correction (MechanicalSystem::project) on x_{k+1}.
//
// verlet (paper 2 Sec. 3.3): velocity Verlet,
//     X(t+h) = X + V h + a h^2/2,   V(t+h) = V + (a(t) + a(t+h)) h/2,
//   written as kick-drift-kick. The linear damping -Gamma v is integrated exactly over each
//   half kick: with e = exp(-gamma h/2) and phi = (1 - e)/gamma (-> h/2 as gamma -> 0),
//     v_{1/2} = e v + phi a_c(x),  x' = x + h v_{1/2},  [project x'],  v' = e v_{1/2} + phi
//     a_c(x').
//   For gamma = 0 this is exactly paper 2's formula. The exact damping removes the explicit
//   damping limit h < 2/gamma, which dominates on the overdamped drape (gamma = c/m ~ 1e5 /s);
//   predict_stable_dt("verlet") gives the resulting limit.
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "solvers/factories.hpp"
#include "src/core/invalid_field.hpp"

namespace knitsim::detail {

namespace {

class FixedStepExplicit : public Integrator {
 public:
  explicit FixedStepExplicit(IntegratorInfo info) : info_(std::move(info)) {}
  const IntegratorInfo& info() const override { return info_; }

  void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
             const IntegratorOptions& opt) override {
    opt.validate();
    sys_ = &sys;
    n_ = sys.dof();
    t_ = t0;
    steps_ = rhs_ = 0;
    runaway_ = opt.runaway_position;
    x_.assign(x0, x0 + n_);
    v_.assign(v0, v0 + n_);
    a_.assign(n_, 0.0);
    dt_predicted_ = predict_stable_dt(info_.name, sys, t0, x0);
    dt_estimated_ = estimate_stable_dt(info_.name, sys, t0, x0);
    dt_ = opt.dt > 0.0 ? opt.dt : opt.dt_safety * dt_predicted_;
    if (!(dt_ > 0.0) || !std::isfinite(dt_)) {
      std::ostringstream os;
      os << info_.name << " has no stable step for this system (predicted limit " << dt_predicted_
         << " s); give dt > 0 explicitly";
      throw InvalidField("dt", "0 (automatic)", os.str());
    }
    prepare();
  }

  double time() const override { return t_; }
  const double* positions() const override { return x_.data(); }
  const double* velocities() const override { return v_.data(); }
  void fill_stats(RunStats& s) const override {
    s.steps = steps_;
    s.rhs_evals = rhs_;
    s.dt = dt_;
    s.dt_predicted = dt_predicted_;
    s.dt_estimated = dt_estimated_;
    s.max_order_used = info_.order;
  }

  void model_changed() override { prepare(); }  // Verlet's cached a(x) is the old model's

 protected:
  virtual void prepare() {}
  Step blown_up() const {
    std::ostringstream os;
    os << info_.name << ": non-finite or runaway state at t = " << t_ << " s (dt = " << dt_
       << " s, predicted stability limit " << dt_predicted_ << " s)";
    return {false, os.str()};
  }
  bool in_bounds(double xi) const { return std::abs(xi) <= runaway_; }

  IntegratorInfo info_;
  const MechanicalSystem* sys_ = nullptr;
  int n_ = 0;
  double t_ = 0.0, dt_ = 0.0, dt_predicted_ = 0.0, dt_estimated_ = 0.0, runaway_ = 1e3;
  long steps_ = 0, rhs_ = 0;
  std::vector<double> x_, v_, a_;
};

class Euler final : public FixedStepExplicit {
 public:
  Euler()
      : FixedStepExplicit(
            {"euler", "explicit Euler, fixed dt, Provot correction (paper 1)", 1, false, true}) {}

  Step step(double t_stop) override {
    const double h = std::min(dt_, t_stop - t_);
    sys_->conservative_acceleration(t_, x_.data(), a_.data());
    ++rhs_;
    const auto& gamma = sys_->damping_rate();
    bool ok = true;
    for (int i = 0; i < n_; ++i) {
      const double vi = v_[i];
      v_[i] += h * (a_[i] - gamma[i] * vi);
      x_[i] += h * vi;
      ok &= in_bounds(x_[i]);
    }
    t_ += h;
    ++steps_;
    if (!ok) return blown_up();
    sys_->project(t_, x_.data(), v_.data());
    return {};
  }
};

class Verlet final : public FixedStepExplicit {
 public:
  Verlet()
      : FixedStepExplicit({"verlet",
                           "velocity Verlet, fixed dt, exact damping half-steps (paper 2)", 2,
                           false, true}) {}

  Step step(double t_stop) override {
    const double h = std::min(dt_, t_stop - t_);
    if (h != h_) set_factors(h);
    bool ok = true;
    for (int i = 0; i < n_; ++i) {
      v_[i] = e_[i] * v_[i] + phi_[i] * a_[i];
      x_[i] += h * v_[i];
      ok &= in_bounds(x_[i]);
    }
    t_ += h;
    ++steps_;
    if (!ok) return blown_up();
    sys_->project(t_, x_.data(), v_.data());
    sys_->conservative_acceleration(t_, x_.data(), a_.data());
    ++rhs_;
    for (int i = 0; i < n_; ++i) v_[i] = e_[i] * v_[i] + phi_[i] * a_[i];
    return {};
  }

 private:
  void prepare() override {
    sys_->conservative_acceleration(t_, x_.data(), a_.data());
    ++rhs_;
    set_factors(dt_);
  }
  void set_factors(double h) {
    h_ = h;
    const auto& gamma = sys_->damping_rate();
    e_.resize(n_);
    phi_.resize(n_);
    for (int i = 0; i < n_; ++i) {
      const double g = gamma[i];
      e_[i] = std::exp(-0.5 * g * h);
      phi_[i] = g > 0.0 ? -std::expm1(-0.5 * g * h) / g : 0.5 * h;
    }
  }
  double h_ = -1.0;
  std::vector<double> e_, phi_;
};

}  // namespace

std::unique_ptr<Integrator> make_euler() { return std::make_unique<Euler>(); }
std::unique_ptr<Integrator> make_verlet() { return std::make_unique<Verlet>(); }

}  // namespace knitsim::detail
