// MirrorQuarter: a SpringNetwork that is symmetric under the two mirrors x -> 2 c_x - x and
// y -> 2 c_y - y, integrated on one quarter (x <= c_x, y <= c_y) with symmetry conditions
// (issue 5 item 5: "model only what a scene requires"). The drape grid's four_corner scene
// (SPEC 2.2) is such a network for every topology a, b, c; make_drape_quarter builds it.
//
// Group G = {e, X, Y, XY}. A symmetric state is one with x_{g(p)} = g(x_p) for all g in G.
// The quarter's unknowns q are the coordinates of the free particles of the domain
//   D = { p : (X(p) = p or x_p < c_x) and (Y(p) = p or y_p < c_y) }   (one particle per orbit),
// minus the coordinates fixed by the mirrors: a particle on the plane x = c_x (X(p) = p) keeps
// x = c_x, so its x is not in q (likewise y on y = c_y; the particle on both keeps only z).
// q layout: domain particles in ascending full index, each with its free coordinates in the
// order x, y, z (3, 2 or 1 entries), so dof() need not be a multiple of 3.
//
// Equations: the exact restriction of the full equations to symmetric states. With
// E the full potential and E_Q(q) = E(x(q)) / 4 (x(q) the unfolded state),
//   E_Q = sum over spring orbits O of (|O|/4) E_s(rep O)  +  sum_{p in D} w_p m_p (-g . x_p),
//   w_p = |orbit(p)| / 4 (1 inside, 1/2 on one plane, 1/4 on both),
// and equivariance gives -dE_Q/dq = w_p F_p (F_p the full net force on p, constrained
// components dropped: they vanish on symmetric states). With quarter mass w_p m_p and damping
// w_p c the quarter's accelerations are exactly the full ones:
//   a_q = F_p / m_p - (c / m_p) v_p.
// Springs: one representative per orbit, stiffness w_s k (w_s = |O|/4: 1/2 for a spring lying
// in a plane or mapped onto itself by one mirror). A representative whose far end lies outside
// D (a spring crossing a plane: for even n the bending springs over the middle line, for odd n
// every spring across the middle) keeps that end as a "ghost" particle, tied to its domain
// image by the mirror: x_ghost = g(x_image). The quarter network (a SpringNetwork, gravity off)
// evaluates the springs on the domain + ghost particles; the tie x_net = P q + o (P: one +-1 per
// row) gives force P^T F_net and Jacobian P^T K_net P exactly (chain rule), so crossing springs
// need no special force law.
// Static residual: max_p |F_p| / F_ref over the domain's free particles with F_p = (force on
// q) / w_p and F_ref the full network's residual_force_scale(): the full criterion (SPEC 2.3)
// at the unfolded state; its round-off floor is the full network's (a copy is kept for it).
// project() (explicit reference paths only) runs the quarter network's Provot pass and keeps the
// domain particles' moves: the full pass runs in spring order and is not exactly symmetric
// itself, so on those paths the quarter agrees with the full model only to that order effect.
//
// Failure modes: a network that is not symmetric (a spring, mass, position or pin without its
// mirror image, image maps that are not commuting involutions, gravity with an x or y
// component) throws std::invalid_argument with one line naming the first offender.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "models/drape_grid.hpp"
#include "models/spring_network.hpp"

namespace knitsim {

// The two mirror planes x = x_plane and y = y_plane (m) and the particle permutations they
// induce: image_x[p] is the particle at (2 x_plane - x_p, y_p, z_p) (p itself on the plane).
struct MirrorPlanes {
  double x_plane = 0.0;
  double y_plane = 0.0;
  std::vector<int> image_x;
  std::vector<int> image_y;
};

class MirrorQuarter final : public MechanicalSystem {
 public:
  // Checks that `full` is symmetric (positions at t = 0, masses, springs, pins) and builds the
  // quarter. Throws std::invalid_argument otherwise.
  MirrorQuarter(const SpringNetwork& full, const MirrorPlanes& planes);

