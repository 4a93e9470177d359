#include "src/fit/drape_fit.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace knitsim {

const std::array<const char*, kDrapeGenes>& drape_gene_names() {
  static const std::array<const char*, kDrapeGenes> names = {
      "stiffness", "damping", "elongation_limit", "natural_length", "topology"};
  return names;
}

void DrapeFitBounds::validate() const {
  for (int g = 0; g < kDrapeGenes; ++g) {
    const double lo = lower[g], hi = upper[g];
    auto bad = [&](const char* range) {
      std::ostringstream m;
      m << "bounds." << drape_gene_names()[g] << " = [" << lo << ", " << hi << "]: " << range;
      throw std::invalid_argument(m.str());
    };
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi))
      bad("must be finite, lower < upper");
    if ((g == kGeneStiffness || g == kGeneNaturalLength) && !(lo > 0.0)) bad("lower must be > 0");
    if ((g == kGeneDamping || g == kGeneElongation) && !(lo >= 0.0)) bad("lower must be >= 0");
    if (g == kGeneTopology &&
        (lo != std::floor(lo) || hi != std::floor(hi) || lo < 0.0 || hi > 3.0))
      bad("must be integers with 0 <= lower < upper <= 3 (0 = a, 1 = b, 2 = c)");
  }
}

void DrapeFitOptions::validate() const {
  bounds.validate();
  ica.validate();
  if (!integrator.empty()) make_integrator(integrator);  // throws for an unknown name
}

DrapeFitProblem::DrapeFitProblem(Scene base, const Target& target, DrapeFitOptions options)
    : base_(std::move(base)), options_(std::move(options)) {
  base_.validate();
  options_.validate();
  if (options_.integrator.empty()) options_.integrator = default_integrator();
  target_scene_ = target_scene_name(base_);
  measured_ = fit_target_scene(target.scene(target_scene_));
  if (measured_.empty())
    throw std::invalid_argument("target scene " + target_scene_ + ": no edges to fit");
}

DrapeParams DrapeFitProblem::params_of(const std::vector<double>& x) const {
  if (x.size() != static_cast<size_t>(kDrapeGenes))
    throw std::invalid_argument("drape fit: a country has " + std::to_string(kDrapeGenes) +
                                " genes, got " + std::to_string(x.size()));
  DrapeParams p = base_.params;
  p.stiffness = x[kGeneStiffness];
  p.damping = x[kGeneDamping];
  p.elongation_limit = x[kGeneElongation];
  p.natural_length = x[kGeneNaturalLength];
  const double lo = options_.bounds.lower[kGeneTopology];
  const double hi = options_.bounds.upper[kGeneTopology];
  p.topology =
      static_cast<char>('a' + static_cast<int>(lo) + category_of(x[kGeneTopology], lo, hi));
  return p;
}

Scene DrapeFitProblem::scene_of(const std::vector<double>& x) const {
  Scene s = base_;
  s.params = params_of(x);
  return s;
}

DrapeEvaluation DrapeFitProblem::evaluate(const std::vector<double>& x) const {
  const DrapeResult run = run_drape(scene_of(x), options_.integrator);
  DrapeEvaluation e;
  e.status = run.stats.status;
  e.objective = std::numeric_limits<double>::quiet_NaN();
  e.message = run.stats.message;
  if (run.stats.status != RunStatus::Equilibrium) return e;
  std::vector<EdgeFit> simulated;
  try {
    simulated = measure_edges(run.grid, run.positions);
  } catch (const std::invalid_argument& err) {  // e.g. a degenerate or non-finite shape
    e.message = std::string("edges not measurable: ") + err.what();
    return e;
  }
  e.objective = objective(measured_, simulated);
  e.failed = !std::isfinite(e.objective);
  return e;
}

Problem DrapeFitProblem::ica_problem() const {
  Problem p;
  p.lower.assign(options_.bounds.lower.begin(), options_.bounds.lower.end());
  p.upper.assign(options_.bounds.upper.begin(), options_.bounds.upper.end());
  p.categorical.assign(kDrapeGenes, false);
  p.categorical[kGeneTopology] = true;
  p.cost = [this](const std::vector<double>& x) { return evaluate(x).objective; };
  return p;
}

DrapeFitResult fit_drape(const DrapeFitProblem& problem) {
  const IcaResult r = run_ica(problem.ica_problem(), problem.options().ica);
  DrapeFitResult f;
  f.status = r.status;
  f.message = r.message;
  f.best_x = r.best_x;
  f.params = problem.params_of(r.best_x);
  f.objective = r.best_cost;
  f.evaluations = r.evaluations;
  f.failed_evaluations = r.failed_evaluations;
  f.history = r.history;
  f.wall_seconds = r.wall_seconds;
  return f;
}

}  // namespace knitsim
