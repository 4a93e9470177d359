#include "solvers/block_ldlt.hpp"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "src/core/memo.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim::detail {

namespace {

// B x B blocks are row-major arrays of B * B: B = 3 (a particle's x, y, z), or B = 2 where the
// third coordinates are split out (a planar network's x, y; see decoupled_third below).

struct BlockPattern {
  std::vector<int> start;              // group J holds columns start[J] .. start[J + 1) - 1
  std::vector<std::vector<int>> rows;  // rows[J]: the groups of group J's stored blocks, sorted
  bool empty() const { return rows.empty(); }
};

// Y -= A B for B x B blocks. Y overlaps neither A nor B (a work block, a factor block, a copy on
// the stack): __restrict lets the compiler keep Y in registers instead of storing and reloading
// each entry between the products (the same operations in the same order; results bit for bit
// the same).
template <int B>
inline void sub_product(double* __restrict Y, const double* __restrict A,
                        const double* __restrict X) {
  for (int r = 0; r < B; ++r)
    for (int c = 0; c < B; ++c) {
      double sum = A[B * r] * X[c];
      for (int q = 1; q < B; ++q) sum += A[B * r + q] * X[B * q + c];
      Y[B * r + c] -= sum;
    }
}

// The solves' block updates, v -= L u and v -= L^T u for a B x B block L of the factor and
// two distinct nodes' entries (restrict, as sub_product).
template <int B>
inline void sub_block_times(double* __restrict v, const double* __restrict l,
                            const double* __restrict u) {
  for (int r = 0; r < B; ++r) {
    double sum = l[B * r] * u[0];
    for (int q = 1; q < B; ++q) sum += l[B * r + q] * u[q];
    v[r] -= sum;
  }
}
template <int B>
inline void sub_block_transposed_times(double* __restrict v, const double* __restrict l,
                                       const double* __restrict u) {
  for (int c = 0; c < B; ++c) {
    double sum = l[c] * u[0];
    for (int q = 1; q < B; ++q) sum += l[B * q + c] * u[q];
    v[c] -= sum;
  }
}

// A pivot block D (symmetric, row-major; its lower triangle is read) as D = l d l^T, l unit
// lower triangular, d diagonal: the scalar LDL^T's own arithmetic inside the block, so the block
// factorisation is as accurate as the scalar one (an explicit cofactor inverse is not: its
// determinant cancels when the block's eigenvalues spread over many decades, as they do at
// large steps, where h^2 K dwarfs M). f = {d0, d1, d2, l10, l20, l21}; false if a pivot is 0
// or not finite.
bool factor_pivot(const double* a, double* f) {
  const double d0 = a[0];
  const double l10 = a[3] / d0, l20 = a[6] / d0;
  const double d1 = a[4] - l10 * l10 * d0;
  const double l21 = (a[7] - l20 * l10 * d0) / d1;
  const double d2 = a[8] - l20 * l20 * d0 - l21 * l21 * d1;
  const double v[6] = {d0, d1, d2, l10, l20, l21};
  for (int q = 0; q < 6; ++q) {
    if (!std::isfinite(v[q]) || (q < 3 && v[q] == 0.0)) return false;
    f[q] = v[q];
  }
  return true;
}

// v = D^-1 v (3 entries) for the pivot block f (factor_pivot).
inline void apply_pivot_inverse(const double* f, double* v) {
  double w0 = v[0];
  double w1 = v[1] - f[3] * w0;
  double w2 = v[2] - f[4] * w0 - f[5] * w1;
  w0 /= f[0];
  w1 /= f[1];
  w2 /= f[2];
  w1 -= f[5] * w2;
  w0 -= f[3] * w1 + f[4] * w2;
  v[0] = w0;
  v[1] = w1;
  v[2] = w2;
}

// The block structure of a blocked S: its columns cut into groups of 1 to 3 consecutive ones
// with the same rows (a particle's coordinates; fewer than 3 where a mirror plane keeps only
// some), and for each group the groups of its stored blocks, in order. Greedy from column 0: a
// group takes the next column while it holds the same rows and the group has fewer than 3, so a
// pattern of whole 3 x 3 particle blocks gives exactly its particles. S is blocked if every
// column holds whole groups, the group pattern is symmetric, and padding every group to 3 adds
// at most a third to the unknowns (a scalar pattern, all groups of 1, is not blocked).
BlockPattern block_pattern(const Eigen::SparseMatrix<double>& S) {
  const int n = static_cast<int>(S.rows());
  if (S.cols() != n || n == 0 || !S.isCompressed()) return {};
  const int* cp = S.outerIndexPtr();
  const int* ri = S.innerIndexPtr();
  auto same_rows = [&](int a, int b) {
    return cp[a + 1] - cp[a] == cp[b + 1] - cp[b] &&
           std::equal(ri + cp[a], ri + cp[a + 1], ri + cp[b]);
  };
  BlockPattern bp;
  bp.start.push_back(0);
  for (int j = 0; j < n;) {
    int size = 1;
    while (size < 3 && j + size < n && same_rows(j, j + size)) ++size;
    j += size;
    bp.start.push_back(j);
  }
  const int nb = static_cast<int>(bp.start.size()) - 1;
  if (3L * nb * 3 > 4L * n) return {};  // padded to 3 x nb unknowns: more than n * 4/3
  std::vector<int> group_of(n);
  for (int J = 0; J < nb; ++J)
    for (int c = bp.start[J]; c < bp.start[J + 1]; ++c) group_of[c] = J;
  bp.rows.resize(nb);
  for (int J = 0; J < nb; ++J) {
    const int col = bp.start[J];
    for (int k = cp[col]; k < cp[col + 1];) {
      const int I = group_of[ri[k]];
      const int size = bp.start[I + 1] - bp.start[I];
      if (ri[k] != bp.start[I] || k + size > cp[col + 1]) return {};
      for (int q = 1; q < size; ++q)
        if (ri[k + q] != ri[k] + q) return {};
      bp.rows[J].push_back(I);
      k += size;
    }
  }
  // Structurally symmetric: the factorisation reads each group column's upper part only.
  std::vector<int> count(nb, 0);
  for (int J = 0; J < nb; ++J)
    for (int I : bp.rows[J]) ++count[I];
  for (int J = 0; J < nb; ++J)
    if (count[J] != static_cast<int>(bp.rows[J].size())) return {};
  for (int J = 0; J < nb; ++J)
    for (int I : bp.rows[J])
      if (!std::binary_search(bp.rows[I].begin(), bp.rows[I].end(), J)) return {};
  return bp;
}

}  // namespace

