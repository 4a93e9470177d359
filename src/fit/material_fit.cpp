#include "src/fit/material_fit.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include "src/base/text.hpp"

namespace knitsim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kForceStep = 1e-4;            // in u, for dF/du
constexpr double kMeasureDisplacement = 1e-7;  // m, for the measurement's tangent
constexpr double kOnBound = 1e-3;              // of the box's width in u

bool is_log(int gene) { return gene != kPoisson; }

// -K = -dF/dx of the free dofs at x (K = M da/dx), as a sparse matrix.
Eigen::SparseMatrix<double> negative_stiffness(const MaterialSheet& sheet, const double* x) {
  const CscPattern& pat = sheet.stiffness_pattern();
  std::vector<double> values(pat.nnz());
  sheet.stiffness_values(0.0, x, values.data());
  const std::vector<double>& mass = sheet.mass();
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(values.size());
  for (int c = 0; c < pat.cols; ++c)
    for (int e = pat.colptr[c]; e < pat.colptr[c + 1]; ++e) {
      const int r = pat.rowind[e];
      if (r >= c) t.emplace_back(r, c, -values[e] * mass[r]);
    }
  Eigen::SparseMatrix<double> K(pat.rows, pat.cols);
  K.setFromTriplets(t.begin(), t.end());
  return K;
}

using Factor = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower>;

int negative_pivots(const Factor& f) {
  int n = 0;
  const Eigen::VectorXd d = f.vectorD();
  for (int i = 0; i < d.size(); ++i) n += d(i) <= 0.0 ? 1 : 0;
  return n;
}

std::vector<Vec3> all_positions(const MaterialSheet& sheet, const std::vector<double>& x) {
  std::vector<Vec3> p(sheet.vertex_count());
  for (int v = 0; v < sheet.vertex_count(); ++v) p[v] = sheet.position(x.data(), v);
  return p;
}

}  // namespace

const std::array<const char*, kMaterialGenes>& material_gene_names() {
  static const std::array<const char*, kMaterialGenes> names = {"membrane_wale",  "membrane_course",
                                                                "membrane_shear", "poisson",
                                                                "bending_wale",   "bending_course"};
  return names;
}

const std::array<const char*, kMaterialGenes>& material_gene_units() {
  static const std::array<const char*, kMaterialGenes> units = {"N/m", "N/m", "N/m",
                                                                "1",   "N m", "N m"};
  return units;
}

std::array<double, kMaterialGenes> material_parameters(const Scene& s) {
  const MaterialScene& m = s.material;
  return {m.membrane_wale, m.membrane_course, m.membrane_shear,
          m.poisson,       m.bending_wale,    m.bending_course};
}

Scene with_material_parameters(Scene s, const std::array<double, kMaterialGenes>& p) {
  MaterialScene& m = s.material;
  m.membrane_wale = p[kMembraneWale];
  m.membrane_course = p[kMembraneCourse];
  m.membrane_shear = p[kMembraneShear];
  m.poisson = p[kPoisson];
  m.bending_wale = p[kBendingWale];
  m.bending_course = p[kBendingCourse];
  return s;
}

std::vector<EdgeFit> measure_material_edges(const MaterialSheet& sheet,
                                            const std::vector<Vec3>& positions) {
  const int nx = sheet.nx(), ny = sheet.ny();
  if (static_cast<int>(positions.size()) != sheet.vertex_count())
    throw std::invalid_argument("measure_material_edges: wrong number of positions");
  auto edge = [&](const char* name, bool row, int at) {
    std::vector<Vec3> pts;
    const int count = row ? nx : ny;
    for (int k = 0; k <= count; ++k)
      pts.push_back(positions[row ? sheet.vertex(at, k) : sheet.vertex(k, at)]);
    return fit_edge(name, normalise_span_edge(pts, pts.front(), pts.back()));
  };
  return {edge("top", true, 0), edge("bottom", true, ny), edge("left", false, 0),
          edge("right", false, nx)};
}

Target material_target(const Scene& scene, const std::string& integrator) {
  const MaterialDrapeResult run =
      run_material_drape(scene, integrator.empty() ? default_integrator() : integrator);
  if (run.stats.status != RunStatus::Equilibrium)
    throw std::runtime_error("material target: the drape did not reach equilibrium: " +
                             run.stats.message);
  TargetScene ts;
  ts.name = "four_corner";
  for (const EdgeFit& e : measure_material_edges(*run.sheet, run.positions)) {
    TargetEdge te;
    te.name = e.name;
    te.kind = TargetKind::Coefficients;
    te.coefficients = e.coefficients;
    ts.edges.push_back(te);
  }
  Target t;
  t.scenes.push_back(ts);
  t.validate();
  return t;
}

