// NURBS: Cox-de Boor vs de Boor, partition of unity, derivatives vs finite differences,
// exact interpolation, C^2 continuity, the rational quarter circle, arc-length sampling (the
// span-polynomial speed against quadrature of evaluate()'s C'), the degree limit.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "src/geometry/nurbs.hpp"

using namespace knitsim;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Points on a 3D helix-like curve with uneven spacing (a realistic interpolation input).
std::vector<Vec3> wiggly_points(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> step(0.3, 1.7);
  std::vector<Vec3> q;
  double s = 0.0;
  for (int k = 0; k < count; ++k) {
    q.push_back({std::cos(s), std::sin(1.3 * s), 0.2 * s});
    s += step(rng);
  }
  return q;
}

// A random valid cubic NURBS with repeated interior knots allowed (clamped).
NurbsCurve random_curve(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  NurbsCurve c;
  c.degree = 3;
  const int n = 9;  // control points
  c.knots = {0, 0, 0, 0, 0.1, 0.35, 0.35, 0.6, 0.8, 1, 1, 1, 1};
  for (int i = 0; i < n; ++i) {
    c.control.push_back({u(rng), u(rng), u(rng)});
    c.weights.push_back(0.3 + 2.0 * u(rng));
  }
  c.validate();
  return c;
}

double dist(Vec3 a, Vec3 b) { return norm(a - b); }

// d^k/du^k of the polynomial piece of knot span `span` of a non-rational curve, at u.
Vec3 piece_derivative(const NurbsCurve& c, int span, double u, int k) {
  std::vector<double> d;
  basis_derivatives(span, u, c.degree, c.knots, k, d);
  Vec3 s;
  for (int j = 0; j <= c.degree; ++j)
    s = s + d[k * (c.degree + 1) + j] * c.control[span - c.degree + j];
  return s;
}

}  // namespace

TEST_CASE("Cox-de Boor basis: partition of unity, non-negativity, local support") {
  const std::vector<double> U = {0, 0, 0, 0, 0.1, 0.35, 0.35, 0.6, 0.8, 1, 1, 1, 1};
  const int p = 3, count = static_cast<int>(U.size()) - p - 1;
  for (int s = 0; s <= 200; ++s) {
    const double u = s / 200.0;
    double sum = 0.0;
    int nonzero = 0;
    for (int i = 0; i < count; ++i) {
      const double N = bspline_basis(i, p, U, u);
      CHECK(N >= 0.0);
      sum += N;
      nonzero += N != 0.0;
    }
    CHECK(sum == Approx(1.0).margin(1e-15));
    CHECK(nonzero <= p + 1);
  }
  // At the domain end only the last function is 1.
  CHECK(bspline_basis(count - 1, p, U, 1.0) == 1.0);
  CHECK(bspline_basis(count - 2, p, U, 1.0) == 0.0);
}

TEST_CASE("basis_derivatives agrees with the recursion and with finite differences") {
  const std::vector<double> U = {0, 0, 0, 0, 0.1, 0.35, 0.35, 0.6, 0.8, 1, 1, 1, 1};
  const int p = 3, count = static_cast<int>(U.size()) - p - 1;
  std::vector<double> d;
  for (double u : {0.0, 0.05, 0.2, 0.34, 0.5, 0.7, 0.93}) {
    const int span = find_span(count, p, U, u);
    basis_derivatives(span, u, p, U, 2, d);
    const double h = 1e-5;
    for (int j = 0; j <= p; ++j) {
      const int i = span - p + j;
      CHECK(d[j] == Approx(bspline_basis(i, p, U, u)).margin(1e-15));
      // Central differences inside the span (all sample points are >= h from the knots).
      const double fp = bspline_basis(i, p, U, u + h), fm = bspline_basis(i, p, U, u - h);
      const double f0 = bspline_basis(i, p, U, u);
      if (u - h < U[span]) continue;  // the one-sided first sample at u = 0
      CHECK(d[(p + 1) + j] == Approx((fp - fm) / (2 * h)).margin(1e-6));
      CHECK(d[2 * (p + 1) + j] == Approx((fp - 2 * f0 + fm) / (h * h)).margin(2e-3));
    }
  }
}