bool BlockLdlt::blocked(const Eigen::SparseMatrix<double>& S) { return !block_pattern(S).empty(); }

void BlockLdlt::analyze(const Eigen::SparseMatrix<double>& S) {
  if (!try_analyze(S))
    throw std::invalid_argument("BlockLdlt: S is not made of dense, symmetric 3 x 3 blocks");
}

// The ordering and symbolic factorisation of a pattern: a pure function of it.
struct BlockLdlt::Symbolic {
  std::vector<int> outer, inner;  // the pattern analysed (the memo's key)
  bool blocked = false;
  int nb = 0;                          // nodes (blocks per side)
  std::vector<int> perm;               // perm[k]: node eliminated k-th
  std::vector<int> first, size;        // for the node eliminated k-th: its first unknown, its count
  std::vector<int> ap, ai;             // upper block pattern of P S P^T by column (rows i <= k)
  std::vector<std::array<int, 3>> at;  // for each: S's value index of the block's column c, row 0
  std::vector<int> parent, lp;         // elimination tree; where each column of L starts
  bool uniform = true;                 // every node has 3 unknowns (no padding)
};

namespace {

using Symbolic = BlockLdlt::Symbolic;

std::shared_ptr<const Symbolic> analyse_pattern(const Eigen::SparseMatrix<double>& S) {
  auto sym = std::make_shared<Symbolic>();
  sym->outer.assign(S.outerIndexPtr(), S.outerIndexPtr() + S.cols() + 1);
  sym->inner.assign(S.innerIndexPtr(), S.innerIndexPtr() + S.nonZeros());
  const BlockPattern bp = block_pattern(S);
  if (bp.empty()) return sym;
  sym->blocked = true;
  const std::vector<std::vector<int>>& rows = bp.rows;
  const int nb = sym->nb = static_cast<int>(rows.size());

  // AMD on the node graph; Eigen's ordering returns the node eliminated k-th at position k.
  std::vector<Eigen::Triplet<double>> entries;
  for (int J = 0; J < nb; ++J)
    for (int I : rows[J]) entries.emplace_back(I, J, 1.0);
  Eigen::SparseMatrix<double> graph(nb, nb);
  graph.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;
  Eigen::AMDOrdering<int>()(graph, order);
  std::vector<int>& perm = sym->perm;
  perm.assign(order.indices().data(), order.indices().data() + nb);
  std::vector<int> pinv(nb);
  for (int k = 0; k < nb; ++k) pinv[perm[k]] = k;
  sym->first.resize(nb);
  sym->size.resize(nb);
  for (int k = 0; k < nb; ++k) {
    sym->first[k] = bp.start[perm[k]];
    sym->size[k] = bp.start[perm[k] + 1] - sym->first[k];
    sym->uniform = sym->uniform && sym->size[k] == 3;
  }

  // Column k of P S P^T, rows i <= k, with where each block's columns start in S's values (-1
  // for a padded column).
  const int* cp = S.outerIndexPtr();
  sym->ap.assign(nb + 1, 0);
  for (int k = 0; k < nb; ++k) {
    const int J = perm[k];
    int offset = 0;  // rows of S above this block in group J's columns
    for (int I : rows[J]) {
      const int i = pinv[I];
      if (i <= k) {
        sym->ai.push_back(i);
        std::array<int, 3> where{-1, -1, -1};
        for (int c = 0; c < sym->size[k]; ++c) where[c] = cp[bp.start[J] + c] + offset;
        sym->at.push_back(where);
      }
      offset += sym->size[i];
    }
    sym->ap[k + 1] = static_cast<int>(sym->ai.size());
  }

  // Elimination tree and column counts of L (ldl_symbolic).
  std::vector<int>& parent = sym->parent;
  parent.assign(nb, -1);
  std::vector<int> lnz(nb, 0), flag(nb, -1);
  for (int k = 0; k < nb; ++k) {
    flag[k] = k;
    for (int p = sym->ap[k]; p < sym->ap[k + 1]; ++p)
      for (int i = sym->ai[p]; flag[i] != k; i = parent[i]) {
        if (parent[i] == -1) parent[i] = k;
        ++lnz[i];
        flag[i] = k;
      }
  }
  sym->lp.assign(nb + 1, 0);
  for (int k = 0; k < nb; ++k) sym->lp[k + 1] = sym->lp[k] + lnz[k];
  return sym;
}

// The analyses of the latest patterns, memoised: a fit or a study builds the same few grids
// (size x topology x reduction) for thousands of drapes, and on a fit's drape the analysis (AMD,
// elimination tree) costs about as much as the reduced solve. The result is a function of the
// pattern alone, so a hit factorises bit for bit as a fresh analysis, on any thread. At most
// 32 MB of integers; the oldest entry goes first.
PatternMemo<BlockLdlt::Symbolic>& symbolic_memo() {
  static PatternMemo<BlockLdlt::Symbolic> memo(std::size_t{1} << 23);
  return memo;
}

std::size_t footprint(const BlockLdlt::Symbolic& e) {
  return e.outer.size() + e.inner.size() + 4 * e.perm.size() + e.ai.size() * 5 + e.lp.size();
}

}  // namespace

