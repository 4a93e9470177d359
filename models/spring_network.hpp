// SpringNetwork: particles joined by linear springs, with pins, gravity, absolute damping and
// an elongation limit -- the one ODE system behind both papers' models.
//
// Equations (paper 1 Eqs. 2-4; docs/numerics.md), SI units throughout:
//   m_i x_i'' = sum_springs F_s + m_i g - c v_i
//   spring (a, b), length L = |x_b - x_a|, axis u = (x_b - x_a)/L, rest L0, stiffness k:
//     F_a = f(L) u,  F_b = -F_a,  f(L) = k (L - L0) + k_lim max(0, L - L_max)
//   L_max = L0 (1 + eps_max). The k_lim term is the implicit paths' elongation limit (a stiff
//   limiting spring, k_lim = limit_stiffness_factor x k); the explicit reference paths
//   instead call project() after each step, which shortens every spring beyond L_max to
//   exactly L_max (Provot 1995, one pass in spring order, half each end, or the free end only
//   if the other is pinned; velocities unchanged). After a projection no spring exceeds L_max,
//   so on the reference paths the k_lim term stays inactive.
//   Spring Jacobian (3x3 block, B = dF_a/dx_b):
//     B = f'(L) u u^T + (f(L)/L) (I - u u^T);  dF_a/dx_a = -B, dF_b/dx_a = B, dF_b/dx_b = -B
//   For k_lim = 0 this is k [ (1 - L0/L)(I - u u^T) + u u^T ].
//   stencil (2-4 particles i, weights w_i, stiffness k; the knit's out-of-plane bending,
//   models/knit_loops.hpp): E = k/2 |v|^2 with v = sum_i w_i x_i, F_i = -k w_i v, Jacobian
//   block dF_i/dx_j = -k w_i w_j I. stiffness_values() writes these blocks row-scaled by 1/m_i
//   (da_c/dx, MechanicalSystem).
//
// Planar (plane_stiffness k_p > 0; the knit's default): the particles move in the plane z = 0,
//   held there by E_p = k_p/2 sum_i z_i^2, and each spring's length is that of its in-plane
//   projection, L = |(x_b - x_a)_xy|, so no spring has z stiffness (B's z row and column are 0) and
//   the z block of the stiffness is k_p I. A flat state stays flat as before (no force has a z
//   component at z = 0); what changes is the z block: without the plane a compressed spring's
//   f/L < 0 makes it indefinite, and solvers that test pivots (the equilibrium solver, the
//   certificate) would read modes that the planar model does not have as saddles.
// State: only free particles are degrees of freedom, 3 per particle in particle order
// (x, y, z). Pinned particles follow a PinPath (fixed, or moved linearly in time).
// Damping: absolute, per particle, gamma_i = c / m_i (paper 1 Eq. 4).
// Static residual (docs/equilibrium.md): max_i |F_spring,i + m_i g| / F_ref over free particles,
// with F_ref = mean free mass x |g| (or residual_force_scale if set, e.g. without gravity).
// Its round-off floor (residual_roundoff): each spring's length is computed from the
// difference of two absolute positions, |delta L| <= eps (|x_a| + |x_b|) (eps = DBL_EPSILON),
// so its force carries up to k eps (|x_a| + |x_b|); a stencil's k v up to k eps sum_j |w_j|
// |x_j|, of which particle i gets |w_i|. The floor is max_i of the sum over i's springs and
// stencils, / F_ref: a bound, not a typical value, that matters only for stiff springs
// (figures: docs/numerics.md, "Round-off floor").
//
// Failure modes: bad specs (sizes that do not match, an index out of range or pinned twice, a
// spring joining a particle to itself, a stencil naming a particle twice or with fewer than 2,
// non-positive mass, rest length or stiffness, negative damping, no gravity and no
// residual_force_scale, NaN) throw std::invalid_argument at construction. Evaluation never
// throws; a non-finite state produces non-finite output for the caller to detect.
#pragma once

#include <array>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "src/core/held_points.hpp"
#include "src/core/mechanical_system.hpp"
#include "src/core/vec3.hpp"

