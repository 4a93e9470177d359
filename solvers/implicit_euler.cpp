// implicit-euler: backward Euler linearised once per step (Baraff & Witkin 1998), fixed h.
//
//   Backward Euler on x'' = a_c(x) - Gamma v, with a_c linearised about x_k (Ax = da_c/dx):
//     dv = h [ a_c(x_k) + h Ax (v_k + dv) - Gamma (v_k + dv) ]
//   Multiplying by M (K = M Ax = dF/dx, symmetric; as in schur_matrix.hpp, the negative of the
//   equilibrium files' Hessian K) gives a symmetric n x n system (n = dof)
//     (M + h C - h^2 K) dv = h M (a_c - Gamma v_k + h Ax v_k),   C = M Gamma,
//   solved by a SymmetricFactor (symmetric_factor.hpp: LDL^T, since K is indefinite when
//   springs are compressed; supernodal LL^T where S allows it on large grids). The pattern is
//   the model's stiffness pattern, analysed once; values are refilled and refactored every
//   step. Then v_{k+1} = v_k + dv, x_{k+1} = x_k + h v_{k+1}. Forces and Jacobian are taken at
//   t_{k+1} (moving pins) and x_k.
//   First order, L-stable; its fixed point is the exact equilibrium, so large steps may be
//   taken when only the equilibrium is wanted, though they can end at another state than the
//   dynamics reach (the driver's energy check flags one above the run's energy;
//   docs/numerics.md). Default h = 1 s. A step through a barrier of the model
//   (MechanicalSystem::admissible_step) is shortened to what it admits.
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <vector>

#include "solvers/factories.hpp"
#include "solvers/schur_matrix.hpp"
#include "solvers/symmetric_factor.hpp"

namespace knitsim::detail {

namespace {

class ImplicitEuler final : public Integrator {
 public:
  const IntegratorInfo& info() const override { return info_; }

  void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
             const IntegratorOptions& opt) override {
    opt.validate();
    sys_ = &sys;
    n_ = sys.dof();
    t_ = t0;
    dt_ = opt.dt > 0.0 ? opt.dt : 1.0;
    steps_ = rhs_ = jac_ = setups_ = 0;
    x_.assign(x0, x0 + n_);
    v_.assign(v0, v0 + n_);
    a_.assign(n_, 0.0);
    rhs_vec_.resize(n_);
    dv_.resize(n_);
    tmp_.resize(n_);
    const CscPattern& p = sys.stiffness_pattern();
    ax_.resize(p.nnz());
    S_ = schur_matrix(sys);  // the stiffness pattern, built once; values per step
    factor_ = std::make_unique<SymmetricFactor>(opt.factorization);
    factor_->analyze(S_);
  }

  Step step(double t_stop) override {
    const double h = std::min(dt_, t_stop - t_);
    const double t1 = t_ + h;
    const CscPattern& p = sys_->stiffness_pattern();
    const auto& m = sys_->mass();
    const auto& gamma = sys_->damping_rate();
    sys_->conservative_acceleration(t1, x_.data(), a_.data());
    sys_->stiffness_values(t1, x_.data(), ax_.data());
    ++rhs_;
    ++jac_;
    fill_schur_values(*sys_, h, ax_.data(), S_);  // S = M + h C - h^2 K
    // right side: h M (a_c - Gamma v + h Ax v)
    csc_multiply(p, ax_.data(), v_.data(), tmp_.data());
    for (int i = 0; i < n_; ++i) rhs_vec_[i] = h * m[i] * (a_[i] - gamma[i] * v_[i] + h * tmp_[i]);
    ++setups_;
    if (!factor_->factorize(S_)) {
      std::ostringstream os;
      os << "implicit-euler: factorisation of the reduced matrix failed at t = " << t_
         << " s (h = " << h << ")";
      return {false, os.str()};
    }
    Eigen::Map<const Eigen::VectorXd> b(rhs_vec_.data(), n_);
    factor_->solve(b, Eigen::Map<Eigen::VectorXd>(dv_.data(), n_));
    for (int i = 0; i < n_; ++i) {
      v_[i] += dv_[i];
      tmp_[i] = h * v_[i];
    }
    // A step the model does not admit whole (it would jump through a contact barrier) moves the
    // admitted fraction, its velocities scaled alike: an inelastic stop at the barrier.
    const double admit = sys_->admissible_step(t1, x_.data(), tmp_.data());
    const double f = admit < 1.0 ? std::max(0.0, admit) : 1.0;
    for (int i = 0; i < n_; ++i) {
      v_[i] *= f;
      x_[i] += f * tmp_[i];
    }
    t_ = t1;
    ++steps_;
    return {};
  }

  double time() const override { return t_; }
  const double* positions() const override { return x_.data(); }
  const double* velocities() const override { return v_.data(); }
  void fill_stats(RunStats& s) const override {
    s.steps = steps_;
    s.rhs_evals = rhs_;
    s.jac_evals = jac_;
    s.lin_setups = setups_;
    s.factorisations = setups_;
    if (factor_) factor_->fill_stats(s);
    s.dt = dt_;
    s.max_order_used = 1;
  }

 private:
  IntegratorInfo info_{"implicit-euler",
                       "backward Euler linearised once per step (Baraff-Witkin), fixed dt, "
                       "sparse LDL^T",
                       1,
                       false,
                       false,
                       true};
  const MechanicalSystem* sys_ = nullptr;
  int n_ = 0;
  double t_ = 0.0, dt_ = 1.0;
  long steps_ = 0, rhs_ = 0, jac_ = 0, setups_ = 0;
  std::vector<double> x_, v_, a_, ax_, rhs_vec_, dv_, tmp_;
  Eigen::SparseMatrix<double> S_;
  std::unique_ptr<SymmetricFactor> factor_;
};

}  // namespace

std::unique_ptr<Integrator> make_implicit_euler() { return std::make_unique<ImplicitEuler>(); }

}  // namespace knitsim::detail