void BlockLdlt::clear_symbolic_memo() { symbolic_memo().clear(); }

bool BlockLdlt::try_analyze(const Eigen::SparseMatrix<double>& S) {
  if (!S.isCompressed()) return false;
  std::shared_ptr<const Symbolic> sym = symbolic_memo().find([&S](const Symbolic& e) {
    return e.outer.size() == static_cast<size_t>(S.cols() + 1) &&
           e.inner.size() == static_cast<size_t>(S.nonZeros()) &&
           std::equal(e.outer.begin(), e.outer.end(), S.outerIndexPtr()) &&
           std::equal(e.inner.begin(), e.inner.end(), S.innerIndexPtr());
  });
  if (!sym) {
    std::shared_ptr<const Symbolic> fresh = analyse_pattern(S);
    sym = symbolic_memo().insert(fresh, footprint(*fresh));
  }
  if (!sym->blocked) return false;
  sym_ = std::move(sym);  // shared with the memo: a hit copies nothing
  nb_ = sym_->nb;
  lnz_.assign(nb_, 0);
  flag_.assign(nb_, -1);
  li_.resize(sym_->lp[nb_]);
  lx_.resize(9 * static_cast<std::size_t>(sym_->lp[nb_]));
  pivot_.resize(6 * static_cast<std::size_t>(nb_));
  work_.assign(9 * static_cast<std::size_t>(nb_), 0.0);
  stack_.resize(nb_);
  return true;
}

long BlockLdlt::nonzeros_l() const { return sym_ ? 9L * sym_->lp.back() : 0; }

