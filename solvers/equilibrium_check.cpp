#include "solvers/equilibrium_check.hpp"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>

#include "solvers/schur_matrix.hpp"
#include "solvers/symmetric_factor.hpp"

namespace knitsim::detail {

namespace {

constexpr int kInverseIterations = 8;
constexpr int kPowerIterations = 2000;

double inf_norm(const Eigen::VectorXd& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; }

// ||A||_inf of a symmetric matrix stored whole (its largest column sum of |a_ij|): a Gershgorin
// bound on its eigenvalues.
double gershgorin(const Eigen::SparseMatrix<double>& A) {
  double bound = 0.0;
  for (int c = 0; c < A.outerSize(); ++c) {
    double sum = 0.0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, c); it; ++it) sum += std::abs(it.value());
    bound = std::max(bound, sum);
  }
  return bound;
}

// A fixed, non-symmetric start vector: the same on every run and every machine.
Eigen::VectorXd start_vector(int n) {
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = 1.0 + 0.5 * std::sin(1.0 + 0.7 * i);
  return v / v.norm();
}

// Six dofs of a free-floating state x (3 per particle) at which its rigid-body modes are
// independent: the first pivots of a column-pivoted QR of the modes' transpose (3 translations
// and 3 rotations about the centroid, each scaled to unit norm); three for a planar model (the
// translations in x and y, the rotation about z). Holding these dofs removes the modes: K
// restricted to the others has K's nonzero inertia when the modes span its null space.
std::vector<int> gauge_dofs(const double* x, int n, bool planar) {
  const int particles = n / 3;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int p = 0; p < particles; ++p) centroid += Eigen::Vector3d(x + 3 * p);
  centroid /= std::max(particles, 1);
  Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(6, n);
  for (int p = 0; p < particles; ++p) {
    const Eigen::Vector3d r = Eigen::Vector3d(x + 3 * p) - centroid;
    for (int a = 0; a < 3; ++a) {
      modes(a, 3 * p + a) = 1.0;
      const Eigen::Vector3d u = Eigen::Vector3d::Unit(a).cross(r);
      modes.block<1, 3>(3 + a, 3 * p) = u.transpose();
    }
  }
  if (planar) modes = Eigen::MatrixXd(modes({0, 1, 5}, Eigen::all));  // x, y, about z
  for (int k = 0; k < modes.rows(); ++k)
    if (modes.row(k).norm() > 0.0) modes.row(k).normalize();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(modes);
  std::vector<int> dofs;
  for (int k = 0; k < std::min(static_cast<int>(modes.rows()), n); ++k)
    dofs.push_back(qr.colsPermutation().indices()[k]);
  return dofs;
}

}  // namespace

void fill_flow_values(const MechanicalSystem& sys, double inv_h, const double* ax,
                      Eigen::SparseMatrix<double>& A) {
  const CscPattern& p = sys.stiffness_pattern();
  const auto& m = sys.mass();
  const auto& g = sys.damping_rate();
  double* a = A.valuePtr();
  for (int c = 0; c < p.cols; ++c)
    for (int k = p.colptr[c]; k < p.colptr[c + 1]; ++k) {
      const int i = p.rowind[k];
      a[k] = -m[i] * ax[k];
      if (i == c) a[k] += m[i] * g[i] * inv_h;
    }
}

StiffnessProbe::StiffnessProbe(const MechanicalSystem& sys,
                               IntegratorOptions::Factorization which)
    : sys_(&sys),
      K_(schur_matrix(sys)),
      factor_(std::make_unique<SymmetricFactor>(which)),
      f_(sys.dof()) {
  factor_->analyze(K_);
}

StiffnessProbe::~StiffnessProbe() = default;

StiffnessProbe::Result StiffnessProbe::probe(double t, const double* x, Measure measure) {
  const int n = sys_->dof();
  Result r;
  fill_stiffness(t, x);
  r.threshold = n * std::numeric_limits<double>::epsilon() * gershgorin(K_);
  ++factorisations_;
  r.factored = factor_->factorize(K_);
  if (!r.factored) {
    r.singular = true;
    return r;
  }
  r.negative_pivots = factor_->negative_pivots();
  // The eigenvalue nearest 0: inverse iteration with the same factor.
  Eigen::VectorXd v = start_vector(n), w(n);
  hold_gauge(v);
  for (int it = 0; it < kInverseIterations; ++it) {
    factor_->solve(v, w);
    hold_gauge(w);
    const double norm = w.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) break;
    v = w / norm;
  }
  r.min_eigenvalue = v.dot(K_.selfadjointView<Eigen::Lower>() * v);
  r.singular = !(std::abs(r.min_eigenvalue) > r.threshold);
  if (measure == Measure::Spectrum) return r;
  // Newton correction and its round-off floor.
  sys_->conservative_acceleration(t, x, f_.data());
  const auto& m = sys_->mass();
  Eigen::VectorXd F(n);
  for (int i = 0; i < n; ++i) F[i] = m[i] * f_[i];
  hold_gauge(F);
  factor_->solve(F, w);
  r.newton_step = inf_norm(w);
  // The model's floor is in its residual's units; their ratio to |F|_inf converts it to N.
  const double fmax = inf_norm(F), residual = sys_->static_residual(t, x);
  if (fmax > 0.0 && residual > 0.0) {
    const double floor_force = sys_->residual_roundoff(t, x) * fmax / residual;
    Eigen::VectorXd round_off = Eigen::VectorXd::Constant(n, floor_force);
    hold_gauge(round_off);
    factor_->solve(round_off, w);
    r.newton_floor = inf_norm(w);
  }
  return r;
}