// --- the problem ------------------------------------------------------------------------------

MaterialFitProblem::MaterialFitProblem(Scene base, const Target& target, std::string integrator)
    : base_(std::move(base)), integrator_(std::move(integrator)) {
  base_.validate();
  if (base_.material.kind != DrapeModelKind::Material)
    throw std::invalid_argument("model.kind = paper: the material fit needs model.kind = material");
  if (base_.material.clamps != ClampLayout::Corners)
    throw std::invalid_argument(
        "clamps.layout = edge: the material fit needs corners (the target's four_corner edges)");
  base_.fit_box.validate();
  if (integrator_.empty()) integrator_ = default_integrator();
  make_integrator(integrator_);  // throws for an unknown name
  for (int g = 0; g < kMaterialGenes; ++g)
    if (base_.fit_box.fitted(g)) fitted_.push_back(g);
  measured_ = fit_target_scene(target.scene("four_corner"));
  if (measured_.empty()) throw std::invalid_argument("target scene four_corner: no edges to fit");
}

std::vector<double> MaterialFitProblem::lower() const {
  std::vector<double> out;
  for (int g : fitted_) {
    const double v = base_.fit_box.lower(g);
    out.push_back(is_log(g) ? std::log(v) : v);
  }
  return out;
}

std::vector<double> MaterialFitProblem::upper() const {
  std::vector<double> out;
  for (int g : fitted_) {
    const double v = base_.fit_box.upper(g);
    out.push_back(is_log(g) ? std::log(v) : v);
  }
  return out;
}

std::vector<double> MaterialFitProblem::u_of(const std::array<double, kMaterialGenes>& p) const {
  std::vector<double> u;
  for (int g : fitted_) u.push_back(is_log(g) ? std::log(p[g]) : p[g]);
  return u;
}

std::array<double, kMaterialGenes> MaterialFitProblem::parameters_of(
    const std::vector<double>& u) const {
  if (u.size() != fitted_.size())
    throw std::invalid_argument("material fit: a point has " + std::to_string(fitted_.size()) +
                                " coordinates, got " + std::to_string(u.size()));
  std::array<double, kMaterialGenes> p = material_parameters(base_);
  for (size_t a = 0; a < fitted_.size(); ++a) {
    const int g = fitted_[a];
    p[g] = is_log(g) ? std::exp(u[a]) : u[a];
  }
  return p;
}

Scene MaterialFitProblem::scene_of(const std::vector<double>& u) const {
  return with_material_parameters(base_, parameters_of(u));
}

