#include "models/material_sheet.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace knitsim {

const char* to_string(SheetEdge e) {
  switch (e) {
    case SheetEdge::XMin:
      return "x_min";
    case SheetEdge::XMax:
      return "x_max";
    case SheetEdge::YMin:
      return "y_min";
    case SheetEdge::YMax:
      return "y_max";
  }
  return "?";
}

namespace {

void require(bool ok, const char* message) {
  if (!ok) throw std::invalid_argument(message);
}

// A value with its gradient and (if Second) its Hessian with respect to N variables: forward-mode
// automatic differentiation of the element energies, exact to round-off. The Hessian is symmetric:
// only its upper triangle h[i N + j], i <= j, is computed (the rest stays zero).
template <int N, bool Second>
struct Jet {
  double v = 0.0;
  std::array<double, N> g{};
  std::array<double, Second ? N * N : 1> h{};

  static Jet variable(double value, int i) {
    Jet r;
    r.v = value;
    r.g[i] = 1.0;
    return r;
  }
  // f(a) with f' = d1, f'' = d2 at a.v.
  Jet chain(double f, double d1, double d2) const {
    Jet r;
    r.v = f;
    for (int i = 0; i < N; ++i) r.g[i] = d1 * g[i];
    if constexpr (Second)
      for (int i = 0; i < N; ++i)
        for (int j = i; j < N; ++j) r.h[i * N + j] = d1 * h[i * N + j] + d2 * g[i] * g[j];
    return r;
  }
};

template <int N, bool S>
Jet<N, S> operator+(const Jet<N, S>& a, const Jet<N, S>& b) {
  Jet<N, S> r;
  r.v = a.v + b.v;
  for (int i = 0; i < N; ++i) r.g[i] = a.g[i] + b.g[i];
  if constexpr (S)
    for (int i = 0; i < N * N; ++i) r.h[i] = a.h[i] + b.h[i];
  return r;
}
template <int N, bool S>
Jet<N, S> operator*(double s, const Jet<N, S>& a) {
  Jet<N, S> r;
  r.v = s * a.v;
  for (int i = 0; i < N; ++i) r.g[i] = s * a.g[i];
  if constexpr (S)
    for (int i = 0; i < N * N; ++i) r.h[i] = s * a.h[i];
  return r;
}
template <int N, bool S>
Jet<N, S> operator-(const Jet<N, S>& a, const Jet<N, S>& b) {
  return a + (-1.0) * b;
}
template <int N, bool S>
Jet<N, S> operator+(const Jet<N, S>& a, double c) {
  Jet<N, S> r = a;
  r.v += c;
  return r;
}
template <int N, bool S>
Jet<N, S> operator*(const Jet<N, S>& a, const Jet<N, S>& b) {
  Jet<N, S> r;
  r.v = a.v * b.v;
  for (int i = 0; i < N; ++i) r.g[i] = a.v * b.g[i] + b.v * a.g[i];
  if constexpr (S)
    for (int i = 0; i < N; ++i)
      for (int j = i; j < N; ++j)
        r.h[i * N + j] =
            a.v * b.h[i * N + j] + b.v * a.h[i * N + j] + a.g[i] * b.g[j] + b.g[i] * a.g[j];
  return r;
}
template <int N, bool S>
Jet<N, S> sqrt(const Jet<N, S>& a) {
  const double s = std::sqrt(a.v);
  return a.chain(s, 0.5 / s, -0.25 / (s * a.v));
}
template <int N, bool S>
Jet<N, S> operator/(const Jet<N, S>& a, const Jet<N, S>& b) {
  const double r = 1.0 / b.v;
  return a * b.chain(r, -r * r, 2.0 * r * r * r);
}

// Each element's energy is a function of 6 variables u, two 3-vectors that are fixed linear
// combinations of its 3 vertices: u_(c, k) = sum_v alpha[c][v] x_(v, k) (c = 0, 1; k = x, y, z),
// stored u[3 c + k]. Differentiating in u and mapping back (g_x = alpha^T g_u, H_x = alpha^T H_u
// alpha per coordinate pair) costs a quarter of differentiating in the 9 coordinates.
using Alpha = std::array<std::array<double, 3>, 2>;

// Triangle: u = the two columns of F = [x1 - x0, x2 - x0] D^-1.
Alpha membrane_alpha(const MaterialSheet::Triangle& tri) {
  const double* d = tri.dinv;
  return {{{-(d[0] + d[2]), d[0], d[2]}, {-(d[1] + d[3]), d[1], d[3]}}};
}

// Stencil (a, centre, b): u = (e1, e2) = (x_c - x_a, x_b - x_c).
constexpr Alpha kBendAlpha{{{-1.0, 1.0, 0.0}, {0.0, -1.0, 1.0}}};

// Membrane energy of one triangle from the columns f0 = u[0..2], f1 = u[3..5] of F.
template <class T>
T membrane_energy(const std::array<T, 6>& u, const MaterialSheet::Triangle& tri, double c11,
                  double c12, double c22, double c66) {
  const std::array<T, 3> f0{u[0], u[1], u[2]}, f1{u[3], u[4], u[5]};
  const T c00 = f0[0] * f0[0] + f0[1] * f0[1] + f0[2] * f0[2];
  const T c01 = f0[0] * f1[0] + f0[1] * f1[1] + f0[2] * f1[2];
  const T cc11 = f1[0] * f1[0] + f1[1] * f1[1] + f1[2] * f1[2];
  const T e11 = 0.5 * (c00 + (-1.0)), e22 = 0.5 * (cc11 + (-1.0)), e12 = 0.5 * c01;
  const T w = (0.5 * c11) * (e11 * e11) + c12 * (e11 * e22) + (0.5 * c22) * (e22 * e22) +
              (2.0 * c66) * (e12 * e12);
  return tri.area * w;
}

// Bending energy of one stencil from its edges e1 = u[0..2], e2 = u[3..5]:
// stiffness/2 x 4 tan^2(phi/2).
template <class T>
T bending_energy(const std::array<T, 6>& u, double stiffness) {
  const std::array<T, 3> e1{u[0], u[1], u[2]}, e2{u[3], u[4], u[5]};
  const T l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  const T l2 = sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
  const T d = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2];
  const T p = l1 * l2;
  return (2.0 * stiffness) * ((p - d) / (p + d));
}

