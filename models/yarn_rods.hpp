// YarnRods: yarns as discrete elastic rods with contact -- the physics kernel of the yarn-level
// knit model (docs/yarn_model.md has the derivations, the sources and the measured cost).
//
// Each yarn is an open polyline of vertices x_0 .. x_{N-1} (m), edges e_j = x_{j+1} - x_j, rest
// edge lengths l_j from the rest polyline. SI units throughout. The potential energy is
//
//   E = E_stretch + E_bend + E_contact - sum_free F_i . x_i - sum_free m_i g . x_i
//
//   stretching   E_s = 1/2 EA sum_j (|e_j| / l_j - 1)^2 l_j        (a spring k_j = EA / l_j)
//   bending      E_b = sum_{interior i} B / (2 lbar_i) (kappa_i - kappa0_i)^2,
//                lbar_i = (l_{i-1} + l_i) / 2 (the vertex's Voronoi length),
//                kappa_i = |kb_i| = 2 tan(phi_i / 2),  kb_i = 2 e_{i-1} x e_i /
//                (|e_{i-1}| |e_i| + e_{i-1} . e_i)   (Bergou et al. 2008, "Discrete elastic
//                rods", SIGGRAPH; phi_i the turning angle at vertex i).
//                kappa_i / lbar_i is the pointwise curvature, so E_b -> 1/2 B int kappa^2 ds as
//                the edges shrink; in Bergou's notation (l_i = |e_{i-1}| + |e_i| = 2 lbar_i) the
//                same term reads B kappa_i^2 / l_i. kappa0_i: rest curvature (integrated, i.e.
//                2 tan of half the rest turning angle), 0 = straight.
//                Computed from three invariants a = |e_{i-1}|, b = |e_i|, c = e_{i-1} . e_i:
//                kappa^2 = 4 (ab - c) / (ab + c), so its gradient and Hessian follow by the chain
//                rule through (a, b, c) (yarn_rods.cpp), analytic, no automatic differentiation.
//   contact      E_c = sum_{segment pairs} sum_{k, m} w_km psi(|p_k - q_m|)        (see below)
//
// Rest curvature: kappa0 is a magnitude only (a twist-free rod has no material frame to give the
// rest curvature a direction), so E_b is a cone in the curvature vector at kb = 0 when kappa0 > 0
// (its gradient jumps there: a bent-at-rest vertex must not be straight) and is not convex for
// 0 < kappa < kappa0 (a Mexican hat): there the stiffness is indefinite and Newton-type solvers
// crawl until the vertex is bent past kappa0 (measured: docs/yarn_model.md). Start such yarns
// bent at least as much as at rest. Yarns of spun cotton are straight at rest (kappa0 = 0, the
// default), and then E_b is a convex quadratic in kb.
//
// Twist is left out: this is a Kirchhoff rod without twist (Kaldor et al. 2008, "Simulating
// knitted cloth at the yarn level", SIGGRAPH, whose knit yarns leave it out too). A
// frictionless isotropic rod (round cross-section, straight rest shape about its own axis) whose
// ends may spin freely carries no twisting moment at equilibrium: twist then relaxes along the
// rod at once and decouples from the centreline (Bergou 2008 treat twist quasi-statically:
// uniform between constraints, zero with a free end). Twist would matter where it cannot relax: a
// yarn held against spinning at both ends and turned (twist-lively yarns, spirality of single
// jersey knitted from singles yarn), a rest curvature that is not planar, anisotropic cross
// sections, or friction at the contacts that stops the yarn rolling. None of these is modelled.
//
// Contact (between different yarns, and between parts of one yarn at least same_yarn_gap apart
// along it at rest). Each edge j carries n_j = ceil(4 l_j / d) sample points at the fixed
// parameters s_k = (k + 1/2) / n_j (the midpoint rule): p = (1 - s_k) x_j + s_k x_{j+1}, affine in
// the vertices. A pair of samples at distance D on edges a and b adds
//   w psi(D),  w = (l_a / n_a)(l_b / n_b) / d^2 (dimensionless: the double integral over the two
//   centrelines of Kaldor 2008's contact energy, in units of d^2),
//   psi(D) = kappa_c (d - d0)^2 phi((D - d0) / (d - d0)),  phi(g) = -(g - 1)^2 ln g (0 < g < 1),
//   phi = 0 for g >= 1 (the IPC barrier of Li et al. 2020, "Incremental potential contact",
//   shifted to a core d0 = core_fraction d; as in models/yarn_contact.hpp).
// Why sampled points and not the segment-segment distance: the distance between two segments
// is only C^1 where its closest points change region (interior to endpoint), so a barrier on it
// is not C^2 there. Here each term is a smooth function of a point-point distance D > 0 with
// constant weights, and phi = phi' = phi'' = 0 at g = 1, so E_c is C^2 (C^inf apart from
// D = d) wherever every sample distance exceeds d0. The samples also bound the true
// clearance: every point of edge j lies within l_j / (2 n_j) <= d / 8 of a sample (while the
// edge is stretched less than it can be here), so while the energy is finite the segment-segment
// distance of any contact pair is at least d0 - d/4 > 0 (core_fraction > 1/4 is required).
// Pairs are found by a broad phase each evaluation: edge boxes grown by d/2 on a uniform grid
// (cell = the largest grown box, so a box meets at most 8 cells), the (cell, edge) entries
// sorted and each pair reported once, in the cell holding the low corner of the two boxes'
// overlap: memory linear in the edges, no state kept between calls.
//
// Step filter (admissible_step): a sample moves at most max(|dx_j|, |dx_{j+1}|) along a straight
// step (a convex combination of its edge's vertex moves), so a pair at distance D whose edges
// move m_a and m_b stays above d0 + keep (D - d0) for fractions up to (1 - keep)(D - d0) /
// (m_a + m_b) (the additive bound of IPC's conservative CCD). The admitted fraction is the
// least over the pairs that can bind: each edge's box grows by d0 / 2 + f m_e / (1 - keep), m_e
// its own vertices' larger move, f = min(1, 2 (1 - keep) d / largest move), and the fraction is
// at most f (a step moves no vertex more than 2 (1 - keep) d: the boxes stay small).
//
// Jacobian pattern: the stretching and bending stencils' vertex blocks, plus every edge pair
// closer than pattern_radius at the start (all 16 blocks of its 4 vertices). A pair that comes
// into contact later outside that set still gets its forces and energy; its Jacobian blocks are
// dropped and counted (pattern_misses(); Newton converges more slowly, to the same state), as
// in ContactNetwork (models/yarn_contact.hpp). A scene that moves far should set a larger
// pattern_radius; renewing the pattern needs the per-run state the contract does not yet have.
//
// Masses: lumped, m_i = rho_l (l_{i-1} + l_i) / 2 with rho_l = tex 1e-6 kg/m. Damping: absolute,
// gamma = 1 / relaxation_time for every dof. Pins: listed vertices are not degrees of freedom
// and stay where they start. Loads: constant forces on free vertices (dead loads).
// State: the free vertices in yarn order then vertex order, 3 dofs each (x, y, z).
// Static residual: max_i |F_i| / F_ref over free vertices (F_ref = residual_force_scale, or the
// mean free vertex's weight under 9.81 m/s^2).
//
// Failure modes: bad input (a yarn with fewer than 2 vertices, a zero rest length, a pin or load
// out of range or pinned twice, rest curvature of the wrong size, a parameter out of range:
// YarnParams::validate) throws std::invalid_argument naming the field and its range. Evaluation
// never throws: a state with a sample pair at or inside the core, or a vertex folded back on
// itself (ab + c = 0), gives E = +inf and NaN accelerations, which the integrators treat as a
// failed step.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "src/core/mechanical_system.hpp"
#include "src/core/vec3.hpp"

