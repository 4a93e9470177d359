// Sparse factorisation of the solvers' symmetric matrices in the model's stiffness pattern: the
// reduced Newton matrices S = M (I + h Gamma) - h^2 K (solvers/schur_matrix.hpp), the
// equilibrium solver's C / h + K, and K itself. One pattern, analysed once, factorised
// numerically at every set-up, then solved against many right-hand sides. Used by
// implicit-euler, the Schur Newton solver of cvode-bdf / arkode-dirk / arkode-imex
// (schur_ldl_solver.hpp), cvode-bdf-gmres's Schur LDL^T preconditioner, the equilibrium solver,
// the stop's probe of K (equilibrium_check.hpp) and the fit's sensitivities.
//
// Three back ends:
//   simplicial  Eigen's SimplicialLDLT (AMD ordering, column by column, scalar loops). LDL^T,
//               so it also factors an indefinite S (K is indefinite when springs are
//               compressed).
//   block       the same up-looking LDL^T in 3 x 3 particle blocks (solvers/block_ldlt.hpp):
//               same fill, one index per block instead of nine, unrolled 3 x 3 kernels. Used
//               where S is made of such blocks: every spring network, the mirror-reduced drapes
//               too (a particle on a mirror plane keeps 1 or 2 coordinates, padded to 3);
//               2 x 2 x-y blocks where a planar network's z unknowns couple to nothing.
//   supernodal  CHOLMOD's supernodal LL^T (AMD or METIS ordering, dense BLAS kernels on the
//               supernodes). Fastest on large grids with an optimised BLAS (Debian's
//               libopenblas0-serial, which run.sh installs); LL^T needs S positive definite,
//               and a factorisation that finds it is not falls back to LDL^T (block where it
//               applies) for that set-up (counted in ldl_fallbacks()).
// `automatic` takes the supernodal back end from supernodal_min_dof unknowns on, below that
// block (or simplicial where S is not blocked). Per factorisation, block takes about half the
// time of simplicial at the same fill; supernodal overtakes block only on large grids, and the
// threshold interpolates where whole four_corner drapes of the two cross over with Debian's
// serial OpenBLAS (experiments/scaling/README.md, "Factorisation back end, 3x3 block LDL^T").
// With the reference BLAS (libblas3) supernodal gains nothing over simplicial (same README,
// "Factorisation back end, supernodal").
#pragma once

#include <Eigen/SparseCore>
#include <memory>

#include "solvers/integrator.hpp"

namespace knitsim::detail {

class SymmetricFactor {
 public:
  using Backend = IntegratorOptions::Factorization;
  // Below this many unknowns `automatic` means block (or simplicial where S is not blocked).
  static constexpr int supernodal_min_dof = 33000;

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

  // Negative eigenvalues of the latest factorised S (Sylvester's law of inertia, from the LDL^T
  // pivots; 0 after a successful supernodal LL^T, which exists only for positive definite S).
  int negative_pivots() const;

  // The back end analyze() chose (Simplicial, Block or Supernodal).
  Backend backend() const;
  // Factorisations the supernodal back end handed to LDL^T because S was not positive definite.
  long ldl_fallbacks() const;

  // Size and cost of one numeric factorisation of the analysed pattern by the chosen back end,
  // in CHOLMOD's convention: with c_j the entries of L below the diagonal in column j,
  // nonzeros = sum_j c_j and flops = sum_j (c_j + 1)^2 (a multiply and an add count 2). The
  // block back end counts its padded coordinates and, where it splits a planar network's z out,
  // the z columns too (the pattern's count: the split does ~30 % of it); the supernodal one
  // reports CHOLMOD's count for the exact pattern, before amalgamation adds explicit zeros to
  // the supernodes. Both 0
  // before analyze(). On a 2-D grid nested dissection's theory has them grow like N log N and
  // N^1.5; on the four_corner drapes (AMD) the flops grew like N^1.75 (experiments/scaling).
  double factor_nonzeros() const;
  double factor_flops() const;
  // Writes backend(), ldl_fallbacks(), factor_nonzeros() and factor_flops() into st.
  void fill_stats(RunStats& st) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace knitsim::detail