double edge_weight(int k, int n) { return (k == 0 || k == n) ? 0.5 : 1.0; }

// One element's energy e at its vertices' positions p and its derivatives in their 9
// coordinates (index 3 a + k: vertex a, coordinate k): g = dE/dx (alpha^T g_u) and, with
// Hessian, h[9 (3 a + k) + 3 b + l] = d^2E / dx_(a,k) dx_(b,l) (alpha^T H_u alpha).
template <bool Hessian, class EnergyOf>
double element_derivatives(const Vec3 (&p)[3], const Alpha& alpha, EnergyOf&& energy_of,
                           double (&g)[9], double* h) {
  using J = Jet<6, Hessian>;
  std::array<J, 6> u;
  for (int c = 0; c < 2; ++c) {
    const Vec3 w = alpha[c][0] * p[0] + alpha[c][1] * p[1] + alpha[c][2] * p[2];
    u[3 * c] = J::variable(w.x, 3 * c);
    u[3 * c + 1] = J::variable(w.y, 3 * c + 1);
    u[3 * c + 2] = J::variable(w.z, 3 * c + 2);
  }
  const J e = energy_of(u);
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 3; ++k) g[3 * a + k] = alpha[0][a] * e.g[k] + alpha[1][a] * e.g[3 + k];
  if constexpr (Hessian) {
    double hu[36];  // H_u in full from its upper triangle
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) hu[6 * i + j] = i <= j ? e.h[6 * i + j] : e.h[6 * j + i];
    for (int a = 0; a < 3; ++a)
      for (int k = 0; k < 3; ++k)
        for (int b = 0; b < 3; ++b)
          for (int l = 0; l < 3; ++l) {
            double sum = 0.0;
            for (int c = 0; c < 2; ++c)
              for (int d = 0; d < 2; ++d)
                sum += alpha[c][a] * alpha[d][b] * hu[6 * (3 * c + k) + 3 * d + l];
            h[9 * (3 * a + k) + 3 * b + l] = sum;
          }
  }
  return e.v;
}

}  // namespace

int MaterialSheetParams::cells_y() const {
  if (cells_length > 0) return cells_length;
  return std::max(1, static_cast<int>(std::lround(cells * length / width)));
}

void MaterialSheetParams::validate() const {
  auto positive = [](double v, double hi) { return std::isfinite(v) && v > 0.0 && v <= hi; };
  require(positive(width, 100.0), "material sheet: width must be in (0, 100] m");
  require(positive(length, 100.0), "material sheet: length must be in (0, 100] m");
  require(cells >= 1 && cells <= 2000, "material sheet: cells must be in [1, 2000]");
  require(cells_length >= 0 && cells_length <= 20000,
          "material sheet: cells_length must be in [0, 20000]");
  require(cells_y() <= 20000, "material sheet: cells x length / width must be <= 20000");
  require(std::isfinite(areal_density) && areal_density >= 0.0,
          "material sheet: areal_density must be >= 0 g/m^2");
  require(positive(membrane_wale, 1e12), "material sheet: membrane_wale must be in (0, 1e12] N/m");
  require(positive(membrane_course, 1e12),
          "material sheet: membrane_course must be in (0, 1e12] N/m");
  require(positive(membrane_shear, 1e12),
          "material sheet: membrane_shear must be in (0, 1e12] N/m");
  require(
      std::isfinite(poisson_cw) && poisson_cw * poisson_cw * membrane_wale / membrane_course < 1.0,
      "material sheet: poisson_cw must satisfy poisson_cw^2 membrane_wale / membrane_course < 1");
  require(positive(bending_wale, 1e3), "material sheet: bending_wale must be in (0, 1e3] N m");
  require(positive(bending_course, 1e3), "material sheet: bending_course must be in (0, 1e3] N m");
  require(std::isfinite(damping_rate) && damping_rate >= 0.0,
          "material sheet: damping_rate must be >= 0 1/s");
  require(is_finite(gravity), "material sheet: gravity must be finite");
  for (const SheetEdgeLoad& l : loads)
    require(is_finite(l.force_per_length), "material sheet: edge load must be finite");
  for (const SheetClamp& c : clamps)
    require(std::isfinite(c.length) && c.length > 0.0,
            "material sheet: clamp length must be > 0 m");
  for (const SheetPatch& p : patches)
    require(std::isfinite(p.x0) && std::isfinite(p.x1) && std::isfinite(p.y0) &&
                std::isfinite(p.y1) && p.x0 <= p.x1 && p.y0 <= p.y1,
            "material sheet: a clamp patch must be a finite rectangle (x0 <= x1, y0 <= y1)");
}

