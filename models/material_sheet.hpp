// MaterialSheet: a rectangular fabric whose parameters are material properties, on a regular grid
// that is a numerical parameter of its own (docs/material_drape.md).
//
// Specimen and axes: width W along x (the courses), length L along y (the wales), flat at z = 0
// at rest; gravity along -z. Mesh: nx = `cells` cells along the width, ny = max(1, round(nx L / W))
// along the length, so the cells are hx = W / nx by hy = L / ny, near-square (hy / hx within
// 1 +- 1 / (2 ny) of 1 where nx L / W >= 1/2; a sheet thinner than half a cell has one cell).
// Vertex (i, j) (row i along y, column j along x) is at (j hx, i hy, 0).
//
// Energy (J), the continuum limit and its discretisation:
//   Membrane: orthotropic plane-stress St Venant-Kirchhoff on the Green strain E = (F^T F - I)/2,
//     w_m = 1/2 (C11 E11^2 + 2 C12 E11 E22 + C22 E22^2 + 4 C66 E12^2)     [J/m^2]
//     C11 = A_c / D, C22 = A_w / D, C12 = nu_cw A_w / D, C66 = A_s, D = 1 - nu_cw^2 A_w / A_c,
//   so a small uniaxial stress T (N/m) along x gives E11 = T / A_c and E22 = -nu_cw E11, and along
//   y E22 = T / A_w and E11 = -nu_wc E22 with nu_wc = nu_cw A_w / A_c (reciprocity:
//   nu_cw / A_c = nu_wc / A_w). Discretised by linear triangles, each cell split along both
//   diagonals (4 triangles of half weight: no preferred diagonal, the x <-> y transpose maps
//   the mesh onto itself).
//   Bending: 1/2 (B_w kappa_w^2 + B_c kappa_c^2) per unit area, kappa_c the curvature of the grid
//     rows (lines along x), kappa_w that of the columns (lines along y). Per interior vertex of a
//     row (neighbours a, b along the row, e1 = x_v - x_a, e2 = x_b - x_v, rest spacing h = hx):
//       E_v = B_c / 2 (2 tan(phi/2) / h)^2 h t_v,
//       4 tan^2(phi/2) = 4 (|e1||e2| - e1.e2) / (|e1||e2| + e1.e2),
//     phi the turning angle between e1 and e2, t_v the vertex's share of the width across the row
//     (hy inside, hy / 2 on the two boundary rows). For a smooth curve 2 tan(phi/2) = kappa h +
//     O(h^3), so E_v -> 1/2 B_c kappa^2 (h t_v): the Riemann sum of the continuum energy. Columns
//     the same with B_w, hy and hx. At a clamp's last row the stencil across it has twice that
//     stiffness: its clamped side is straight, so it sees half the turning angle (kappa h / 2) over
//     the free half cell (h / 2): 1/2 B kappa^2 h/2 = 2 x 1/2 B (kappa/2)^2 h (second order at the
//     clamp, as the mirror-ghost scheme of a clamped beam; first order without). Each stencil lies
//     on one row or one column: the two directions never couple (a cylindrical bend along x costs
//     B_c only, whatever B_w).
//   Gravity: m_i g z_i, masses lumped by area (rho_A hx hy x 1 inside, 1/2 on an edge, 1/4 at a
//     corner; total rho_A W L). Edge loads: -f . x_i with f = q l_i, q (N/m) the load per unit
//     length of edge, l_i the vertex's share of that edge.
// Derivatives: forces -dE/dx and the Jacobian are exact, by forward-mode automatic
//   differentiation (value, gradient, Hessian) of the element energies above (material_sheet.cpp);
//   checked against finite differences (tests/test_material_sheet.cpp).
// Clamps: a clamped edge holds every vertex within `length` of that edge, k = 1 + round(length / h)
//   rows (h the spacing across the edge), k >= 2 so the slope is held; clamped vertices are not
//   degrees of freedom and stay at rest. A patch (SheetPatch) holds every vertex of a rest
//   rectangle (corner clamps, a jaw), at least 2 x 2; the stencil rule at a clamp's boundary is
//   the edge's (by vertex: centre and one neighbour held, the other free).
// State: 3 dofs (x, y, z) per free vertex in vertex order (index i (nx + 1) + j).
// Damping: gamma_i = damping_rate (1/s) on every dof (mass-proportional).
// Static residual: max_i |F_i| / F_ref over free vertices, F_ref = mean free vertex weight (or,
//   without gravity, the largest edge-load force on a vertex).
// Units: SI except areal density, g/m^2 (as DrapeParams). Bad parameters throw
//   std::invalid_argument naming the field and its range; evaluation never throws.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "src/core/mechanical_system.hpp"
#include "src/core/vec3.hpp"

