#include "solvers/symmetric_factor.hpp"

#include <cholmod.h>

#include <Eigen/SparseCholesky>
#include <mutex>
#include <stdexcept>

#include "solvers/block_ldlt.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim::detail {

namespace {

// Held around every CHOLMOD call that reaches BLAS (numeric factorisation, solve). CHOLMOD is
// re-entrant with one cholmod_common per instance, but the BLAS under it need not be: Debian's
// libopenblas0-serial (which run.sh installs) is built without USE_LOCKING, and two threads
// inside it at once can corrupt each other's work buffers (the case that OpenBLAS build option
// exists for): without this lock, test_symmetric_factor's "instances in concurrent threads"
// gets solves off the one-thread result (silently wrong drapes under `knitsim fit --jobs J` on
// grids from supernodal_min_dof unknowns); with it they are bit-identical. The lock serialises
// only the supernodal back end, which runs on grids large enough for a factorisation to take
// ~0.1-1 s; the other back ends call no BLAS.
std::mutex& blas_mutex() {
  static std::mutex m;
  return m;
}

// A CHOLMOD view of S's lower triangle (no copy): S's arrays, stype -1.
cholmod_sparse view_lower(const Eigen::SparseMatrix<double>& S) {
  cholmod_sparse A{};
  A.nrow = static_cast<size_t>(S.rows());
  A.ncol = static_cast<size_t>(S.cols());
  A.nzmax = static_cast<size_t>(S.nonZeros());
  A.p = const_cast<int*>(S.outerIndexPtr());
  A.i = const_cast<int*>(S.innerIndexPtr());
  A.x = const_cast<double*>(S.valuePtr());
  A.stype = -1;
  A.itype = CHOLMOD_INT;
  A.xtype = CHOLMOD_REAL;
  A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1;
  A.packed = 1;
  return A;
}

}  // namespace

struct SymmetricFactor::Impl {
  Backend requested = Backend::Automatic;
  Backend chosen = Backend::Simplicial;
  // The LDL^T back end, used alone or as the supernodal one's fallback: Block where S is made
  // of 3 x 3 node blocks, else Simplicial.
  Backend ldlt_kind = Backend::Simplicial;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
  BlockLdlt block;
  bool ldlt_analysed = false;
  bool latest_is_ldlt = true;  // which back end holds the latest factor
  long fallbacks = 0;
  // CHOLMOD (supernodal only)
  cholmod_common cm{};
  bool cm_started = false;
  cholmod_factor* L = nullptr;
  cholmod_dense *X = nullptr, *Y = nullptr, *E = nullptr;  // cholmod_solve2's reused arrays

  ~Impl() {
    if (!cm_started) return;
    cholmod_free_dense(&X, &cm);
    cholmod_free_dense(&Y, &cm);
    cholmod_free_dense(&E, &cm);
    cholmod_free_factor(&L, &cm);
    cholmod_finish(&cm);
  }

  // Analyses S's pattern for LDL^T, in 3 x 3 blocks where S has them (unless simplicial was
  // requested), and records which.
  void analyze_ldlt(const Eigen::SparseMatrix<double>& S) {
    const bool blocks = requested != Backend::Simplicial && block.try_analyze(S);
    ldlt_kind = blocks ? Backend::Block : Backend::Simplicial;
    if (!blocks) ldlt.analyzePattern(S);
    ldlt_analysed = true;
  }

  bool factorize_ldlt(const Eigen::SparseMatrix<double>& S) {
    if (!ldlt_analysed) analyze_ldlt(S);
    latest_is_ldlt = true;
    if (ldlt_kind == Backend::Block) return block.factorize(S);
    ldlt.factorize(S);
    return ldlt.info() == Eigen::Success;
  }
};

SymmetricFactor::SymmetricFactor(Backend which) : impl_(std::make_unique<Impl>()) {
  impl_->requested = which;
}

SymmetricFactor::~SymmetricFactor() = default;

void SymmetricFactor::analyze(const Eigen::SparseMatrix<double>& S) {
  Impl& c = *impl_;
  if (!S.isCompressed() || S.rows() != S.cols())
    throw std::invalid_argument("SymmetricFactor: S must be square and compressed");
  const bool large = S.rows() >= supernodal_min_dof;
  if (c.requested != Backend::Supernodal && !(c.requested == Backend::Automatic && large)) {
    c.analyze_ldlt(S);
    c.chosen = c.ldlt_kind;
    return;
  }
  c.chosen = Backend::Supernodal;
  if (!c.cm_started) {
    cholmod_start(&c.cm);
    c.cm_started = true;
    c.cm.print = 0;  // a matrix that is not positive definite is handled here, not printed
    c.cm.supernodal = CHOLMOD_SUPERNODAL;
    c.cm.final_asis = 1;
  }
  cholmod_free_factor(&c.L, &c.cm);
  cholmod_sparse A = view_lower(S);
  c.L = cholmod_analyze(&A, &c.cm);
  if (!c.L) throw std::runtime_error("SymmetricFactor: CHOLMOD analysis failed");
  c.ldlt_analysed = false;  // the fallback analyses S's pattern when first needed
}

