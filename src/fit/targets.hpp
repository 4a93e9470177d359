// Drape targets: the "measured" edges the simulation is compared with (docs/fitting.md; paper 1
// Eq. 5). Per scene (four_corner | two_corner | two_corner_slack) and edge (top | bottom |
// left | right), a target gives ONE of
//   * normalised points (s, d)        -> fitted with the 4th-order polynomial,
//   * the 5 coefficients p0..p4        -> used as given,
//   * lab points in mm in the camera plane, with the pins -> normalised by the rules
//     of src/measure/measurement.hpp (the same functions as the simulation), then fitted.
//
// CSV format (one format for reading and writing; UTF-8/ASCII, comma-separated, no quoting):
//   Lines starting with '#' and blank lines are ignored anywhere (use them for provenance).
//   The first other line is the header, exactly:  scene,edge,kind,a,b
//   Each row has exactly 5 fields (surrounding spaces and a trailing CR are ignored):
//     kind       meaning of a, b                                 edge field
//     point      a = s, b = d (dimensionless)                   top|bottom|left|right
//     coeff      a = power i (integer 0..4), b = p_i            top|bottom|left|right
//     lab_point  a = x_mm, b = z_mm (camera plane)              top|bottom|left|right
//     pin        a = x_mm, b = z_mm (camera plane)              four_corner: the edge;
//                                                               two_corner*: empty
//   Example:
//     scene,edge,kind,a,b
//     four_corner,top,coeff,0,0.0012
//     ...
//     two_corner,,pin,0,0
//     two_corner,,pin,500,0
//     two_corner,left,lab_point,3.1,-52.0
//   Camera plane: x horizontal (to the right in the photo), z vertical (UP: a point below the
//   pins has a smaller z; negate image-row coordinates, which grow downward; `knitsim fit`
//   warns when every edge hangs above its pins). A worked lab file: docs/examples/
//   lab_targets.csv; the user's page: docs/fitting.md. Millimetres by
//   convention; any common unit works since the normalisation divides by a pin distance.
//   * four_corner lab data: each edge is its own photo, taken from outside the sheet
//     perpendicular to that edge, so its points lie in that edge's vertical plane. The edge's
//     two pin rows are its corners, in order: the first is A (s = 0), the second B (s = 1).
//     The model's A is the edge's first particle: (0,0) for top and left, (n,0) for bottom,
//     (0,n) for right (src/measure/measurement.hpp). List the corners as lab_point rows too if they
//     should enter the fit as the simulated edges' corners do.
//   * two_corner / two_corner_slack lab data: one front photo per scene: two scene-level pin
//     rows (empty edge field), in order pin1 then pin2 (the model's (0,0) then (0,n)); the left
//     edge hangs from pin1, the right from pin2.
// Validation (read_target_csv): a line with an unknown scene, edge or kind, a wrong field count,
// a non-numeric or non-finite number, a power that is not an integer 0..4 or repeats, a second
// kind of data for one edge, a misplaced or third pin; per edge, fewer than 5 points (or 5
// distinct abscissae), missing coefficients, lab points without both pins or pins without lab
// points, coinciding pins -> std::invalid_argument with one line "FILE:LINE: field ... : why".
// Target::validate() makes the same per-edge checks on targets built in code.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "src/measure/measurement.hpp"

namespace knitsim {

enum class TargetKind { Points, Coefficients, LabPoints };

// A point in a lab photo's camera plane (x to the right, z up), mm.
struct CameraPoint {
  double x_mm = 0.0, z_mm = 0.0;
};

struct TargetEdge {
  std::string name;  // top | bottom | left | right
  TargetKind kind = TargetKind::Points;
  EdgePoints points;                    // Points: normalised (s, d) as given
  EdgeCoefficients coefficients{};      // Coefficients: p0..p4 as given
  std::vector<CameraPoint> lab_points;  // LabPoints: the edge in the camera plane
  std::vector<CameraPoint> pins;        // LabPoints of four_corner: corners A, B; else empty
};

struct TargetScene {
  std::string name;               // four_corner | two_corner | two_corner_slack
  std::vector<TargetEdge> edges;  // each edge name at most once
  std::vector<CameraPoint> pins;  // two_corner* with lab edges: pin1, pin2; else empty
};

struct Target {
  std::vector<TargetScene> scenes;  // each scene name at most once

  // Throws std::invalid_argument naming the scene, edge and field (checks of the header).
  void validate() const;
  // The scene of that name; throws std::invalid_argument listing the scenes present.
  const TargetScene& scene(const std::string& name) const;
};

// True for four_corner, two_corner, two_corner_slack.
bool is_target_scene(const std::string& name);

// Measured edge fits of one scene, in its edge order: points fitted, coefficients copied, lab
// points normalised (span rule for four_corner, hanging rule otherwise) and fitted. These are
// the `measured` argument of objective(). Throws std::invalid_argument for an invalid edge.
std::vector<EdgeFit> fit_target_scene(const TargetScene& scene);

// Whether a measured edge of target scene `scene` hangs ABOVE its pins, which no drape does:
// the sign of lab data given with z growing downward (image rows). Span edges (four_corner;
// top and bottom of two_corner*): the mean d of its points, or d(0.5) from its coefficients,
// is negative. Side edges of two_corner* (left, right): the mean s (depth below the own pin)
// of its points is negative; std::nullopt for a side edge given only as coefficients (no
// depth range to look at). `knitsim fit` warns when every edge that can tell sags upward.
std::optional<bool> sags_upward(const EdgeFit& edge, const std::string& scene);

// Reads and validates a target CSV (format above). A file longer than kMaxTargetFileBytes is
// refused unread ("FILE: cannot open target file: larger than ...").
Target read_target_csv(const std::string& path);
constexpr std::size_t kMaxTargetFileBytes = std::size_t{64} << 20;
// The same from the CSV text itself; `path` names it in the messages ("PATH:LINE: ...").
Target parse_target_csv(const std::string& csv, const std::string& path);
// Writes `target` in the same format (17 significant digits, so it reads back bit for bit),
// after `comment` lines (each prefixed with "# "; e.g. the command that made the target).
// Validates first (std::invalid_argument); std::runtime_error if the file cannot be written.
void write_target_csv(const Target& target, const std::string& path,
                      const std::vector<std::string>& comment = {});

}  // namespace knitsim
