#include "src/nurbs.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace knitsim {

namespace {

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument(what); }

// a / b with the Cox-de Boor convention 0/0 = 0 (b = 0 only on repeated knots, where the
// matching basis function is identically zero).
double ratio(double a, double b) { return b == 0.0 ? 0.0 : a / b; }

// Homogeneous point (w x, w y, w z, w).
struct Vec4 {
  double x = 0, y = 0, z = 0, w = 0;
};
Vec4 lerp(const Vec4& a, const Vec4& b, double t) {
  return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z),
          a.w + t * (b.w - a.w)};
}

double clamp_to_domain(const NurbsCurve& c, double u) {
  return std::clamp(u, c.u_min(), c.u_max());
}

// Speed |C'(u)|.
double speed(const NurbsCurve& c, double u) { return norm(evaluate(c, u).first); }

// 5-point Gauss-Legendre quadrature of |C'| over [a, b].
double speed_integral(const NurbsCurve& c, double a, double b) {
  static constexpr std::array<double, 5> x{0.0, -0.5384693101056831, 0.5384693101056831,
                                           -0.9061798459386640, 0.9061798459386640};
  static constexpr std::array<double, 5> w{0.5688888888888889, 0.4786286704993665,
                                           0.4786286704993665, 0.2369268850561891,
                                           0.2369268850561891};
  const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
  double s = 0.0;
  for (int k = 0; k < 5; ++k) s += w[k] * speed(c, mid + half * x[k]);
  return half * s;
}

// Quadrature pieces: 8 equal parts of every non-empty knot span, as ascending breakpoints.
std::vector<double> quadrature_breaks(const NurbsCurve& c) {
  constexpr int kPiecesPerSpan = 8;
  std::vector<double> breaks{c.u_min()};
  for (size_t s = c.degree; s < c.control.size(); ++s) {
    const double a = c.knots[s], b = c.knots[s + 1];
    if (!(b > a)) continue;
    for (int k = 1; k <= kPiecesPerSpan; ++k) breaks.push_back(a + (b - a) * k / kPiecesPerSpan);
  }
  return breaks;
}

}  // namespace

