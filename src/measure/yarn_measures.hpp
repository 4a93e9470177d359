// Yarn measures of a knit state (SPEC 2.9, issue 31 item 3): the clearance between yarn
// centrelines and the over/under order of the designed crossings. They are read off a state;
// nothing here enters the dynamics.
//
// Measuring polyline. Each course's centreline (the C^2 cubic NURBS through its yarn points,
// models/knit_loops.hpp) is sampled at S points per interpolation interval, uniformly in the
// curve parameter between the interval's ends ubar_k, ubar_k+1 (the curve passes through yarn
// point k at ubar_k): vertex k S + m is at ubar_k + (m / S)(ubar_k+1 - ubar_k). The label of a
// vertex (course, k S + m) therefore names the same piece of yarn in every state, which is what
// the crossing check needs; the chord-length parameter is close to arc length, so the pieces
// are near-uniform in length. With S = 8 the polyline lies within ~0.035 r of the curve (the
// same sampling density as centerlines.csv).
//
// Clearance: the smallest segment-to-segment distance (continuous, src/geometry/
// segment_distance.hpp) between polyline segments of different courses, and between segments
// of one course whose separation along the yarn (the polyline's arc length from the end of the
// first to the start of the second) is at least kSameYarnGap r. Why pi r: a yarn of diameter
// d = r bent round a circle of radius d/2 comes back to within d of itself only after an arc of
// pi d/2; pi r = pi d is twice that, so neighbouring pieces of one bend are never counted while
// a loop's two legs (~20 r apart along the yarn) and a float and the loops it passes are.
// Reported in units of r; pairs further apart than the search radius are not examined, so a
// clearance equal to the search radius means "at least that".
// Broad phase: a uniform grid of cell size (search radius + longest segment) on the segments'
// midpoints; pairs are tested in the 27 neighbouring cells. Cost O(segments): ~0.1 s for the
// 40 x 40 tucks40 chart (~100k segments).
//
// Designed crossings: at rest (the start), every pair of segments whose front-view projections
// (x, y) cross, between different courses or non-adjacent pieces of one course as above. Each
// carries the sign of the triple product
//     sigma = sign( (a - b) . (t_a x t_b) )
// with a, b the closest points of the two segments and t_a, t_b their directions (vertex k to
// k + 1). sigma says which yarn passes over the other and with which orientation; it is
// invariant under rigid motions and changes only if the two pieces pass through each other
// (a - b -> 0) or turn parallel. The check at a later state: for each designed crossing the
// closest pair of segments within +-S segments (one interval) of each rest segment, and its
// sigma; a crossing whose sigma differs from the rest state's has changed (the yarns swapped
// over and under there).
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

constexpr double kSameYarnGap = 3.14159265358979323846;  // in r, see above
constexpr int kYarnSamplesPerInterval = 8;               // S

struct YarnPolylines {
  int samples_per_interval = kYarnSamplesPerInterval;
  std::vector<std::vector<Vec3>> vertices;  // per course (bottom first): segment k = k to k+1
  std::vector<std::vector<double>> arc;     // per course: arc length at each vertex, m
};

YarnPolylines yarn_polylines(const KnitModel& m, const std::vector<Vec3>& positions,
                             int samples_per_interval = kYarnSamplesPerInterval);

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
YarnClearance yarn_clearance(const KnitModel& m, const YarnPolylines& lines,
                             double search_radius_over_r = 2.0);

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

// The clearance over a run (issue 31: its minimum over the whole run, not only at the end):
// a RunObserver that measures the state at a residual check when some interlacing point has
// moved since the last measured state by at least max(resample_over_r r, resample_fraction c),
// c the last measured clearance (dense sampling where yarns are close, sparse where they are
// far apart: a clearance c cannot close unless the yarn moves by ~c/2), and always the first state
// it sees and a state given to observe(..., true) (the end of the run). A heuristic, not a bound:
// between two measured states the clearance could dip by a few times the interlacing points'
// motion (the type-value points and the NURBS amplify it). Forwards every
// RunObserver call to `next` (may be nullptr).
class ClearanceOverRun final : public RunObserver {
 public:
  ClearanceOverRun(const KnitModel& m, RunObserver* next, double resample_over_r = 0.05,
                   double resample_fraction = 0.25);
  void observe(double t, const double* x, bool force);  // x: free dofs, as integrators hold them
  void on_step(double t, double h, int order) override;
  void on_check(double t, const double* x, const double* v, double residual) override;
  const YarnClearance& minimum() const { return min_; }
  double t_of_minimum() const { return t_min_; }
  int measured_states() const { return measured_; }

 private:
  const KnitModel& m_;
  RunObserver* next_;
  double resample_;  // m
  double fraction_;
  double last_clearance_ = 0.0;  // m
  std::vector<Vec3> last_, pos_;
  YarnClearance min_;
  double t_min_ = 0.0;
  int measured_ = 0;
};

}  // namespace knitsim