MaterialSheet::MaterialSheet(MaterialSheetParams params) : params_(std::move(params)) {
  params_.validate();
  nx_ = params_.cells_x();
  ny_ = params_.cells_y();
  hx_ = params_.width / nx_;
  hy_ = params_.length / ny_;
  const double nu = params_.poisson_cw, aw = params_.membrane_wale, ac = params_.membrane_course;
  const double den = 1.0 - nu * nu * aw / ac;
  c11_ = ac / den;
  c22_ = aw / den;
  c12_ = nu * aw / den;
  c66_ = params_.membrane_shear;

  const int nv = vertex_count();
  // Clamps.
  std::vector<bool> clamped(nv, false);
  for (const SheetClamp& c : params_.clamps) {
    const bool along_x = c.edge == SheetEdge::XMin || c.edge == SheetEdge::XMax;
    const double h = along_x ? hx_ : hy_;
    const int across = along_x ? nx_ : ny_;
    const int k = 1 + static_cast<int>(std::lround(c.length / h));
    if (k < 2 || k > across + 1)
      throw std::invalid_argument(
          "material sheet: clamp length must hold between 2 rows and the whole sheet (>= h/2 and "
          "<= the sheet's extent across the clamped edge)");
    for (int i = 0; i <= ny_; ++i)
      for (int j = 0; j <= nx_; ++j) {
        const int r = c.edge == SheetEdge::XMin   ? j
                      : c.edge == SheetEdge::XMax ? nx_ - j
                      : c.edge == SheetEdge::YMin ? i
                                                  : ny_ - i;
        if (r < k) clamped[vertex(i, j)] = true;
      }
  }
  for (const SheetPatch& p : params_.patches) {
    const double ex = 1e-9 * hx_, ey = 1e-9 * hy_;
    int rows = 0, cols = 0;
    for (int i = 0; i <= ny_; ++i) rows += (i * hy_ >= p.y0 - ey && i * hy_ <= p.y1 + ey);
    for (int j = 0; j <= nx_; ++j) cols += (j * hx_ >= p.x0 - ex && j * hx_ <= p.x1 + ex);
    if (rows < 2 || cols < 2)
      throw std::invalid_argument(
          "material sheet: a clamp patch must hold at least 2 x 2 vertices (at least one cell "
          "in each direction)");
    for (int i = 0; i <= ny_; ++i)
      for (int j = 0; j <= nx_; ++j)
        if (i * hy_ >= p.y0 - ey && i * hy_ <= p.y1 + ey && j * hx_ >= p.x0 - ex &&
            j * hx_ <= p.x1 + ex)
          clamped[vertex(i, j)] = true;
  }
  free_index_.assign(nv, -1);
  free_count_ = 0;
  for (int v = 0; v < nv; ++v)
    if (!clamped[v]) free_index_[v] = free_count_++;

  // Masses and edge loads.
  const double rho = params_.areal_density * 1e-3;  // kg/m^2
  vertex_mass_.assign(nv, 0.0);
  vertex_load_.assign(nv, Vec3{});
  for (int i = 0; i <= ny_; ++i)
    for (int j = 0; j <= nx_; ++j)
      vertex_mass_[vertex(i, j)] = rho * hx_ * hy_ * edge_weight(i, ny_) * edge_weight(j, nx_);
  for (const SheetEdgeLoad& l : params_.loads) {
    const bool along_y =
        l.edge == SheetEdge::XMin || l.edge == SheetEdge::XMax;  // edge runs along y
    const int count = along_y ? ny_ : nx_;
    const double h = along_y ? hy_ : hx_;
    for (int k = 0; k <= count; ++k) {
      const int v = l.edge == SheetEdge::XMin   ? vertex(k, 0)
                    : l.edge == SheetEdge::XMax ? vertex(k, nx_)
                    : l.edge == SheetEdge::YMin ? vertex(0, k)
                                                : vertex(ny_, k);
      vertex_load_[v] = vertex_load_[v] + (h * edge_weight(k, count)) * l.force_per_length;
    }
  }
  const int n = dof();
  gamma_.assign(n, params_.damping_rate);
  dof_mass_.assign(n, 0.0);
  double weight_sum = 0.0, load_max = 0.0;
  for (int v = 0; v < nv; ++v) {
    const int f = free_index_[v];
    if (f < 0) continue;
    require(vertex_mass_[v] > 0.0, "material sheet: areal_density must be > 0 g/m^2");
    for (int c = 0; c < 3; ++c) dof_mass_[3 * f + c] = vertex_mass_[v];
    weight_sum += vertex_mass_[v] * norm(params_.gravity);
    load_max = std::max(load_max, norm(vertex_load_[v]));
  }
  require(free_count_ > 0, "material sheet: the clamps hold every vertex");
  force_scale_ = weight_sum > 0.0 ? weight_sum / free_count_ : load_max;
  require(force_scale_ > 0.0, "material sheet: needs gravity or an edge load");

  // Elements: 4 half-weight triangles per cell (both diagonals), bending stencils on rows and
  // columns; elements whose vertices are all clamped are constant and left out.
  auto any_free = [&](std::initializer_list<int> vs) {
    for (int v : vs)
      if (free_index_[v] >= 0) return true;
    return false;
  };
  auto add_triangle = [&](int a, int b, int c) {
    if (!any_free({a, b, c})) return;
    const Vec3 pa = rest_position(a), pb = rest_position(b), pc = rest_position(c);
    const double m00 = pb.x - pa.x, m01 = pc.x - pa.x, m10 = pb.y - pa.y, m11 = pc.y - pa.y;
    const double det = m00 * m11 - m01 * m10;
    Triangle t{{a, b, c}, {m11 / det, -m01 / det, -m10 / det, m00 / det}, 0.25 * std::abs(det)};
    triangles_.push_back(t);
  };
  for (int i = 0; i < ny_; ++i)
    for (int j = 0; j < nx_; ++j) {
      const int v00 = vertex(i, j), v10 = vertex(i, j + 1), v01 = vertex(i + 1, j),
                v11 = vertex(i + 1, j + 1);
      add_triangle(v00, v10, v11);
      add_triangle(v00, v11, v01);
      add_triangle(v00, v10, v01);
      add_triangle(v10, v11, v01);
    }
  for (int i = 0; i <= ny_; ++i)
    for (int j = 1; j < nx_; ++j) {  // rows: curvature along x (courses)
      const int a = vertex(i, j - 1), c = vertex(i, j), b = vertex(i, j + 1);
      if (any_free({a, b, c}))
        stencils_.push_back({{a, c, b}, params_.bending_course * hy_ * edge_weight(i, ny_) / hx_});
    }
  for (int j = 0; j <= nx_; ++j)
    for (int i = 1; i < ny_; ++i) {  // columns: curvature along y (wales)
      const int a = vertex(i - 1, j), c = vertex(i, j), b = vertex(i + 1, j);
      if (any_free({a, b, c}))
        stencils_.push_back({{a, c, b}, params_.bending_wale * hx_ * edge_weight(j, nx_) / hy_});
    }

  // A stencil centred on a clamp's last row, across it: the clamped side is straight, so its
  // turning angle is that of the free side alone, kappa h / 2 + O(h^2), half an interior one; the
  // energy it stands for is the free half cell's, 1/2 B kappa^2 h/2. Both together: twice the
  // interior stiffness (the linear limit is the clamped beam's mirror-ghost scheme, second order).
  for (BendStencil& s : stencils_)
    if (free_index_[s.v[1]] < 0 && (free_index_[s.v[0]] < 0) != (free_index_[s.v[2]] < 0))
      s.stiffness *= 2.0;

  // Stiffness pattern: every ordered pair of free vertices of an element.
  std::vector<std::pair<int, int>> pairs;
  auto element_pairs = [&](const int* vs) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const int r = free_index_[vs[a]], c = free_index_[vs[b]];
        if (r >= 0 && c >= 0) pairs.emplace_back(r, c);
      }
  };
  for (const Triangle& t : triangles_) element_pairs(t.v);
  for (const BendStencil& s : stencils_) element_pairs(s.v);
  std::vector<int> position;
  nodes_ = make_csc_pattern(free_count_, free_count_, pairs, /*with_diagonal=*/true, &position);
  pattern_ = expand_node_pattern(nodes_);
  int next = 0;
  auto slots = [&](const int* vs, std::vector<int>& out) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const bool both = free_index_[vs[a]] >= 0 && free_index_[vs[b]] >= 0;
        out.push_back(both ? position[next++] : -1);
      }
  };
  for (const Triangle& t : triangles_) slots(t.v, tri_slots_);
  for (const BendStencil& s : stencils_) slots(s.v, stencil_slots_);
}

