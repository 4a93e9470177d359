// NURBS curves: evaluation, derivatives and global interpolation (paper 2 Sec. 3.2, where the
// loop centrelines are cubic NURBS through the loops' type-value points, "inverse calculation").
// Reference: Piegl & Tiller, The NURBS Book, 2nd ed. (1997), chapters 2 (basis functions),
// 4 (rational curves) and 9.2 (global interpolation). Written from the equations there.
//
// Conventions (those of the book):
//   degree p, control points P_0..P_n (n + 1 of them) with weights w_i > 0, knot vector
//   U = {u_0 <= ... <= u_m}, m = n + p + 1. The curve is defined on [u_p, u_{n+1}].
//   Interpolated curves are clamped (first and last p + 1 knots equal) on [0, 1].
//   B-spline basis by the Cox-de Boor recursion, with 0/0 = 0:
//     N_{i,0}(u) = 1 if u_i <= u < u_{i+1}, else 0   (half-open spans; at the domain end
//                  u = u_{n+1} the last non-empty span is taken closed, so N_{n,p}(u_max) = 1)
//     N_{i,q}(u) = (u - u_i)/(u_{i+q} - u_i) N_{i,q-1}(u)
//                + (u_{i+q+1} - u)/(u_{i+q+1} - u_{i+1}) N_{i+1,q-1}(u)
//   (paper 2 prints the first denominator as u_{i+k+1} - u: a typo; this is the standard form).
//   Derivatives: N'_{i,q} = q [ N_{i,q-1}/(u_{i+q} - u_i) - N_{i+1,q-1}/(u_{i+q+1} - u_{i+1}) ].
//   Rational curve: C(u) = A(u)/W(u), A = sum N_{i,p} w_i P_i, W = sum N_{i,p} w_i, so
//     C' = (A' - W' C)/W,   C'' = (A'' - 2 W' C' - W'' C)/W.
//   de Boor's algorithm (P&T Sec. 3.2/4.2 via homogeneous points (w P, w)) is an independent
//   evaluator of C(u), used to cross-check the basis-function path.
//
// Global interpolation (P&T Sec. 9.2.1) through points Q_0..Q_n: parameters ubar_k by chord
// length (|Q_k - Q_{k-1}| / total) or centripetal (square roots of those lengths), interior
// knots by averaging u_{j+p} = (1/p) sum_{i=j}^{j+p-1} ubar_i (j = 1..n-p), degree
// p = min(3, n). The control points solve sum_i N_{i,p}(ubar_k) P_i = Q_k, a banded system
// (bandwidth p) whose matrix is totally positive for averaged knots, so Gaussian elimination
// without pivoting is stable (de Boor 1976); weights are 1. The curve then passes through
// Q_k at u = ubar_k and is C^2 (cubic, simple interior knots).
//
// Failure modes: invalid curves (sizes, decreasing knots, non-positive weights) and degenerate
// interpolation data (fewer than 2 points, coincident consecutive points, non-finite input)
// throw std::invalid_argument. Evaluation outside [u_min, u_max] clamps u to the domain.
#pragma once

#include <vector>

#include "src/core/vec3.hpp"

namespace knitsim {

// Largest degree supported (evaluation keeps its basis tables on the stack).
constexpr int kMaxNurbsDegree = 7;

struct NurbsCurve {
  int degree = 3;               // p, 1..kMaxNurbsDegree
  std::vector<double> knots;    // U, size control.size() + degree + 1, non-decreasing
  std::vector<Vec3> control;    // P_i
  std::vector<double> weights;  // w_i > 0, one per control point (all 1: a plain B-spline)

  double u_min() const { return knots[degree]; }
  double u_max() const { return knots[control.size()]; }
  // Throws std::invalid_argument naming what is inconsistent.
  void validate() const;
};

// N_{i,p}(u) by the recursive Cox-de Boor definition (exponential in p: for tests and
// small degrees; evaluation uses basis_derivatives).
double bspline_basis(int i, int p, const std::vector<double>& knots, double u);

// Knot span s with u_s <= u < u_{s+1}, p <= s <= n (n + 1 = control_count); u >= u_{n+1}
// gives s = n. Binary search.
int find_span(int control_count, int p, const std::vector<double>& knots, double u);

// Nonzero basis functions of span s and their derivatives up to order `order` at u:
// out[k * (p + 1) + j] = d^k/du^k N_{s-p+j,p}(u), k = 0..order, j = 0..p. Throws
// std::invalid_argument for p outside [1, kMaxNurbsDegree].
void basis_derivatives(int span, double u, int p, const std::vector<double>& knots, int order,
                       std::vector<double>& out);

struct CurvePoint {
  Vec3 point;   // C(u)
  Vec3 first;   // C'(u)
  Vec3 second;  // C''(u)
};
// C(u), C'(u), C''(u) of the rational curve (one-sided from the right at interior knots,
// from the left at u_max). Does not allocate; throws std::invalid_argument for a degree outside
// [1, kMaxNurbsDegree] (other inconsistencies are the caller's: see validate()).
CurvePoint evaluate(const NurbsCurve& curve, double u);

// C(u) by de Boor's algorithm on homogeneous control points (independent of evaluate()).
Vec3 evaluate_de_boor(const NurbsCurve& curve, double u);

enum class Parametrization { ChordLength, Centripetal };

// The parameters ubar_k in [0, 1] of the interpolation points (see above).
std::vector<double> interpolation_parameters(const std::vector<Vec3>& points,
                                             Parametrization parametrization);

// The clamped cubic (degree min(3, n)) curve through all points, weights 1.
NurbsCurve interpolate_cubic(const std::vector<Vec3>& points,
                             Parametrization parametrization = Parametrization::ChordLength);

// Arc length of the curve between parameters u0 <= u1 (Gauss-Legendre quadrature, 5 nodes
// on 8 pieces of every non-empty knot span: about 1e-12 relative on smooth curves,
// tests/test_nurbs.cpp). The speed |C'| comes from each span's power form (the Taylor
// coefficients of the homogeneous A and W at the span start, exact for these degree-p
// polynomials) by Horner's rule: cheaper than evaluate() and equal to it to round-off.
double arc_length(const NurbsCurve& curve, double u0, double u1);

enum class Spacing { Parameter, ArcLength };
struct CurveSamples {
  std::vector<double> u;     // parameters, ascending, first u_min, last u_max
  std::vector<Vec3> points;  // C(u)
};
// `count` >= 2 samples, uniform in u or in arc length (then u is found by Newton's method
// on the arc-length function, to 1e-13 of the total length); points by evaluate().
CurveSamples sample_curve(const NurbsCurve& curve, int count, Spacing spacing);

}  // namespace knitsim
