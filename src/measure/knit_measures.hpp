// Textile measures of a knitted state (user's view and the definitions' sources: docs/knit.md,
// "Textile measures"): per chart cell its loop's centre, height, width and yarn length, the
// lengths of held loops, tucks and floats and a float's depth behind the face; per fabric the
// courses and wales per cm, the relative width and length change and the stitch length.
// Read off a state; nothing here enters the dynamics.
//
// Input (KnitYarns): what a yarn-level description of any model gives, so that another model
// than the interlacing-point network reuses the measures unchanged:
//   - per course (bottom first), the yarn centreline as a polyline with its arc length at each
//     vertex (YarnPolylines; only vertices and arc are read);
//   - per chart cell (course * wales + wale), arc-length marks along its course's yarn
//     (StitchMarks): the cell's yarn [begin, end] and its loop [loop_begin, loop_end].
// The cells' yarns partition the course: a cell runs from the middle of the sinker loop on its
// left to the middle of the one on its right (T0 to T8 of models/knit_loops.hpp), so its
// length is the yarn the needle takes in one course, the stitch length l of the knitting
// literature (one needle loop and one sinker loop). A knit's loop is the needle loop with its
// legs, from foot to foot (T1 to T7); a tuck has no feet, and its loop is its whole cell, the
// open arc from sinker to sinker; a miss has no loop (NaN marks).
// The network supplies the marks from its type-value points (knit_stitch_points: the yarn
// points of T0, T1, T7, T8 of every loop and of the sinkers around a float); its yarn polylines
// pass through yarn point k at vertex k S exactly, so a mark is the arc length at that vertex.
//
// Definitions (lengths in m; "the loop's arc" is the polyline between loop_begin and loop_end,
// cut at the marks by linear interpolation along the segment):
//   centre        the arc-length weighted centroid of the loop's arc (the mean point of the
//                 yarn along it); NaN for a miss.
//   loop_height   the extent of the loop's arc along y (the wale direction of the chart as
//                 drawn): max y - min y over the arc. Plain jersey at rest: 8 r (feet at the
//                 course's base, the head r above the upper interlacing point).
//   loop_width    its extent along x (the course direction): max x - min x.
//   yarn_length   the cell's yarn, end - begin: a knit's stitch length (a held loop's, longer,
//                 is its own length), a tuck's loop length, a miss's piece of float.
//   float_length  (misses) the whole float the cell is part of: from begin of the first to end
//                 of the last of the run of consecutive misses in its course.
//   float_depth   (misses) how far the float passes behind the face: z_face - min z over the
//                 cell's yarn, with z_face the z of the feet of the nearest knit loops of its
//                 course either side (the left one's right foot, the right one's left foot),
//                 interpolated linearly in wale. Plain geometry at rest: ~r.
//   held_over     courses above the cell on its needle that tuck or miss before the next knit
//                 (a held loop is held over held_over courses; a tuck's loop is held too);
//                 0 for a miss (no loop).
// Fabric (over the interior: cells at least two from every edge, 2 <= wale <= W - 3 and
// 2 <= course <= C - 3, and among them the plain knit loops, K with held_over = 0):
//   wale spacing  per interior course, the distance between the centres of its first and last
//                 plain knit loop divided by the wales between them, pooled over the courses
//                 (sum of distances / sum of wale counts); wales_per_cm = 0.01 m / spacing.
//   course spacing  the same per interior wale along the courses; courses_per_cm.
//   width_change, length_change  the end spacing over the rest spacing, minus 1, on the same
//                 loops (relative: -0.1 = 10 % narrower, shorter).
//   stitch_length the mean yarn_length over all interior cells (K, T, M): the yarn a needle
//                 takes per course, l for plain jersey; also at rest.
// A chart too small for the interior (fewer than 6 wales or 6 courses: no two interior wales or
// courses) or with no two plain knit loops in one interior course (wale) gives NaN for the
// spacing it lacks and everything derived from it (summary.json: null); fewer than 5 wales or
// courses leaves no interior cell, and stitch_length is NaN too.
//
// Failure modes: inconsistent input (sizes, marks outside their course's arc or out of order)
// throws std::invalid_argument naming the cell; non-finite positions give non-finite measures.
#pragma once