Vec3 MaterialSheet::rest_position(int v) const {
  const int i = v / (nx_ + 1), j = v % (nx_ + 1);
  return {j * hx_, i * hy_, 0.0};
}

Vec3 MaterialSheet::position(const double* x, int v) const {
  const int f = free_index_[v];
  if (f < 0) return rest_position(v);
  return {x[3 * f], x[3 * f + 1], x[3 * f + 2]};
}

void MaterialSheet::initial_state(double* x, double* v) const {
  for (int p = 0; p < vertex_count(); ++p) {
    const int f = free_index_[p];
    if (f < 0) continue;
    const Vec3 r = rest_position(p);
    x[3 * f] = r.x;
    x[3 * f + 1] = r.y;
    x[3 * f + 2] = r.z;
  }
  std::fill(v, v + dof(), 0.0);
}

template <bool Hessian>
void MaterialSheet::assemble(const double* x, double* energy, double* force, double* values) const {
  using J = Jet<6, Hessian>;
  auto element = [&](const int* vs, const int* slot, const Alpha& alpha, auto&& energy_of) {
    const Vec3 p[3] = {position(x, vs[0]), position(x, vs[1]), position(x, vs[2])};
    double g[9], h[Hessian ? 81 : 1];
    const double e = element_derivatives<Hessian>(p, alpha, energy_of, g, h);
    if (energy) *energy += e;
    for (int a = 0; a < 3; ++a) {
      const int fa = free_index_[vs[a]];
      if (fa < 0) continue;
      if (force)
        for (int k = 0; k < 3; ++k) force[3 * fa + k] -= g[3 * a + k];
      if constexpr (Hessian) {
        const double inv_m = 1.0 / vertex_mass_[vs[a]];
        for (int b = 0; b < 3; ++b) {
          const int entry = slot[3 * a + b];
          if (entry < 0) continue;
          const int fb = free_index_[vs[b]];
          for (int k = 0; k < 3; ++k)
            for (int l = 0; l < 3; ++l)
              values[node_block_entry(nodes_, entry, fb, k, l)] -=
                  inv_m * h[9 * (3 * a + k) + 3 * b + l];
        }
      }
    }
  };
  for (std::size_t k = 0; k < triangles_.size(); ++k) {
    const Triangle& t = triangles_[k];
    element(t.v, &tri_slots_[9 * k], membrane_alpha(t), [&](const std::array<J, 6>& u) {
      return membrane_energy(u, t, c11_, c12_, c22_, c66_);
    });
  }
  for (std::size_t k = 0; k < stencils_.size(); ++k) {
    const BendStencil& s = stencils_[k];
    element(s.v, &stencil_slots_[9 * k], kBendAlpha,
            [&](const std::array<J, 6>& u) { return bending_energy(u, s.stiffness); });
  }
}

