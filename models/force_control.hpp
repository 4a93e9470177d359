// ForceControl: force control of a model that holds points (docs/knit.md, "Under load"). A clamp
// under a force is a rigid bar: its points move together with the bar, the bar's position
// components along the loaded directions are unknowns of the system, the force a dead load on
// them; the other components stay where the driver holds them (HeldPoints, as displacement
// control). Forces on free points are dead loads on their coordinates. Written against the model
// contract only (MechanicalSystem + HeldPoints), so any model that offers both serves it: the
// knit network now; the yarn-level model once it offers HeldPoints (its clamped courses as held
// points) and the dof of each free point.
//
// Equations. The inner model's state x (n dofs) and one unknown u_j per loaded component j of a
// bar (m in all, bar b's components in x, y, z order, bars in order): the unknowns are
// (x, u), length n + m. Held point k of bar b stands at base_k + sum_j u_j e_c(j) (base_k: where
// the driver holds it, set_held_positions; along a loaded component a force clamp's base is its
// rest, so u_j is the bar's displacement from rest). At load fraction s (set_load):
//     E(x, u)     = E_inner(x; held at u) - s sum_j F_j u_j - s sum_p F_p . x_p
//     F_bar,j     = s F_j - R_j(x, u),   R_j = sum over the bar's points of the reactions'
//                   component c(j) (HeldPoints::held_reactions: the force the hold exerts)
//     a_bar,j     = F_bar,j / M_b,   M_b = the bar's points x the inner model's mean dof mass
// so at an equilibrium each bar's reaction along its loaded components is the applied s F.
// Jacobian: the inner block is the inner model's; the bar columns da/du_j by central differences
// of the inner accelerations (step fd_step, m) and of R; the bar rows by the Hessian's symmetry
// (M_b da_bar,j/dx_i = m_i da_i/du_j), so M da/dx stays symmetric; the bar-bar block symmetrised.
// Pattern: every bar column and row is dense (a bar couples to whatever its points touch, and a
// contact renewal may change that), so a loaded run's factorisation has m dense rows more.
// Static residual: max(inner's, max_j |F_bar,j| / residual_force_scale).
//
// Run state (src/core/mechanical_system.hpp): set_load, set_held_positions and update change the
// functions; a driver calls them between runs to equilibrium. Every evaluation holds the inner
// model's points at the u it is given (the inner model's held positions are this object's
// scratch): it serves one thread, and after a run hold_at(x) leaves the inner model holding the
// points where x puts them (so the inner model's reactions and positions at x[0, n) are the run's).
//
// Units: SI (m, N, kg). Failure modes: the constructor throws std::invalid_argument for a model
// without held points, a bar without points or an index out of range, a non-finite force, a
// point load on a dof out of range, or fd_step <= 0.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "src/core/held_points.hpp"
#include "src/core/mechanical_system.hpp"
#include "src/core/vec3.hpp"

namespace knitsim {

// A clamp under a force: its held points (indices into HeldPoints), the force at load fraction 1
// (N); its loaded components are the non-zero ones.
struct ForceBar {
  std::string name;
  std::vector<int> held;
  Vec3 force;
};
// A dead load on a free point: its x coordinate's index in the inner state (y, z follow), N.
struct PointLoad {
  int dof = 0;
  Vec3 force;
};

class ForceControl final : public MechanicalSystem, public HeldPoints {
 public:
  // inner must outlive this object and offer held_points(); residual_force_scale (N) as the
  // inner model's static residual's (SpringNetwork::residual_force_scale).
  ForceControl(MechanicalSystem& inner, std::vector<ForceBar> bars, std::vector<PointLoad> loads,
               double residual_force_scale, double fd_step);

  // The load fraction s in [0, 1] (run state).
  void set_load(double s);
  double load() const { return load_; }
  // Holds the inner model's points where x (length dof()) puts them (run state).
  void hold_at(const double* x);
  // The bars' unknowns' components: unknown j is component component(j) (0 x, 1 y, 2 z) of bar
  // bar_of(j); it lies at x[inner dof + j].
  int unknowns() const { return static_cast<int>(comp_.size()); }
  int bar_of(int j) const { return bar_of_[j]; }
  int component(int j) const { return comp_[j]; }
  const std::vector<ForceBar>& bars() const { return bars_; }
  // Each bar's displacement along its loaded components (m; zero elsewhere) at x.
  std::vector<Vec3> bar_displacements(const double* x) const;
  // The applied loads at the current load fraction: bars' and points', summed (N).
  Vec3 applied_load() const;

  // MechanicalSystem
  int dof() const override { return n_ + unknowns(); }
  void initial_state(double* x, double* v) const override;
  void conservative_acceleration(double t, const double* x, double* a) const override;
  void constant_acceleration(double t, double* a) const override;
  const std::vector<double>& damping_rate() const override { return gamma_; }
  const std::vector<double>& mass() const override { return mass_; }
  const CscPattern& stiffness_pattern() const override { return pattern_; }
  void stiffness_values(double t, const double* x, double* values) const override;
  double static_residual(double t, const double* x) const override;
  double residual_roundoff(double t, const double* x) const override;
  bool planar() const override { return inner_.planar(); }
  double equilibrium_start_time() const override { return inner_.equilibrium_start_time(); }
  double admissible_step(double t, const double* x, const double* dx) const override;
  bool update(double t, const double* x) override;
  bool has_run_state() const override { return true; }
  double potential_energy(double t, const double* x) const override;
  std::string describe() const override;
  HeldPoints* held_points() override { return this; }
  const HeldPoints* held_points() const override { return this; }

  // HeldPoints: the inner model's held points; set_held_positions sets their base positions.
  int held_count() const override { return held_.held_count(); }
  int held_particle(int k) const override { return held_.held_particle(k); }
  std::vector<Vec3> held_positions(double t) const override { return held_.held_positions(t); }
  void set_held_positions(const std::vector<Vec3>& p) override;
  void held_reactions(double t, const double* x, std::vector<Vec3>& out) const override;

 private:
  void hold(const double* u) const;  // the inner model's held points at base + u (scratch)
  // The bars' net forces F_bar,j (N) at (t, x), the inner model holding at x's u.
  void bar_forces(double t, const double* x, double* f) const;

  MechanicalSystem& inner_;
  HeldPoints& held_;
  std::vector<ForceBar> bars_;
  std::vector<PointLoad> loads_;
  double residual_scale_;
  double fd_step_;
  int n_;
  std::vector<int> bar_of_, comp_;
  std::vector<Vec3> base_;
  std::vector<double> u0_;  // the unknowns' start (initial_state): the last hold_at's
  double load_ = 1.0;
  std::vector<double> mass_, gamma_;
  CscPattern pattern_;
  std::vector<int> inner_nnz_end_;  // per inner column, where its inner entries end in pattern_
  // Scratch (one thread): the u the inner model holds at, and buffers.
  mutable std::vector<double> held_u_;
  mutable bool held_valid_ = false;
  mutable std::vector<double> scratch_a_, scratch_b_, scratch_k_;
  mutable std::vector<Vec3> scratch_r_;
};

}  // namespace knitsim
