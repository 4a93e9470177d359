// Clamps of a knit chart (knit.clamps; docs/knit.md, "Under load"): which interlacing points a
// clamp holds, named by an edge or by wales or courses, and how it moves (fixed, or a path of
// displacements in the load fraction). The model holds them as its pins (models/knit_loops.cpp),
// so what moves and measures them sees only HeldPoints (src/core/held_points.hpp).
//
// Syntax of knit.clamps: clamps separated by ';', each
//     SELECTION [fixed | move DX,DY | path S1:DX,DY S2:DX,DY ...]
//   SELECTION  bottom | top | left | right (the chart's edges: level 0, the top level, wale 0,
//              the last wale) | wales A-B | wale A | courses A-B | course A (0-based as
//              stitches.csv; a course's points are its loops' lower and upper points, levels A to
//              B + 1)
//   fixed      (the default) held at rest
//   move DX,DY displaced by (DX, DY) m at the last load step, linearly in the load fraction
//   path ...   piecewise linear through (0, 0) and (S_k, (DX_k, DY_k)), 0 < S_1 < ... <= 1
//   force FX,FY[,FZ]  a rigid bar under the force (N at the last load step, linearly in the
//              load fraction; models/force_control.hpp): its points move together, free along
//              the non-zero components (|F| <= kMaxKnitForce each), held at rest along the others
// A point two clamps select belongs to the first. Units: m, N.
//
// Forces on points (knit.forces): separated by ';', each
//     wale W course C lower|upper FX,FY[,FZ]
// a dead load (N at the last load step) on the loop's lower point O (a knit's) or upper point U
// (where its yarn turns over the loop above: for a held loop, higher up) of chart cell (W, C);
// refused (select_knit_point_forces, models/knit_loads.hpp) for a cell out of range, a miss
// (no loop), a tuck's lower point (it has none) or a held point.
//
// Failure modes: std::invalid_argument (InvalidField of knit.clamps, one line naming the clamp
// and the accepted syntax or range) from parse_knit_clamps for bad text, and from
// select_knit_clamps for a selection the chart does not have: a wale or course out of range, an
// edge of a chart of one course, a clamp that selects no point not held already, or clamps that
// hold every point.
#pragma once

#include <string>
#include <vector>

#include "src/core/held_points.hpp"

namespace knitsim {

struct KnitClampSpec {
  enum class Where { Bottom, Top, Left, Right, Wales, Courses };
  Where where = Where::Bottom;
  int first = 0, last = 0;  // Wales, Courses: the range, inclusive
  ClampPath path;
  Vec3 force{};      // force: N at load fraction 1 (zero: displacement control)
  std::string text;  // the clamp as given, trimmed: its name in outputs and messages
};

// The largest force component a clamp or point takes, N (a knit swatch carries ~1 N).
inline constexpr double kMaxKnitForce = 1e3;

struct KnitPointForce {
  int wale = 0, course = 0;
  bool upper = false;  // the loop's upper point U, else its lower point O
  Vec3 force;          // N at load fraction 1
  std::string text;    // as given, trimmed
};

// Parses knit.clamps ("" = none); throws InvalidField of "knit.clamps".
std::vector<KnitClampSpec> parse_knit_clamps(const std::string& text);
// The clamps as text again (their `text`, joined by "; ").
std::string knit_clamps_text(const std::vector<KnitClampSpec>& clamps);
// Parses knit.forces ("" = none); throws InvalidField of "knit.forces".
std::vector<KnitPointForce> parse_knit_point_forces(const std::string& text);
std::string knit_point_forces_text(const std::vector<KnitPointForce>& forces);

}  // namespace knitsim