void MaterialSheet::net_force(const double* x, double* f) const {
  std::fill(f, f + dof(), 0.0);
  assemble<false>(x, nullptr, f, nullptr);
  for (int v = 0; v < vertex_count(); ++v) {
    const int fv = free_index_[v];
    if (fv < 0) continue;
    const Vec3 ext = vertex_mass_[v] * params_.gravity + vertex_load_[v];
    f[3 * fv] += ext.x;
    f[3 * fv + 1] += ext.y;
    f[3 * fv + 2] += ext.z;
  }
}

void MaterialSheet::conservative_acceleration(double /*t*/, const double* x, double* a) const {
  net_force(x, a);
  for (int i = 0; i < dof(); ++i) a[i] /= dof_mass_[i];
}

void MaterialSheet::constant_acceleration(double /*t*/, double* a) const {
  for (int v = 0; v < vertex_count(); ++v) {
    const int f = free_index_[v];
    if (f < 0) continue;
    const Vec3 acc = params_.gravity + (1.0 / vertex_mass_[v]) * vertex_load_[v];
    a[3 * f] = acc.x;
    a[3 * f + 1] = acc.y;
    a[3 * f + 2] = acc.z;
  }
}

void MaterialSheet::stiffness_values(double /*t*/, const double* x, double* values) const {
  std::fill(values, values + pattern_.nnz(), 0.0);
  assemble<true>(x, nullptr, nullptr, values);
}

double MaterialSheet::static_residual(double /*t*/, const double* x) const {
  std::vector<double> f(dof());
  net_force(x, f.data());
  double worst = 0.0;
  for (int i = 0; i < free_count_; ++i)
    worst = std::max(worst, std::sqrt(f[3 * i] * f[3 * i] + f[3 * i + 1] * f[3 * i + 1] +
                                      f[3 * i + 2] * f[3 * i + 2]));
  return worst / force_scale_;
}

double MaterialSheet::potential_energy(double /*t*/, const double* x) const {
  double e = 0.0;
  assemble<false>(x, &e, nullptr, nullptr);
  for (int v = 0; v < vertex_count(); ++v)
    if (free_index_[v] >= 0)
      e -= dot(vertex_mass_[v] * params_.gravity + vertex_load_[v], position(x, v));
  return e;
}

std::string MaterialSheet::describe() const {
  std::ostringstream s;
  s << "material sheet " << params_.width << " x " << params_.length << " m, " << nx_ << " x "
    << ny_ << " cells, " << free_count_ << " free vertices";
  return s.str();
}

}  // namespace knitsim

// ---- Mirrors (MirroredSheet) -----------------------------------------------------------------

namespace knitsim {

namespace {

// One element of a sheet's mirror group, g = Y^fy X^fx D^s (D first): its vertex map and its
// action on a position, x_out[k] = sign[k] x_in[perm[k]] + offset[k].
struct Mirror {
  std::vector<int> vertex;
  int perm[3];
  double sign[3], offset[3];
};

std::vector<Mirror> mirror_group(const MaterialSheet& s, SheetMirrors m) {
  const int nx = s.nx(), ny = s.ny();
  const double w = nx * s.hx(), l = ny * s.hy();
  std::vector<Mirror> group;
  for (int d = 0; d <= (m.diagonal ? 1 : 0); ++d)
    for (int fx = 0; fx <= (m.x ? 1 : 0); ++fx)
      for (int fy = 0; fy <= (m.y ? 1 : 0); ++fy) {
        Mirror g;
        g.vertex.resize(s.vertex_count());
        for (int i = 0; i <= ny; ++i)
          for (int j = 0; j <= nx; ++j) {
            int a = i, b = j;
            if (d) std::swap(a, b);  // the diagonal needs nx == ny (sheet_lacks checks it)
            if (fx) b = nx - b;
            if (fy) a = ny - a;
            g.vertex[s.vertex(i, j)] = (a >= 0 && a <= ny && b >= 0 && b <= nx) ? s.vertex(a, b) : -1;
          }
        // Positions: D swaps x and y (a square: W = L), X takes x to W - x, Y y to L - y.
        int perm[3] = {d ? 1 : 0, d ? 0 : 1, 2};
        for (int k = 0; k < 3; ++k) g.perm[k] = perm[k], g.sign[k] = 1.0, g.offset[k] = 0.0;
        if (fx) g.sign[0] = -1.0, g.offset[0] = w;
        if (fy) g.sign[1] = -1.0, g.offset[1] = l;
        group.push_back(std::move(g));
      }
  return group;
}

Vec3 apply_linear(const Mirror& g, const Vec3& v) {  // the mirror's linear part (forces, loads)
  const double in[3] = {v.x, v.y, v.z};
  return {g.sign[0] * in[g.perm[0]], g.sign[1] * in[g.perm[1]], g.sign[2] * in[g.perm[2]]};
}

bool near(double a, double b) { return std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b)); }
bool near(const Vec3& a, const Vec3& b) {
  const double s = std::max(norm(a), norm(b));
  return norm(a - b) <= 1e-12 * s;
}

