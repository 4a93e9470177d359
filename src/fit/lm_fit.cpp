#include "src/fit/lm_fit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <stdexcept>

#include "src/core/invalid_field.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNullEigenvalue = 1e-10;  // relative to the largest: a numerically null direction

double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

const std::array<DrapeParameter, kDrapeContinuous> kParameters = {
    DrapeParameter::Stiffness, DrapeParameter::Damping, DrapeParameter::ElongationLimit,
    DrapeParameter::NaturalLength};

}  // namespace

const char* to_string(LmStatus s) {
  switch (s) {
    case LmStatus::StepTolerance:
      return "step_tolerance";
    case LmStatus::CostTolerance:
      return "cost_tolerance";
    case LmStatus::EvaluationLimit:
      return "evaluation_limit";
    case LmStatus::StartFailed:
      return "start_failed";
  }
  return "?";
}

LmResult run_lm(const LmProblem& problem, std::vector<double> x0, const LmOptions& options) {
  options.validate();
  const int p = static_cast<int>(problem.lower.size());
  if (p == 0 || problem.upper.size() != problem.lower.size() || x0.size() != problem.lower.size())
    throw std::invalid_argument("run_lm: lower, upper and x0 must have the same non-zero size");
  for (int i = 0; i < p; ++i)
    if (!(problem.lower[i] <= problem.upper[i]))
      bad_field("run_lm: bounds[" + std::to_string(i) + "].lower", problem.lower[i],
                "must be <= upper");
  Eigen::VectorXd scale(p);
  for (int i = 0; i < p; ++i) {
    scale(i) = problem.upper[i] - problem.lower[i];
    if (scale(i) == 0.0) scale(i) = 1.0;  // a fixed coordinate: clipping holds it
    x0[i] = std::clamp(x0[i], problem.lower[i], problem.upper[i]);
  }

  LmResult res;
  res.x = x0;
  Eigen::VectorXd r, r_trial;
  Eigen::MatrixXd J, J_trial;
  auto evaluate = [&](const std::vector<double>& x, Eigen::VectorXd& rr, Eigen::MatrixXd& JJ) {
    ++res.evaluations;
    const bool ok = problem.evaluate(x, rr, JJ) && rr.allFinite() && JJ.allFinite();
    if (!ok) ++res.failed_evaluations;
    return ok;
  };
  if (!evaluate(res.x, r, J)) {
    res.status = LmStatus::StartFailed;
    res.message = "the starting point failed to evaluate";
    return res;
  }
  res.cost = 0.5 * r.squaredNorm();
  double lambda = -1.0, nu = 2.0;
  res.status = LmStatus::EvaluationLimit;
  res.message = "evaluation cap reached";
  while (res.evaluations < options.max_evaluations) {
    const Eigen::MatrixXd Ju = J * scale.asDiagonal();  // unit-box coordinates
    const Eigen::VectorXd g = Ju.transpose() * r;
    const Eigen::MatrixXd A = Ju.transpose() * Ju;
    if (lambda < 0.0) lambda = options.initial_lambda * std::max(A.diagonal().maxCoeff(), 1e-300);
    // Free coordinates: not at a bound with the descent direction -g pointing outward.
    std::vector<int> free;
    for (int i = 0; i < p; ++i) {
      const double u = (res.x[i] - problem.lower[i]) / scale(i);
      if (problem.lower[i] == problem.upper[i]) continue;
      if ((u <= 0.0 && g(i) > 0.0) || (u >= 1.0 && g(i) < 0.0)) continue;
      free.push_back(i);
    }
    Eigen::VectorXd delta = Eigen::VectorXd::Zero(p);
    if (!free.empty()) {
      const int f = static_cast<int>(free.size());
      Eigen::MatrixXd Af(f, f);
      Eigen::VectorXd gf(f);
      for (int a = 0; a < f; ++a) {
        gf(a) = g(free[a]);
        for (int b = 0; b < f; ++b) Af(a, b) = A(free[a], free[b]);
      }
      Af.diagonal().array() += lambda;
      const Eigen::VectorXd df = Af.ldlt().solve(-gf);
      for (int a = 0; a < f; ++a) delta(free[a]) = df(a);
    }
    std::vector<double> trial = res.x;
    for (int i = 0; i < p; ++i) {
      trial[i] = std::clamp(res.x[i] + delta(i) * scale(i), problem.lower[i], problem.upper[i]);
      delta(i) = (trial[i] - res.x[i]) / scale(i);  // the step actually taken
    }
    if (delta.lpNorm<Eigen::Infinity>() <= options.step_tol) {
      res.status = LmStatus::StepTolerance;
      res.message = "step below step_tol";
      break;
    }
    const double predicted = -(g.dot(delta) + 0.5 * delta.dot(A * delta));
    const bool ok = evaluate(trial, r_trial, J_trial);
    const double cost_trial = ok ? 0.5 * r_trial.squaredNorm() : kInf;
    const double rho = predicted > 0.0 ? (res.cost - cost_trial) / predicted : -1.0;
    if (ok && rho > 1e-3) {
      const double decrease = (res.cost - cost_trial) / std::max(res.cost, 1e-300);
      res.x = trial;
      res.cost = cost_trial;
      r = r_trial;
      J = J_trial;
      ++res.accepted_steps;
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
      nu = 2.0;
      if (decrease <= options.cost_tol) {
        res.status = LmStatus::CostTolerance;
        res.message = "relative decrease below cost_tol";
        break;
      }
    } else {
      lambda *= nu;
      nu *= 2.0;
    }
  }
  res.r = r;
  res.J = J;
  return res;
}

