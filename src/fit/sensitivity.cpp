#include "src/fit/sensitivity.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "solvers/symmetric_factor.hpp"
#include "src/core/invalid_field.hpp"
#include "src/measure/measurement.hpp"

namespace knitsim {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double a : v) m = std::max(m, std::abs(a));
  return m;
}

// Tangent of one normalised edge (the rules of src/measure/measurement.hpp) along dX.
EdgePoints span_edge_tangent(const std::vector<Vec3>& X, const std::vector<Vec3>& dX,
                             const EdgePoints& p) {
  const Vec3 a = X.front(), b = X.back(), da = dX.front(), db = dX.back();
  const Vec3 ab = b - a, dab = db - da;
  const double len = norm(ab);
  const double dlen = dot(ab, dab) / len;
  EdgePoints t;
  for (size_t k = 0; k < X.size(); ++k) {
    const double s = p.s[k], d = p.d[k];
    const double ds =
        (dot(dX[k] - da, ab) + dot(X[k] - a, dab)) / (len * len) - 2.0 * s * dlen / len;
    const double dz_line = da.z + ds * (b.z - a.z) + s * (db.z - da.z);
    t.s.push_back(ds);
    t.d.push_back(-(dX[k].z - dz_line) / len - d * dlen / len);
  }
  return t;
}

EdgePoints hanging_edge_tangent(EdgeSide side, const std::vector<Vec3>& X,
                                const std::vector<Vec3>& dX, Vec3 pin1, Vec3 pin2, Vec3 dpin1,
                                Vec3 dpin2, const EdgePoints& p) {
  const double span = std::hypot(pin2.x - pin1.x, pin2.z - pin1.z);
  const double dspan =
      ((pin2.x - pin1.x) * (dpin2.x - dpin1.x) + (pin2.z - pin1.z) * (dpin2.z - dpin1.z)) / span;
  const double sigma = pin2.x > pin1.x ? 1.0 : -1.0;
  const double dz_ref = 0.5 * (dpin1.z + dpin2.z);
  EdgePoints t;
  for (size_t k = 0; k < X.size(); ++k) {
    const Vec3 dx = dX[k];
    double ds = 0.0, dd = 0.0;  // numerators of d(s S) and d(d S)
    switch (side) {
      case EdgeSide::Top:
      case EdgeSide::Bottom:
        ds = sigma * (dx.x - dpin1.x);
        dd = dz_ref - dx.z;
        break;
      case EdgeSide::Left:
        ds = dpin1.z - dx.z;
        dd = sigma * (dx.x - dpin1.x);
        break;
      case EdgeSide::Right:
        ds = dpin2.z - dx.z;
        dd = -sigma * (dx.x - dpin2.x);
        break;
    }
    t.s.push_back((ds - p.s[k] * dspan) / span);
    t.d.push_back((dd - p.d[k] * dspan) / span);
  }
  return t;
}

// Tangent of the least-squares quartic (see the header) at the fit `c` of points p.
EdgeCoefficients fit_tangent(const EdgePoints& p, const EdgeCoefficients& c, const EdgePoints& dp) {
  const int m = static_cast<int>(p.s.size());
  constexpr int cols = kEdgePolynomialDegree + 1;
  Eigen::MatrixXd V(m, cols), dV(m, cols);
  Eigen::VectorXd r(m), rhs(m);
  for (int k = 0; k < m; ++k) {
    double power = 1.0, fitted = 0.0;
    for (int j = 0; j < cols; ++j) {
      V(k, j) = power;
      dV(k, j) = j == 0 ? 0.0 : j * std::pow(p.s[k], j - 1) * dp.s[k];
      fitted += c[j] * power;
      power *= p.s[k];
    }
    r(k) = p.d[k] - fitted;
  }
  const Eigen::Map<const Eigen::VectorXd> cvec(c.data(), cols);
  rhs = Eigen::Map<const Eigen::VectorXd>(dp.d.data(), m) - dV * cvec;
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(V);
  Eigen::VectorXd dc = qr.solve(rhs);
  // (V^T V)^-1 y = P R^-1 R^-T P^T y with V P = Q R.
  const Eigen::VectorXd y = qr.colsPermutation().transpose() * (dV.transpose() * r);
  const auto R = qr.matrixR().topLeftCorner(cols, cols).triangularView<Eigen::Upper>();
  const Eigen::VectorXd z = R.solve(R.transpose().solve(y));
  const Eigen::VectorXd pz = qr.colsPermutation() * z;
  dc += pz;
  EdgeCoefficients out{};
  for (int j = 0; j < cols; ++j) out[j] = dc(j);
  return out;
}

}  // namespace

// --- StiffnessFactor ----------------------------------------------------------------------