std::array<int, 3> sorted_key(int a, int b, int c) {
  std::array<int, 3> k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

}  // namespace

std::string sheet_lacks(const MaterialSheet& s, SheetMirrors m) {
  if (m.diagonal && !(m.x && m.y)) return "the diagonal mirror comes with the x and y mirrors";
  if (m.order() == 1) return "";
  const MaterialSheetParams& p = s.params();
  if (m.diagonal) {
    if (!(s.nx() == s.ny() && s.hx() == s.hy()))
      return "the diagonal mirror needs a square sheet on a square mesh (fabric.length = "
             "fabric.width)";
    if (!(p.membrane_wale == p.membrane_course && p.bending_wale == p.bending_course))
      return "the diagonal mirror needs an isotropic sheet (material.membrane_wale = "
             "material.membrane_course and material.bending_wale = material.bending_course; "
             "here A_w = " + std::to_string(p.membrane_wale) + ", A_c = " +
             std::to_string(p.membrane_course) + " N/m, B_w = " + std::to_string(p.bending_wale) +
             ", B_c = " + std::to_string(p.bending_course) + " N m)";
  }
  const char* names[3] = {"x", "y", "diagonal"};
  // Check each generator alone (the group they generate then maps the sheet onto itself).
  for (int which = 0; which < 3; ++which) {
    if (!(which == 0 ? m.x : which == 1 ? m.y : m.diagonal)) continue;
    SheetMirrors one;
    (which == 0 ? one.x : which == 1 ? one.y : one.diagonal) = true;
    if (which == 2) one.x = one.y = true;
    const std::vector<Mirror> group = mirror_group(s, one);
    // The generator: x alone, y alone, or D itself (s = 1, no flips: the 5th element).
    const Mirror& g = which == 2 ? group[4] : group[1];
    const std::string what = std::string("the ") + names[which] + " mirror: ";
    if (!near(apply_linear(g, p.gravity), p.gravity))
      return what + "gravity is not symmetric";
    for (int v = 0; v < s.vertex_count(); ++v) {
      const int u = g.vertex[v];
      if ((s.free_index(v) < 0) != (s.free_index(u) < 0))
        return what + "the clamps are not symmetric";
      if (!near(s.vertex_mass_[u], s.vertex_mass_[v])) return what + "the masses are not symmetric";
      if (!near(apply_linear(g, s.vertex_load_[v]), s.vertex_load_[u]))
        return what + "the edge loads are not symmetric";
    }
    std::map<std::array<int, 3>, double> stiffness;
    for (const MaterialSheet::BendStencil& b : s.stencils_)
      stiffness[sorted_key(b.v[0], b.v[1], b.v[2])] = b.stiffness;
    for (const MaterialSheet::BendStencil& b : s.stencils_) {
      const auto it = stiffness.find(sorted_key(g.vertex[b.v[0]], g.vertex[b.v[1]], g.vertex[b.v[2]]));
      if (it == stiffness.end() || !near(it->second, b.stiffness))
        return what + "the bending stiffness is not symmetric";
    }
  }
  return "";
}

SheetMirrors largest_mirrors(const MaterialSheet& s) {
  for (SheetMirrors m : {SheetMirrors{true, true, true}, SheetMirrors{true, true, false},
                         SheetMirrors{true, false, false}, SheetMirrors{false, true, false}})
    if (sheet_lacks(s, m).empty()) return m;
  return {};
}