namespace knitsim {

// One yarn's material, with units. Defaults: a 25 tex ring-spun cotton yarn. Each default's
// source and arithmetic: docs/yarn_sources.md (the measurements found, with citations) and
// docs/yarn_model.md, "Parameters".
struct YarnParams {
  double tex = 25.0;  // linear density, tex = g/km = 1e-6 kg/m; (0, 1e4]
  // rho_f, kg/m^3; [500, 3000]. Cotton 1.52 g/cm^3 (Morton & Hearle, Physical Properties of
  // Textile Fibres, 4th ed. 2008, Table 5.1).
  double fibre_density = 1520.0;
  // phi, fibre area / yarn area; (0.1, 0.9]. Peirce's specific volume of cotton yarn, 1.1 cm^3/g,
  // gives 1 / (1.1 x 1.52) = 0.60 (the value a study of cotton plain and rib knits found to
  // reproduce their measured stitch lengths); the handbooks' d = 4.44e-3 sqrt(tex / rho) cm
  // hides 0.646.
  double packing_fraction = 0.6;
  // Initial tensile modulus per linear density, N/tex: EA = tensile_modulus x tex, N; (0, 100].
  // Carded ring-spun cotton yarns of 15-30 tex break at 0.17 N/tex and 6.4-5.6 % (Uster
  // Tensorapid means, Elmogahzy & Chewning 2001, tabulated in Handbook of Properties of Textile
  // and Technical Fibres, 2nd ed. 2018, Table 7.3): their chord modulus is 2.7-3.0 N/tex; 2.7 at
  // 25 tex (6.3 %). The fibre's own initial modulus is 5.0 N/tex (Morton & Hearle, Table 13.1).
  double tensile_modulus = 2.7;
  // B, N m^2; (0, 1e-3]. The free-fibre bound n_f B_f = R_f tex_f tex: cotton's specific flexural
  // rigidity R_f = 0.53 mN mm^2 / tex^2 (Morton & Hearle, Table 17.2) with 0.165 tex fibres;
  // no measured single-yarn value for a 20-30 tex cotton yarn was found (docs/yarn_sources.md).
  double bending_rigidity = 2.2e-9;
  // tau, s: gamma = 1 / tau on every dof; (0, 1e6]. A numerical choice, not a measurement (no
  // source gives a yarn's relaxation time): it overdamps every mode of a yarn cut into edges of
  // d/2 or longer (gamma >= 2 omega_max = 4 c / l, c = sqrt(EA / rho_l) the yarn's wave speed,
  // 1643 m/s by default), so the dynamics is the gradient flow to the steady state, not a
  // transient in real time (docs/yarn_model.md, "Damping").
  double relaxation_time = 1e-8;
  // kappa_c, N/m; 0: 10 B / d^3 (a sample pair's force at half the barrier's width is then
  // 3.6 w B / d^2 at the default core_fraction).
  double contact_stiffness = 0.0;  // [0, 1e9]
  double core_fraction = 0.7;      // d0 / d; (0.25, 1)
  double same_yarn_gap = 2.0;      // in d: samples of one yarn closer along it never pair; [1, 100]
  double pattern_radius = 2.0;     // in d: edge pairs this close at the start have blocks; [1, 1e3]
  double step_keep = 0.2;          // a step keeps at least this fraction of each gap to d0; [0, 1)