  // MechanicalSystem (layouts as in the header comment)
  int dof() const override { return static_cast<int>(mass_.size()); }
  void initial_state(double* q, double* v) const override;
  void conservative_acceleration(double t, const double* q, double* a) const override;
  void constant_acceleration(double t, double* a) const override;  // gravity
  const std::vector<double>& damping_rate() const override { return gamma_; }
  const std::vector<double>& mass() const override { return mass_; }
  const CscPattern& stiffness_pattern() const override { return pattern_; }
  void stiffness_values(double t, const double* q, double* values) const override;
  double static_residual(double t, const double* q) const override;
  // The full network's floor at the unfolded state (one pass over the full springs; the
  // driver asks only near equilibrium).
  double residual_roundoff(double t, const double* q) const override;
  double equilibrium_start_time() const override { return net_->equilibrium_start_time(); }
  bool project(double t, double* q, double* v) const override;
  double potential_energy(double t, const double* q) const override;  // E(x(q)) / 4, J
  std::string describe() const override;

  // The full network's free state (length full.dof()) of the symmetric state q: every
  // particle's coordinates are those of its domain image, mirrored.
  void unfold(const double* q, double* x_full) const;
  // q entry j is the full free dof full_dof()[j] (the coordinate of a domain particle), so
  // the restriction of a full state or force is x_full[full_dof()[j]].
  const std::vector<int>& full_dof() const { return full_dof_; }
  // The springs the quarter evaluates (domain + ghost particles, weighted stiffness).
  const SpringNetwork& quarter_network() const { return *net_; }

 private:
  // x_full[k] in the state q (k a full free dof).
  double tied_value(const double* q, int k) const {
    const int j = tie_dof_[k];
    return (j >= 0 ? tie_sign_[k] * q[j] : 0.0) + tie_offset_[k];
  }
  void expand(const double* q) const;                   // x_net_ from q
  void reduced_force(double t, const double* q) const;  // f_red_ = P^T F_net (springs only)

  std::unique_ptr<SpringNetwork> net_;
  std::unique_ptr<SpringNetwork> full_;  // a copy of the full model, for residual_roundoff
  Vec3 gravity_;
  double residual_scale_ = 1.0;  // N, the full network's F_ref
  int full_dof_count_ = 0;
  // Full free dof k: x_full[k] = tie_sign_[k] q[tie_dof_[k]] + tie_offset_[k] (tie_dof_ -1: the
  // constant tie_offset_, a coordinate on a plane).
  std::vector<int> tie_dof_;
  std::vector<double> tie_sign_, tie_offset_;
  std::vector<int> net_full_dof_;    // quarter network free dof -> full free dof
  std::vector<int> full_dof_;        // q entry -> full free dof
  std::vector<int> coordinate_;      // q entry -> 0, 1, 2 (x, y, z)
  std::vector<int> particle_begin_;  // q entries of domain free particle r: [begin r, begin r+1)
  std::vector<double> weight_;       // per domain free particle: w_p
  std::vector<double> mass_, gamma_, initial_;
  CscPattern pattern_;
  std::vector<int> jac_target_;     // per quarter network nnz: q pattern position or -1
  std::vector<double> jac_factor_;  // sign_row sign_col m_net,row / m_q,row
  mutable std::vector<double> x_net_, f_net_, k_net_, f_red_, x_full_;
};

// The mid-planes x = y = n L0 / 2 of a drape grid and its particle images (i, n - j), (n - i, j).
MirrorPlanes drape_mirror_planes(const DrapeGrid& grid);

// The quarter of a four_corner drape grid (planes through the grid's centre). Throws
// std::invalid_argument "model.symmetry = quarter: ..." naming the layout, the perturbation or
// the topology that makes the grid asymmetric.
MirrorQuarter make_drape_quarter(const DrapeGrid& grid);

}  // namespace knitsim
