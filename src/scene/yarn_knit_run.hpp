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
#include "src/scene/knit_run.hpp"

namespace knitsim {

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
    RunStatus status = RunStatus::SolverFailure;
    long steps = 0;
    double residual = 0.0, cpu_seconds = 0.0, wall_seconds = 0.0;
  };
  std::vector<Stage> stages;  // the ramp's stages as run
  long pattern_misses = 0;    // summed over the stages (YarnRods::pattern_misses)
  int vertices = 0, free_vertices = 0;
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