  // Throws std::invalid_argument "yarn.<field> = <value>: must be in <range>".
  void validate() const;
  double linear_density() const { return tex * 1e-6; }  // kg/m
  // d = sqrt(4 tex 1e-6 / (pi rho_f phi)), m (the yarn a solid cylinder of packed fibres).
  double diameter() const;
  double stretch_stiffness() const { return tensile_modulus * tex; }  // EA, N
  double contact_kappa() const;                                       // kappa_c, N/m
};

struct YarnVertex {
  int yarn = 0;
  int vertex = 0;
};

struct YarnLoad {
  YarnVertex at;
  Vec3 force;  // N
};

struct YarnRodsSpec {
  YarnParams yarn;
  std::vector<std::vector<Vec3>> rest;     // per yarn its rest polyline (>= 2 vertices), m
  std::vector<std::vector<Vec3>> initial;  // per yarn its start (empty: the rest polyline), m
  // Per yarn, per vertex, kappa0 (dimensionless, 2 tan(rest turning angle / 2)); the end
  // vertices' entries are ignored. Empty: every yarn straight at rest.
  std::vector<std::vector<double>> rest_curvature;
  std::vector<YarnVertex> pins;
  std::vector<YarnLoad> loads;
  Vec3 gravity{0.0, 0.0, 0.0};        // m/s^2
  double residual_force_scale = 0.0;  // F_ref, N; 0: mean free vertex weight under 9.81 m/s^2
  bool contact = true;
};

class YarnRods final : public MechanicalSystem {
 public:
  explicit YarnRods(YarnRodsSpec spec);

  // MechanicalSystem
  int dof() const override { return 3 * free_count_; }
  void initial_state(double* x, double* v) const override;
  void conservative_acceleration(double t, const double* x, double* a) const override;
  void constant_acceleration(double t, double* a) const override;  // gravity
  const std::vector<double>& damping_rate() const override { return gamma_; }
  const std::vector<double>& mass() const override { return dof_mass_; }
  const CscPattern& stiffness_pattern() const override { return pattern_; }
  void stiffness_values(double t, const double* x, double* values) const override;
  double static_residual(double t, const double* x) const override;
  double residual_roundoff(double t, const double* x) const override;
  double admissible_step(double t, const double* x, const double* dx) const override;
  double potential_energy(double t, const double* x) const override;
  std::string describe() const override;