// Node i's three scalar columns hold, below the diagonal, its 3 b blocks' rows (b = its blocks
// in L) plus 2, 1 and 0 entries of its own pivot block.
double BlockLdlt::scalar_nonzeros() const {
  if (!sym_) return 0.0;  // nothing analysed
  const Symbolic& sym = *sym_;
  double n = 0.0;
  for (int i = 0; i < nb_; ++i) n += 9.0 * (sym.lp[i + 1] - sym.lp[i]) + 3.0;
  return n;
}

double BlockLdlt::scalar_flops() const {
  if (!sym_) return 0.0;  // nothing analysed
  const Symbolic& sym = *sym_;
  double f = 0.0;
  for (int i = 0; i < nb_; ++i) {
    const double c = 3.0 * (sym.lp[i + 1] - sym.lp[i]);
    f += (c + 3) * (c + 3) + (c + 2) * (c + 2) + (c + 1) * (c + 1);
  }
  return f;
}

bool BlockLdlt::factorize(const Eigen::SparseMatrix<double>& S) {
  if (nb_ == 0) throw std::logic_error("BlockLdlt::factorize before analyze");
  const double* s = S.valuePtr();
  split_ = sym_->uniform && allow_split_ && decoupled_third(s);
  if (split_) return factorize_blocks<2, true>(s);
  return sym_->uniform ? factorize_blocks<3, true>(s) : factorize_blocks<3, false>(s);
}

// Every node's third coordinate couples to nothing: in the blocks the factorisation reads (the
// upper block pattern of P S P^T), its rows and columns are 0 but for its own diagonal. The 3 x 3
// arithmetic would then keep every third-coordinate entry of L at 0 and leave that pivot S_zz,
// and the x-y entries would add only those zeros: the 2 x 2 kernel below does the rest of the
// same operations in the same order, bit for bit the same factor at about a third of the flops.
bool BlockLdlt::decoupled_third(const double* s) const {
  const Symbolic& sym = *sym_;
  for (int k = 0; k < nb_; ++k)
    for (int p = sym.ap[k]; p < sym.ap[k + 1]; ++p) {
      const bool own = sym.ai[p] == k;
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
          if ((r == 2 || c == 2) && !(own && r == 2 && c == 2) && s[sym.at[p][c] + r] != 0.0)
            return false;
    }
  return true;
}

// Padded groups (Uniform false) enter as identity rows and columns: their entries of L stay
// exactly 0 and their pivots 1, so the real unknowns' arithmetic is that of the unpadded
// matrix. Uniform (every group 3, the spring networks) is the same loop with the sizes known at
// compile time, which the compiler unrolls (docs/numerics.md, "Linear algebra", has the
// measurement); the results are the same bit for bit. B = 2 (uniform only): the x-y blocks of a
// matrix whose third coordinates are decoupled (decoupled_third), each third pivot its S_zz.
template <int B, bool Uniform>
bool BlockLdlt::factorize_blocks(const double* s) {
  static_assert(B == 3 || (B == 2 && Uniform), "the 2 x 2 kernel is for uniform nodes");
  constexpr int BB = B * B;
  const Symbolic& sym = *sym_;
  std::fill(lnz_.begin(), lnz_.end(), 0);
  std::fill(flag_.begin(), flag_.end(), -1);
  std::fill(work_.begin(), work_.end(), 0.0);  // clean even after a failed factorisation
  for (int k = 0; k < nb_; ++k) {
    // A stop request (src/core/stop_request.hpp) ends a factorisation that may take minutes as
    // a failed one; every 1024 nodes, a load per ~1e5 flops at the least.
    if ((k & 1023) == 0 && stop_requested()) return false;
    // Scatter column k of P S P^T into work_ and find row k's pattern: the tree paths from
    // each entry's row up to k, in topological order at stack_[top..nb_).
    int top = nb_;
    flag_[k] = k;
    double szz = 0.0;  // B = 2: the third coordinate's diagonal, its pivot
    for (int p = sym.ap[k]; p < sym.ap[k + 1]; ++p) {
      double* y = &work_[BB * static_cast<std::size_t>(sym.ai[p])];
      const int rows = Uniform ? B : sym.size[sym.ai[p]];
      const int cols = Uniform ? B : sym.size[k];
      for (int c = 0; c < cols; ++c)
        for (int r = 0; r < rows; ++r) y[B * r + c] += s[sym.at[p][c] + r];
      if constexpr (B == 2)
        if (sym.ai[p] == k) szz = s[sym.at[p][2] + 2];
      int len = 0;
      for (int i = sym.ai[p]; flag_[i] != k; i = sym.parent[i]) {
        stack_[len++] = i;
        flag_[i] = k;
      }
      while (len > 0) stack_[--top] = stack_[--len];
    }
    double d[BB];
    double* yk = &work_[BB * static_cast<std::size_t>(k)];
    std::copy(yk, yk + BB, d);
    std::fill(yk, yk + BB, 0.0);
    if constexpr (!Uniform)
      for (int q = sym.size[k]; q < 3; ++q) d[4 * q] = 1.0;  // a padded coordinate's pivot
    // Row k of L: solve L(0:k, 0:k) y = column k along the pattern; L(k, i) = y_i^T D_i^-1,
    // D_k = S_kk - sum_i L(k, i) y_i.
    for (; top < nb_; ++top) {
      const int i = stack_[top];
      double* wi = &work_[BB * static_cast<std::size_t>(i)];
      double y[BB];
      std::copy(wi, wi + BB, y);
      std::fill(wi, wi + BB, 0.0);
      const int end = sym.lp[i] + lnz_[i];
      for (int p = sym.lp[i]; p < end; ++p)
        sub_product<B>(&work_[BB * static_cast<std::size_t>(li_[p])],
                       &lx_[BB * static_cast<std::size_t>(p)], y);
      // L(k, i) = y^T D_i^-1: its row r is D_i^-1 times y's column r (D_i symmetric; with
      // B = 2 the column's third entry is the 0 the 3 x 3 arithmetic would carry).
      double* l = &lx_[BB * static_cast<std::size_t>(end)];
      for (int r = 0; r < B; ++r) {
        double col[3] = {y[r], y[B + r], 0.0};
        if constexpr (B == 3) col[2] = y[2 * B + r];
        apply_pivot_inverse(&pivot_[6 * static_cast<std::size_t>(i)], col);
        std::copy(col, col + B, l + B * r);
      }
      sub_product<B>(d, l, y);
      li_[end] = k;
      ++lnz_[i];
    }
    double* f = &pivot_[6 * static_cast<std::size_t>(k)];
    if constexpr (B == 2) {  // the pivot block as the 3 x 3 arithmetic holds it
      const double full[9] = {d[0], d[1], 0.0, d[2], d[3], 0.0, 0.0, 0.0, szz};
      if (!factor_pivot(full, f)) return false;
    } else if (!factor_pivot(d, f)) {
      return false;
    }
  }
  return true;
}

