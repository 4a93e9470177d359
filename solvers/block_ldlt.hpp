// Sparse LDL^T in 3 x 3 node blocks, for symmetric matrices whose pattern is made of dense
// 3 x 3 blocks: S = M (I + h Gamma) - h^2 K of a spring network (solvers/schur_matrix.hpp),
// where every particle's three coordinates couple to the same neighbours. On the mirror-reduced
// drapes (models/mirror_reduced.hpp) a particle on a mirror plane keeps 1 or 2 coordinates: its
// node is padded to 3 with identity rows and columns, which the arithmetic keeps exact (their
// entries of L stay 0, their pivots 1), so those matrices are factorised in blocks too. A
// planar network (the knit's default: z held by k_p I, models/spring_network.hpp) keeps its
// z unknowns coupled to nothing: where S's values say so, the factorisation runs in 2 x 2 x-y
// blocks, each z pivot its diagonal, the same factor bit for bit at ~30 % of the flops (factorize).
//
//   S = P^T L D L^T P,  L unit block lower triangular (3 x 3 blocks), D block diagonal.
//
// The up-looking algorithm of Davis's LDL (ACM TOMS 31(4), 2005), applied to nodes instead of
// scalars: an AMD ordering and an elimination tree of the node graph (one-ninth the size of the
// scalar one), then row k of L by a sparse triangular solve along the tree. The arithmetic is
// that of the scalar LDL^T, in 3 x 3 block products with one index per block instead of nine,
// so the compiler unrolls it: a factorisation takes about half the time of Eigen's scalar
// SimplicialLDLT with the same fill, or less on small grids (whole drapes:
// experiments/scaling/README.md, "Factorisation back end, 3x3 block LDL^T").
//
// No pivoting, like the scalar LDL^T: each 3 x 3 pivot block D_k is factorised in turn as
// l d l^T (the scalar LDL^T's arithmetic inside the block; an explicit cofactor inverse loses
// accuracy when the block's eigenvalues spread over many decades, as h^2 K's and M's do at large
// steps), and a zero or non-finite pivot ends the factorisation (factorize returns false). An
// indefinite S (compressed springs) is fine as long as no pivot vanishes.
#pragma once

#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <vector>

namespace knitsim::detail {

class BlockLdlt {
 public:
  // True if S (square, compressed, full symmetric pattern with sorted rows) is made of dense
  // blocks between nodes of 1 to 3 consecutive unknowns with the same rows, each stored entry's
  // block stored whole, and padding the nodes to 3 adds at most a third to the unknowns.
  static bool blocked(const Eigen::SparseMatrix<double>& S);

  // Ordering and symbolic factorisation of S's pattern; throws std::invalid_argument if
  // !blocked(S). Every later S must have this pattern.
  void analyze(const Eigen::SparseMatrix<double>& S);
  // The same, returning false (and analysing nothing) if !blocked(S). Analyses are memoised by
  // pattern, process-wide (block_ldlt.cpp, symbolic_memo): a repeated pattern costs a lookup.
  bool try_analyze(const Eigen::SparseMatrix<double>& S);
  // Forgets the memoised analyses (tests: a fresh analysis against a remembered one).
  static void clear_symbolic_memo();
  // Numeric factorisation; false if a pivot block is singular or not finite. Where every node
  // has 3 unknowns and the third couples to nothing (S's entries in its row and column are 0
  // but its diagonal: a planar spring network's z, whose stiffness is k_p I), the x-y blocks
  // are factorised 2 x 2 and each z pivot is its diagonal: the same factor bit for bit at about
  // a third of the flops (split()). Decided from S's values at each factorisation.
  bool factorize(const Eigen::SparseMatrix<double>& S);
  // Whether the latest factorisation split the third coordinates out; allow_split(false) keeps
  // every factorisation in 3 x 3 blocks (tests compare the two).
  bool split() const { return split_; }
  void allow_split(bool allow) { allow_split_ = allow; }
  // x = S^-1 b for the latest successful factorisation; b and x must not overlap.
  void solve(const double* b, double* x);
  // Negative pivots d of the latest successful factorisation: by Sylvester's law of inertia the
  // number of negative eigenvalues of S (padded coordinates have pivot 1).
  int negative_pivots() const;

  // Stored entries of L (3 x 3 blocks, counted as scalars).
  long nonzeros_l() const;
  // Entries of L below the diagonal and flops of one factorisation, counted on the scalar
  // columns (SymmetricFactor::factor_flops): the pattern's count, so padded coordinates count,
  // their zeros are computed too, and a split factorisation's third coordinates count too
  // (it does about 30 % of these flops).
  double scalar_nonzeros() const;
  double scalar_flops() const;

  struct Symbolic;  // one pattern's analysis (block_ldlt.cpp)

 private:
  std::shared_ptr<const Symbolic> sym_;       // the ordering and L's pattern (shared with the memo)
  int nb_ = 0;                                // nodes (blocks per side)
  std::vector<int> lnz_, li_, flag_, stack_;  // L's row indices as they are formed
  std::vector<double> lx_;                    // L's blocks, 9 per entry (row-major)
  std::vector<double> pivot_;  // D_k = l d l^T, 6 per node: d0, d1, d2, l10, l20, l21
  std::vector<double> work_;   // 9 per node: the row of L being formed; 3 per node in solve
  bool split_ = false;         // the latest factorisation's blocks are 2 x 2 (lx_: 4 per entry)
  bool allow_split_ = true;

  bool decoupled_third(const double* s) const;
  template <int B, bool Uniform>
  bool factorize_blocks(const double* s);
  template <int B>
  void solve_blocks(const double* b, double* x);
};

}  // namespace knitsim::detail