namespace knitsim {

enum class SheetEdge { XMin, XMax, YMin, YMax };  // j = 0, j = nx, i = 0, i = ny

struct SheetClamp {
  SheetEdge edge = SheetEdge::YMin;
  double length = 0.0;  // m, how far into the sheet the clamp reaches (>= one cell)
};

// A clamped rectangle of the rest sheet (a corner patch, a jaw): every vertex whose rest position
// lies in [x0, x1] x [y0, y1] (to 1e-9 of a cell) is held. To hold the slope it must hold at
// least 2 x 2 vertices (docs/material_drape.md, "Clamps").
struct SheetPatch {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;  // m
};

struct SheetEdgeLoad {
  SheetEdge edge = SheetEdge::XMax;
  Vec3 force_per_length;  // q, N/m of edge
};

struct MaterialSheetParams {
  double width = 0.5;              // W, m along x (courses), (0, 100]
  double length = 0.5;             // L, m along y (wales), (0, 100]
  int cells = 20;                  // nx, cells along the width, [1, 2000]
  int cells_length = 0;            // ny, cells along the length; 0 = max(1, round(nx L / W))
  double areal_density = 200.0;    // rho_A, g/m^2, >= 0
  double membrane_wale = 500.0;    // A_w, N/m, tensile stiffness per unit width along y, > 0
  double membrane_course = 500.0;  // A_c, N/m, along x, > 0
  double membrane_shear = 200.0;   // A_s, N/m, in-plane shear, > 0
  double poisson_cw = 0.3;         // nu_cw = -E22/E11 under stress along x; nu_cw^2 A_w/A_c < 1
  double bending_wale = 1e-5;      // B_w, N m (per unit width), curvature along y, > 0
  double bending_course = 1e-5;    // B_c, N m, curvature along x, > 0
  double damping_rate = 10.0;      // gamma, 1/s, >= 0
  Vec3 gravity{0.0, 0.0, -9.81};   // m/s^2
  std::vector<SheetClamp> clamps;
  std::vector<SheetPatch> patches;
  std::vector<SheetEdgeLoad> loads;

  void validate() const;  // throws std::invalid_argument naming the field and range
  int cells_x() const { return cells; }
  int cells_y() const;  // cells_length, or max(1, round(cells L / W)) where it is 0
};

struct SheetMirrors;

class MaterialSheet final : public MechanicalSystem {
 public:
  explicit MaterialSheet(MaterialSheetParams params);

  int dof() const override { return 3 * free_count_; }
  void initial_state(double* x, double* v) const override;
  void conservative_acceleration(double t, const double* x, double* a) const override;
  void constant_acceleration(double t, double* a) const override;
  const std::vector<double>& damping_rate() const override { return gamma_; }
  const std::vector<double>& mass() const override { return dof_mass_; }
  const CscPattern& stiffness_pattern() const override { return pattern_; }
  void stiffness_values(double t, const double* x, double* values) const override;
  double static_residual(double t, const double* x) const override;
  double potential_energy(double t, const double* x) const override;
  std::string describe() const override;