void BlockLdlt::solve(const double* b, double* x) {
  if (split_)
    solve_blocks<2>(b, x);
  else
    solve_blocks<3>(b, x);
}

template <int B>
void BlockLdlt::solve_blocks(const double* b, double* x) {
  constexpr int BB = B * B;
  const Symbolic& sym = *sym_;
  double* w = work_.data();  // 3 per node, in elimination order
  for (int k = 0; k < nb_; ++k)
    for (int r = 0; r < 3; ++r) w[3 * k + r] = r < sym.size[k] ? b[sym.first[k] + r] : 0.0;
  // Node j's entries are copied out while its column updates other nodes' (rows li_ > j): the
  // same operations, without a reload after every store. With B = 2 the third coordinates'
  // entries of L are 0: L leaves them as they are.
  for (int j = 0; j < nb_; ++j) {  // L z = P b
    const double wj[3] = {w[3 * j], w[3 * j + 1], w[3 * j + 2]};
    for (int p = sym.lp[j]; p < sym.lp[j + 1]; ++p)
      sub_block_times<B>(&w[3 * li_[p]], &lx_[BB * static_cast<std::size_t>(p)], wj);
  }
  for (int j = 0; j < nb_; ++j)  // D^-1
    apply_pivot_inverse(&pivot_[6 * static_cast<std::size_t>(j)], &w[3 * j]);
  for (int j = nb_ - 1; j >= 0; --j) {  // L^T
    double wj[3] = {w[3 * j], w[3 * j + 1], w[3 * j + 2]};
    for (int p = sym.lp[j]; p < sym.lp[j + 1]; ++p)
      sub_block_transposed_times<B>(wj, &lx_[BB * static_cast<std::size_t>(p)], &w[3 * li_[p]]);
    std::copy(wj, wj + 3, &w[3 * j]);
  }
  for (int k = 0; k < nb_; ++k)
    for (int r = 0; r < sym.size[k]; ++r) x[sym.first[k] + r] = w[3 * k + r];
}

int BlockLdlt::negative_pivots() const {
  int negative = 0;
  for (int k = 0; k < nb_; ++k)
    for (int c = 0; c < 3; ++c) negative += pivot_[6 * static_cast<std::size_t>(k) + c] < 0.0;
  return negative;
}

}  // namespace knitsim::detail
