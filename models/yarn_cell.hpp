// YarnCell: a periodic cell of knitted yarn -- p wales x q courses of a fabric that repeats
// without end -- whose size is an unknown besides its yarn, so that relaxing it gives the
// fabric's relaxed dimensions (courses and wales per cm) with no edge to hold
// (docs/yarn_model.md, "Periodic cell", has the derivation, the keys and measured figures).
//
// Yarn. Course c of the cell (c = 0 .. q-1) is a periodic discrete elastic rod along x: vertices
// x_0 .. x_{N_c - 1} (m), and vertex N_c is the image of vertex 0, x_0 + W e_x -- the same yarn
// continuing into the next repeat. The course above course q-1 is course 0's image x + H e_y, a
// different pass of yarn. The energies are YarnRods' (models/yarn_rods.hpp, shared through
// models/rod_elements.hpp): stretching 1/2 EA (|e| / l - 1)^2 l per edge (the closing edge
// N_c - 1 -> N_c included), bending B / (2 lbar) kappa^2 at every vertex (the yarn straight at
// rest), and contact of sampled points by the shifted IPC barrier between every edge and every
// image of every edge: shifts s = (s_x, s_y) in Z^2, position y = x_j + s_x W e_x + s_y H e_y,
// each unordered pair counted once (edge i with edge j shifted by s, for i < j and every s, and
// for i = j every s > 0 lexicographically), over the shifts whose images can come within d
// (|s_x| <= ceil((extent_x + d) / W), likewise in y). Same-yarn exclusion uses the arc length of
// the unrolled yarn: two samples of course c at arc a (shift 0) and b (shift s with s_y = 0) are
// |a - b - s_x L_c| apart along the yarn, L_c the course's rest length in the cell; samples of
// different passes (s_y != 0, or different courses) always pair.
//
// Unknowns. Every vertex but course 0's vertex 0 (3 dofs each; holding one vertex removes the
// three translations: a cell whose lattice vectors are fixed along e_x and e_y has no free
// rotation), then W and H, each where free (CellSize). The energy depends on W, H through the
// images only, so forces and Jacobian fold back by the chain rule: dy/dx_j = I, dy/dW = s_x e_x,
// dy/dH = s_y e_y; a term over images y_a, y_b has gradient sum_a J_a^T g_a and Hessian
// sum_ab J_a^T H_ab J_b. The generalised forces -dE/dW, -dE/dH (N per cell) are the tension the
// cell carries across its x and y faces: zero at a relaxed state (both free), the reaction per
// cell of a tensile step (H or W held).
//
// Mass: lumped rho_l (l_{i-1} + l_i) / 2 per vertex; W and H get the cell's yarn mass. Damping
// gamma = 1 / relaxation_time on every dof. The Jacobian pattern is dense (a cell has a few
// hundred dofs: no pattern misses, no renewal).
//
// Failure modes: a bad spec (fewer than 3 vertices in a course, a rest length <= 0, W or H <= 0,
// a parameter out of range: YarnParams::validate) throws std::invalid_argument. Evaluation never
// throws: a sample pair at or inside the barrier's core, a folded vertex, W or H <= 0, or images
// needed beyond kMaxCellShift give E = +inf and NaN forces, which the integrators treat as a
// failed step.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "models/knit_loops.hpp"
#include "models/yarn_knit.hpp"
#include "models/yarn_rods.hpp"
#include "src/core/mechanical_system.hpp"
#include "src/core/vec3.hpp"

namespace knitsim {

// Which of the cell's lengths are unknowns; a held one keeps its start value.
enum class CellSize { Free, HeightHeld, WidthHeld, Held };

// Images at most this many cells away are searched; a state that needs more is infeasible.
constexpr int kMaxCellShift = 12;

struct YarnCellSpec {
  YarnParams yarn;
  // Per course, its vertices over one period (>= 3), m; vertex N is vertex 0 + (W, 0, 0).
  std::vector<std::vector<Vec3>> initial;
  // Per course, per edge k (vertex k to k + 1, the last to vertex 0's image), rest length, m.
  std::vector<std::vector<double>> rest;
  double width = 0.0, height = 0.0;  // W, H at the start, m
  CellSize size = CellSize::Free;
  double residual_force_scale = 0.0;  // F_ref, N; 0: B / (mean course rest length)^2
  bool contact = true;
};

class YarnCell final : public MechanicalSystem {
 public:
  explicit YarnCell(YarnCellSpec spec);

  // MechanicalSystem
  int dof() const override { return dof_; }
  void initial_state(double* x, double* v) const override;
  void conservative_acceleration(double t, const double* x, double* a) const override;
  const std::vector<double>& damping_rate() const override { return gamma_; }
  const std::vector<double>& mass() const override { return mass_; }
  const CscPattern& stiffness_pattern() const override { return pattern_; }
  void stiffness_values(double t, const double* x, double* values) const override;
  double static_residual(double t, const double* x) const override;
  double residual_roundoff(double t, const double* x) const override;
  double admissible_step(double t, const double* x, const double* dx) const override;
  double potential_energy(double t, const double* x) const override;
  std::string describe() const override;