bool SymmetricFactor::factorize(const Eigen::SparseMatrix<double>& S) {
  Impl& c = *impl_;
  if (c.chosen != Backend::Supernodal) return c.factorize_ldlt(S);
  cholmod_sparse A = view_lower(S);
  const int ok = [&] {
    const std::lock_guard<std::mutex> lock(blas_mutex());
    return cholmod_factorize(&A, c.L, &c.cm);
  }();
  if (ok && c.cm.status == CHOLMOD_OK && c.L->minor == c.L->n) {
    c.latest_is_ldlt = false;
    return true;
  }
  if (stop_requested()) return false;  // cut short (dpotrf_, blas_on_demand.cpp): no fallback
  ++c.fallbacks;  // not positive definite (CHOLMOD_NOT_POSDEF): LDL^T handles indefinite S
  return c.factorize_ldlt(S);
}

void SymmetricFactor::solve(const Eigen::Ref<const Eigen::VectorXd>& b,
                            Eigen::Ref<Eigen::VectorXd> x) {
  Impl& c = *impl_;
  if (x.size() != b.size()) throw std::invalid_argument("SymmetricFactor::solve: size mismatch");
  if (c.latest_is_ldlt && c.ldlt_kind == Backend::Block) {
    c.block.solve(b.data(), x.data());
    return;
  }
  if (c.latest_is_ldlt) {
    x = c.ldlt.solve(b);
    return;
  }
  cholmod_dense B{};
  B.nrow = static_cast<size_t>(b.size());
  B.ncol = 1;
  B.nzmax = B.nrow;
  B.d = B.nrow;
  B.x = const_cast<double*>(b.data());
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  const std::lock_guard<std::mutex> lock(blas_mutex());
  if (!cholmod_solve2(CHOLMOD_A, c.L, &B, nullptr, &c.X, nullptr, &c.Y, &c.E, &c.cm))
    throw std::runtime_error("SymmetricFactor: CHOLMOD solve failed (out of memory)");
  x = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(c.X->x), b.size());
}

SymmetricFactor::Backend SymmetricFactor::backend() const { return impl_->chosen; }

int SymmetricFactor::negative_pivots() const {
  const Impl& c = *impl_;
  if (!c.latest_is_ldlt) return 0;
  if (c.ldlt_kind == Backend::Block) return c.block.negative_pivots();
  return static_cast<int>((c.ldlt.vectorD().array() < 0.0).count());
}

double SymmetricFactor::factor_nonzeros() const {
  const Impl& c = *impl_;
  if (c.chosen == Backend::Supernodal)  // CHOLMOD's lnz counts the diagonal
    return c.L ? c.cm.lnz - static_cast<double>(c.L->n) : 0.0;
  if (!c.ldlt_analysed) return 0.0;
  if (c.ldlt_kind == Backend::Block) return c.block.scalar_nonzeros();
  return static_cast<double>(c.ldlt.matrixL().nestedExpression().nonZeros());
}

double SymmetricFactor::factor_flops() const {
  const Impl& c = *impl_;
  if (c.chosen == Backend::Supernodal) return c.L ? c.cm.fl : 0.0;
  if (!c.ldlt_analysed) return 0.0;
  if (c.ldlt_kind == Backend::Block) return c.block.scalar_flops();
  // Eigen's LDL^T stores the entries below the diagonal, column by column.
  const auto& L = c.ldlt.matrixL().nestedExpression();
  double f = 0.0;
  for (Eigen::Index j = 0; j < L.outerSize(); ++j) {
    const double cj = L.outerIndexPtr()[j + 1] - L.outerIndexPtr()[j];
    f += (cj + 1) * (cj + 1);
  }
  return f;
}

void SymmetricFactor::fill_stats(RunStats& st) const {
  st.factorization = to_string(backend());
  st.ldl_fallbacks = ldl_fallbacks();
  st.factor_nonzeros = factor_nonzeros();
  st.factor_flops = factor_flops();
}

long SymmetricFactor::ldl_fallbacks() const { return impl_->fallbacks; }

}  // namespace knitsim::detail

namespace knitsim {

std::string suitesparse_version() {
  return std::to_string(SUITESPARSE_MAIN_VERSION) + "." + std::to_string(SUITESPARSE_SUB_VERSION) +
         "." + std::to_string(SUITESPARSE_SUBSUB_VERSION);
}

}  // namespace knitsim
