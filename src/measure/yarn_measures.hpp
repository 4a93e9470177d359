// Yarn measures of a knit state (user's view: docs/knit.md, "Yarn measures"): the
// clearance between yarn centrelines and the over/under order of the designed crossings. They
// are read off a state; nothing here enters the dynamics. knitsim knit reports them
// (src/cli/cmd_knit.cpp); tests/test_yarn_measures.cpp checks the committed charts at rest.
//
// Measuring polyline: the yarn polylines of models/knit_loops.hpp (S = 8 samples per
// interpolation interval; a vertex's label names the same piece of yarn in every state).
//
// Clearance: the smallest segment-to-segment distance (continuous, src/geometry/
// segment_distance.hpp) between polyline segments of different courses, and between segments
// of one course whose separation along the yarn (the polyline's arc length from the end of the
// first to the start of the second) is at least kSameYarnGap r (pi r; why: models/knit_loops.hpp).
// Reported in units of r; pairs further apart than the search radius are not examined, so a
// clearance equal to the search radius means "at least that".
// Broad phase: a dense front-view (x, y) grid of cell size >= search radius + longest segment on
// the segments' midpoints (the fabric is a few r thick: z is not binned), pairs tested in the 9
// neighbouring cells after a bounding-box test. Cost O(segments); figures for the 40 x 40
// tucks40 chart in docs/knit.md, "Yarn measures".
//
// Designed crossings: at rest (the start), every pair of segments whose front-view projections
// (x, y) cross, between different courses or non-adjacent pieces of one course as above. Each
// carries its over/under order: sigma = +1 if the first piece is in front (larger z) where the
// two cross in the front view, -1 if behind (the depths at the crossing point, linear along
// each segment; at rest they differ by at least the clearance). The check at a later state
// takes the order where the same two pieces cross in the front view, at the segment pair
// nearest the rest one (rings of growing index distance, at most two intervals, 2 S segments,
// along each yarn), or, where their projections no longer cross within that reach, where they
// come closest in the front view; a crossing whose order differs from the rest state's has
// changed. The front view is the chart's plane: the order is invariant under rigid motions in
// the plane, not under tilts large enough to uncross the pieces' projections. (A 3D invariant such
// as the sign of (a - b) . (t_a x t_b) at the pieces' closest points turns where the pieces lie
// near parallel without passing through each other: measured on several_tucks, pieces 3 r apart in
// depth.)
//
// Failure modes: positions of the wrong length throw std::invalid_argument (as the model's
// geometry functions); a non-finite state gives a non-finite clearance (NaN compares false:
// callers test std::isfinite).
#pragma once

#include <limits>
#include <vector>

#include "models/knit_loops.hpp"
#include "solvers/integrator.hpp"
#include "src/core/vec3.hpp"

namespace knitsim {

struct YarnSegment {
  int course = -1;
  int segment = -1;
};

struct YarnClearance {
  double over_r = std::numeric_limits<double>::infinity();  // smallest distance / r
  YarnSegment a, b;  // the closest pair (a.course <= b.course); course -1 if none was examined
  Vec3 where;        // midpoint of the closest points, m
};

// search_radius_over_r: pairs further apart are not examined (then over_r = the radius).
// hint (optional): a pair (e.g. the closest of a nearby state) whose distance in `lines`, if
// the pair is counted, bounds the search radius; the result is the same, found faster.
YarnClearance yarn_clearance(const KnitModel& m, const YarnPolylines& lines,
                             double search_radius_over_r = 2.0,
                             const YarnClearance* hint = nullptr);

struct YarnCrossing {
  YarnSegment a, b;
  int sign = 0;  // sigma at rest, +1 or -1
};

// The designed crossings of the rest state `rest` (see above).
std::vector<YarnCrossing> designed_crossings(const KnitModel& m, const YarnPolylines& rest);

struct CrossingCheck {
  int designed = 0;
  int changed = 0;
  std::vector<int> changed_index;  // into the crossings, ascending
};

CrossingCheck check_crossings(const std::vector<YarnCrossing>& crossings,
                              const YarnPolylines& lines);

// The clearance over a run (its minimum over the whole run, not only at the end): a
// RunObserver that measures the first state it sees, every state given to observe(..., true)
// (the end of the run) and every residual check at which some interlacing point has moved by at
// least tau r (tau = resample_over_r) since the last measured state.
// What that guarantees, over the states the observer is given (every residual check; for
// cvode-bdf and implicit-euler every step):
//   - The clearance of the polylines is 2-Lipschitz in their vertices: every point of a segment
//     is a convex combination of its two vertices, so if no vertex moved by more than D, no
//     segment-to-segment distance changed by more than 2 D.
//   - A checked state that was not measured has its interlacing points within tau r of the last
//     measured state's, and its vertices within A tau r, A the amplification of the map from
//     interlacing points to polyline vertices (frames, type-value points, the interpolating
//     cubic). So its clearance is above (last measured clearance) - 2 A tau r >= (reported
//     minimum) - 2 A tau r: a dip between measured states shallower than 2 A tau r can be missed,
//     no deeper one.
//   - A is not bounded a priori (the frames' unit vectors and the centripetal parameters are
//     nonlinear); it is measured: at each measured state the ratio of the vertices' largest
//     displacement to the interlacing points' since the previous measured state, the largest
//     ratio over the run as amplification(). Small (~1-2) where the yarns stay apart, large
//     where they pass through each other and the frames swing (no guarantee there; figures per
//     chart in docs/knit.md, "Yarn measures"). That A stands for the unmeasured states too
//     assumes the map is smooth on the scale tau r.
// The states between residual checks (Verlet and the other explicit integrators check every
// 1000 steps) are not seen. Forwards every RunObserver call to `next` (may be nullptr).
class ClearanceOverRun final : public RunObserver {
 public:
  ClearanceOverRun(const KnitModel& m, RunObserver* next, double resample_over_r = 0.05);
  void observe(double t, const double* x, bool force);  // x: free dofs, as integrators hold them
  void on_run_start() override {
    if (next_) next_->on_run_start();
  }
  void on_step(double t, double h, int order) override;
  void on_check(double t, const double* x, const double* v, double residual) override;
  const YarnClearance& minimum() const { return min_; }
  double t_of_minimum() const { return t_min_; }
  // The residual check of the minimum (0: the start): where t stands still (the equilibrium
  // solver's flow) the only place of it.
  long check_of_minimum() const { return check_min_; }
  int measured_states() const { return measured_; }
  double amplification() const { return amplification_; }  // A, see above; 0 before 2 states
  // 2 A tau: a dip below minimum() deeper than this would have been measured (see above), in r.
  double resolution_over_r() const { return 2.0 * amplification_ * tau_; }
  // CPU seconds spent measuring (std::clock, the clock of RunStats::cpu_seconds, which includes
  // them when the run calls this observer): what to subtract for the integrator's own cost.
  double cpu_seconds() const { return cpu_seconds_; }

 private:
  const KnitModel& m_;
  RunObserver* next_;
  double tau_;  // 1
  std::vector<Vec3> last_, pos_;
  YarnPolylines last_lines_;
  YarnClearance last_clearance_;
  YarnClearance min_;
  double t_min_ = 0.0;
  long checks_ = 0, check_min_ = 0;
  double amplification_ = 0.0;
  int measured_ = 0;
  double cpu_seconds_ = 0.0;
};

}  // namespace knitsim
