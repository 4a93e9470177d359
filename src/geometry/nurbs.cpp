#include "src/geometry/nurbs.hpp"

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

void check_degree(int p) {
  if (p < 1 || p > kMaxNurbsDegree)
    bad("NURBS degree = " + std::to_string(p) + ": must be in [1, " +
        std::to_string(kMaxNurbsDegree) + "]");
}

// basis_derivatives without allocating: out[k * (p + 1) + j] for k = 0..order, order <= p <=
// kMaxNurbsDegree (entries of higher orders are left alone).
void basis_derivatives_into(int span, double u, int p, const std::vector<double>& knots, int order,
                            double* out) {
  // Basis functions of every degree q <= p on this span: ndu[q][a] = N_{span-q+a, q}(u),
  // a = 0..q, raised one degree at a time with the Cox-de Boor recursion.
  double ndu[kMaxNurbsDegree + 1][kMaxNurbsDegree + 1];
  ndu[0][0] = 1.0;
  for (int q = 1; q <= p; ++q)
    for (int a = 0; a <= q; ++a) {
      const int i = span - q + a;
      const double left = a >= 1 ? ndu[q - 1][a - 1] : 0.0;  // N_{i,q-1}
      const double right = a < q ? ndu[q - 1][a] : 0.0;      // N_{i+1,q-1}
      ndu[q][a] = ratio(u - knots[i], knots[i + q] - knots[i]) * left +
                  ratio(knots[i + q + 1] - u, knots[i + q + 1] - knots[i + 1]) * right;
    }
  // Derivative k of N_{i,p}: start from N_{.,p-k} and apply k times
  //   D N_{i,q} = q [ N_{i,q-1}/(u_{i+q} - u_i) - N_{i+1,q-1}/(u_{i+q+1} - u_{i+1}) ].
  for (int k = 0; k <= order; ++k) {
    const int q0 = p - k;
    // cur[a] = derivative-level values of N_{span-q+a, q}, a = 0..q, starting at q = q0.
    double cur[kMaxNurbsDegree + 1], next[kMaxNurbsDegree + 1];
    std::copy(ndu[q0], ndu[q0] + q0 + 1, cur);
    for (int q = q0 + 1; q <= p; ++q) {
      for (int a = 0; a <= q; ++a) {
        const int i = span - q + a;
        const double left = a >= 1 ? cur[a - 1] : 0.0;
        const double right = a < q ? cur[a] : 0.0;
        next[a] = q * (ratio(left, knots[i + q] - knots[i]) -
                       ratio(right, knots[i + q + 1] - knots[i + 1]));
      }
      std::copy(next, next + q + 1, cur);
    }
    std::copy(cur, cur + p + 1, out + static_cast<size_t>(k) * (p + 1));
  }
}

// The derivatives 0..order (order <= p) of the homogeneous numerator A(u) = sum N_{i,p} w_i P_i
// and denominator W(u) = sum N_{i,p} w_i at u in knot span `span`.
struct Homogeneous {
  Vec3 A[kMaxNurbsDegree + 1];
  double W[kMaxNurbsDegree + 1] = {};
};
Homogeneous homogeneous_derivatives(const NurbsCurve& c, int span, double u, int order) {
  const int p = c.degree;
  double d[(kMaxNurbsDegree + 1) * (kMaxNurbsDegree + 1)] = {};
  basis_derivatives_into(span, u, p, c.knots, order, d);
  Homogeneous h;
  for (int k = 0; k <= order; ++k)
    for (int j = 0; j <= p; ++j) {
      const int i = span - p + j;
      const double nw = d[k * (p + 1) + j] * c.weights[i];
      h.A[k] = h.A[k] + nw * c.control[i];
      h.W[k] += nw;
    }
  return h;
}

// What arc-length computations need, built once per curve. The quadrature pieces are 8 equal
// parts of every non-empty knot span; `cumulative` holds the length up to each piece's start.
// The speed |C'| comes from each span's power form in t = u - u_s,
//   A(u) = sum_k a_k t^k,  W(u) = sum_k w_k t^k,  a_k = A^(k)(u_s)/k!, w_k = W^(k)(u_s)/k!
// (exact: A and W are polynomials of degree p on a span), C' = (A' - W' A/W)/W by Horner's
// rule: a few dozen flops per speed instead of the basis recursion with its divisions.
struct ArcLengthTable {
  explicit ArcLengthTable(const NurbsCurve& c);
  // |C'(u)| for u in piece k.
  double speed(size_t k, double u) const;
  // 5-point Gauss-Legendre quadrature of |C'| over [a, b] inside piece k.
  double integral(size_t k, double a, double b) const;

  std::vector<double> breaks;      // piece k is [breaks[k], breaks[k + 1]]; first u_min
  std::vector<double> cumulative;  // arc length from u_min to breaks[k]; last = total

