// A quasi-static tensile test of a knit chart or scene (`knitsim tensile`; docs/knit.md, "Under
// load"): a strip of the chart clamped at two opposite edges, one edge moved in equal steps to a
// strain, each step's equilibrium found by the equilibrium solver warm-started from the last
// and certified, and optionally unloaded back along the same steps.
//
// The driver sees the model through its contract only: MechanicalSystem (the solver) and
// HeldPoints (the clamps moved between steps as run state, their reactions), so a model that
// offers both serves it; the model is built once and its clamps moved (the contact's set-up is
// most of a large chart's cost).
//
// Specimen: along the pull the chart's own extent (wale: its courses, level 0 to the top level;
// course: its wales, wale 0 to the last); across it as many wales (courses) as make the clamp
// distance / width = gauge_ratio, the chart's columns (rows) repeated or cut, so a chart tiles
// its repeat. Width W = wales x w (courses x h); gauge G = the clamps' rest distance.
// Per step: strain = displacement / G; force_N = the moving clamp's reaction along the pull
// (positive in tension); force_per_width = force / W at rest; lateral_strain = the width change
// at mid-length over the rest width (the edge wales' points on the middle level; the bottom and
// top points of the middle wale); energy_J = the potential energy (springs, contact, gravity of
// the free points).
//
// Step 0 settles the chart between its clamps at rest (the rest lattice is not an equilibrium of
// the network: the clamps may hold a force there already, the curve's offset).
// Warm start: step 1 from step 0 stretched affinely to its clamp positions, step 2 from the
// secant through the last two equilibria (in the load fraction), later steps from the quadratic
// through the last three, each dropped for the next if its energy is not finite (a contact pair
// inside its core), the last for the last equilibrium as it is; where even that is not finite
// (the moved clamp's yarn lands inside another's contact core) the step's move is halved, each
// half solved in turn (up to 6 halvings; the row is the step's end, its counters the halves'
// sum). At the predicted state the contact's maps are renewed (MechanicalSystem::update, as the
// solver's checks do) and one Newton step is taken where K is positive definite, the model admits
// the step whole and the energy falls (StiffnessProbe::newton_correction); the solver starts
// there, and its stop certifies the state at once where that step converged (a step's
// newton_steps and factorisations count it).
//
// Energy check: a step whose end lies above its start's energy after renewals of the contact's
// maps (which change E(x) itself) is solved again from there with the renewed energy as the
// reference (at most 3 times); its status is then the second solve's.
//
// Failure modes: bad options throw std::invalid_argument naming the flag and its range (before
// anything is built or written); a step that does not reach equilibrium ends the test with its
// status, the steps so far kept.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "models/knit_loops.hpp"
#include "solvers/integrator.hpp"
#include "src/core/vec3.hpp"
#include "src/scene/knit_scene.hpp"

namespace knitsim {

struct TensileOptions {
  std::string direction = "wale";  // wale (pull along y) | course (pull along x)
  int steps = 20;                  // loading steps, >= 1
  double strain = 0.2;             // engineering strain of the clamp distance at the last step
  double gauge_ratio = 2.0;        // clamp distance / width, > 0
  bool unload = false;             // then back to 0 along the same steps
  int outputs = 3;                 // steps whose whole state is kept (first, ..., last), >= 0
  // Throws std::invalid_argument naming the flag (--direction, --steps, --strain,
  // --gauge-ratio, --outputs) and its accepted range.
  void validate() const;
};

// The tensile test's specimen: the chart repeated or cut across the pull (see the header).
// Throws std::invalid_argument for a specimen the chart rules refuse (naming the row, column).
KnitChart tensile_specimen(const KnitChart& chart, const TensileOptions& options,
                           const KnitParams& params);

struct TensileStep {
  int step = 0;  // 0 = settled between the clamps at rest, 1..steps loading, then unloading
  double strain = 0.0;        // 1
  double displacement = 0.0;  // m, the moving clamp's along the pull
  double force = 0.0;         // N
  double force_per_width = 0.0;  // N/m
  double lateral_strain = 0.0;   // 1
  double energy = 0.0;           // J
  // equilibrium | equilibrium_after_saddle (the solver left a saddle along its negative mode:
  // the strip wrinkled or buckled) | equilibrium_inconclusive (K singular, the residual decided)
  // | the run status of a step that did not end at equilibrium (the last row).
  std::string status;
  std::vector<Vec3> reactions;  // per clamp (fixed, moving), N
  RunStats stats;               // this step's solve
};

struct TensileResult {
  KnitModel model;  // the specimen's model; its clamps: [0] fixed, [1] moving
  KnitChart specimen;
  double gauge = 0.0;  // m, the clamps' rest distance
  double width = 0.0;  // m
  Vec3 pull;           // unit, along the pull
  std::vector<TensileStep> steps;  // step 0 first, then each step run (the failed one last)
  // The whole state at the kept steps (TensileOptions::outputs): step, t, x, all positions.
  struct Kept {
    int step = 0;
    std::vector<double> x;
    std::vector<Vec3> positions;
    RunStats stats;
  };
  std::vector<Kept> kept;
  bool complete = false;  // every step reached equilibrium
  double cpu_seconds = 0.0, wall_seconds = 0.0;  // the steps' solves together
};

// Runs the test on `scene` (its chart made into the specimen; knit.pins and knit.clamps must be
// unset: the test clamps the specimen itself: std::invalid_argument). `observer` (may be null)
// sees every solver step; `on_kept` (may be empty) is called at each kept step with the result
// so far (its last kept entry that step) and the velocities, while the model is in that step's
// state (its clamps and contact maps), so the step's outputs can be written then.
using TensileKeptCallback =
    std::function<void(const TensileResult&, int step, const std::vector<double>& v)>;
TensileResult run_tensile(const KnitScene& scene, const TensileOptions& options,
                          RunObserver* observer = nullptr, const TensileKeptCallback& on_kept = {});

// The work of the moving clamp over the steps, J: the trapezoid rule on (displacement, force)
// from step `from` to step `to` (indices into steps).
double tensile_work(const std::vector<TensileStep>& steps, std::size_t from, std::size_t to);

}  // namespace knitsim