// --- drape residuals and Jacobian -----------------------------------------------------------

DrapeResiduals drape_residuals(const DrapeFitProblem& problem, const std::vector<double>& x,
                               const PolishOptions& polish) {
  const double cpu0 = cpu_now();
  DrapeResiduals out;
  const DrapeResult run = run_drape(problem.scene_of(x), problem.integrator());
  auto finish = [&] {
    out.cpu_seconds = cpu_now() - cpu0;
    return out;
  };
  if (run.stats.status != RunStatus::Equilibrium) {
    out.message = "drape run: " + run.stats.message;
    return finish();
  }
  const SpringNetwork& net = run.grid.network;
  DrapeSensitivity sens;
  try {
    sens = drape_sensitivity(run.grid, run.stats.t_final, free_state(net, run.positions),
                             {kParameters.begin(), kParameters.end()}, polish);
  } catch (const std::invalid_argument& e) {  // edges not measurable
    out.message = std::string("measurement: ") + e.what();
    return finish();
  }
  if (sens.status != SensitivityStatus::Ok) {
    out.message = "sensitivity: " + sens.message;
    return finish();
  }
  const std::vector<EdgeFit>& measured = problem.measured();
  const int m = static_cast<int>(measured.size()) * (kEdgePolynomialDegree + 1);
  out.r.resize(m);
  out.J.resize(m, kDrapeContinuous);
  int row = 0;
  for (const EdgeFit& target : measured) {
    size_t e = 0;
    while (e < sens.edges.size() && sens.edges[e].name != target.name) ++e;
    if (e == sens.edges.size()) {
      out.message = "measured edge " + target.name + " is not among the simulated edges";
      return finish();
    }
    for (int i = 0; i <= kEdgePolynomialDegree; ++i, ++row) {
      out.r(row) = target.coefficients[i] - sens.edges[e].coefficients[i];
      for (int c = 0; c < kDrapeContinuous; ++c)
        out.J(row, c) = -sens.parameters[c].dcoefficients[e][i];
    }
  }
  for (int c = 0; c < kDrapeContinuous; ++c)
    out.structural_zero[c] = sens.parameters[c].structural_zero;
  out.objective = 100.0 * std::sqrt(out.r.squaredNorm() / m);
  out.positive_pivots = sens.positive_pivots;
  out.residual_before_polish = sens.polish.residual_before;
  out.residual = sens.polish.residual;
  out.failed = !std::isfinite(out.objective);
  return finish();
}