 private:
  struct SpanPolynomial {
    double u0 = 0.0;  // u_s
    Vec3 a[kMaxNurbsDegree + 1];
    double w[kMaxNurbsDegree + 1] = {};
  };
  int degree_;
  std::vector<SpanPolynomial> spans_;
  std::vector<size_t> piece_span_;  // piece -> index into spans_
};

ArcLengthTable::ArcLengthTable(const NurbsCurve& c) : degree_(c.degree) {
  constexpr int kPiecesPerSpan = 8;
  check_degree(c.degree);
  breaks.push_back(c.u_min());
  for (size_t s = c.degree; s < c.control.size(); ++s) {
    const double a = c.knots[s], b = c.knots[s + 1];
    if (!(b > a)) continue;
    const Homogeneous h = homogeneous_derivatives(c, static_cast<int>(s), a, degree_);
    SpanPolynomial poly;
    poly.u0 = a;
    double factorial = 1.0;
    for (int k = 0; k <= degree_; ++k) {
      if (k > 0) factorial *= k;
      poly.a[k] = (1.0 / factorial) * h.A[k];
      poly.w[k] = h.W[k] / factorial;
    }
    spans_.push_back(poly);
    for (int k = 1; k <= kPiecesPerSpan; ++k) {
      breaks.push_back(a + (b - a) * k / kPiecesPerSpan);
      piece_span_.push_back(spans_.size() - 1);
    }
  }
  cumulative.assign(breaks.size(), 0.0);
  for (size_t k = 0; k + 1 < breaks.size(); ++k)
    cumulative[k + 1] = cumulative[k] + integral(k, breaks[k], breaks[k + 1]);
}

double ArcLengthTable::speed(size_t k, double u) const {
  const SpanPolynomial& s = spans_[piece_span_[k]];
  const double t = u - s.u0;
  Vec3 A = s.a[degree_], dA;
  double W = s.w[degree_], dW = 0.0;
  for (int i = degree_ - 1; i >= 0; --i) {
    dA = t * dA + A;
    dW = dW * t + W;
    A = t * A + s.a[i];
    W = W * t + s.w[i];
  }
  return norm((1.0 / W) * (dA - (dW / W) * A));
}

double ArcLengthTable::integral(size_t k, double a, double b) const {
  static constexpr std::array<double, 5> x{0.0, -0.5384693101056831, 0.5384693101056831,
                                           -0.9061798459386640, 0.9061798459386640};
  static constexpr std::array<double, 5> w{0.5688888888888889, 0.4786286704993665,
                                           0.4786286704993665, 0.2369268850561891,
                                           0.2369268850561891};
  const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
  double s = 0.0;
  for (int i = 0; i < 5; ++i) s += w[i] * speed(k, mid + half * x[i]);
  return half * s;
}

}  // namespace

void NurbsCurve::validate() const {
  const size_t n = control.size();
  check_degree(degree);
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
    if (!is_finite(p)) bad("NURBS control point " + std::to_string(i) + " is not finite");
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
  check_degree(p);
  out.assign(static_cast<size_t>(order + 1) * (p + 1), 0.0);
  basis_derivatives_into(span, u, p, knots, std::min(order, p), out.data());
}

CurvePoint evaluate(const NurbsCurve& c, double u) {
  u = clamp_to_domain(c, u);
  check_degree(c.degree);
  const int span = find_span(static_cast<int>(c.control.size()), c.degree, c.knots, u);
  const Homogeneous h = homogeneous_derivatives(c, span, u, std::min(2, c.degree));
  CurvePoint r;
  r.point = (1.0 / h.W[0]) * h.A[0];
  r.first = (1.0 / h.W[0]) * (h.A[1] - h.W[1] * r.point);
  r.second = (1.0 / h.W[0]) * (h.A[2] - 2.0 * h.W[1] * r.first - h.W[2] * r.point);
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
  const ArcLengthTable table(c);
  double length = 0.0;
  for (size_t k = 0; k + 1 < table.breaks.size(); ++k) {
    const double a = std::max(u0, table.breaks[k]), b = std::min(u1, table.breaks[k + 1]);
    if (b > a) length += table.integral(k, a, b);
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
    // Newton on S(u) = S(a) + int_a^u |C'| - target inside the bracketing piece [a, b].
    const ArcLengthTable table(c);
    const std::vector<double>& cum = table.cumulative;
    const double total = cum.back();
    const size_t pieces = cum.size() - 1;
    for (int k = 0; k < count; ++k) {
      const double target = total * k / (count - 1);
      size_t piece = std::upper_bound(cum.begin(), cum.end(), target) - cum.begin();
      piece = std::clamp<size_t>(piece, 1, pieces) - 1;
      const double a = table.breaks[piece], b = table.breaks[piece + 1];
      const double la = cum[piece], lb = cum[piece + 1];
      double u = lb > la ? a + (b - a) * (target - la) / (lb - la) : a;
      for (int it = 0; it < 30; ++it) {
        const double f = la + table.integral(piece, a, u) - target;
        const double df = table.speed(piece, u);
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
