// A knit run with knit.model = yarn (models/yarn_knit.hpp; docs/yarn_model.md): the chart made
// into one yarn of discrete elastic rods, its rest lengths ramped to the knitted stitch length in
// relaxed stages, each run to its steady state by the run's integrator; paper 2's interlacing
// points, the textile measures and the yarn's own measures read off the relaxed yarn. Reached
// through start_knit / run_knit (src/scene/knit_run.hpp), which call these for knit.model = yarn.
//
// Failure modes: bad input throws std::invalid_argument (one line); a stage that does not reach
// its steady state ends the run with that stage's status (the later stages are not run).
#pragma once

#include <string>
#include <vector>

#include "models/yarn_knit.hpp"
#include "solvers/integrator.hpp"
#include "src/geometry/nurbs.hpp"
#include "src/measure/knit_measures.hpp"
#include "src/measure/yarn_measures.hpp"
#include "src/scene/knit_run.hpp"

namespace knitsim {

// Whether a yarn kept its knitted structure (docs/yarn_model.md, "The structure check"):
//   - designed crossings: the network's check (src/measure/yarn_measures.hpp, check_crossings) on
//     the yarn's own course polylines, against those of the start; a changed over/under order
//     means a yarn passed through another or round its end;
//   - interlocks: at every interlacing point where a loop's head holds the loop above, the
//     closest approach of the head arc (T3..T5) to that loop (loop begin to loop end), both
//     stretches widened by a quarter cell each side (the yarn slides through the loops), segment
//     to segment; interlocked they touch (~1 d), a loop withdrawn from the head leaves it by more
//     than kYarnWithdrawn d (a frictionless yarn may withdraw without any crossing, so the
//     crossings alone miss it).
constexpr double kYarnWithdrawn = 2.5;
struct YarnStructure {
  CrossingCheck crossings;  // changed -1: the state is not finite
  int interlocks = 0;       // head-holds-feet points checked
  int withdrawn = 0;        // of those, the held loop further than kYarnWithdrawn d from the head
  double interlock_gap_max_over_d = 0.0;  // the largest head-to-held-loop distance, in d
  bool lost() const { return crossings.changed != 0 || withdrawn > 0; }
};
// The start's designed crossings of y's yarn (its course polylines at y.start).
std::vector<YarnCrossing> yarn_designed_crossings(const YarnKnit& y);
// y's structure at `all` (every vertex) against the start's `designed` crossings.
YarnStructure check_yarn_structure(const YarnKnit& y, const std::vector<YarnCrossing>& designed,
                                   const std::vector<Vec3>& all);
// "" if the structure held, else one line saying what was lost.
std::string yarn_structure_message(const YarnStructure& s);
// A run whose structure was lost says so: an equilibrium with loops withdrawn (or a state not
// finite) becomes outside_model_limits with the message; any other status, and an equilibrium
// whose crossings alone changed, keeps its name and gains the message.
void report_yarn_structure(const YarnStructure& s, RunStats& stats);

// What a yarn run adds to its KnitResult.
struct YarnKnitRun {
  std::shared_ptr<const YarnKnit> knit;
  std::vector<Vec3> end;  // every yarn vertex at the end, m
  // Least segment distance over the pairs the contact sees, in d: at the start, at the end and
  // over the run (at every residual check of every stage).
  double clearance_start_over_d = 0.0, clearance_end_over_d = 0.0, clearance_min_over_d = 0.0;
  int clearance_checks = 0;  // states measured
  // Per course: its yarn length knitted (the ramp's target), at the start and at the end, m.
  std::vector<double> course_knitted, course_start, course_end;
  struct Stage {
    double fraction = 1.0;  // the ramp's fraction this stage relaxed (its rest lengths)
    RunStatus status = RunStatus::SolverFailure;
    long steps = 0;
    double residual = 0.0, cpu_seconds = 0.0, wall_seconds = 0.0;
  };
  std::vector<Stage> stages;  // the ramp's stages as run
  long pattern_misses = 0;    // summed over the stages (YarnRods::pattern_misses)
  int carries_refused = 0;    // stages started uncarried: every halved carry too near the core
  int vertices = 0, free_vertices = 0;
  YarnStructure structure_start, structure_end;  // the check at the start and at the end
  // Verlet's stable step at the end state (docs/yarn_model.md, "Verlet"): the axial mode's
  // 2 / omega_max = l_min / c (c = sqrt(EA / rho_l), l_min the shortest rest edge), and
  // estimate_stable_dt / predict_stable_dt("verlet", ...) over the whole stiffness (stretching,
  // bending and the barrier at the clearance reached); its cost to the steady state at the
  // estimated step: t_final / dt steps (where the run advanced t), each one force evaluation.
  struct Verlet {
    double dt_axial = 0.0, dt_estimated = 0.0, dt_predicted = 0.0;  // s
    double force_cpu_seconds = 0.0;  // one conservative_acceleration, CPU s
    double steps_to_steady = 0.0;    // NaN where the run did not advance t
  } verlet;
  TextileMeasures textile;                // from the yarn itself, the start as the rest
  std::vector<CurveSamples> centerlines;  // per course, the yarn's polyline at the end
};

// The yarn of scene's chart (build_yarn_knit) and its start.
KnitStart start_yarn_knit(const KnitScene& scene);
// The ramp and the relaxation (start.yarn must be set).
KnitResult run_yarn_knit(KnitStart start, const KnitScene& scene, const std::string& integrator,
                         RunObserver* observer);

// A yarn's courses as the textile measures read them: its polylines at `all` (every vertex) with
// each cell's marks at its material points.
KnitYarns yarn_knit_yarns(const YarnKnit& y, const std::vector<Vec3>& all);

}  // namespace knitsim