namespace knitsim {

// Position of a pinned particle: `start` until t = 0, then linear to `end` at t = move_time,
// then held. move_time = 0 means a fixed pin at `end` (= start).
struct PinPath {
  Vec3 start;
  Vec3 end;
  double move_time = 0.0;  // s
  Vec3 at(double t) const;
};

struct Spring {
  int a = 0, b = 0;        // particle indices
  double rest = 0.0;       // L0, m
  double stiffness = 0.0;  // k, N/m
};

// A stencil's energy k/2 |sum_i w_i x_i|^2 (see the header comment); particles[i] < 0 ends the
// list (2 to 4 particles, distinct).
struct Stencil {
  std::array<int, 4> particles{-1, -1, -1, -1};
  std::array<double, 4> weights{};  // dimensionless
  double stiffness = 0.0;           // k, N/m
};

struct SpringNetworkSpec {
  std::vector<Vec3> positions;  // initial positions of all particles, m
  std::vector<double> masses;   // kg, all particles (pinned ones are ignored)
  std::vector<Spring> springs;
  std::vector<Stencil> stencils;
  std::vector<int> pinned;                // particle indices
  std::vector<PinPath> pin_paths;         // one per pinned particle
  double damping = 0.0;                   // c, N s/m per particle (absolute damping)
  double elongation_limit = 0.0;          // eps_max as a fraction (0.05 = 5 %); <= 0: no limit
  double limit_stiffness_factor = 100.0;  // k_lim / k above the limit (implicit paths)
  Vec3 gravity{0.0, 0.0, -9.81};          // m/s^2
  double residual_force_scale = 0.0;      // N; 0: mean free mass x |g|
  // Declares a body free in space (no pins, no gravity): the equilibrium certificate then factors
  // out its 6 rigid-body modes (MechanicalSystem::free_floating). Opt-in: a planar network whose
  // out-of-plane motion has no stiffness (paper 2's knit) would have those modes read as a saddle.
  bool free_floating = false;
  // Planar (> 0; N/m): the particles move in the plane z = 0 (see "Planar" above).
  double plane_stiffness = 0.0;
};

// A direction in the network's data (d(data)/dp for one parameter p), for the equilibrium
// sensitivities dx*/dp = -K^-1 dF/dp (src/fit/sensitivity.hpp). An empty vector means zero.
// Stencils enter only through their pinned particles (their stiffness and weights are not
// parameters of a fit).
struct SpringNetworkTangent {
  std::vector<double> stiffness;   // per spring: dk_s/dp, N/m per unit of p
  std::vector<double> rest;        // per spring: dL0_s/dp, m per unit of p
  std::vector<double> mass;        // per particle: dm_i/dp, kg per unit of p
  std::vector<Vec3> pin_position;  // per pin: d(position at the evaluation time t)/dp, m per unit
  double elongation_limit = 0.0;   // d eps_max/dp, fraction per unit of p
};

class SpringNetwork final : public MechanicalSystem, public HeldPoints {
 public:
  explicit SpringNetwork(SpringNetworkSpec spec);

  // MechanicalSystem
  int dof() const override { return 3 * free_count_; }
  void initial_state(double* x, double* v) const override;
  void conservative_acceleration(double t, const double* x, double* a) const override;
  void constant_acceleration(double t, double* a) const override;  // gravity
  const std::vector<double>& damping_rate() const override { return gamma_; }
  const std::vector<double>& mass() const override { return dof_mass_; }
  const CscPattern& stiffness_pattern() const override { return stiffness_layout().pattern; }
  void stiffness_values(double t, const double* x, double* values) const override;
  double static_residual(double t, const double* x) const override;
  double residual_roundoff(double t, const double* x) const override;
  double equilibrium_start_time() const override { return pin_move_time_; }
  bool free_floating() const override;  // spec.free_floating, with no pins and no gravity
  bool planar() const override { return spec_.plane_stiffness > 0.0; }
  bool project(double t, double* x, double* v) const override;
  double potential_energy(double t, const double* x) const override;
  std::string describe() const override;
  HeldPoints* held_points() override { return this; }
  const HeldPoints* held_points() const override { return this; }