DrapeIdentifiability identifiability(const DrapeResiduals& at, const std::vector<double>& x) {
  DrapeIdentifiability id;
  id.residuals = static_cast<int>(at.r.size());
  std::vector<int> live;  // parameters with a non-zero column
  for (int c = 0; c < kDrapeContinuous; ++c) {
    ParameterIdentifiability& p = id.parameters[c];
    p.value = x[c];
    p.structural_zero = at.structural_zero[c] || at.J.col(c).norm() == 0.0;
    p.standard_error = p.conditional_standard_error = kInf;
    if (!p.structural_zero) live.push_back(c);
  }
  const int q = static_cast<int>(live.size());
  if (q == 0) return id;
  Eigen::MatrixXd Jr(at.J.rows(), q);
  for (int a = 0; a < q; ++a) Jr.col(a) = at.J.col(live[a]) * x[live[a]];
  const Eigen::MatrixXd A = Jr.transpose() * Jr;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
  const Eigen::VectorXd lam = eig.eigenvalues();  // ascending
  const Eigen::MatrixXd V = eig.eigenvectors();
  const double lmax = lam(q - 1);
  std::vector<bool> null(q);
  for (int j = 0; j < q; ++j) {
    null[j] = !(lam(j) > kNullEigenvalue * lmax);
    if (!null[j]) ++id.rank;
  }
  id.condition_number = lam(0) > 0.0 ? lmax / lam(0) : kInf;
  const int dofs = id.residuals - id.rank;
  id.sigma = dofs > 0 ? std::sqrt(at.r.squaredNorm() / dofs) : 0.0;
  auto pinv_quadratic = [&](const Eigen::VectorXd& w) {  // w^T A^+ w, +inf on a null direction
    double sum = 0.0;
    for (int j = 0; j < q; ++j) {
      const double proj = V.col(j).dot(w);
      if (null[j]) {
        if (std::abs(proj) > 1e-6 * w.norm()) return kInf;
        continue;
      }
      sum += proj * proj / lam(j);
    }
    return sum;
  };
  int k_at = -1, l_at = -1;
  for (int a = 0; a < q; ++a) {
    ParameterIdentifiability& p = id.parameters[live[a]];
    const Eigen::VectorXd e = Eigen::VectorXd::Unit(q, a);
    p.standard_error = std::abs(p.value) * id.sigma * std::sqrt(pinv_quadratic(e));
    p.conditional_standard_error = std::abs(p.value) * id.sigma / std::sqrt(A(a, a));
    if (live[a] == kGeneStiffness) k_at = a;
    if (live[a] == kGeneNaturalLength) l_at = a;
  }
  if (k_at >= 0 && l_at >= 0) {
    id.correlation_stiffness_length = -A(k_at, l_at) / std::sqrt(A(k_at, k_at) * A(l_at, l_at));
    Eigen::VectorXd w = Eigen::VectorXd::Zero(q);
    w(k_at) = 1.0;
    w(l_at) = -1.0;
    id.ratio_relative_error = id.sigma * std::sqrt(pinv_quadratic(w));
  } else {
    id.correlation_stiffness_length = std::numeric_limits<double>::quiet_NaN();
    id.ratio_relative_error = kInf;
  }
  return id;
}

// --- multi-start fit ------------------------------------------------------------------------

void DrapeLmOptions::validate() const {
  lm.validate();
  LmStartOptions::validate();
  polish.validate();
}