#include <limits>
#include <vector>

#include "models/knit_loops.hpp"
#include "src/core/vec3.hpp"

namespace knitsim {

constexpr double kNoMark = std::numeric_limits<double>::quiet_NaN();

// Where a chart cell's stitch lies along its course's yarn: arc lengths from the course's
// start, m (see the header).
struct StitchMarks {
  double begin = kNoMark, end = kNoMark;            // the cell's yarn, sinker to sinker
  double loop_begin = kNoMark, loop_end = kNoMark;  // its loop; NaN for a miss
};

// A knitted state as the measures see it (see the header).
struct KnitYarns {
  KnitChart chart;
  YarnPolylines lines;             // per course: vertices and their arc length
  std::vector<StitchMarks> marks;  // course * wales + wale
};

// The network's marks: per cell the yarn-point indices (into course_yarn_points' course) of
// its begin, loop_begin, loop_end and end (-1 where there is none: a miss's loop), from the
// model's type-value points. State-independent.
struct StitchPoints {
  int begin = -1, loop_begin = -1, loop_end = -1, end = -1;
};
std::vector<StitchPoints> knit_stitch_points(const KnitModel& m);

// Marks from yarn-point indices, for polylines that pass through yarn point k at vertex
// k * lines.samples_per_interval (yarn_polylines). Throws std::invalid_argument if an index is
// past its course's polyline.
KnitYarns knit_yarns(const KnitChart& chart, YarnPolylines lines,
                     const std::vector<StitchPoints>& points);

// Samples per interpolation interval of the measuring polylines: 32 keeps a loop's polyline
// length within ~5e-5 of its curve's (the chord deficit ~ (kappa ds)^2 / 24 per piece; at the
// tightest bend, the head, kappa ~ 1 / 3r and ds ~ 0.1 r).
constexpr int kStitchSamplesPerInterval = 32;
// The network's state at positions (all points) as KnitYarns.
KnitYarns knit_yarns(const KnitModel& m, const std::vector<Vec3>& positions,
                     int samples_per_interval = kStitchSamplesPerInterval);

struct StitchMeasure {
  int wale = 0, course = 0;
  Stitch stitch = Stitch::Knit;
  int held_over = 0;
  Vec3 centre, centre_rest;  // NaN for a miss
  double loop_height = kNoMark, loop_height_rest = kNoMark;
  double loop_width = kNoMark, loop_width_rest = kNoMark;
  double yarn_length = kNoMark, yarn_length_rest = kNoMark;
  double float_length = kNoMark, float_length_rest = kNoMark;  // misses only
  double float_depth = kNoMark, float_depth_rest = kNoMark;    // misses only
};

struct FabricMeasure {
  double courses_per_cm = kNoMark, wales_per_cm = kNoMark;  // at the end
  double courses_per_cm_rest = kNoMark, wales_per_cm_rest = kNoMark;
  double width_change = kNoMark, length_change = kNoMark;        // relative, end against rest
  double stitch_length = kNoMark, stitch_length_rest = kNoMark;  // m
  int interior_cells = 0;  // cells at least two from every edge
  int wale_steps = 0;      // sum over interior courses of the wales between first and last
  int course_steps = 0;    // likewise over interior wales
};

struct TextileMeasures {
  std::vector<StitchMeasure> stitches;  // course * wales + wale
  FabricMeasure fabric;
};

// Both states must have the same chart. Throws std::invalid_argument on inconsistent input.
TextileMeasures textile_measures(const KnitYarns& now, const KnitYarns& rest);
// The network's state at positions (all points) against its rest (the chart's start).
TextileMeasures textile_measures(const KnitModel& m, const std::vector<Vec3>& positions);

}  // namespace knitsim
