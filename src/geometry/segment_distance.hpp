// Closest points of two line segments in 3-D (the yarn clearance, src/measure/yarn_measures.hpp).
//
// Segments A(s) = a0 + s (a1 - a0) and B(t) = b0 + t (b1 - b0), s, t in [0, 1]. The squared
// distance |A(s) - B(t)|^2 is a convex quadratic on the unit square; its minimiser is found by
// the clamped normal equations (Ericson, Real-Time Collision Detection (2005) Sec. 5.1.9):
// the unconstrained s for the infinite lines, clamped to [0, 1], t from it, clamped, and s
// recomputed from the clamped t. Parallel (or degenerate, zero-length) segments take s = 0
// on the ambiguous side; the distance is then still the minimum, only the witnesses are one of
// several. Exact to round-off; never throws; non-finite input gives non-finite output.
#pragma once

#include "src/core/vec3.hpp"

namespace knitsim {

struct SegmentClosest {
  double s = 0.0, t = 0.0;  // parameters of the closest points on A and B, in [0, 1]
  Vec3 a, b;                // the closest points A(s), B(t)
  double distance = 0.0;    // |a - b|
};

SegmentClosest closest_points(Vec3 a0, Vec3 a1, Vec3 b0, Vec3 b1);

}  // namespace knitsim
