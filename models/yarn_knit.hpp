// YarnKnit: a stitch chart as one yarn of discrete elastic rods (models/yarn_rods.hpp), made in
// one step from paper 2's structure model (models/knit_loops.hpp: its interlacing points, loops
// and NURBS centrelines) -- the front end of the yarn-level knit model (knit.model = yarn;
// docs/yarn_model.md, "From a chart to yarns", has the construction and its sources).
//
// The construction (physics only, SI units):
//   1. paper 2's structure is built for the chart at a loop radius r (no springs are used: only
//      its points, loops and per-course NURBS centrelines at rest);
//   2. each course's centreline is sampled uniformly in arc length, vertices_per_loop edges per
//      chart cell; course j runs left to right for even j and right to left for odd j, and the
//      courses are joined at the selvedges by half-ellipses bulging 2 r outwards, so the chart is
//      one continuous yarn as knitted;
//   3. r is chosen so that the start is intersection-free at the yarn diameter d: the least
//      segment distance over the pairs the contact sees (YarnRods::min_clearance) is at least
//      kYarnStartClearance d (iterated, since the same-yarn exclusion window is 2 d of arc);
//   4. the rest lengths are then ramped from the start's own to the knitted stitch length
//      (knit.stitch_length, per chart cell; Kaldor et al. 2008 shrink the rest lengths of their
//      loose start the same way) in `ramp_stages` equal steps, each relaxed to its steady state.
// Held: the yarn's first vertex (the start of the first course) and last vertex, and the head
// arc (T3..T5) of every loop of the first course (the cast-on, held) and of the last course (the
// loops still on the needles): a frictionless yarn unravels from a free end or a free first or last course.
//
// Failure modes: bad parameters throw std::invalid_argument naming the key and its range
// (YarnKnitParams::validate); a chart the structure model refuses throws its message; a start
// that cannot be made intersection-free throws std::invalid_argument saying so.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "models/knit_loops.hpp"
#include "models/yarn_rods.hpp"
#include "src/core/vec3.hpp"
#include "src/geometry/nurbs.hpp"

namespace knitsim {

// knit.model: the interlacing-point network (paper 2's and the stabilised one) or yarns.
enum class KnitModelKind { Network, Yarn };
const char* to_string(KnitModelKind kind);

// The start's clearance, in d: the scale puts the closest pair the contact sees between this and
// kYarnStartClearanceMax d.
constexpr double kYarnStartClearance = 1.02;
constexpr double kYarnStartClearanceMax = 1.10;

// Edge pairs this close (in d) when the rods are made get Jacobian blocks (YarnParams::
// pattern_radius); the run makes the rods afresh every few steps so the pattern follows the yarn.
constexpr double kYarnPatternRadius = 2.0;

struct YarnKnitParams {
  KnitModelKind model = KnitModelKind::Network;  // knit.model
  YarnParams yarn;                               // yarn.* keys (models/yarn_rods.hpp)
  // The yarn knitted into one cell, sinker to sinker, m; 0 = the start's own (no ramp). 0 by
  // default this session: a ramp to a tighter stitch jams against the held edge courses
  // (docs/yarn_model.md, "What is not met"); 3.4e-3 is the default yarn at tightness 1.47.
  double stitch_length = 0.0;  // knit.stitch_length, [0, 0.1]
  double tuck_length = 0.0;       // knit.tuck_length, m, [0, 0.1]; 0 = the knit's ratio
  double miss_length = 0.0;       // knit.miss_length, m, [0, 0.1]; 0 = the knit's ratio
  double vertices_per_loop = 16;  // knit.yarn_vertices: edges per chart cell, whole, [4, 256]
  double ramp_stages = 4;         // knit.yarn_ramp: relaxed steps of the ramp, whole, [1, 100]
  // knit.boundary: the chart as a swatch with held edge courses, or as one repeat of a fabric
  // without edges (a periodic cell whose size is free: models/yarn_cell.hpp).
  bool periodic = false;
  // knit.cell_pull, knit.cell_strain (knit.boundary = periodic): after relaxing, the cell pulled
  // along the courses (x, W held) or the wales (y, H held) to this strain in steps of 0.01, the
  // other length free: 0 none, 1 courses, 2 wales.
  int cell_pull = 0;
  double cell_strain = 0.1;  // [0.01, 1]