MaterialResiduals MaterialFitProblem::evaluate(const std::vector<double>& u, bool jacobian) const {
  MaterialResiduals out;
  out.objective = kNaN;
  MaterialDrapeResult run;
  try {
    run = run_material_drape(scene_of(u), integrator_);
  } catch (const std::invalid_argument& e) {  // parameters the model refuses
    out.message = e.what();
    return out;
  }
  if (run.stats.status != RunStatus::Equilibrium) {
    out.message = "drape run: " + run.stats.message;
    return out;
  }
  const MaterialSheet& sheet = *run.sheet;
  std::vector<double> x = run.state_x;
  const int n = sheet.dof();
  out.centre_sag = run.centre_sag;
  std::vector<EdgeFit> edges;
  Eigen::MatrixXd dcoef;  // (edges x 5) x fitted, dc/du
  try {
    if (jacobian) {
      // Newton polish, then one factorisation for every parameter's tangent.
      Factor factor;
      std::vector<double> f(n);
      for (int it = 0; it < 4; ++it) {
        factor.compute(negative_stiffness(sheet, x.data()));
        if (factor.info() != Eigen::Success) throw std::runtime_error("singular stiffness");
        sheet.net_force(x.data(), f.data());
        const Eigen::VectorXd dx =
            factor.solve(Eigen::Map<const Eigen::VectorXd>(f.data(), n));  // -K dx = F
        std::vector<double> trial(x);
        for (int i = 0; i < n; ++i) trial[i] += dx(i);
        if (!(sheet.static_residual(0.0, trial.data()) < sheet.static_residual(0.0, x.data())))
          break;
        x = trial;
      }
      factor.compute(negative_stiffness(sheet, x.data()));
      if (factor.info() != Eigen::Success) throw std::runtime_error("singular stiffness");
      out.negative_pivots = negative_pivots(factor);
      const std::vector<Vec3> pos = all_positions(sheet, x);
      edges = measure_material_edges(sheet, pos);
      dcoef.resize(edges.size() * (kEdgePolynomialDegree + 1), fitted_.size());
      const std::array<double, kMaterialGenes> p = parameters_of(u);
      for (size_t a = 0; a < fitted_.size(); ++a) {
        const int g = fitted_[a];
        Eigen::VectorXd dF(n);
        for (int side : {1, -1}) {
          std::array<double, kMaterialGenes> q = p;
          q[g] = is_log(g) ? p[g] * std::exp(side * kForceStep) : p[g] + side * kForceStep;
          const MaterialSheet moved(
              with_material_parameters(base_, q).material.sheet(base_.params));
          std::vector<double> fq(n);
          moved.net_force(x.data(), fq.data());
          for (int i = 0; i < n; ++i)
            dF(i) = (side > 0 ? 0.0 : dF(i)) + side * fq[i] / (2.0 * kForceStep);
        }
        const Eigen::VectorXd dxdu = factor.solve(dF);  // -K dx/du = dF/du
        double largest = 0.0;
        for (int i = 0; i < n; ++i) largest = std::max(largest, std::abs(dxdu(i)));
        const double eps = largest > 0.0 ? kMeasureDisplacement / largest : 0.0;
        std::vector<EdgeFit> plus, minus;
        for (int side : {1, -1}) {
          std::vector<double> xs(x);
          for (int i = 0; i < n; ++i) xs[i] += side * eps * dxdu(i);
          (side > 0 ? plus : minus) = measure_material_edges(sheet, all_positions(sheet, xs));
        }
        for (size_t e = 0; e < edges.size(); ++e)
          for (int i = 0; i <= kEdgePolynomialDegree; ++i)
            dcoef(e * (kEdgePolynomialDegree + 1) + i, a) =
                eps > 0.0 ? (plus[e].coefficients[i] - minus[e].coefficients[i]) / (2.0 * eps)
                          : 0.0;
      }
    } else {
      edges = measure_material_edges(sheet, run.positions);
    }
  } catch (const std::exception& e) {
    out.message = std::string("measurement: ") + e.what();
    return out;
  }
  out.residual = sheet.static_residual(0.0, x.data());
  const int m = static_cast<int>(measured_.size()) * (kEdgePolynomialDegree + 1);
  out.r.resize(m);
  if (jacobian) out.J.resize(m, fitted_.size());
  int row = 0;
  for (const EdgeFit& target : measured_) {
    size_t e = 0;
    while (e < edges.size() && edges[e].name != target.name) ++e;
    if (e == edges.size()) {
      out.message = "measured edge " + target.name + " is not among the simulated edges";
      return out;
    }
    for (int i = 0; i <= kEdgePolynomialDegree; ++i, ++row) {
      out.r(row) = target.coefficients[i] - edges[e].coefficients[i];
      if (jacobian) out.J.row(row) = -dcoef.row(e * (kEdgePolynomialDegree + 1) + i);
    }
  }
  out.objective = 100.0 * std::sqrt(out.r.squaredNorm() / m);
  out.failed = !std::isfinite(out.objective) || (jacobian && !out.J.allFinite());
  if (out.failed) out.message = "non-finite residuals";
  return out;
}

Problem MaterialFitProblem::ica_problem() const {
  Problem p;
  p.lower = lower();
  p.upper = upper();
  p.categorical.assign(fitted_.size(), false);
  p.cost = [this](const std::vector<double>& u) { return evaluate(u, false).objective; };
  return p;
}