std::vector<LengthBracket> length_brackets(double width, double lower, double upper) {
  auto cells = [width](double L0) {
    DrapeParams p;
    p.width = width;
    p.natural_length = L0;
    return p.cells();
  };
  std::vector<LengthBracket> out;
  for (int n = cells(lower); n >= cells(upper); --n) {
    // Exact ends W / (n +- 1/2), then moved inward by a few ulps until n is right at both.
    LengthBracket b{n, std::max(lower, width / (n + 0.5)),
                    n == 2 ? upper : std::min(upper, width / (n - 0.5))};
    for (int i = 0; i < 64 && cells(b.lower) != n; ++i) b.lower = std::nextafter(b.lower, upper);
    for (int i = 0; i < 64 && cells(b.upper) != n; ++i) b.upper = std::nextafter(b.upper, lower);
    if (b.lower <= b.upper && cells(b.lower) == n && cells(b.upper) == n) out.push_back(b);
  }
  return out;
}

namespace {
// The LM box of the continuous genes with L0 restricted to one n bracket (no evaluate yet).
LmProblem bracket_box(const DrapeFitBounds& box, const LengthBracket& b) {
  std::vector<double> lower(box.lower.begin(), box.lower.begin() + kDrapeContinuous);
  std::vector<double> upper(box.upper.begin(), box.upper.begin() + kDrapeContinuous);
  lower[kGeneNaturalLength] = b.lower;
  upper[kGeneNaturalLength] = b.upper;
  return LmProblem{std::move(lower), std::move(upper), {}};
}
}  // namespace