struct StiffnessFactor::Impl {
  // The integrators' symmetric factorisation (3 x 3 block LDL^T on these networks, its symbolic
  // analysis memoised per pattern) of the stiffness -K, positive definite at a stable state.
  detail::SymmetricFactor factor;
  int dof = 0;
  bool ok = false;
  int positive = 0;
};

StiffnessFactor::StiffnessFactor(const SpringNetwork& network, double t, const double* x)
    : impl_(new Impl) {
  const CscPattern& pat = network.stiffness_pattern();
  std::vector<double> values(pat.nnz());
  network.stiffness_values(t, x, values.data());  // M^-1 dF/dx: scale row r back by -m_r
  const std::vector<double>& m = network.mass();
  for (int col = 0; col < pat.cols; ++col)
    for (int e = pat.colptr[col]; e < pat.colptr[col + 1]; ++e) values[e] *= -m[pat.rowind[e]];
  const SparseMatrix stiffness = Eigen::Map<const SparseMatrix>(
      pat.rows, pat.cols, pat.nnz(), pat.colptr.data(), pat.rowind.data(), values.data());
  impl_->dof = pat.rows;
  impl_->factor.analyze(stiffness);
  impl_->ok = impl_->factor.factorize(stiffness);
  if (impl_->ok) impl_->positive = impl_->factor.negative_pivots();  // K = -stiffness
}

StiffnessFactor::~StiffnessFactor() { delete impl_; }
bool StiffnessFactor::ok() const { return impl_->ok; }
int StiffnessFactor::positive_pivots() const { return impl_->positive; }
int StiffnessFactor::dof() const { return impl_->dof; }

void StiffnessFactor::solve(const double* b, double* y) const {
  const int n = dof();
  Eigen::Map<Eigen::VectorXd> out(y, n);
  impl_->factor.solve(Eigen::Map<const Eigen::VectorXd>(b, n), out);
  out = -out;  // K y = b with K = -stiffness
}

// --- Newton polish ------------------------------------------------------------------------

void PolishOptions::validate() const {
  if (!(tol > 0.0)) bad_field("polish.tol", tol, "must be > 0");
  if (max_iterations < 1) bad_field("polish.max_iterations", max_iterations, "must be >= 1");
  if (!(max_correction > 0.0)) bad_field("polish.max_correction", max_correction, "must be > 0 m");
}

const char* to_string(PolishStatus s) {
  switch (s) {
    case PolishStatus::Converged:
      return "converged";
    case PolishStatus::NotConverged:
      return "not_converged";
    case PolishStatus::Rejected:
      return "rejected";
    case PolishStatus::SingularStiffness:
      return "singular_stiffness";
  }
  return "?";
}

PolishSummary polish_equilibrium(const SpringNetwork& network, double t, std::vector<double>& x,
                                 const PolishOptions& options) {
  options.validate();
  const int n = network.dof();
  if (static_cast<int>(x.size()) != n)
    throw std::invalid_argument("polish_equilibrium: x has " + std::to_string(x.size()) +
                                " entries for " + std::to_string(n) + " dof");
  PolishSummary s;
  s.residual_before = s.residual = network.static_residual(t, x.data());
  std::vector<double> y = x, f(n), step(n);
  std::vector<double> best = x;
  while (s.iterations < options.max_iterations) {  // to the arithmetic floor (no progress)
    const StiffnessFactor K(network, t, y.data());
    if (!K.ok()) {
      s.status = PolishStatus::SingularStiffness;
      s.message = "zero pivot in K = dF/dx";
      s.residual = s.residual_before;
      return s;
    }
    network.net_force(t, y.data(), f.data());
    K.solve(f.data(), step.data());
    for (int i = 0; i < n; ++i) y[i] -= step[i];
    ++s.iterations;
    const double r = network.static_residual(t, y.data());
    if (!(r < s.residual)) break;  // no progress: the floor of the arithmetic
    s.residual = r;
    best = y;
  }
  double correction = 0.0;
  for (int i = 0; i < n; ++i) correction = std::max(correction, std::abs(best[i] - x[i]));
  s.correction = correction;
  if (correction > options.max_correction) {
    s.status = PolishStatus::Rejected;
    s.message = "Newton moved the state by " + std::to_string(correction) +
                " m: another branch than the one the dynamics reached";
    s.residual = s.residual_before;
    return s;
  }
  x = best;
  s.status = s.residual <= options.tol ? PolishStatus::Converged : PolishStatus::NotConverged;
  s.message = std::to_string(s.iterations) + " Newton steps, residual " +
              std::to_string(s.residual_before) + " -> " + std::to_string(s.residual);
  return s;
}