  // HeldPoints: the pinned particles, in spec().pinned order. set_held_positions makes every pin
  // a fixed one at its new position (equilibrium_start_time() becomes 0).
  int held_count() const override { return static_cast<int>(spec_.pinned.size()); }
  int held_particle(int k) const override { return spec_.pinned[k]; }
  std::vector<Vec3> held_positions(double t) const override { return pins_at(t); }
  void set_held_positions(const std::vector<Vec3>& p) override;
  void held_reactions(double t, const double* x, std::vector<Vec3>& out) const override;
  // The held point a particle is (index into held_positions), or -1 if it is free.
  int held_index(int particle) const { return pin_slot_[particle]; }

  // Topology and bookkeeping.
  const SpringNetworkSpec& spec() const { return spec_; }
  int particle_count() const { return static_cast<int>(spec_.positions.size()); }
  int free_index(int particle) const { return free_index_[particle]; }  // -1 if pinned
  // F_ref of the static residual, N (residual_force_scale, or mean free mass x |g|).
  double residual_force_scale() const { return residual_scale_; }
  // Positions of all particles (free from x, pinned from their paths at t).
  void all_positions(double t, const double* x, std::vector<Vec3>& out) const;
  // Largest strain (L - L0)/L0 over all springs at (t, x).
  double max_strain(double t, const double* x) const;
  // Net spring + gravity force on each free particle, N (length dof()).
  void net_force(double t, const double* x, double* f) const;
  // dF/dp: derivative of net_force(t, x) along the data direction `dp` at fixed free positions x
  // (length dof(), N per unit of p). Per spring (force on end a; b gets the opposite):
  //   dF_a = (df/L) (x_b - x_a) + B (d x_b - d x_a),  B = dF_a/dx_b as in the header,
  //   df   = dk (L - L0) - k dL0 + [L > L_max] (k_lim/k dk (L - L_max)
  //          - k_lim (dL0 (1 + eps_max) + L0 d eps_max)),
  // with d x = the pin tangent for pinned ends (0 for free ends); gravity adds dm_i g. An
  // inactive elongation limit contributes exactly zero; damping never enters F.
  // Throws std::invalid_argument if a non-empty vector has the wrong length.
  void net_force_tangent(double t, const double* x, const SpringNetworkTangent& dp,
                         double* df) const;

  // The stiffness pattern and where each spring's blocks go (see stiffness_layout below).
  struct StiffnessLayout {
    int free_count = 0;
    std::vector<int> ends;  // per spring: the free indices of a and b (-1: pinned)
    std::vector<int> stencil_ends;  // per stencil: 4 free indices (-1: pinned or absent)
    CscPattern pattern;
    std::vector<int> slots;  // per spring: 4 blocks (aa, ab, ba, bb) x 9 value positions, or -1
    // per stencil: 16 blocks (i, j) x 3 diagonal value positions (i's row, j's column), or -1
    std::vector<int> stencil_slots;
  };

 private:
  // Positions of an end and of a spring's b minus a, given the pins' positions at t (pins_at).
  Vec3 end_position(int particle, const double* x, const std::vector<Vec3>& pins) const;
  Vec3 spring_vector(const Spring& s, const double* x, const std::vector<Vec3>& pins) const;
  std::vector<Vec3> pins_at(double t) const;  // per pin, its position at t
  void spring_force_law(const Spring& s, double L, double& f, double& df) const;
  // v = sum_i w_i x_i
  Vec3 stencil_vector(const Stencil& st, const double* x, const std::vector<Vec3>& pins) const;
  void add_stencil_force(const Stencil& st, Vec3 kv, double* out) const;

  SpringNetworkSpec spec_;
  int free_count_ = 0;
  std::vector<int> free_index_;  // particle -> free index or -1
  std::vector<int> pin_slot_;    // particle -> pin index or -1
  std::vector<double> gamma_, dof_mass_, inv_mass_;
  double residual_scale_ = 1.0;
  double pin_move_time_ = 0.0;
  // The stiffness pattern, a function of the springs' and stencils' free ends alone: built on first
  // use (a drape run on its mirror reduction never needs the whole sheet's), shared by copies, and
  // memoised for the process (spring_network.cpp, layout_memo: a fit's drapes share a mesh).
  struct StiffnessStructure {
    std::once_flag once;
    std::shared_ptr<const StiffnessLayout> layout;
  };
  const StiffnessLayout& stiffness_layout() const;
  std::shared_ptr<StiffnessStructure> structure_;
};

}  // namespace knitsim