void NurbsCurve::validate() const {
  const size_t n = control.size();
  if (degree < 1) bad("NURBS degree = " + std::to_string(degree) + ": must be >= 1");
  if (n < static_cast<size_t>(degree) + 1)
    bad("NURBS control points = " + std::to_string(n) +
        ": need at least degree + 1 = " + std::to_string(degree + 1));
  if (weights.size() != n)
    bad("NURBS weights = " + std::to_string(weights.size()) + ": need one per control point (" +
        std::to_string(n) + ")");
  if (knots.size() != n + degree + 1)
    bad("NURBS knots = " + std::to_string(knots.size()) +
        ": need control points + degree + 1 = " + std::to_string(n + degree + 1));
  for (size_t i = 0; i < knots.size(); ++i) {
    if (!std::isfinite(knots[i])) bad("NURBS knot " + std::to_string(i) + " is not finite");
    if (i > 0 && knots[i] < knots[i - 1])
      bad("NURBS knot " + std::to_string(i) + " decreases: knots must be non-decreasing");
  }
  if (!(u_max() > u_min())) bad("NURBS knots: the domain [u_p, u_{n+1}] is empty");
  for (size_t i = 0; i < n; ++i) {
    if (!(weights[i] > 0.0) || !std::isfinite(weights[i]))
      bad("NURBS weight " + std::to_string(i) + ": must be > 0 and finite");
    const Vec3 p = control[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      bad("NURBS control point " + std::to_string(i) + " is not finite");
  }
}

double bspline_basis(int i, int p, const std::vector<double>& knots, double u) {
  if (p == 0) {
    const double a = knots[i], b = knots[i + 1];
    if (a <= u && u < b) return 1.0;
    // The domain end closes the last non-empty span.
    return (u == knots.back() && b == u && a < b) ? 1.0 : 0.0;
  }
  return ratio(u - knots[i], knots[i + p] - knots[i]) * bspline_basis(i, p - 1, knots, u) +
         ratio(knots[i + p + 1] - u, knots[i + p + 1] - knots[i + 1]) *
             bspline_basis(i + 1, p - 1, knots, u);
}

int find_span(int control_count, int p, const std::vector<double>& knots, double u) {
  const int n = control_count - 1;
  if (u >= knots[n + 1]) {
    // The last non-empty span ending at u_{n+1}.
    int s = n;
    while (s > p && knots[s] == knots[n + 1]) --s;
    return s;
  }
  if (u <= knots[p]) {
    int s = p;
    while (s < n && knots[s + 1] <= u) ++s;
    return s;
  }
  // The last s in [p, n] with u_s <= u.
  const auto it = std::upper_bound(knots.begin() + p, knots.begin() + n + 1, u);
  return static_cast<int>(it - knots.begin()) - 1;
}

void basis_derivatives(int span, double u, int p, const std::vector<double>& knots, int order,
                       std::vector<double>& out) {
  // Basis functions of every degree q <= p on this span: ndu[q][a] = N_{span-q+a, q}(u),
  // a = 0..q, raised one degree at a time with the Cox-de Boor recursion.
  std::vector<std::vector<double>> ndu(p + 1);
  ndu[0] = {1.0};
  for (int q = 1; q <= p; ++q) {
    ndu[q].assign(q + 1, 0.0);
    for (int a = 0; a <= q; ++a) {
      const int i = span - q + a;
      const double left = a >= 1 ? ndu[q - 1][a - 1] : 0.0;  // N_{i,q-1}
      const double right = a < q ? ndu[q - 1][a] : 0.0;      // N_{i+1,q-1}
      ndu[q][a] = ratio(u - knots[i], knots[i + q] - knots[i]) * left +
                  ratio(knots[i + q + 1] - u, knots[i + q + 1] - knots[i + 1]) * right;
    }
  }
  // Derivative k of N_{i,p}: start from N_{.,p-k} and apply k times
  //   D N_{i,q} = q [ N_{i,q-1}/(u_{i+q} - u_i) - N_{i+1,q-1}/(u_{i+q+1} - u_{i+1}) ].
  out.assign(static_cast<size_t>(order + 1) * (p + 1), 0.0);
  std::vector<double> cur, next;
  for (int k = 0; k <= order; ++k) {
    if (k > p) break;  // derivatives beyond the degree vanish
    const int q0 = p - k;
    // cur[a] = derivative-level values of N_{span-q+a, q}, a = 0..q, starting at q = q0.
    cur = ndu[q0];
    for (int q = q0 + 1; q <= p; ++q) {
      next.assign(q + 1, 0.0);
      for (int a = 0; a <= q; ++a) {
        const int i = span - q + a;
        const double left = a >= 1 ? cur[a - 1] : 0.0;
        const double right = a < q ? cur[a] : 0.0;
        next[a] = q * (ratio(left, knots[i + q] - knots[i]) -
                       ratio(right, knots[i + q + 1] - knots[i + 1]));
      }
      cur.swap(next);
    }
    std::copy(cur.begin(), cur.end(), out.begin() + static_cast<size_t>(k) * (p + 1));
  }
}

CurvePoint evaluate(const NurbsCurve& c, double u) {
  u = clamp_to_domain(c, u);
  const int p = c.degree;
  const int span = find_span(static_cast<int>(c.control.size()), p, c.knots, u);
  std::vector<double> d;
  basis_derivatives(span, u, p, c.knots, 2, d);
  // Derivatives of the homogeneous numerator A and denominator W.
  Vec3 A[3];
  double W[3] = {0.0, 0.0, 0.0};
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j <= p; ++j) {
      const int i = span - p + j;
      const double nw = d[k * (p + 1) + j] * c.weights[i];
      A[k] = A[k] + nw * c.control[i];
      W[k] += nw;
    }
  CurvePoint r;
  r.point = (1.0 / W[0]) * A[0];
  r.first = (1.0 / W[0]) * (A[1] - W[1] * r.point);
  r.second = (1.0 / W[0]) * (A[2] - 2.0 * W[1] * r.first - W[2] * r.point);
  return r;
}

Vec3 evaluate_de_boor(const NurbsCurve& c, double u) {
  u = clamp_to_domain(c, u);
  const int p = c.degree;
  const int s = find_span(static_cast<int>(c.control.size()), p, c.knots, u);
  std::vector<Vec4> d(p + 1);
  for (int j = 0; j <= p; ++j) {
    const int i = s - p + j;
    const double w = c.weights[i];
    d[j] = {w * c.control[i].x, w * c.control[i].y, w * c.control[i].z, w};
  }
  // Level r: d_j <- (1 - alpha) d_{j-1} + alpha d_j for the control point i = s - p + j,
  // alpha = (u - u_i) / (u_{i+p-r+1} - u_i).
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const int i = s - p + j;
      const double alpha = ratio(u - c.knots[i], c.knots[i + p - r + 1] - c.knots[i]);
      d[j] = lerp(d[j - 1], d[j], alpha);
    }
  return {d[p].x / d[p].w, d[p].y / d[p].w, d[p].z / d[p].w};
}

std::vector<double> interpolation_parameters(const std::vector<Vec3>& points,
                                             Parametrization parametrization) {
  const size_t n = points.size();
  if (n < 2) bad("NURBS interpolation: " + std::to_string(n) + " points, need at least 2");
  std::vector<double> ubar(n, 0.0);
  for (size_t k = 1; k < n; ++k) {
    const double chord = norm(points[k] - points[k - 1]);
    if (!std::isfinite(chord))
      bad("NURBS interpolation: point " + std::to_string(k) + " is not finite");
    if (!(chord > 0.0))
      bad("NURBS interpolation: points " + std::to_string(k - 1) + " and " + std::to_string(k) +
          " coincide");
    ubar[k] =
        ubar[k - 1] + (parametrization == Parametrization::Centripetal ? std::sqrt(chord) : chord);
  }
  const double total = ubar.back();
  for (double& u : ubar) u /= total;
  ubar.back() = 1.0;
  return ubar;
}