std::vector<double> free_state(const SpringNetwork& network, const std::vector<Vec3>& positions) {
  if (static_cast<int>(positions.size()) != network.particle_count())
    throw std::invalid_argument("free_state: " + std::to_string(positions.size()) +
                                " positions for " + std::to_string(network.particle_count()) +
                                " particles");
  std::vector<double> x(network.dof());
  for (int p = 0; p < network.particle_count(); ++p) {
    const int f = network.free_index(p);
    if (f < 0) continue;
    x[3 * f] = positions[p].x;
    x[3 * f + 1] = positions[p].y;
    x[3 * f + 2] = positions[p].z;
  }
  return x;
}

// --- measurement chain --------------------------------------------------------------------

std::vector<EdgeCoefficients> measure_edges_tangent(const DrapeGrid& grid,
                                                    const std::vector<Vec3>& positions,
                                                    const std::vector<Vec3>& dpositions) {
  if (dpositions.size() != positions.size())
    throw std::invalid_argument("measure_edges_tangent: " + std::to_string(dpositions.size()) +
                                " tangents for " + std::to_string(positions.size()) + " positions");
  const std::vector<EdgeFit> fits = measure_edges(grid, positions);  // validates positions
  const int pin1 = grid.index(0, 0), pin2 = grid.index(0, grid.n);
  std::vector<EdgeCoefficients> out;
  for (size_t e = 0; e < grid.edges.size(); ++e) {
    std::vector<Vec3> X, dX;
    for (int p : grid.edges[e].particles) {
      X.push_back(positions[p]);
      dX.push_back(dpositions[p]);
    }
    const EdgePoints& points = fits[e].points;
    const EdgePoints dpoints =
        grid.params.layout == PinLayout::FourCorner
            ? span_edge_tangent(X, dX, points)
            : hanging_edge_tangent(*edge_side_from_name(grid.edges[e].name), X, dX, positions[pin1],
                                   positions[pin2], dpositions[pin1], dpositions[pin2], points);
    out.push_back(fit_tangent(points, fits[e].coefficients, dpoints));
  }
  return out;
}

// --- drape sensitivities ------------------------------------------------------------------

const char* to_string(SensitivityStatus s) {
  switch (s) {
    case SensitivityStatus::Ok:
      return "ok";
    case SensitivityStatus::PolishFailed:
      return "polish_failed";
    case SensitivityStatus::SingularStiffness:
      return "singular_stiffness";
  }
  return "?";
}

DrapeSensitivity drape_sensitivity(const DrapeGrid& grid, double t, std::vector<double> x,
                                   const std::vector<DrapeParameter>& parameters,
                                   const PolishOptions& polish) {
  const SpringNetwork& net = grid.network;
  DrapeSensitivity out;
  out.polish = polish_equilibrium(net, t, x, polish);
  if (out.polish.status == PolishStatus::Rejected ||
      out.polish.status == PolishStatus::SingularStiffness) {
    out.status = out.polish.status == PolishStatus::Rejected ? SensitivityStatus::PolishFailed
                                                             : SensitivityStatus::SingularStiffness;
    out.message = "polish: " + out.polish.message;
    return out;
  }
  out.x = x;
  net.all_positions(t, x.data(), out.positions);
  out.edges = measure_edges(grid, out.positions);
  const StiffnessFactor K(net, t, x.data());
  out.positive_pivots = K.ok() ? K.positive_pivots() : 0;
  if (!K.ok()) {
    out.status = SensitivityStatus::SingularStiffness;
    out.message = "zero pivot in K = dF/dx at the equilibrium";
    return out;
  }
  const int n = net.dof();
  std::vector<double> dF(n);
  const std::vector<int>& pinned = net.spec().pinned;
  for (DrapeParameter p : parameters) {
    ParameterSensitivity s;
    s.parameter = p;
    const SpringNetworkTangent tangent = drape_tangent(grid, p, t);
    net.net_force_tangent(t, x.data(), tangent, dF.data());
    s.dx.assign(n, 0.0);
    s.structural_zero = max_abs(dF) == 0.0 && tangent.pin_position.empty();
    if (!s.structural_zero) {
      for (double& v : dF) v = -v;
      K.solve(dF.data(), s.dx.data());
    }
    s.dpositions.assign(net.particle_count(), Vec3{});
    for (int q = 0; q < net.particle_count(); ++q) {
      const int f = net.free_index(q);
      if (f >= 0) s.dpositions[q] = {s.dx[3 * f], s.dx[3 * f + 1], s.dx[3 * f + 2]};
    }
    for (size_t k = 0; k < tangent.pin_position.size(); ++k)
      s.dpositions[pinned[k]] = tangent.pin_position[k];
    s.dcoefficients = s.structural_zero
                          ? std::vector<EdgeCoefficients>(grid.edges.size(), EdgeCoefficients{})
                          : measure_edges_tangent(grid, out.positions, s.dpositions);
    out.parameters.push_back(std::move(s));
  }
  out.message = out.polish.message;
  return out;
}

}  // namespace knitsim
