// Drape measurement (paper 1, "Strategy of determining model error", Eq. 5, Figs 11-12;
// user's view: docs/fitting.md, "1. Measure"): the fabric's boundary edges at equilibrium, seen in
// a camera view, are turned into dimensionless points (s, d), each edge is fitted with a 4th-order
// polynomial
//   d(s) = p0 + p1 s + p2 s^2 + p3 s^3 + p4 s^4
// by least squares, and the model error is the RMS difference of the coefficients:
//   E = 100 sqrt( mean over all measured edges and the 5 coefficients of (P_meas - P_sim)^2 )
// ("error, %"). Paper 1's Eq. 5 is written for one edge (a sum over 5 coefficients / 5); over
// several edges the mean runs over all edges x 5 coefficients.
//
// Normalisation (all lengths divided by a reference length, so s and d are dimensionless and
// the same rules serve the simulation (metres) and lab photos (millimetres)):
//
// * Span edge (scene four_corner): an edge between its two pinned corners A and B, seen from
//   outside, perpendicular to the edge. With e = (B - A)/|B - A| (3D unit vector),
//     s = ((x - A) . e) / |B - A|                      (0 at A, 1 at B)
//     d = -(z - z_line(s)) / |B - A|,  z_line(s) = z_A + s (z_B - z_A)   (sag positive)
//   Only the projection on e and the height z enter: in-plane bulging of the edge toward the
//   sheet's centre is invisible to this camera, as in a photo. The model's A is the edge's
//   first particle (DrapeGrid::edges): top (row 0) and left (column 0) start at particle
//   (0,0), bottom (row n) at (n,0), right (column n) at (0,n); B is the last particle. Every
//   particle of the edge is a point, the pinned corners included (they give d = 0 at s = 0, 1).
//
// * Hanging edges (scenes two_corner and two_corner_slack): front view along y, i.e. only x
//   (horizontal, to the right) and z (up) are used. pin1 = particle (0,0), pin2 = particle
//   (0,n), both at their FINAL positions (after a pins.span move). Definitions:
//     S     = |pin2 - pin1| in the x-z plane (the span; > 0, else invalid_argument)
//     sigma = sign(x_pin2 - x_pin1) (+1 for the model; lets a lab photo taken from the back
//             list the pins in the model's order; x_pin1 = x_pin2 is invalid_argument)
//     z_ref = (z_pin1 + z_pin2) / 2 (the pins' mean height; they are level in the model)
//   top (row 0, between the pins) and bottom (row n):
//     s = sigma (x - x_pin1) / S,   d = (z_ref - z) / S            (drop below the pins)
//   left (column 0, hanging from pin1) and right (column n, hanging from pin2), with P the
//   edge's own pin:
//     s = (z_P - z) / S   (depth below its own pin; NOT confined to [0, 1]: a sheet of
//                          width W hung with span S reaches s ~ W/S, e.g. 1.67 at span 0.6)
//     d = sigma (x - x_pin1) / S   for left,   d = -sigma (x - x_pin2) / S   for right
//         (horizontal offset from the own pin's vertical, positive toward the fabric's centre)
//   Points are ordered along the edge from its first particle (sides: from the pin down).
//
// Fit: the polynomial is fitted on the given s (no rescaling to [0, 1]; the coefficients are
// those of d in powers of s as defined above), by column-pivoted Householder QR of the
// Vandermonde matrix (never the normal equations, which square its condition number).
//
// Failure modes: std::invalid_argument for fewer than degree+1 points, fewer than degree+1
// distinct abscissae (rank-deficient fit), mismatched lengths, non-finite input (so check a
// run's status before measuring: a diverged run has non-finite positions), a wrong number of
// positions, degenerate pins; for the objective, an empty or duplicated measured edge set or a
// measured edge missing from the simulation. The objective itself does not check finiteness
// (NaN coefficients built by hand give a NaN error).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "models/drape_grid.hpp"
#include "src/core/vec3.hpp"

namespace knitsim {

constexpr int kEdgePolynomialDegree = 4;  // paper 1: "fourth-order polynomial equation"
using EdgeCoefficients = std::array<double, kEdgePolynomialDegree + 1>;  // p0..p4

// Normalised points of one edge, s[k] and d[k] for point k (dimensionless, see above).
struct EdgePoints {
  std::vector<double> s, d;
};

struct EdgeFit {
  std::string name;                 // top | bottom | left | right
  EdgePoints points;                // empty when the edge was given only as coefficients
  EdgeCoefficients coefficients{};  // p0..p4 of d(s)
};

// The four boundary edges and their roles in the hanging (two_corner) front view.
enum class EdgeSide { Top, Bottom, Left, Right };
const char* to_string(EdgeSide side);
// "top" -> Top, ...; std::nullopt for any other name.
std::optional<EdgeSide> edge_side_from_name(const std::string& name);

// Span-edge rule (four_corner): points of one edge between corners a (s = 0) and b (s = 1).
EdgePoints normalise_span_edge(const std::vector<Vec3>& points, Vec3 a, Vec3 b);
// Hanging-edge rule (two_corner): points of edge `side` in the front view (y is ignored).
EdgePoints normalise_hanging_edge(EdgeSide side, const std::vector<Vec3>& points, Vec3 pin1,
                                  Vec3 pin2);

// Least-squares polynomial coefficients c[0..degree] of d(s) = sum c_k s^k, by
// ColPivHouseholderQR. Throws std::invalid_argument (see failure modes).
std::vector<double> fit_polynomial(const std::vector<double>& s, const std::vector<double>& d,
                                   int degree);

// Fits the 4th-order edge polynomial to `points` and packs the result.
EdgeFit fit_edge(const std::string& name, EdgePoints points);

// All boundary edges of a drape at rest or at equilibrium. all_positions: every particle
// (index i (n+1) + j), pins at their final positions, as SpringNetwork::all_positions(t_final,
// x, out) gives them. The rule follows grid.params.layout (FourCorner: span edges; TwoCorner,
// whatever pins.span: hanging edges). Returns one EdgeFit per grid edge, in grid.edges order.
std::vector<EdgeFit> measure_edges(const DrapeGrid& grid, const std::vector<Vec3>& all_positions);

// Eq. 5 over all measured edges, percent (see above). Edges are matched by name; simulated
// edges without a measured counterpart are ignored.
double objective(const std::vector<EdgeFit>& measured, const std::vector<EdgeFit>& simulated);

// Writes a run's edges.csv, header `edge,kind,index,s,d,coefficient`:
//   point rows  `top,point,k,s_k,d_k,`      k = 0.. along the edge (from its first particle)
//   coeff rows  `top,coeff,i,,,p_i`         i = 0..4, d(s) = sum p_i s^i
// per edge its points then its 5 coefficients; numbers with 17 significant digits.
// Throws std::runtime_error if the file cannot be written.
void write_edges_csv(const std::vector<EdgeFit>& edges, const std::string& path);

}  // namespace knitsim