MaterialIdentifiability MaterialFitProblem::identifiability(const MaterialResiduals& at,
                                                            const std::vector<double>& u) const {
  MaterialIdentifiability id;
  id.fitted = fitted_;
  const int q = static_cast<int>(fitted_.size());
  const int m = static_cast<int>(at.r.size());
  id.residuals = m;
  const std::array<double, kMaterialGenes> p = parameters_of(u);
  const std::vector<double> lo = lower(), hi = upper();
  id.parameters.resize(q);
  for (int a = 0; a < q; ++a) {
    MaterialParameterError& e = id.parameters[a];
    e.value = p[fitted_[a]];
    const double w = hi[a] - lo[a];
    e.on_bound = u[a] <= lo[a] + kOnBound * w || u[a] >= hi[a] - kOnBound * w;
    e.relative_standard_error = e.conditional_relative_error = kInf;
  }
  if (q == 0 || at.J.rows() != m || at.J.cols() != q) return id;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(at.J, Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const Eigen::MatrixXd V = svd.matrixV();
  for (int j = 0; j < sv.size(); ++j) {
    MaterialDetermined c;
    c.singular_value = sv(j);
    // The sign making the largest component positive, so the text reads the same every run.
    int big = 0;
    for (int a = 0; a < q; ++a)
      if (std::abs(V(a, j)) > std::abs(V(big, j))) big = a;
    const double sign = V(big, j) < 0.0 ? -1.0 : 1.0;
    for (int a = 0; a < q; ++a) c.combination.push_back(sign * V(a, j));
    c.edge_change_percent = 100.0 * sv(j) * 0.1 / std::sqrt(static_cast<double>(m));
    c.determined = c.edge_change_percent >= MaterialIdentifiability::kDeterminedPercent;
    id.determined += c.determined ? 1 : 0;
    id.combinations.push_back(c);
  }
  const int dofs = m - id.determined;
  id.sigma = dofs > 0 ? std::sqrt(at.r.squaredNorm() / dofs) : 0.0;
  const Eigen::MatrixXd A = at.J.transpose() * at.J;
  for (int a = 0; a < q; ++a) {
    MaterialParameterError& e = id.parameters[a];
    double sum = 0.0;
    bool null = false;
    for (int j = 0; j < sv.size(); ++j) {
      if (!id.combinations[j].determined) {
        null = null || std::abs(V(a, j)) > 1e-3;
        continue;
      }
      sum += V(a, j) * V(a, j) / (sv(j) * sv(j));
    }
    e.relative_standard_error = null ? kInf : id.sigma * std::sqrt(sum);
    e.conditional_relative_error = A(a, a) > 0.0 ? id.sigma / std::sqrt(A(a, a)) : kInf;
  }
  return id;
}

// --- the fits ---------------------------------------------------------------------------------

namespace {

std::vector<std::string> bound_warnings(const MaterialFitProblem& problem,
                                        const MaterialFitResult& fit) {
  std::vector<std::string> out;
  const std::vector<double> lo = problem.lower(), hi = problem.upper();
  for (size_t a = 0; a < problem.fitted().size(); ++a) {
    if (!fit.identifiability.parameters[a].on_bound) continue;
    const int g = problem.fitted()[a];
    const bool low = fit.u[a] - lo[a] < hi[a] - fit.u[a];
    const std::string key =
        std::string("fit.") + material_gene_names()[g] + (low ? "_min" : "_max");
    out.push_back(std::string(material_gene_names()[g]) + " = " +
                  format_number(fit.parameters[g], 4) + " " + material_gene_units()[g] +
                  " ends on its " + (low ? "lower" : "upper") + " bound (" + key +
                  "): the best fit may lie outside the box; widen it, or the edges cannot "
                  "tell this parameter (docs/fitting.md)");
  }
  return out;
}

void finish(const MaterialFitProblem& problem, MaterialFitResult& fit,
            const MaterialResiduals& at) {
  fit.parameters = problem.parameters_of(fit.u);
  fit.identifiability = problem.identifiability(at, fit.u);
  fit.warnings = bound_warnings(problem, fit);
}

}  // namespace

MaterialFitResult fit_material_lm(const MaterialFitProblem& problem, const LmStartOptions& starts,
                                  const LmOptions& lm, std::uint64_t seed) {
  starts.validate();
  lm.validate();
  const auto wall0 = std::chrono::steady_clock::now();
  MaterialFitResult out;
  out.optimizer = "lm";
  const std::vector<double> lo = problem.lower(), hi = problem.upper();
  const size_t q = lo.size();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto evaluate = [&](const std::vector<double>& u) {
    MaterialResiduals e = problem.evaluate(u);
    ++out.evaluations;
    if (e.failed) ++out.failed_evaluations;
    return e;
  };
  struct Start {
    std::vector<double> u;
    MaterialResiduals at;
  };
  std::vector<Start> screened;
  for (int s = 0; s < starts.starts_per_bracket; ++s) {
    std::vector<double> u(q);
    for (size_t a = 0; a < q; ++a)
      u[a] = s == 0 ? 0.5 * (lo[a] + hi[a]) : lo[a] + unit(rng) * (hi[a] - lo[a]);
    screened.push_back({u, evaluate(u)});
  }
  std::stable_sort(screened.begin(), screened.end(), [](const Start& a, const Start& b) {
    return std::isnan(b.at.objective) ? !std::isnan(a.at.objective)
                                      : a.at.objective < b.at.objective;
  });
  MaterialResiduals best_at;
  out.parameters = material_parameters(problem.base());  // until a start evaluates
  for (int k = 0; k < starts.refine && k < static_cast<int>(screened.size()); ++k) {
    Start& st = screened[k];
    if (st.at.failed) break;
    MaterialResiduals last = st.at;
    bool first = true;
    std::vector<std::pair<std::vector<double>, MaterialResiduals>> seen;
    LmProblem lp{lo, hi, {}};
    lp.evaluate = [&](const std::vector<double>& u, Eigen::VectorXd& r, Eigen::MatrixXd& J) {
      MaterialResiduals e = first ? st.at : evaluate(u);
      first = false;
      if (e.failed) return false;
      r = e.r;
      J = e.J;
      seen.emplace_back(u, std::move(e));
      return true;
    };
    const LmResult res = run_lm(lp, st.u, lm);
    if (res.status == LmStatus::StartFailed) continue;
    const double objective = 100.0 * std::sqrt(res.r.squaredNorm() / res.r.size());
    if (!out.ok || objective < out.objective) {
      out.ok = true;
      out.objective = objective;
      out.u = res.x;
      for (const auto& [u, e] : seen)
        if (u == res.x) best_at = e;
    }
  }
  if (out.ok) {
    finish(problem, out, best_at);
    out.message = std::to_string(screened.size()) + " start(s), " +
                  std::to_string(std::min<int>(starts.refine, screened.size())) + " refined, " +
                  std::to_string(out.evaluations) + " drape evaluations";
  } else {
    out.message = "every start failed to evaluate (the first: " + screened.front().at.message + ")";
  }
  out.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return out;
}

MaterialFitResult fit_material_ica(const MaterialFitProblem& problem, const IcaOptions& options) {
  const auto wall0 = std::chrono::steady_clock::now();
  const IcaResult r = run_ica(problem.ica_problem(), options);
  MaterialFitResult out;
  out.optimizer = "ica";
  out.message = r.message;
  out.evaluations = r.evaluations;
  out.failed_evaluations = r.failed_evaluations;
  out.parameters = material_parameters(problem.base());  // until the best point evaluates
  if (r.status != IcaStatus::AllFailed) {
    out.u = r.best_x;
    const MaterialResiduals at = problem.evaluate(out.u);  // the sensitivities at the best
    ++out.evaluations;
    out.ok = !at.failed;
    out.objective = at.failed ? r.best_cost : at.objective;
    if (out.ok) finish(problem, out, at);
  }
  out.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return out;
}

std::string identifiability_text(const MaterialFitProblem& problem, const MaterialFitResult& fit) {
  if (!fit.ok) return "";
  const MaterialIdentifiability& id = fit.identifiability;
  std::ostringstream os;
  auto combination = [&](const MaterialDetermined& c) {
    std::string s;
    for (size_t a = 0; a < c.combination.size(); ++a) {
      const double w = c.combination[a];
      if (std::abs(w) < 0.05) continue;
      const int g = problem.fitted()[a];
      s += (s.empty() ? (w < 0 ? "-" : "") : (w < 0 ? " - " : " + ")) +
           format_number(std::abs(w), 2) + (is_log(g) ? " ln " : " ") + material_gene_names()[g];
    }
    return s;
  };
  os << "identifiability (singular values of d edges / d ln parameter; a combination is "
        "determined when a 10 % change of it moves the edges by >= "
     << format_number(MaterialIdentifiability::kDeterminedPercent, 2) << " %):\n";
  for (const MaterialDetermined& c : id.combinations)
    os << "  " << (c.determined ? "determined:     " : "not determined: ") << combination(c)
       << "  (singular value " << format_number(c.singular_value, 3) << ", 10 % moves the edges "
       << format_number(c.edge_change_percent, 3) << " %)\n";
  if (id.determined < static_cast<int>(id.combinations.size()))
    os << "not determined by the edges: the fitted values along the combinations above marked "
          "so are the start's or the box's, not the fabric's (docs/fitting.md)\n";
  for (const std::string& w : fit.warnings) os << "warning: " << w << "\n";
  return os.str();
}

}  // namespace knitsim