TEST_CASE("evaluate (basis functions) equals de Boor's algorithm on rational curves") {
  for (unsigned seed : {1u, 2u, 3u}) {
    const NurbsCurve c = random_curve(seed);
    double worst = 0.0, worst_recursive = 0.0;
    for (int s = 0; s <= 500; ++s) {
      const double u = s / 500.0;
      const Vec3 de_boor = evaluate_de_boor(c, u);
      worst = std::max(worst, dist(evaluate(c, u).point, de_boor));
      // The rational sum with the recursive Cox-de Boor definition of every N_{i,3}.
      Vec3 num;
      double den = 0.0;
      for (size_t i = 0; i < c.control.size(); ++i) {
        const double nw = bspline_basis(static_cast<int>(i), 3, c.knots, u) * c.weights[i];
        num = num + nw * c.control[i];
        den += nw;
      }
      worst_recursive = std::max(worst_recursive, dist((1.0 / den) * num, de_boor));
    }
    CHECK(worst < 1e-14);
    CHECK(worst_recursive < 1e-14);
  }
}

TEST_CASE("rational first and second derivatives match finite differences") {
  const NurbsCurve c = random_curve(4);
  const double h = 1e-5;
  for (double u : {0.05, 0.2, 0.5, 0.7, 0.9}) {
    const CurvePoint e = evaluate(c, u);
    const Vec3 fp = evaluate(c, u + h).point, fm = evaluate(c, u - h).point;
    const Vec3 d1 = (1.0 / (2 * h)) * (fp - fm);
    const Vec3 d2 = (1.0 / (h * h)) * (fp - 2.0 * e.point + fm);
    CHECK(dist(e.first, d1) < 1e-7 * std::max(1.0, norm(e.first)));
    CHECK(dist(e.second, d2) < 1e-3 * std::max(1.0, norm(e.second)));
  }
}