MirroredSheet::MirroredSheet(std::shared_ptr<const MaterialSheet> sheet, SheetMirrors m)
    : sheet_(std::move(sheet)), mirrors_(m) {
  const MaterialSheet& s = *sheet_;
  if (const std::string why = sheet_lacks(s, m); !why.empty()) throw std::invalid_argument(why);
  const std::vector<Mirror> group = mirror_group(s, m);
  const int order = static_cast<int>(group.size());
  const int nv = s.vertex_count(), nx = s.nx(), ny = s.ny();
  const double cx = 0.5 * nx * s.hx(), cy = 0.5 * ny * s.hy();
  auto in_domain = [&](int v) {
    const int i = v / (nx + 1), j = v % (nx + 1);
    return (!m.x || 2 * j <= nx) && (!m.y || 2 * i <= ny) && (!m.diagonal || i <= j);
  };
  // Representatives: the free vertices of the domain, in vertex order, with their entries.
  std::vector<int> rep_entry(3 * nv, -1);
  std::vector<double> rep_offset(3 * nv, 0.0);
  for (int v = 0; v < nv; ++v) {
    if (!in_domain(v) || s.free_index(v) < 0) continue;
    const int i = v / (nx + 1), j = v % (nx + 1);
    const bool on_x = m.x && 2 * j == nx, on_y = m.y && 2 * i == ny, on_d = m.diagonal && i == j;
    std::set<int> orbit;
    for (const Mirror& g : group) orbit.insert(g.vertex[v]);
    Rep r{v, static_cast<double>(orbit.size()) / order, static_cast<int>(mult_.size()), 0};
    if (on_x) {
      rep_offset[3 * v] = cx;
    } else {
      rep_entry[3 * v] = static_cast<int>(mult_.size());
      mult_.push_back(on_d && !on_y ? 2 : 1);
    }
    if (on_y || (on_d && on_x)) {
      rep_offset[3 * v + 1] = cy;
    } else if (on_d) {
      rep_entry[3 * v + 1] = rep_entry[3 * v];  // y - c_y = x - c_x
      rep_offset[3 * v + 1] = cy - cx;
    } else {
      rep_entry[3 * v + 1] = static_cast<int>(mult_.size());
      mult_.push_back(1);
    }
    rep_entry[3 * v + 2] = static_cast<int>(mult_.size());
    mult_.push_back(1);
    r.count = static_cast<int>(mult_.size()) - r.first;
    reps_.push_back(r);
  }
  // Every vertex's coordinates from its representative's: x_p = g(x_r), g(r) = p.
  index_.assign(3 * nv, -1);
  sign_.assign(3 * nv, 0.0);
  offset_.assign(3 * nv, 0.0);
  for (int r = 0; r < nv; ++r) {
    if (!in_domain(r)) continue;
    for (const Mirror& g : group) {
      const int p = g.vertex[r];
      if (s.free_index(p) < 0) {
        const Vec3 x = s.rest_position(p);
        offset_[3 * p] = x.x, offset_[3 * p + 1] = x.y, offset_[3 * p + 2] = x.z;
        continue;
      }
      for (int k = 0; k < 3; ++k) {
        const int c = g.perm[k];
        index_[3 * p + k] = rep_entry[3 * r + c];
        sign_[3 * p + k] = g.sign[k];
        offset_[3 * p + k] = g.sign[k] * rep_offset[3 * r + c] + g.offset[k];
      }
    }
  }
  // One element of each orbit (the least by its sorted vertices), weighted |O| / |G|.
  auto pick = [&](const int* v, std::vector<int>& kept, std::vector<double>& weight, int e) {
    const std::array<int, 3> own = sorted_key(v[0], v[1], v[2]);
    std::set<std::array<int, 3>> orbit;
    for (const Mirror& g : group) {
      const std::array<int, 3> k = sorted_key(g.vertex[v[0]], g.vertex[v[1]], g.vertex[v[2]]);
      if (k < own) return;
      orbit.insert(k);
    }
    kept.push_back(e);
    weight.push_back(static_cast<double>(orbit.size()) / order);
  };
  for (std::size_t e = 0; e < s.triangles_.size(); ++e)
    pick(s.triangles_[e].v, triangles_, tri_weight_, static_cast<int>(e));
  for (std::size_t e = 0; e < s.stencils_.size(); ++e)
    pick(s.stencils_[e].v, stencils_, stencil_weight_, static_cast<int>(e));

  // Masses, damping, and the pattern: every pair of entries an element's coordinates touch.
  const int n = static_cast<int>(mult_.size());
  mass_.assign(n, 0.0);
  for (const Rep& r : reps_)
    for (int j = r.first; j < r.first + r.count; ++j)
      mass_[j] = mult_[j] * r.weight * s.vertex_mass_[r.vertex];
  gamma_.assign(n, s.params().damping_rate);
  std::vector<std::pair<int, int>> pairs;
  auto element_pairs = [&](const int* v) {
    for (int a = 0; a < 9; ++a)
      for (int b = 0; b < 9; ++b) {
        const int r = index_[3 * v[a / 3] + a % 3], c = index_[3 * v[b / 3] + b % 3];
        if (r >= 0 && c >= 0) pairs.emplace_back(r, c);
      }
  };
  for (int e : triangles_) element_pairs(s.triangles_[e].v);
  for (int e : stencils_) element_pairs(s.stencils_[e].v);
  std::vector<int> position;
  pattern_ = make_csc_pattern(n, n, pairs, /*with_diagonal=*/true, &position);
  int next = 0;
  auto slots = [&](const int* v, std::vector<int>& out) {
    for (int a = 0; a < 9; ++a)
      for (int b = 0; b < 9; ++b) {
        const bool both = index_[3 * v[a / 3] + a % 3] >= 0 && index_[3 * v[b / 3] + b % 3] >= 0;
        out.push_back(both ? position[next++] : -1);
      }
  };
  for (int e : triangles_) slots(s.triangles_[e].v, tri_slots_);
  for (int e : stencils_) slots(s.stencils_[e].v, stencil_slots_);
}

double MirroredSheet::coordinate(const double* q, int v, int k) const {
  const int j = index_[3 * v + k];
  return j < 0 ? offset_[3 * v + k] : sign_[3 * v + k] * q[j] + offset_[3 * v + k];
}

void MirroredSheet::initial_state(double* q, double* v) const {
  for (const Rep& r : reps_) {
    const Vec3 x = sheet_->rest_position(r.vertex);
    const double c[3] = {x.x, x.y, x.z};
    for (int k = 2; k >= 0; --k) {  // z, then y, then x (a diagonal's y shares x's entry)
      const int j = index_[3 * r.vertex + k];
      if (j >= 0) q[j] = c[k] - offset_[3 * r.vertex + k];  // a representative's sign is +1
    }
  }
  std::fill(v, v + dof(), 0.0);
}