  const MaterialSheetParams& params() const { return params_; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double hx() const { return hx_; }
  double hy() const { return hy_; }
  int vertex(int i, int j) const { return i * (nx_ + 1) + j; }
  int vertex_count() const { return (nx_ + 1) * (ny_ + 1); }
  int free_index(int vertex) const { return free_index_[vertex]; }  // -1 if clamped
  Vec3 rest_position(int vertex) const;
  // Position of a vertex in the state x (its rest position if clamped).
  Vec3 position(const double* x, int vertex) const;
  // Net force (elastic + gravity + loads) on each free vertex, N (length dof()).
  void net_force(const double* x, double* f) const;

  struct Triangle {
    int v[3];
    double dinv[4];  // inverse of the rest edge matrix [X1 - X0, X2 - X0], row-major 2 x 2
    double area;     // rest area x weight (1/2: each cell is covered twice), m^2
  };
  struct BendStencil {
    int v[3];          // a, centre, b along one grid line
    double stiffness;  // B t_v / h, N m (E = stiffness / 2 x 4 tan^2(phi/2))
  };

 private:
  friend class MirroredSheet;
  friend std::string sheet_lacks(const MaterialSheet& sheet, SheetMirrors m);
  template <bool Hessian>
  void assemble(const double* x, double* energy, double* force, double* values) const;

  MaterialSheetParams params_;
  int nx_ = 0, ny_ = 0;
  double hx_ = 0.0, hy_ = 0.0;
  double c11_ = 0.0, c12_ = 0.0, c22_ = 0.0, c66_ = 0.0;
  std::vector<Triangle> triangles_;
  std::vector<BendStencil> stencils_;
  std::vector<double> vertex_mass_;  // kg, every vertex
  std::vector<Vec3> vertex_load_;    // N, every vertex (edge loads)
  int free_count_ = 0;
  std::vector<int> free_index_;
  std::vector<double> gamma_, dof_mass_;
  double force_scale_ = 1.0;
  CscPattern nodes_;    // vertex-level pattern of the free vertices
  CscPattern pattern_;  // expand_node_pattern(nodes_)
  // Per element (triangle, then stencil), 3 x 3 vertex blocks (a, b): the entry of nodes_ for
  // (row a, column b), or -1 where either vertex is clamped.
  std::vector<int> tri_slots_, stencil_slots_;
};

const char* to_string(SheetEdge e);  // x_min | x_max | y_min | y_max

// Mirrors of a sheet (docs/material_drape.md, "Symmetry"): x, x -> W - x; y, y -> L - y;
// diagonal, (x, y) -> (y, x) (needs x and y: the square's dihedral group, an eighth). The group
// they generate has order() elements: 1, 2 (a half), 4 (a quarter) or 8 (an eighth).
struct SheetMirrors {
  bool x = false, y = false, diagonal = false;
  int order() const { return (x ? 2 : 1) * (y ? 2 : 1) * (diagonal ? 2 : 1); }
};

// Why `sheet` lacks one of the mirrors `m` ("" if it has them all). A mirror is the sheet's when
// it maps the clamped vertices, the masses, the edge loads, gravity and every element's
// stiffness onto themselves: the x and y mirrors hold for any orthotropic sheet (its axes are
// the grid's) under symmetric clamps; the diagonal also needs a square sheet with A_w = A_c and
// B_w = B_c exactly (shear and Poisson map onto themselves), so an anisotropic sheet never has it.
std::string sheet_lacks(const MaterialSheet& sheet, SheetMirrors m);
// The largest group `sheet` has: x, y and diagonal; else x and y; else x; else y; else none.
SheetMirrors largest_mirrors(const MaterialSheet& sheet);

// MirroredSheet: a MaterialSheet with a mirror group G, run on one orbit representative per
// vertex orbit (the fundamental domain 2 j <= n_x, 2 i <= n_y, and i <= j with the diagonal),
// the exact restriction of the whole sheet's equations to symmetric states (as MirrorReduced
// does for paper 1's networks, models/mirror_reduced.hpp):
//   unknowns q: each free representative's coordinates, less what its mirrors fix: on x = W/2
//     its x is W/2, on y = L/2 its y is L/2, on the diagonal its y is its x (one entry, carrying
//     two coordinates: multiplicity 2); every vertex's coordinate is then x_k = s_k q_j + o_k
//     (s_k = +-1, or the constant o_k), its representative's mirrored.
//   energy E_R(q) = E(x(q)) / |G| = sum over element orbits (|O| / |G|) E_e(one element of O)
//     + the external potential of the representatives weighted |orbit| / |G|; forces -dE_R/dq
//     and the Jacobian by the chain rule through x(q) (the elements' derivatives as the whole
//     sheet's), masses M_j = mult_j w_r m_r, so that the accelerations are the whole sheet's.
//   static residual: the whole sheet's criterion at the unfolded state, max over representatives
//     of |F_r| / F_ref, |F_r|^2 = sum over r's entries f_j^2 / (w_r^2 mult_j).
// Throws std::invalid_argument (sheet_lacks' reason) when the sheet lacks a mirror of `m`.
class MirroredSheet final : public MechanicalSystem {
 public:
  MirroredSheet(std::shared_ptr<const MaterialSheet> sheet, SheetMirrors m);

  int dof() const override { return static_cast<int>(mass_.size()); }
  void initial_state(double* q, double* v) const override;
  void conservative_acceleration(double t, const double* q, double* a) const override;
  void constant_acceleration(double t, double* a) const override;
  const std::vector<double>& damping_rate() const override { return gamma_; }
  const std::vector<double>& mass() const override { return mass_; }
  const CscPattern& stiffness_pattern() const override { return pattern_; }
  void stiffness_values(double t, const double* q, double* values) const override;
  double static_residual(double t, const double* q) const override;
  double potential_energy(double t, const double* q) const override;
  std::string describe() const override;

  const MaterialSheet& sheet() const { return *sheet_; }
  SheetMirrors mirrors() const { return mirrors_; }
  // The whole sheet's state (length sheet().dof()) of the symmetric state q.
  void unfold(const double* q, double* x_full) const;

 private:
  template <bool Hessian>
  void assemble(const double* q, double* energy, double* force, double* values) const;
  double coordinate(const double* q, int vertex, int k) const;

  std::shared_ptr<const MaterialSheet> sheet_;
  SheetMirrors mirrors_;
  // Per vertex and coordinate (3 v + k): x = sign q[index] + offset, or offset (index -1).
  std::vector<int> index_;
  std::vector<double> sign_, offset_;
  struct Rep {
    int vertex;
    double weight;   // |orbit| / |G|
    int first, count;  // its entries of q
  };
  std::vector<Rep> reps_;
  std::vector<int> mult_;  // per entry of q: the coordinates it carries (1, or 2 on the diagonal)
  std::vector<int> triangles_, stencils_;  // one element of each orbit (indices into the sheet's)
  std::vector<double> tri_weight_, stencil_weight_;  // |O| / |G|
  std::vector<int> tri_slots_, stencil_slots_;       // 81 per element: pattern entry, or -1
  std::vector<double> mass_, gamma_;
  CscPattern pattern_;
};

}  // namespace knitsim