bool StiffnessProbe::newton_correction(double t, const double* x, std::vector<double>& w) {
  const int n = sys_->dof();
  fill_stiffness(t, x);
  ++factorisations_;
  if (!factor_->factorize(K_) || factor_->negative_pivots() > 0) return false;
  sys_->conservative_acceleration(t, x, f_.data());
  const auto& m = sys_->mass();
  Eigen::VectorXd F(n), dx(n);
  for (int i = 0; i < n; ++i) F[i] = m[i] * f_[i];
  hold_gauge(F);
  factor_->solve(F, dx);
  hold_gauge(dx);
  if (!dx.allFinite()) return false;
  w.assign(dx.data(), dx.data() + n);
  return true;
}

std::vector<double> StiffnessProbe::negative_mode(double t, const double* x) {
  const int n = sys_->dof();
  fill_stiffness(t, x);
  const auto K = K_.selfadjointView<Eigen::Lower>();
  const double shift = gershgorin(K_);  // every eigenvalue of K is below it
  Eigen::VectorXd v = start_vector(n), w(n);
  hold_gauge(v);
  double lambda = 0.0;
  for (int it = 0; it < kPowerIterations; ++it) {
    w = shift * v - K * v;
    hold_gauge(w);
    v = w / w.norm();
    const double next = v.dot(K * v);
    if (it > 10 && std::abs(next - lambda) <= 1e-10 * shift) break;
    lambda = next;
  }
  if (!(lambda < 0.0)) return {};
  Eigen::Index at = 0;
  v.cwiseAbs().maxCoeff(&at);
  if (v[at] < 0.0) v = -v;
  return {v.data(), v.data() + n};
}

void StiffnessProbe::fill_stiffness(double t, const double* x) {
  // K's values written in place over the model's (same pattern, entry by entry): no array of
  // their own, whose pages every probe of a new model would fault in.
  sys_->stiffness_values(t, x, K_.valuePtr());
  fill_flow_values(*sys_, 0.0, K_.valuePtr(), K_);
  gauge_.clear();
  if (!sys_->free_floating()) return;
  // Rows and columns of the gauge dofs become those of a stiff support: zero off the diagonal,
  // K's largest diagonal entry on it (6 eigenvalues there, far from the smallest).
  const int n = sys_->dof();
  gauge_ = gauge_dofs(x, n, sys_->planar());
  std::vector<char> held(n, 0);
  for (int g : gauge_) held[g] = 1;
  double diagonal = 0.0;
  for (int c = 0; c < n; ++c) diagonal = std::max(diagonal, std::abs(K_.coeff(c, c)));
  if (!(diagonal > 0.0)) diagonal = 1.0;
  double* values = K_.valuePtr();
  for (int c = 0; c < K_.outerSize(); ++c)
    for (int k = K_.outerIndexPtr()[c]; k < K_.outerIndexPtr()[c + 1]; ++k) {
      const int i = K_.innerIndexPtr()[k];
      if (held[i] || held[c]) values[k] = (i == c) ? diagonal : 0.0;
    }
}

void StiffnessProbe::hold_gauge(Eigen::VectorXd& v) const {
  for (int g : gauge_) v[g] = 0.0;
}

bool StiffnessProbe::leave_saddle(double t, double* x, double move) {
  const std::vector<double> mode = negative_mode(t, x);
  if (mode.empty()) return false;
  double largest = 0.0;
  for (double d : mode) largest = std::max(largest, std::abs(d));
  std::vector<double> dx(mode.size());
  for (size_t i = 0; i < mode.size(); ++i) dx[i] = move * mode[i] / largest;
  const double admit = sys_->admissible_step(t, x, dx.data());
  if (!(admit > 0.0)) return false;
  for (size_t i = 0; i < mode.size(); ++i) x[i] += admit * dx[i];
  return true;
}

}  // namespace knitsim::detail
