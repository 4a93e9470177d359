// One knit run (paper 2's interlacing-point network, models/knit_loops.hpp; docs/knit.md): a
// stitch chart with its knit parameters run to its steady state, with the frames and the yarn
// measures every report of it shows. What `knitsim knit` runs and writes (src/io/knit_outputs.hpp),
// callable without the command line.
//
// Failure modes as run_drape's: bad input throws std::invalid_argument (one line); a run that
// does not reach its steady state is a status in the result's stats, not an exception.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "models/knit_loads.hpp"
#include "models/knit_loops.hpp"
#include "models/yarn_knit.hpp"
#include "solvers/integrator.hpp"
#include "src/core/vec3.hpp"
#include "src/measure/yarn_measures.hpp"
#include "src/scene/frame_recorder.hpp"
#include "src/scene/knit_scene.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

// The knit model's integrator: cvode-bdf, which keeps a flat chart in its plane; on paper 2's
// network (a mechanism, its stiffness singular) the overdamped flow of `equilibrium` crawls along
// the zero modes (docs/knit.md, "Out-of-plane bending"). With yarn contact: equilibrium, whose
// flow steps the contact's filter cuts (cvode-bdf crawls on the barrier's stiff, lightly damped
// modes and restarts at each renewal of the contact points; implicit-euler lets an unpinned
// chart slide: docs/knit.md, "Yarn contact").
std::string default_knit_integrator(bool yarn_contact = false);

// The velocity tolerance of a knit run given none (IntegratorOptions::velocity_atol), in m/s:
// with the stabiliser on and an adaptive integrator, 1e-3 (~ atol 1e-9 m x 1e6 rad/s, above the
// network's fastest modes, omega ~ 2e5 rad/s): the stabilised steady state is unique, so the
// ringing of the stiff modes need not be followed. Paper 2's network is a mechanism whose end
// state depends on the path, so it keeps atol on the velocities; the fixed-step methods have no
// error control, and keep the value given. Steps and shape against it:
// experiments/benchmark/README.md, "Knit case".
constexpr double kStabilisedVelocityAtol = 1e-3;
void set_default_knit_velocity_atol(IntegratorOptions& options, const KnitParams& params,
                                    const IntegratorInfo& integrator);

// A run whose yarns came closer than this (in r) warns: the clearance the knit model aims at
// (docs/knit.md, "Yarn measures").
constexpr double kClearanceWarning = 0.9;

// The yarn measures of a run (src/measure/yarn_measures.hpp), in units of r.
struct KnitMeasures {
  double rest_clearance = 0.0;  // at rest (t = 0 of the chart, whatever the run started from)
  double end_clearance = 0.0;   // NaN where the end state is not finite
  YarnClearance min_clearance;  // over the measured states of the run, start and end included
  double t_min_clearance = 0.0;
  long check_min_clearance = 0;  // the residual check of the minimum (0: the start)
  int measured_states = 0;
  double measure_cpu_seconds = 0.0;  // the clearance over the run, inside stats.cpu_seconds
  double min_resolution = 0.0;  // 2 A tau: a deeper dip between measured states would be seen
  CrossingCheck crossings;      // at the end against the rest state (changed -1: not finite)
};

// The warnings of a knit run before it starts, one line each: an explicit method with yarn
// contact (it fails at the first impacts: docs/knit.md, "What is not met, and why"), and paper 2's
// bare network (a mechanism: its steady state depends on the path).
std::vector<std::string> knit_run_warnings(const KnitParams& params, const std::string& integrator,
                                           const IntegratorInfo& info);
// After it: the yarns came closer than kClearanceWarning r or a designed crossing changed its
// over/under order ("" if neither).
std::string knit_overlap_warning(const KnitMeasures& measures);

// A knit run's model and start: the chart built, and the state the run starts from.
struct YarnKnitRun;  // src/scene/yarn_knit_run.hpp
struct KnitStart {
  KnitModel model;
  double t = 0.0;            // s
  std::vector<double> x, v;  // the free dofs, m and m/s
  // knit.model = yarn: the chart's yarn (then `model` is its structure at the start's scale and
  // x, v the yarn's state); null for the network.
  std::shared_ptr<const YarnKnit> yarn;
};

// Builds the model of `scene` (build_knit: throws std::invalid_argument for bad parameters) and
// its state at rest.
KnitStart start_knit(const KnitScene& scene);
// Moves `start` to the state `from` of an earlier run of the same scene, with the contact points
// linearised afresh about it (they were made at rest). Throws std::invalid_argument ("the state
// has N unknowns; this chart has M", or that its yarns lie inside the contact's core).
void continue_knit(KnitStart& start, const RunState& from);

// Each clamp's reaction at (t, x) (src/core/held_points.hpp): the force the clamp exerts on the
// fabric, N, its points, and its displacement from rest, m.
struct ClampReaction {
  std::string name;
  int points = 0;
  Vec3 displacement;
  Vec3 reaction;
};

// One load step's end (src/scene/knit_load_steps.hpp): its load fraction, its run's statistics,
// each clamp's displacement and reaction, and the balance (models/knit_loads.hpp).
struct KnitLoadStep {
  int step = 0;       // 1..N
  double load = 0.0;  // step / N
  RunStats stats;
  std::vector<ClampReaction> clamps;
  KnitBalance balance;
};

// One knit run and what its reports show.
struct KnitResult {
  KnitModel model;
  RunStats stats;            // status, counters, residual, wall time
  double t_start = 0.0;      // s: where the run began
  std::vector<double> x, v;  // the integrated state at stats.t_final (state.json)
  std::vector<Vec3> positions;  // all points at stats.t_final, m
  std::vector<FrameRecorder::Frame> frames;  // scene.frames states, the start first
  KnitMeasures measures;
  // knit.model = yarn: what the yarn run adds (x, v are then the yarn's; positions, frames and
  // measures the interlacing points read off it); null for the network.
  std::shared_ptr<const YarnKnitRun> yarn;
  // A run under load (knit_load_stepped): each load step's end, in order; empty otherwise.
  std::vector<KnitLoadStep> load_steps;
};

// Runs `start` with the named integrator (make_integrator: throws std::invalid_argument for an
// unknown name; so does run_to_equilibrium for an option it refuses at the start), recording
// scene.frames frames and measuring the yarns' clearance over the run. `observer` (may be null)
// sees every step and residual check.
KnitResult run_knit(KnitStart start, const KnitScene& scene, const std::string& integrator,
                    RunObserver* observer = nullptr);
// start_knit, continue_knit where `from` is given, and the run.
KnitResult run_knit(const KnitScene& scene, const std::string& integrator,
                    RunObserver* observer = nullptr, const RunState* from = nullptr);

std::vector<ClampReaction> knit_clamp_reactions(const KnitModel& m, double t,
                                                const std::vector<double>& x);
// The whole chart's weight, N (zero without gravity): at an equilibrium the clamps' reactions
// sum to minus it.
Vec3 knit_weight(const KnitModel& m);

// All points at (t, x), m.
std::vector<Vec3> knit_positions(const KnitModel& m, double t, const std::vector<double>& x);
// The largest displacement from rest of `positions` (all points), in loop radii.
double max_displacement_over_r(const KnitModel& m, const std::vector<Vec3>& positions);

}  // namespace knitsim