TEST_CASE("rational quadratic with weights (1, sqrt2/2, 1) is an exact quarter circle") {
  NurbsCurve c;
  c.degree = 2;
  c.knots = {0, 0, 0, 1, 1, 1};
  c.control = {{1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  c.weights = {1.0, std::sqrt(2.0) / 2.0, 1.0};
  c.validate();
  double worst = 0.0;
  for (int s = 0; s <= 1000; ++s) {
    const double u = s / 1000.0;
    worst = std::max(worst, std::abs(norm(evaluate(c, u).point) - 1.0));
    worst = std::max(worst, std::abs(norm(evaluate_de_boor(c, u)) - 1.0));
  }
  CHECK(worst <= 1e-14);
  // Curvature 1 everywhere: |C' x C''| / |C'|^3.
  for (double u : {0.0, 0.3, 0.5, 1.0}) {
    const CurvePoint e = evaluate(c, u);
    CHECK(norm(cross(e.first, e.second)) / std::pow(norm(e.first), 3) ==
          Approx(1.0).epsilon(1e-12));
  }
  // Arc length pi/2, and arc-length samples are equally spaced in angle.
  CHECK(arc_length(c, 0.0, 1.0) == Approx(kPi / 2).epsilon(1e-12));
  const CurveSamples s = sample_curve(c, 7, Spacing::ArcLength);
  for (int k = 0; k < 7; ++k) {
    const double angle = std::atan2(s.points[k].y, s.points[k].x);
    CHECK(angle == Approx(kPi / 2 * k / 6).margin(1e-11));
  }
}

// int_a^b |C'(u)| du by composite 5-point Gauss-Legendre on `pieces` equal parts of every knot
// span, with C' from evaluate() (the basis-function path): independent of arc_length's span
// polynomials.
double slow_length(const NurbsCurve& c, double a, double b, int pieces) {
  const double x[5] = {0.0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640,
                       0.9061798459386640};
  const double w[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665,
                       0.2369268850561891, 0.2369268850561891};
  double length = 0.0;
  for (size_t s = c.degree; s < c.control.size(); ++s)
    for (int k = 0; k < pieces; ++k) {
      const double span = c.knots[s + 1] - c.knots[s];
      const double lo = std::max(a, c.knots[s] + span * k / pieces);
      const double hi = std::min(b, c.knots[s] + span * (k + 1) / pieces);
      if (!(hi > lo)) continue;
      const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
      for (int i = 0; i < 5; ++i)
        length += half * w[i] * norm(evaluate(c, mid + half * x[i]).first);
    }
  return length;
}

TEST_CASE("arc length and arc-length samples agree with quadrature of evaluate()'s C'") {
  // Rational cubics with a repeated interior knot, a degree-5 curve and an interpolant.
  std::vector<NurbsCurve> curves = {random_curve(1), random_curve(2)};
  NurbsCurve quintic;
  quintic.degree = 5;
  quintic.knots = {0, 0, 0, 0, 0, 0, 0.3, 0.55, 1, 1, 1, 1, 1, 1};
  for (int i = 0; i < 8; ++i) {
    quintic.control.push_back({std::cos(0.9 * i), std::sin(1.7 * i), 0.1 * i * i});
    quintic.weights.push_back(1.0 + 0.25 * (i % 3));
  }
  quintic.validate();
  curves.push_back(quintic);
  curves.push_back(interpolate_cubic(wiggly_points(30, 9)));
  for (const NurbsCurve& c : curves) {
    const double total = slow_length(c, c.u_min(), c.u_max(), 8);
    CHECK(arc_length(c, c.u_min(), c.u_max()) == Approx(total).epsilon(1e-14));
    CHECK(arc_length(c, 0.13, 0.71) == Approx(slow_length(c, 0.13, 0.71, 8)).epsilon(1e-14));
    // Equal spacing in arc length: S(u_k) = k total / (count - 1), S measured with the
    // independent quadrature on the same pieces (whole pieces, then [piece start, u_k]).
    const int count = 41;
    const CurveSamples s = sample_curve(c, count, Spacing::ArcLength);
    double worst = 0.0;
    for (int k = 0; k < count; ++k)
      worst =
          std::max(worst, std::abs(slow_length(c, c.u_min(), s.u[k], 8) - total * k / (count - 1)));
    CHECK(worst < 1e-12 * total);
    for (int k = 0; k < count; ++k) CHECK(dist(s.points[k], evaluate(c, s.u[k]).point) == 0.0);
  }
}

TEST_CASE("degrees outside [1, kMaxNurbsDegree] are refused, not evaluated") {
  NurbsCurve c;
  c.degree = kMaxNurbsDegree + 1;
  c.knots.assign(2 * (c.degree + 1), 0.0);
  std::fill(c.knots.begin() + c.degree + 1, c.knots.end(), 1.0);
  c.control.assign(c.degree + 1, Vec3{});
  c.weights.assign(c.degree + 1, 1.0);
  CHECK_THROWS_WITH(c.validate(), Catch::Contains("NURBS degree = 8: must be in [1, 7]"));
  CHECK_THROWS_AS(evaluate(c, 0.5), std::invalid_argument);
  CHECK_THROWS_AS(arc_length(c, 0.0, 1.0), std::invalid_argument);
  std::vector<double> d;
  CHECK_THROWS_AS(basis_derivatives(c.degree, 0.5, c.degree, c.knots, 1, d), std::invalid_argument);
}

TEST_CASE("global cubic interpolation passes through every point and is C2") {
  for (Parametrization par : {Parametrization::ChordLength, Parametrization::Centripetal}) {
    const std::vector<Vec3> q = wiggly_points(40, 11);
    const NurbsCurve c = interpolate_cubic(q, par);
    c.validate();
    REQUIRE(c.degree == 3);
    REQUIRE(c.control.size() == q.size());
    const std::vector<double> ubar = interpolation_parameters(q, par);
    double worst = 0.0;
    for (size_t k = 0; k < q.size(); ++k)
      worst = std::max(worst, dist(evaluate(c, ubar[k]).point, q[k]) / norm(q[k]));
    CHECK(worst <= 1e-12);
    // Interior knots: the one-sided derivatives agree. The left limit is the polynomial
    // piece of the span ending at the knot, evaluated at the knot (basis_derivatives takes
    // the span explicitly); evaluate() gives the right one. The third derivative must jump
    // (else the test could not see a discontinuity).
    double worst_jump3 = 0.0;
    for (size_t i = c.degree + 1; i < c.control.size(); ++i) {
      const double knot = c.knots[i];
      const CurvePoint right = evaluate(c, knot);
      const Vec3 first_left = piece_derivative(c, static_cast<int>(i) - 1, knot, 1);
      const Vec3 second_left = piece_derivative(c, static_cast<int>(i) - 1, knot, 2);
      CHECK(dist(first_left, right.first) <= 1e-11 * norm(right.first));
      CHECK(dist(second_left, right.second) <= 1e-9 * norm(right.second));
      const Vec3 third_left = piece_derivative(c, static_cast<int>(i) - 1, knot, 3);
      const Vec3 third_right = piece_derivative(c, static_cast<int>(i), knot, 3);
      worst_jump3 = std::max(worst_jump3, dist(third_left, third_right) / norm(third_right));
    }
    CHECK(worst_jump3 > 1e-3);
  }
}

TEST_CASE("interpolation with few points lowers the degree; degenerate data throws") {
  const NurbsCurve line = interpolate_cubic({{0, 0, 0}, {1, 2, 3}});
  CHECK(line.degree == 1);
  CHECK(dist(evaluate(line, 0.5).point, {0.5, 1, 1.5}) < 1e-15);
  const NurbsCurve quad = interpolate_cubic({{0, 0, 0}, {1, 1, 0}, {2, 0, 0}});
  CHECK(quad.degree == 2);
  CHECK_THROWS_AS(interpolate_cubic({{0, 0, 0}}), std::invalid_argument);
  CHECK_THROWS_AS(interpolate_cubic({{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {2, 0, 0}}),
                  std::invalid_argument);
  NurbsCurve bad = random_curve(1);
  bad.weights[3] = 0.0;
  CHECK_THROWS_AS(bad.validate(), std::invalid_argument);
  bad = random_curve(1);
  bad.knots[5] = 0.9;  // decreasing
  CHECK_THROWS_AS(bad.validate(), std::invalid_argument);
}

TEST_CASE("sample_curve spaces samples evenly in u, or in arc length to 1e-9") {
  const NurbsCurve c = interpolate_cubic(wiggly_points(12, 5));
  const CurveSamples u = sample_curve(c, 11, Spacing::Parameter);
  CHECK(u.u.front() == c.u_min());
  CHECK(u.u.back() == c.u_max());
  CHECK(u.u[5] == Approx(0.5));
  const CurveSamples s = sample_curve(c, 31, Spacing::ArcLength);
  const double total = arc_length(c, c.u_min(), c.u_max());
  for (int k = 1; k < 31; ++k)
    CHECK(arc_length(c, s.u[k - 1], s.u[k]) == Approx(total / 30).epsilon(1e-9));
  // The arc length of an interpolant exceeds its chord polygon's length, by little.
  double polygon = 0.0;
  const std::vector<Vec3> q = wiggly_points(12, 5);
  for (size_t k = 1; k < q.size(); ++k) polygon += dist(q[k], q[k - 1]);
  CHECK(total > polygon);
  CHECK(total < 1.2 * polygon);
}
