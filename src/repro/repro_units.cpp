// The work units of a reproduction: one ICA or LM fit of a sample, and the Taguchi experiments'
// ICA options; their keys and scenes.
// Each function's contract is in repro_internal.hpp.
#include <cmath>
#include <cstdio>
#include <ctime>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "src/base/text.hpp"
#include "src/fit/taguchi.hpp"
#include "src/paper/paper_data.hpp"
#include "src/repro/repro_internal.hpp"
#include "src/scene/scene.hpp"

namespace knitsim::repro_internal {

using nlohmann::json;

double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

double thread_cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

Scene sample_scene(const std::string& scene, int sample, const ReproOptions& o) {
  std::vector<std::string> sets = {"fabric.areal_density=" +
                                   format_number(paper_sample(sample).areal_density, 17)};
  if (scene == "four_corner")
    sets.push_back(std::string("model.symmetry=") + to_string(o.four_corner_symmetry));
  Scene s = load_scene(scene, sets);
  s.options.rtol = o.rtol;
  s.validate();
  return s;
}

DrapeFitOptions fit_options(const ReproOptions& o, const IcaOptions& ica) {
  DrapeFitOptions f;
  f.ica = ica;
  f.integrator = repro_integrator(o);
  return f;
}

namespace {

// k fitted by LM with L0 and the topology held at the twin's true values (damping and the
// elongation limit, which the equilibrium does not see, held at the box centre): the stiffness
// the edges give when L0 is known. Result {stiffness, objective, evaluations, status}.
json stiffness_at_true_length(const DrapeFitProblem& problem, const PaperSample& truth,
                              const DrapeLmOptions& options) {
  const DrapeFitBounds& box = problem.options().bounds;
  LmProblem lp;
  lp.lower.assign(box.lower.begin(), box.lower.begin() + kDrapeContinuous);
  lp.upper.assign(box.upper.begin(), box.upper.begin() + kDrapeContinuous);
  lp.lower[kGeneNaturalLength] = lp.upper[kGeneNaturalLength] = truth.natural_length;
  lp.lower[kGeneDamping] = lp.upper[kGeneDamping] =
      0.5 * (box.lower[kGeneDamping] + box.upper[kGeneDamping]);
  lp.lower[kGeneElongation] = lp.upper[kGeneElongation] =
      0.5 * (box.lower[kGeneElongation] + box.upper[kGeneElongation]);
  const double topology_gene = truth.topology - 'a' + 0.5;
  lp.evaluate = [&](const std::vector<double>& x, Eigen::VectorXd& r, Eigen::MatrixXd& J) {
    std::vector<double> country = x;
    country.push_back(topology_gene);
    DrapeResiduals e = drape_residuals(problem, country, options.polish);
    if (e.failed) return false;
    r = std::move(e.r);
    J = std::move(e.J);
    return true;
  };
  std::vector<double> x0 = lp.lower;
  x0[kGeneStiffness] = 0.5 * (box.lower[kGeneStiffness] + box.upper[kGeneStiffness]);
  const LmResult fit = run_lm(lp, x0, options.lm);
  const bool ok = fit.status != LmStatus::StartFailed;
  return {{"stiffness", ok ? json(fit.x[kGeneStiffness]) : json(nullptr)},
          {"objective",
           ok ? json(100.0 * std::sqrt(fit.r.squaredNorm() / fit.r.size())) : json(nullptr)},
          {"evaluations", fit.evaluations},
          {"status", to_string(fit.status)}};
}

// The LM status of the start that gave the best point ("screened": never refined).
std::string lm_status(const DrapeLmResult& r) {
  for (const DrapeLmStart& s : r.starts)
    if (s.x == r.best_x) return s.refined ? to_string(s.lm.status) : "screened";
  return "no start";
}

}  // namespace

json fit_unit(const ReproOptions& o, const Target& target, SyntheticSet set, int sample,
              const FitMethod& m) {
  const DrapeFitProblem problem(sample_scene("four_corner", sample, o), target,
                                fit_options(o, m.ica));
  // The fit's CPU: its thread's when the fit runs on one (other units may run beside it), the
  // process's when it runs alone on ica.jobs threads (fit_work_units).
  const auto cpu = [&m] { return m.ica.jobs > 1 ? cpu_now() : thread_cpu_now(); };
  const double cpu0 = cpu();
  json unit;
  if (m.optimizer == ReproOptimizer::Ica) {
    const DrapeFitResult r = fit_drape(problem);
    json history = json::array();
    for (const IcaDecade& d : r.history) history.push_back({d.best_cost, d.mean_cost});
    unit = {{"best_x", r.best_x},
            {"objective", r.objective},
            {"evaluations", r.evaluations},
            {"failed_evaluations", r.failed_evaluations},
            {"status", to_string(r.status)},
            {"seed", m.ica.seed},
            {"history", history},
            {"wall_seconds", r.wall_seconds}};
  } else {
    const DrapeLmResult r = fit_drape_lm(problem, m.lm);
    if (!r.ok) throw std::runtime_error("lm: " + r.message);
    unit = {{"best_x", r.best_x},
            {"objective", r.objective},
            {"evaluations", r.evaluations},
            {"failed_evaluations", r.failed_evaluations},
            {"status", lm_status(r)},
            {"seed", m.lm.seed},
            {"wall_seconds", r.wall_seconds}};
  }
  unit["cpu_seconds"] = cpu() - cpu0;
  if (m.optimizer == ReproOptimizer::Lm && set == SyntheticSet::Twin)
    unit["known_length"] = stiffness_at_true_length(problem, paper_sample(sample), m.lm);
  return unit;
}

std::vector<WorkUnit> fit_work_units(const ReproOptions& o, std::vector<FitSpec> specs) {
  std::vector<WorkUnit> units;
  for (FitSpec& s : specs) {
    s.method.ica.jobs = specs.size() == 1 ? o.jobs : 1;
    units.push_back({s.key, [&o, s] { return fit_unit(o, *s.target, s.set, s.sample, s.method); }});
  }
  return units;
}

std::string fit_key(ReproOptimizer optimizer, SyntheticSet set, int sample, int run) {
  char buf[64];
  if (optimizer == ReproOptimizer::Ica)
    std::snprintf(buf, sizeof buf, "fit/%s/s%d/run%02d", to_string(set), sample, run);
  else
    std::snprintf(buf, sizeof buf, "lm/%s/s%d", to_string(set), sample);
  return buf;
}

std::string taguchi_key(const ReproOptions& o, int experiment, int replicate) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "taguchi/%s/s%d/e%02d/r%d", to_string(o.taguchi_set),
                o.taguchi_sample, experiment + 1, replicate);
  return buf;
}

std::array<int, 7> experiment_levels(int e) {
  std::array<int, 7> levels{};
  for (int f = 0; f < 7; ++f) levels[f] = l27_level(e, default_l27_columns()[f]) + 1;
  return levels;
}

IcaOptions taguchi_ica(const ReproOptions& o, int e) {
  const std::array<int, 7> levels = experiment_levels(e);
  IcaOptions ica = ica_table1_options(levels);
  ica.decades = o.taguchi_decades[levels[0] - 1];
  return ica;
}

}  // namespace knitsim::repro_internal