  // Net force on each free vertex, N (length dof()): -dE/dx.
  void net_force(const double* x, double* f) const;
  const YarnRodsSpec& spec() const { return spec_; }
  double diameter() const { return d_; }
  int vertex_count() const { return static_cast<int>(vertex_yarn_.size()); }
  int vertex_index(int yarn, int vertex) const { return yarn_first_[yarn] + vertex; }
  int free_index(int vertex) const { return free_index_[vertex]; }  // -1 if pinned
  // Every vertex's position (free from x, pinned from its start), in vertex_index order.
  void all_positions(const double* x, std::vector<Vec3>& out) const;
  // Current length of a yarn's centreline, m, and its rest length.
  double yarn_length(int yarn, const double* x) const;
  double rest_length(int yarn) const;
  // Smallest segment-segment distance (exact, src/geometry/segment_distance.hpp) over edge pairs
  // that can touch (different yarns, or one yarn's edges more than same_yarn_gap apart along it
  // at rest), m; +inf if none is closer than 2 d. Edges of one yarn nearer than the gap along it
  // (adjacent ones share a vertex) count by their sample pairs that pair: within d/8 of exact.
  double min_clearance(const double* x) const;
  // Energies by kind, J.
  double stretch_energy(const double* x) const;
  double bend_energy(const double* x) const;
  double contact_energy(const double* x) const;
  // Contact pairs whose Jacobian blocks were not in the pattern, over all stiffness evaluations.
  long pattern_misses() const { return pattern_misses_; }

 private:
  struct Edge {
    int a, b;     // vertex indices
    double rest;  // l, m
    double arc;   // arc length of a along its yarn at rest, m
    int yarn;
    int samples;  // n
  };
  struct Bend {
    std::array<int, 3> v;  // vertex indices
    double lbar;           // m
    double kappa0;
  };
  enum class Mode { Energy, Force, Stiffness };
  struct Accumulator;  // where an evaluation writes (yarn_rods.cpp)

  void evaluate(const double* x, Mode mode, Accumulator& acc) const;
  void contact_terms(const std::vector<Vec3>& pos, Mode mode, Accumulator& acc) const;
  // Edge pairs (i < j) whose boxes, grown by `grow` (plus edge_grow[e] for edge e where given)
  // on every side, overlap (the broad phase).
  void edge_pairs(const std::vector<Vec3>& pos, double grow, std::vector<std::pair<int, int>>& out,
                  const std::vector<double>* edge_grow = nullptr) const;
  // The same pairs, each passed to visit(i, j) as found (nothing stored).
  template <class Visit>
  void visit_edge_pairs(const std::vector<Vec3>& pos, double grow,
                        const std::vector<double>* edge_grow, Visit&& visit) const;
  // True if some sample pair of edges i and j may interact (not wholly inside the same-yarn gap).
  bool may_pair(int i, int j) const;
  bool samples_pair(int i, double si, int j, double sj) const;

  YarnRodsSpec spec_;
  double d_ = 0.0, d0_ = 0.0, kappa_c_ = 0.0, gap_ = 0.0;
  int free_count_ = 0;
  std::vector<int> yarn_first_, vertex_yarn_, free_index_;
  std::vector<Vec3> start_;  // every vertex's start position
  std::vector<Edge> edges_;
  std::vector<Bend> bends_;
  std::vector<double> gamma_, dof_mass_, vertex_mass_;
  std::vector<double> load_;  // per dof, N
  double residual_scale_ = 1.0;
  // Pattern: node-level pattern (free vertices) and, per stencil block, its entry there.
  CscPattern nodes_, pattern_;
  std::vector<std::array<int, 4>> edge_blocks_;  // (aa, ab, ba, bb)
  std::vector<std::array<int, 9>> bend_blocks_;  // (r, c) row-major over the stencil
  // Edge pairs (i < j) with contact blocks, by i: partners contact_partner_[contact_first_[i] ..
  // contact_first_[i + 1]) sorted, each with its 16 blocks (r, c) over (a_i, b_i, a_j, b_j).
  std::vector<int> contact_first_, contact_partner_;
  std::vector<std::array<int, 16>> contact_blocks_;
  const std::array<int, 16>* contact_blocks(int i, int j) const;
  mutable long pattern_misses_ = 0;
  mutable std::vector<Vec3> pos_;
  // The contact's pairs (boxes grown by d/2) and the positions they were found at: the force,
  // stiffness and energy evaluations of one state share one broad phase.
  mutable std::vector<std::pair<int, int>> pairs_;
  mutable std::vector<Vec3> pairs_pos_;
  mutable std::vector<std::pair<std::uint64_t, int>> cells_;
  mutable std::vector<double> scratch_;
};

}  // namespace knitsim