void MirroredSheet::unfold(const double* q, double* x_full) const {
  const MaterialSheet& s = *sheet_;
  for (int v = 0; v < s.vertex_count(); ++v) {
    const int f = s.free_index(v);
    if (f < 0) continue;
    for (int k = 0; k < 3; ++k) x_full[3 * f + k] = coordinate(q, v, k);
  }
}

template <bool Hessian>
void MirroredSheet::assemble(const double* q, double* energy, double* force, double* values) const {
  using J = Jet<6, Hessian>;
  const MaterialSheet& s = *sheet_;
  auto element = [&](const int* vs, double weight, const int* slot, const Alpha& alpha,
                     auto&& energy_of) {
    Vec3 p[3];
    for (int a = 0; a < 3; ++a)
      p[a] = {coordinate(q, vs[a], 0), coordinate(q, vs[a], 1), coordinate(q, vs[a], 2)};
    double g[9], h[Hessian ? 81 : 1];
    const double e = element_derivatives<Hessian>(p, alpha, energy_of, g, h);
    if (energy) *energy += weight * e;
    // Through the tie x = sign q[index] + offset: dE_R/dq = weight sign g, and likewise H.
    int idx[9];
    double sg[9];
    for (int a = 0; a < 9; ++a)
      idx[a] = index_[3 * vs[a / 3] + a % 3], sg[a] = sign_[3 * vs[a / 3] + a % 3];
    for (int a = 0; a < 9; ++a) {
      if (idx[a] < 0) continue;
      if (force) force[idx[a]] -= weight * sg[a] * g[a];
      if constexpr (Hessian) {
        const double row = weight * sg[a] / mass_[idx[a]];
        for (int b = 0; b < 9; ++b)
          if (slot[9 * a + b] >= 0) values[slot[9 * a + b]] -= row * sg[b] * h[9 * a + b];
      }
    }
  };
  for (std::size_t k = 0; k < triangles_.size(); ++k) {
    const MaterialSheet::Triangle& t = s.triangles_[triangles_[k]];
    element(t.v, tri_weight_[k], &tri_slots_[81 * k], membrane_alpha(t),
            [&](const std::array<J, 6>& u) {
              return membrane_energy(u, t, s.c11_, s.c12_, s.c22_, s.c66_);
            });
  }
  for (std::size_t k = 0; k < stencils_.size(); ++k) {
    const MaterialSheet::BendStencil& b = s.stencils_[stencils_[k]];
    element(b.v, stencil_weight_[k], &stencil_slots_[81 * k], kBendAlpha,
            [&](const std::array<J, 6>& u) { return bending_energy(u, b.stiffness); });
  }
  // Gravity and edge loads on the representatives, weighted.
  for (const Rep& r : reps_) {
    const Vec3 f = s.vertex_mass_[r.vertex] * s.params().gravity + s.vertex_load_[r.vertex];
    const double fc[3] = {f.x, f.y, f.z};
    for (int k = 0; k < 3; ++k) {
      if (energy) *energy -= r.weight * fc[k] * coordinate(q, r.vertex, k);
      const int j = index_[3 * r.vertex + k];
      if (force && j >= 0) force[j] += r.weight * fc[k];
    }
  }
}

void MirroredSheet::conservative_acceleration(double /*t*/, const double* q, double* a) const {
  std::fill(a, a + dof(), 0.0);
  assemble<false>(q, nullptr, a, nullptr);
  for (int i = 0; i < dof(); ++i) a[i] /= mass_[i];
}

void MirroredSheet::constant_acceleration(double /*t*/, double* a) const {
  std::fill(a, a + dof(), 0.0);
  for (const Rep& r : reps_) {
    const Vec3 f = sheet_->vertex_mass_[r.vertex] * sheet_->params().gravity +
                   sheet_->vertex_load_[r.vertex];
    const double fc[3] = {f.x, f.y, f.z};
    for (int k = 0; k < 3; ++k) {
      const int j = index_[3 * r.vertex + k];
      if (j >= 0) a[j] += r.weight * fc[k];
    }
  }
  for (int i = 0; i < dof(); ++i) a[i] /= mass_[i];
}

void MirroredSheet::stiffness_values(double /*t*/, const double* q, double* values) const {
  std::fill(values, values + pattern_.nnz(), 0.0);
  assemble<true>(q, nullptr, nullptr, values);
}

double MirroredSheet::static_residual(double /*t*/, const double* q) const {
  std::vector<double> f(dof(), 0.0);
  assemble<false>(q, nullptr, f.data(), nullptr);
  double worst = 0.0;
  for (const Rep& r : reps_) {
    double sum = 0.0;
    for (int j = r.first; j < r.first + r.count; ++j)
      sum += f[j] * f[j] / (r.weight * r.weight * mult_[j]);
    worst = std::max(worst, std::sqrt(sum));
  }
  return worst / sheet_->force_scale_;
}

double MirroredSheet::potential_energy(double /*t*/, const double* q) const {
  double e = 0.0;
  assemble<false>(q, &e, nullptr, nullptr);
  return e;
}

std::string MirroredSheet::describe() const {
  const int order = mirrors_.order();
  return sheet_->describe() + ", " +
         (order == 8 ? "an eighth" : order == 4 ? "a quarter" : order == 2 ? "a half" : "whole") +
         " by its mirrors (" + std::to_string(reps_.size()) + " representatives)";
}

}  // namespace knitsim
