#include "src/geometry/segment_distance.hpp"

#include <algorithm>

namespace knitsim {

namespace {
double clamp01(double v) { return std::min(1.0, std::max(0.0, v)); }
}  // namespace

SegmentClosest closest_points(Vec3 a0, Vec3 a1, Vec3 b0, Vec3 b1) {
  const Vec3 d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
  // Relative to the segments' own scale: a segment shorter than this is a point.
  const double tiny = 1e-30 + 1e-28 * (a + e);
  double s = 0.0, t = 0.0;
  if (a <= tiny && e <= tiny) {
    s = t = 0.0;
  } else if (a <= tiny) {
    t = clamp01(f / e);
  } else {
    const double c = dot(d1, r);
    if (e <= tiny) {
      s = clamp01(-c / a);
    } else {
      const double b = dot(d1, d2), denom = a * e - b * b;  // >= 0
      s = denom > 1e-14 * a * e ? clamp01((b * f - c * e) / denom) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = clamp01(-c / a);
      } else if (t > 1.0) {
        t = 1.0;
        s = clamp01((b - c) / a);
      }
    }
  }
  SegmentClosest out;
  out.s = s;
  out.t = t;
  out.a = a0 + s * d1;
  out.b = b0 + t * d2;
  out.distance = norm(out.a - out.b);
  return out;
}

}  // namespace knitsim