NurbsCurve interpolate_cubic(const std::vector<Vec3>& points, Parametrization parametrization) {
  const std::vector<double> ubar = interpolation_parameters(points, parametrization);
  const int n = static_cast<int>(points.size()) - 1;
  const int p = std::min(3, n);
  NurbsCurve c;
  c.degree = p;
  c.knots.assign(n + p + 2, 0.0);
  for (int j = 1; j <= n - p; ++j) {
    double sum = 0.0;
    for (int i = j; i <= j + p - 1; ++i) sum += ubar[i];
    c.knots[j + p] = sum / p;
  }
  for (int j = n + 1; j <= n + p + 1; ++j) c.knots[j] = 1.0;

  // Banded collocation matrix B (bandwidth p each side), row k = N_{.,p}(ubar_k):
  // band[k * width + (col - k + p)], width = 2p + 1.
  const int width = 2 * p + 1;
  std::vector<double> band(static_cast<size_t>(n + 1) * width, 0.0);
  auto at = [&](int row, int col) -> double& {
    return band[static_cast<size_t>(row) * width + (col - row + p)];
  };
  std::vector<double> nb;
  for (int k = 0; k <= n; ++k) {
    const int span = find_span(n + 1, p, c.knots, ubar[k]);
    basis_derivatives(span, ubar[k], p, c.knots, 0, nb);
    for (int j = 0; j <= p; ++j) {
      const int col = span - p + j;
      if (nb[j] != 0.0) at(k, col) = nb[j];  // |col - k| <= p for averaged knots
    }
  }
  // Gaussian elimination without pivoting (totally positive matrix), then back substitution.
  std::vector<Vec3> rhs = points;
  for (int k = 0; k <= n; ++k) {
    const double pivot = at(k, k);
    if (!(std::abs(pivot) > 0.0)) bad("NURBS interpolation: singular collocation matrix");
    for (int row = k + 1; row <= std::min(n, k + p); ++row) {
      const double f = at(row, k) / pivot;
      if (f == 0.0) continue;
      for (int col = k; col <= std::min(n, k + p); ++col) at(row, col) -= f * at(k, col);
      rhs[row] = rhs[row] - f * rhs[k];
    }
  }
  c.control.assign(n + 1, Vec3{});
  for (int k = n; k >= 0; --k) {
    Vec3 s = rhs[k];
    for (int col = k + 1; col <= std::min(n, k + p); ++col) s = s - at(k, col) * c.control[col];
    c.control[k] = (1.0 / at(k, k)) * s;
  }
  c.weights.assign(n + 1, 1.0);
  return c;
}

double arc_length(const NurbsCurve& c, double u0, double u1) {
  u0 = clamp_to_domain(c, u0);
  u1 = clamp_to_domain(c, u1);
  double length = 0.0;
  const std::vector<double> breaks = quadrature_breaks(c);
  for (size_t k = 1; k < breaks.size(); ++k) {
    const double a = std::max(u0, breaks[k - 1]), b = std::min(u1, breaks[k]);
    if (b > a) length += speed_integral(c, a, b);
  }
  return length;
}

CurveSamples sample_curve(const NurbsCurve& c, int count, Spacing spacing) {
  if (count < 2) bad("curve samples = " + std::to_string(count) + ": must be >= 2");
  CurveSamples s;
  s.u.resize(count);
  const double u0 = c.u_min(), u1 = c.u_max();
  if (spacing == Spacing::Parameter) {
    for (int k = 0; k < count; ++k) s.u[k] = u0 + (u1 - u0) * k / (count - 1);
  } else {
    // Cumulative length at the quadrature breakpoints, then Newton on
    // S(u) = S(a) + int_a^u |C'| - target inside the bracketing piece [a, b].
    const std::vector<double> breaks = quadrature_breaks(c);
    std::vector<double> cum(breaks.size(), 0.0);
    for (size_t k = 1; k < breaks.size(); ++k)
      cum[k] = cum[k - 1] + speed_integral(c, breaks[k - 1], breaks[k]);
    const double total = cum.back();
    for (int k = 0; k < count; ++k) {
      const double target = total * k / (count - 1);
      size_t piece = std::upper_bound(cum.begin(), cum.end(), target) - cum.begin();
      piece = std::clamp<size_t>(piece, 1, breaks.size() - 1);
      const double a = breaks[piece - 1], b = breaks[piece];
      const double la = cum[piece - 1], lb = cum[piece];
      double u = lb > la ? a + (b - a) * (target - la) / (lb - la) : a;
      for (int it = 0; it < 30; ++it) {
        const double f = la + speed_integral(c, a, u) - target;
        const double df = speed(c, u);
        if (std::abs(f) <= 1e-13 * total || !(df > 0.0)) break;
        u = std::clamp(u - f / df, a, b);
      }
      s.u[k] = u;
    }
    s.u.front() = u0;
    s.u.back() = u1;
  }
  s.points.resize(count);
  for (int k = 0; k < count; ++k) s.points[k] = evaluate(c, s.u[k]).point;
  return s;
}

}  // namespace knitsim
