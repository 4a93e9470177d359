// Sparse factorisation of the symmetric reduced Newton matrices S = M (I + h Gamma) - h^2 K
// (solvers/schur_matrix.hpp): one pattern, analysed once, factorised numerically at every set-up,
// then solved against many right-hand sides. Used by implicit-euler, the Schur Newton solver
// of cvode-bdf / arkode-dirk / arkode-imex (schur_ldl_solver.hpp) and cvode-bdf-gmres's Schur
// LDL^T preconditioner.
//
// Two back ends:
//   simplicial  Eigen's SimplicialLDLT (AMD ordering, column by column, scalar loops). LDL^T,
//               so it also factors an indefinite S (K is indefinite when springs are
//               compressed). The cheapest below a few thousand dof: on the 11 x 11 drapes one
//               factorisation costs ~0.3 ms, CHOLMOD's supernodal one ~0.9 ms.
//   supernodal  CHOLMOD's supernodal LL^T (AMD or METIS ordering, dense BLAS kernels on the
//               supernodes). Faster on large grids with an optimised BLAS (Debian's
//               libopenblas0-serial, which run.sh installs); LL^T needs S positive definite,
//               and a factorisation that finds it is not falls back to the simplicial LDL^T
//               for that set-up (counted in ldl_fallbacks()).
// `automatic` takes the supernodal back end from supernodal_min_dof unknowns on. Measured on
// the four_corner Schur matrix at h = 100 s, OpenBLAS 0.3.21 serial, one factorisation / one
// solve (scratch harness, 2026-11-23):
//   dof     simplicial          supernodal
//   1311    3.0 ms / 0.12 ms    5.7 ms / 0.07 ms
//   5031    33 ms / 0.79 ms     30 ms / 0.35 ms
//   11151   122 ms / 3.4 ms     80 ms / 0.90 ms
//   19671   381 ms / 8.5 ms     177 ms / 3.5 ms
// Whole drapes (README "Performance"): at 5031 dof both take 2.8 s, at 30 591 dof the
// supernodal back end halves the time. The threshold sits above the tie, where a run whose S is
// often indefinite (the knit chart tucks40, 4851 dof: 10 of 13 factorisations fall back) would
// lose by trying LL^T first. With Debian's reference BLAS (libblas3) the supernodal back end is
// no faster (19671 dof: 389 ms per factorisation).
#pragma once

#include <Eigen/SparseCore>
#include <memory>

#include "solvers/integrator.hpp"

namespace knitsim::detail {

class SymmetricFactor {
 public:
  using Backend = IntegratorOptions::Factorization;
  // Below this many unknowns `automatic` means simplicial.
  static constexpr int supernodal_min_dof = 8000;

  explicit SymmetricFactor(Backend which = Backend::Automatic);
  ~SymmetricFactor();
  SymmetricFactor(const SymmetricFactor&) = delete;
  SymmetricFactor& operator=(const SymmetricFactor&) = delete;

  // Symbolic analysis of S's pattern (S square, compressed; its lower triangle is used).
  // Chooses the back end. Every later S must have this pattern.
  void analyze(const Eigen::SparseMatrix<double>& S);
  // Numeric factorisation; false if S is singular (then solve must not be called).
  bool factorize(const Eigen::SparseMatrix<double>& S);
  // x = S^-1 b for the latest successful factorisation; b and x must not overlap.
  void solve(const Eigen::Ref<const Eigen::VectorXd>& b, Eigen::Ref<Eigen::VectorXd> x);

  // The back end analyze() chose (Simplicial or Supernodal).
  Backend backend() const;
  // Factorisations the supernodal back end handed to LDL^T because S was not positive definite.
  long ldl_fallbacks() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace knitsim::detail
