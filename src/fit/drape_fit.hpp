// Fitting the drape model to measured edges with the ICA (paper 1, "Optimization of model
// parameters using ICA", Table 3; user's view: docs/fitting.md).
//
// A country of the ICA (src/fit/ica.hpp) is the 5-vector, in this order (DrapeGene),
//   x = [ stiffness k (N/m), damping c (N s/m), elongation limit eps (percent),
//         natural length L0 (m), topology gene u ]
// in the box of paper 1's Table 3 (DrapeFitBounds defaults): k 500-1200, c 10-20, eps 5-20 %,
// L0 0.04-0.06 m (the table prints 4-6 cm), u in [0, 3). Topology encoding: u is a categorical
// gene, topology = 'a' + floor(u) (a = structural + shear + bending, b = structural + shear,
// c = structural + bending); narrower integer bounds restrict the topologies (e.g. [0, 1): a
// only). Everything else (fabric width and areal density, pins, run options) comes from the
// base scene.
//
// Cost of a country: the drape built from those parameters runs from the flat state to
// equilibrium with the chosen integrator (run_drape), its edges are measured (measure_edges)
// and compared with the target's edges of the matching scene by Eq. 5 (objective(), percent).
// The target scene is the base scene's name when it is four_corner | two_corner |
// two_corner_slack, else the one its pins imply (four_corner layout -> four_corner; two_corner
// -> two_corner, or two_corner_slack when pins.span < 1).
//
// Failure modes: set-up errors (bad bounds, a target without the matching scene, an unknown
// integrator) throw std::invalid_argument before any run. A run that does not reach
// Equilibrium (time, step or wall limit, solver failure, divergence) or whose edges cannot be
// measured is a FAILED evaluation: its cost is NaN, which the ICA scores as
// IcaOptions::failure_cost and counts in failed_evaluations; the fit carries on.
// At cvode-bdf's default rtol 1e-6 some drapes of the fit box end at t_max with the static
// residual stuck just above equilibrium_tol; such false failures rank last, so `knitsim fit`
// defaults to rtol 1e-8 (--rtol to change it; docs/numerics.md, "Known limitations";
// experiments/fit_tolerance/README.md).
//
// Threads: every evaluation builds its own DrapeGrid and integrator (nothing is shared between
// threads but the read-only base scene and target edges), so DrapeFitProblem::evaluate is
// reentrant and the ICA's `jobs` threads may call it at once. The ICA draws every random number
// on the calling thread and the drape runs are deterministic, so the result is bit-identical for
// any number of jobs.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "src/fit/ica.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"
#include "src/fit/targets.hpp"

namespace knitsim {

// Positions of the parameters in a country.
enum DrapeGene {
  kGeneStiffness,
  kGeneDamping,
  kGeneElongation,
  kGeneNaturalLength,
  kGeneTopology,
  kDrapeGenes
};

// The search box (paper 1 Table 3; topology gene u, see above). Units as DrapeParams.
struct DrapeFitBounds {
  std::array<double, kDrapeGenes> lower = {500.0, 10.0, 5.0, 0.04, 0.0};
  std::array<double, kDrapeGenes> upper = {1200.0, 20.0, 20.0, 0.06, 3.0};

  // Throws std::invalid_argument "bounds.<gene> = [lo, hi]: accepted range": every box
  // non-empty (lower < upper), stiffness and natural length > 0, damping and elongation >= 0,
  // topology bounds integers with 0 <= lower < upper <= 3.
  void validate() const;
};

// Gene names in country order: stiffness, damping, elongation_limit, natural_length, topology.
const std::array<const char*, kDrapeGenes>& drape_gene_names();

struct DrapeFitOptions {
  DrapeFitBounds bounds;
  IcaOptions ica;          // budget, seed, jobs (defaults: paper 1's Taguchi-best settings)
  std::string integrator;  // registry name; empty = default_integrator()

  // bounds.validate(), ica.validate(), and the integrator name (std::invalid_argument).
  void validate() const;
};

// The outcome of one cost evaluation.
struct DrapeEvaluation {
  RunStatus status = RunStatus::SolverFailure;  // of the drape run
  bool failed = true;      // not Equilibrium, or the edges could not be measured
  double objective = 0.0;  // Eq. 5, percent; NaN when failed
  std::string message;     // why it failed (the run's message or the measurement error)
};

class DrapeFitProblem {
 public:
  // Checks the options and reads the target's matching scene (std::invalid_argument).
  DrapeFitProblem(Scene base, const Target& target, DrapeFitOptions options);

  // The drape parameters of country x (kDrapeGenes values): base.params with the 5 genes set.
  DrapeParams params_of(const std::vector<double>& x) const;
  // The base scene with params_of(x).
  Scene scene_of(const std::vector<double>& x) const;
  // One evaluation; reentrant.
  DrapeEvaluation evaluate(const std::vector<double>& x) const;
  // The ICA problem: the box, the topology gene categorical, cost = evaluate(x).objective.
  // Its cost refers to this object, which must outlive the ICA run.
  Problem ica_problem() const;

  const std::string& target_scene() const { return target_scene_; }
  const std::vector<EdgeFit>& measured() const { return measured_; }
  const std::string& integrator() const { return options_.integrator; }
  const DrapeFitOptions& options() const { return options_; }

 private:
  Scene base_;
  DrapeFitOptions options_;  // integrator resolved (never empty)
  std::string target_scene_;
  std::vector<EdgeFit> measured_;  // fit_target_scene of the target's matching scene
};

struct DrapeFitResult {
  IcaStatus status = IcaStatus::DecadeLimit;
  std::string message;         // the ICA's
  std::vector<double> best_x;  // best country (kDrapeGenes values)
  DrapeParams params;          // params_of(best_x)
  double objective = 0.0;      // its Eq. 5 error, percent (failure_cost if AllFailed)
  long evaluations = 0;
  long failed_evaluations = 0;
  std::vector<IcaDecade> history;  // per decade: best and mean imperialist cost
  double wall_seconds = 0.0;
};

// Runs the ICA on problem.ica_problem() with problem.options().ica.
DrapeFitResult fit_drape(const DrapeFitProblem& problem);

}  // namespace knitsim