  // -dE/dx per dof, N (NaN where infeasible).
  void net_force(const double* x, double* f) const;
  const YarnCellSpec& spec() const { return spec_; }
  double diameter() const { return d_; }
  int courses() const { return static_cast<int>(spec_.initial.size()); }
  double width(const double* x) const;   // W, m
  double height(const double* x) const;  // H, m
  // dE/dW and dE/dH at x (N per cell), whether W, H are free or held.
  std::array<double, 2> size_gradient(const double* x) const;
  // Per course its vertices at x (the cell's own, not images), m.
  std::vector<std::vector<Vec3>> courses_at(const double* x) const;
  double course_length(int course, const double* x) const;  // m, closing edge included
  double course_rest_length(int course) const { return period_[course]; }
  // Least distance over the pairs the contact sees (exact segment distance where the two edges
  // are wholly more than same_yarn_gap apart along the yarn, else the pairing samples'), m;
  // +inf if none is closer than 2 d.
  double min_clearance(const double* x) const;
  double stretch_energy(const double* x) const;
  double bend_energy(const double* x) const;
  double contact_energy(const double* x) const;

 private:
  struct Ref {  // an image of a cell vertex: x_v + kx W e_x + ky H e_y
    int v, kx, ky;
  };
  struct Edge {
    Ref a, b;
    double rest, arc;  // m; arc of a along its course
    int course, samples;
  };
  struct Bend {
    Ref v[3];
    double lbar;
  };
  enum class Mode { Energy, Force, Stiffness };  // in order: bend_element's order 0, 1, 2
  struct Accumulator;
  struct State;  // positions, W, H of a state

  void unpack(const double* x, State& s) const;
  void evaluate(const double* x, Mode mode, Accumulator& acc) const;
  // Adds a term over n images: its gradient g (3n) and Hessian h (3n x 3n, row-major; null in
  // Force mode), folded onto the unknowns.
  void fold(const Ref* refs, int n, const double* g, const double* h, Accumulator& acc) const;
  void contact_terms(const State& s, Mode mode, Accumulator& acc) const;
  // Calls visit(i, j, sx, sy) for every pair (each once) whose boxes, grown by `grow`, overlap;
  // false if the images needed exceed kMaxCellShift.
  template <class Visit>
  bool for_each_pair(const State& s, double grow, Visit visit) const;
  bool samples_pair(const Edge& A, double sa, const Edge& B, double sb, int sx, int sy) const;
  // Edge A and edge B shifted by (sx, sy): some sample pair pairs (may_pair); every one does
  // (whole: different passes, or more than same_yarn_gap apart along the yarn).
  bool may_pair(const Edge& A, const Edge& B, int sx, int sy) const;
  bool whole(const Edge& A, const Edge& B, int sx, int sy) const;

  YarnCellSpec spec_;
  double d_ = 0.0, d0_ = 0.0, kappa_c_ = 0.0, gap_ = 0.0, residual_scale_ = 1.0;
  int dof_ = 0, w_index_ = -1, h_index_ = -1;
  std::vector<int> course_first_, vertex_course_, free_index_;
  std::vector<Vec3> start_;
  std::vector<double> period_;  // per course L_c, m
  std::vector<Edge> edges_;
  std::vector<Bend> bends_;
  std::vector<double> vertex_mass_, mass_, gamma_;
  CscPattern pattern_;
  mutable std::vector<double> hess_;  // dense scratch of a stiffness evaluation
};

// The cell's start from paper 2's structure model (docs/yarn_model.md, "Periodic cell"): the
// repeat (p wales x q courses) tiled into a chart at least 5 x 5, made into a yarn by the yarn
// model's front end (build_yarn_knit: paper 2's NURBS centrelines, scaled clear of d), and one
// interior period of each course -- the middle repeat's, sinker to sinker -- resampled uniformly
// in arc length with `vertices_per_loop` edges per wale; the small mismatch of its end with its
// start's image (the centreline is not exactly periodic) spread linearly along it; W = p w,
// H = q h of the structure. Then scaled until the least clearance with every image is between
// kYarnStartClearance d and kYarnStartClearanceMax d. Rest lengths: the start's, and the
// knitted target per edge (knit.stitch_length over the mean knit cell's start length, likewise
// tuck_length and miss_length; 0: the knit's ratio; all 0: no ramp).
struct YarnCellStart {
  KnitChart repeat;
  YarnKnitParams params;
  double d = 0.0;
  double r = 0.0;  // the structure's loop radius at the start (after the cell's own scale), m
  std::vector<std::vector<Vec3>> start;                          // per course, its vertices
  std::vector<std::vector<double>> start_length, target_length;  // per course, per edge, m
  // Per course, per wale of the repeat, the knitted target length of its cell (sinker to
  // sinker, m) and its start length.
  std::vector<std::vector<double>> cell_target, cell_start;
  double width = 0.0, height = 0.0;  // W, H at the start, m
  double start_clearance = 0.0;      // m
  // The cell at ramp stage s of n (rest lengths start + s/n (target - start)), started at the
  // given vertices and size (empty: the start's).
  YarnCellSpec spec(int s, int n, const std::vector<std::vector<Vec3>>& initial = {},
                    double width = 0.0, double height = 0.0, CellSize size = CellSize::Free) const;
  bool ramp() const;  // any target length differs from the start's
  // Per course its knitted length in the cell (sum of targets), m.
  double knitted_length(int course) const;
};

// Throws std::invalid_argument for a bad repeat or parameters (as build_yarn_knit), or a cell
// that cannot be made clear at d.
YarnCellStart build_yarn_cell_start(const KnitChart& repeat, const KnitParams& structure,
                                    const YarnKnitParams& params);

}  // namespace knitsim
