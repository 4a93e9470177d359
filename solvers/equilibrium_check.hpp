// What makes an end state an equilibrium, for every integrator (docs/equilibrium.md): a stop in
// positions and a certificate that the state is a stable minimum the damped dynamics can reach.
//
//   K = -M Ax        the symmetric stiffness (N/m): the Hessian of the potential energy, from the
//                    model's stiffness values (Ax = da_c/dx, row i over m_i)
//   F = M a_c(t, x)  the net static force (N); F = -dE/dx
//   delta = K^-1 F   the Newton correction (m): the distance to the equilibrium to first order
//
// Stop: delta's largest component below IntegratorOptions::position_tol, or below its round-off
// floor (one solve against the forces' round-off, MechanicalSystem::residual_roundoff) where
// that is larger, at a state where K is positive definite (LDL^T with no negative pivot).
// A free-floating model (MechanicalSystem::free_floating: no pins, no external field) has the
// 6 rigid-body modes in K's null space (3 for a planar model: MechanicalSystem::planar); they are
// factored out by holding as many gauge dofs (where the modes are independent) fixed in K, the
// forces and the Newton correction, so a free knit chart is certified on its deformations. Where K
// is still singular (mechanism modes: its smallest eigenvalue within n eps ||K||_inf of 0) the
// static residual decides (equilibrium_threshold, solvers/integrator.hpp), and the certificate is
// inconclusive.
#pragma once

#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "solvers/integrator.hpp"

namespace knitsim::detail {

class SymmetricFactor;

// An n x n matrix with the model's stiffness pattern (values zero); A(h) = C / h + K with
// C = M Gamma the damping matrix (N s/m), written by fill_flow_values (inv_h = 1 / h; 0 gives K;
// ax, the model's stiffness values, may be A's own values array: entry k is read before written).
void fill_flow_values(const MechanicalSystem& sys, double inv_h, const double* ax,
                      Eigen::SparseMatrix<double>& A);

// K at states of one model: analysed once, factorised per call.
class StiffnessProbe {
 public:
  StiffnessProbe(const MechanicalSystem& sys, IntegratorOptions::Factorization which);
  ~StiffnessProbe();
  StiffnessProbe(const StiffnessProbe&) = delete;
  StiffnessProbe& operator=(const StiffnessProbe&) = delete;

  struct Result {
    bool factored = false;     // K factorised (false: a zero pivot, K singular)
    int negative_pivots = 0;   // negative eigenvalues of K (inertia)
    bool singular = false;     // not factored, or |smallest eigenvalue| <= threshold
    double min_eigenvalue = 0.0;  // N/m: the eigenvalue of K nearest 0 (inverse iteration)
    double threshold = 0.0;       // N/m: n eps ||K||_inf, what round-off cannot tell from 0
    double newton_step = 0.0;     // m: ||K^-1 F||_inf
    double newton_floor = 0.0;    // m: ||K^-1 f||_inf, f the forces' round-off, uniform
  };
  // What probe measures: everything, or K's inertia and smallest eigenvalue only (newton_step
  // and newton_floor stay 0: the whole-sheet certificate of a reduced drape reads only these).
  enum class Measure { All, Spectrum };
  // Factorises K at (t, x) and measures it.
  Result probe(double t, const double* x, Measure measure = Measure::All);
  // A unit eigenvector of K's most negative eigenvalue after probe() found negative pivots
  // (power iteration on s I - K, s a Gershgorin bound; deterministic), its largest component
  // positive (the documented sign of a saddle escape). Empty if it did not converge.
  std::vector<double> negative_mode(double t, const double* x);
  // Moves x (length dof) `move` metres, at its largest component, along negative_mode(t, x),
  // shortened to the fraction the model admits (MechanicalSystem::admissible_step: a contact
  // barrier it would jump through): how a saddle is left (the equilibrium solver; model.symmetry =
  // auto on the whole sheet). False, x unchanged, where no negative mode is found or the model
  // admits none of the move.
  bool leave_saddle(double t, double* x, double move);
  // The Newton correction K^-1 F at (t, x) into w (length dof; zero at the gauge dofs of a
  // free-floating model), with one factorisation of K: true where K is positive definite (no
  // zero or negative pivot) and w is finite, else false (w unspecified). The warm start of a
  // stepped run (src/scene/tensile_run.cpp): one Newton step from its predictor, the solver's
  // stop then certifying the result.
  bool newton_correction(double t, const double* x, std::vector<double>& w);
  long factorisations() const { return factorisations_; }
  // The gauge dofs of the last factorisation (empty unless the model is free-floating).
  const std::vector<int>& gauge() const { return gauge_; }

 private:
  void fill_stiffness(double t, const double* x);  // K at (t, x), the gauge held
  void hold_gauge(Eigen::VectorXd& v) const;       // zero v at the gauge dofs

  const MechanicalSystem* sys_;
  Eigen::SparseMatrix<double> K_;
  std::unique_ptr<SymmetricFactor> factor_;
  std::vector<double> f_;
  std::vector<int> gauge_;
  long factorisations_ = 0;
};

}  // namespace knitsim::detail