  // Throws InvalidField naming the key (yarn.tex, knit.stitch_length, ...) and its range.
  void validate() const;
};

// Per chart cell, where its yarn lies: fractional vertex indices along its course (vertex 0 at
// the course's left end, whatever the knitting direction), NaN where the cell has none.
struct YarnCellMarks {
  double begin = 0.0, end = 0.0, loop_begin = 0.0, loop_end = 0.0;
};

struct YarnKnit {
  explicit YarnKnit(KnitModel s) : structure(std::move(s)) {}
  KnitModel structure;  // paper 2's structure at the start's scale (points, loops, curves)
  YarnKnitParams params;
  double r = 0.0;  // the start's loop radius, m
  double d = 0.0;  // yarn diameter, m
  // The one yarn's vertices at the start, in knitting order.
  std::vector<Vec3> start;
  std::vector<double> start_length, target_length;  // per edge, m
  // Per course, its vertices from the left end to the right end, as indices into `start`.
  std::vector<std::vector<int>> course_vertices;
  std::vector<YarnCellMarks> marks;  // course * wales + wale
  // Per loop (structure.loops), the fractional vertex indices of its T1, T7, T3, T5 along its
  // course (NaN where the loop has none: a tuck's feet).
  std::vector<std::array<double, 4>> loop_points;
  std::vector<int> pins;             // vertex indices held where they start
  // The held vertices as the ramp moves them: each head arc (T3..T5 of a loop of the first or
  // last course) and each yarn end is one group, moved as a rigid body (a needle keeps the loop
  // it holds at its size); a group's edges keep their start lengths.
  std::vector<std::vector<int>> held_groups;
  Vec3 centre{0.0, 0.0, 0.0};  // the start's centroid (every vertex), m: the ramp scales to it
  // The knit cells' knitted over start yarn length (1: no ramp; the fabric's scale at the ramp's
  // end).
  double knit_ratio = 1.0;
  double start_clearance = 0.0;      // m, YarnRods::min_clearance at the start

  // The rods at the ramp's fraction f in [0, 1] (0: the start's rest lengths; 1: the target's),
  // started at `initial` (empty: the start); pinned vertices are held where `initial` has them.
  YarnRodsSpec spec_at(double f, const std::vector<Vec3>& initial = {}) const;
  // The same at ramp stage s of n (f = s / n).
  YarnRodsSpec spec(int s, int n, const std::vector<Vec3>& initial = {}) const {
    return spec_at(n > 0 ? static_cast<double>(s) / n : 1.0, initial);
  }
  int ramp_stages() const { return static_cast<int>(params.ramp_stages); }
  // The fabric's scale at ramp fraction f: 1 + f (knit_ratio - 1).
  double ramp_scale(double f) const { return 1.0 + f * (knit_ratio - 1.0); }
  // `pos` (every vertex, at ramp scale `from`) carried to scale `to`: the free vertices scaled
  // about `centre` by to / from, each held group translated so its centroid sits at
  // centre + to (its start centroid - centre), its shape as at the start. The stage's needles
  // close up with the fabric, so the held edge courses do not keep the loose start's extent.
  std::vector<Vec3> carried(const std::vector<Vec3>& pos, double from, double to) const;
  // Each course's polyline (left to right) at the given positions of every vertex.
  std::vector<std::vector<Vec3>> course_polylines(const std::vector<Vec3>& all) const;
  // A course's yarn length at the given positions (its own vertices, without the turns), m.
  double course_length(int course, const std::vector<Vec3>& all) const;
  // The structure's interlacing points read off the yarn at `all`: each point the mean of the
  // loops' feet (T1 + T7)/2 where it is a loop's lower point and heads (T3 + T5)/2 where it is
  // an upper point, taken at the yarn's material points that were there at the start; a point
  // with neither keeps its rest position plus the mean displacement of the others.
  std::vector<Vec3> interlacing_points(const std::vector<Vec3>& all) const;
};

// `structure_params` gives the network's keys the structure needs (pins and network kind are
// ignored; its loop radius is replaced by the start's scale).
YarnKnit build_yarn_knit(const KnitChart& chart, const KnitParams& structure_params,
                         const YarnKnitParams& params);

}  // namespace knitsim