DrapeLmResult fit_drape_lm(const DrapeFitProblem& problem, const DrapeLmOptions& options) {
  options.validate();
  const auto wall0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_now();
  const DrapeFitBounds& box = problem.options().bounds;
  const double width =
      problem.params_of(std::vector<double>(box.lower.begin(), box.lower.end())).width;
  const std::vector<LengthBracket> brackets =
      length_brackets(width, box.lower[kGeneNaturalLength], box.upper[kGeneNaturalLength]);
  DrapeLmResult out;
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto country = [](const std::vector<double>& x, int topo) {
    std::vector<double> c(x.begin(), x.begin() + kDrapeContinuous);
    c.push_back(topo + 0.5);  // the middle of the category's unit interval
    return c;
  };
  auto evaluate = [&](const std::vector<double>& c) {
    DrapeResiduals e = drape_residuals(problem, c, options.polish);
    ++out.evaluations;
    if (e.failed) ++out.failed_evaluations;
    if (options.on_evaluation) options.on_evaluation(c, e);
    return e;
  };

  // 1. Screening.
  struct Screened {
    DrapeLmStart start;
    DrapeResiduals at;
    LengthBracket bracket;
  };
  std::vector<Screened> screened;
  for (int topo = static_cast<int>(box.lower[kGeneTopology]);
       topo < static_cast<int>(box.upper[kGeneTopology]); ++topo)
    for (const LengthBracket& b : brackets)
      for (int s = 0; s < options.starts_per_bracket; ++s) {
        std::vector<double> x0(kDrapeContinuous);
        for (int i = 0; i < kDrapeContinuous; ++i) x0[i] = 0.5 * (box.lower[i] + box.upper[i]);
        if (s > 0)
          x0[kGeneStiffness] = box.lower[kGeneStiffness] +
                               unit(rng) * (box.upper[kGeneStiffness] - box.lower[kGeneStiffness]);
        x0[kGeneNaturalLength] = 0.5 * (b.lower + b.upper);
        Screened sc{{}, evaluate(country(x0, topo)), b};
        DrapeLmStart& st = sc.start;
        st.topology = static_cast<char>('a' + topo);
        st.cells = b.cells;
        st.x0 = st.x = country(x0, topo);
        st.screened = st.objective =
            sc.at.failed ? std::numeric_limits<double>::quiet_NaN() : sc.at.objective;
        st.predicted = st.screened;
        if (!sc.at.failed) {  // Gauss-Newton prediction within the bracket's box
          const LmProblem lp = bracket_box(box, b);
          Eigen::VectorXd r0 = sc.at.r;
          const Eigen::MatrixXd J0 = sc.at.J;
          Eigen::VectorXd delta(kDrapeContinuous);
          const Eigen::MatrixXd A = J0.transpose() * J0;
          const Eigen::VectorXd g = J0.transpose() * r0;
          Eigen::MatrixXd scale = Eigen::MatrixXd::Zero(kDrapeContinuous, kDrapeContinuous);
          for (int i = 0; i < kDrapeContinuous; ++i) scale(i, i) = lp.upper[i] - lp.lower[i];
          const Eigen::MatrixXd Au = scale * A * scale;
          Eigen::MatrixXd reg = Au;
          reg.diagonal().array() += 1e-9 * std::max(Au.diagonal().maxCoeff(), 1e-300);
          const Eigen::VectorXd du = reg.ldlt().solve(-(scale * g));
          for (int i = 0; i < kDrapeContinuous; ++i) {
            const double xi = std::clamp(x0[i] + du(i) * scale(i, i), lp.lower[i], lp.upper[i]);
            delta(i) = xi - x0[i];
          }
          st.predicted = 100.0 * std::sqrt((r0 + J0 * delta).squaredNorm() / r0.size());
        }
        screened.push_back(std::move(sc));
      }

  // 2. Refinement of the best predictions.
  std::vector<size_t> order(screened.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const double pa = screened[a].start.predicted, pb = screened[b].start.predicted;
    return std::isnan(pb) ? !std::isnan(pa) : pa < pb;
  });
  for (size_t rank = 0; rank < order.size() && static_cast<int>(rank) < options.refine; ++rank) {
    Screened& sc = screened[order[rank]];
    if (sc.at.failed) break;
    DrapeLmStart& st = sc.start;
    const int topo = st.topology - 'a';
    LmProblem lp = bracket_box(box, sc.bracket);
    bool first = true;  // the screening evaluation is x0's
    lp.evaluate = [&](const std::vector<double>& x, Eigen::VectorXd& r, Eigen::MatrixXd& J) {
      DrapeResiduals e = first ? sc.at : evaluate(country(x, topo));
      first = false;
      if (e.failed) return false;
      r = std::move(e.r);
      J = std::move(e.J);
      return true;
    };
    st.lm = run_lm(lp, std::vector<double>(st.x0.begin(), st.x0.begin() + kDrapeContinuous),
                   options.lm);
    st.refined = true;
    st.x = country(st.lm.x, topo);
    st.objective = 100.0 * std::sqrt(st.lm.r.squaredNorm() / st.lm.r.size());
  }

  DrapeResiduals best_at;
  for (Screened& sc : screened) {
    const DrapeLmStart& st = sc.start;
    if (!std::isnan(st.objective) && (!out.ok || st.objective < out.objective)) {
      out.ok = true;
      out.objective = st.objective;
      out.best_x = st.x;
      best_at = sc.at;
      if (st.refined) {
        best_at.r = st.lm.r;
        best_at.J = st.lm.J;
      }
    }
    out.starts.push_back(sc.start);
  }
  if (out.ok) {
    out.params = problem.params_of(out.best_x);
    out.identifiability = identifiability(best_at, out.best_x);
    out.message = std::to_string(out.starts.size()) + " screened starts (" +
                  std::to_string(brackets.size()) + " n brackets), " +
                  std::to_string(std::min<int>(options.refine, out.starts.size())) + " refined, " +
                  std::to_string(out.evaluations) + " drape evaluations";
  } else {
    out.message = "every start failed to evaluate";
  }
  out.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  out.cpu_seconds = cpu_now() - cpu0;
  return out;
}

nlohmann::json to_json(const DrapeLmOptions& o) {
  return {{"starts_per_bracket", o.starts_per_bracket},
          {"refine", o.refine},
          {"seed", o.seed},
          {"max_evaluations", o.lm.max_evaluations},
          {"initial_lambda", o.lm.initial_lambda},
          {"step_tol", o.lm.step_tol},
          {"cost_tol", o.lm.cost_tol}};
}

}  // namespace knitsim
