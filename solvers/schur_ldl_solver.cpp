#include "solvers/schur_ldl_solver.hpp"

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include "solvers/symmetric_factor.hpp"

namespace knitsim::detail {

namespace {

struct SchurLdl {
  explicit SchurLdl(const SchurOptions& o) : options(o), factor(o.factorization) {}
  SchurOptions options;
  const FirstOrderSystem* sys = nullptr;
  int n = 0;                    // dof (half the first-order size)
  std::vector<int> ax_begin;    // column j < n: first Ax entry of A's column j
  std::vector<int> diag;        // reduced matrix: position of (j, j)
  bool node_columns = false;    // columns 3p, 3p+1, 3p+2 of Ax share one row list (every p)
  std::vector<double> rhs, x2;  // length n
  Eigen::SparseMatrix<double> S;
  SymmetricFactor factor;
  double gamma = 0.0;
  bool factorised = false;               // this setup's S has been factorised
  bool try_cg = false;                   // this setup's S passed the radius test
  double radius = -1.0;                  // its Gershgorin radius (D^-1 S), when try_cg
  Eigen::VectorXd inv_diag, r, z, p, q;  // CG: 1 / S_jj and work vectors (length n)
  SchurCounts counts;
  int last_flag = SUNLS_SUCCESS;
};

SchurLdl* content(SUNLinearSolver LS) { return static_cast<SchurLdl*>(LS->content); }

SUNLinearSolver_Type get_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID get_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int initialize(SUNLinearSolver) { return SUNLS_SUCCESS; }

int factorise(SchurLdl& c) {
  c.factorised = c.factor.factorize(c.S);
  ++c.counts.factorisations;
  return c.factorised ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_REC;
}

// Gershgorin radius of D^-1 S, rho = max_j sum_{i != j} |S_ij| / S_jj (S is symmetric, so
// column sums are row sums), if every S_jj > 0 and rho <= bound; fills inv_diag on the way.
// Returns -1 otherwise. The eigenvalues of D^-1 S then lie in [1 - rho, 1 + rho].
double jacobi_radius(SchurLdl& c, double bound) {
  if (!(bound > 0.0)) return -1.0;
  const double* s = c.S.valuePtr();
  const int* colptr = c.S.outerIndexPtr();
  double rho = 0.0;
  for (int j = 0; j < c.n; ++j) {
    const double d = s[c.diag[j]];
    if (!(d > 0.0)) return -1.0;
    double off = -d;
    for (int k = colptr[j]; k < colptr[j + 1]; ++k) off += std::abs(s[k]);
    if (!(off <= bound * d)) return -1.0;
    rho = std::max(rho, off / d);
    c.inv_diag[j] = 1.0 / d;
  }
  return rho;
}

// Jacobi-preconditioned CG on S x = b from x = 0, until the relative error in the D norm is
// at most cg_rel_tol: with B = D^-1/2 S D^-1/2 (spectrum in [1 - rho, 1 + rho]), |e|_D <=
// |r|_{D^-1} / (1 - rho) and |x|_D >= |b|_{D^-1} / (1 + rho), and |r|_{D^-1}^2 = r'z is CG's
// own r'z. False if CG breaks down or has not got there within cg_max_iterations.
bool cg_solve(SchurLdl& c, const Eigen::Ref<const Eigen::VectorXd>& b,
              Eigen::Ref<Eigen::VectorXd> x) {
  x.setZero();
  c.r = b;
  c.z = c.inv_diag.cwiseProduct(c.r);
  c.p = c.z;
  double rz = c.r.dot(c.z);
  const double shrink = c.options.cg_rel_tol * (1.0 - c.radius) / (1.0 + c.radius);
  const double target = shrink * shrink * rz;
  if (!(rz > 0.0)) return rz == 0.0;  // b = 0: x = 0
  for (int it = 0; it < c.options.cg_max_iterations; ++it) {
    c.q.noalias() = c.S.transpose() * c.p;  // S symmetric: the row-wise (gathering) product
    const double pq = c.p.dot(c.q);
    ++c.counts.cg_iterations;
    if (!(pq > 0.0)) return false;
    const double alpha = rz / pq;
    x += alpha * c.p;
    c.r -= alpha * c.q;
    c.z = c.inv_diag.cwiseProduct(c.r);
    const double rz_next = c.r.dot(c.z);
    if (rz_next <= target) return true;
    c.p = c.z + (rz_next / rz) * c.p;
    rz = rz_next;
  }
  return false;
}

// c.rhs -= A_vx b1 (A_vx: the rows n..2n-1 of A's columns j < n; the entries of column j
// from ax_begin[j] on, in the order of the stiffness pattern's column j). Where every
// particle's three columns share one row list (node_columns: spring networks), the three are
// applied together per row: one pass over the rows instead of three, and each row still
// receives its terms in ascending column order, so the sums are bit for bit those of the
// column-by-column loop below (test_schur_ldl compares the two bit for bit).
void subtract_ax_product(SchurLdl& c, const double* a, const sunindextype* colptr,
                         const sunindextype* rowind, const double* b1) {
  const int n = c.n;
  double* rhs = c.rhs.data();
  if (c.node_columns) {
    const CscPattern& kp = c.sys->mechanical().stiffness_pattern();
    for (int j = 0; j < n; j += 3) {
      const int* rows = kp.rowind.data() + kp.colptr[j];
      const int count = kp.colptr[j + 1] - kp.colptr[j];
      const double *a0 = a + c.ax_begin[j], *a1 = a + c.ax_begin[j + 1], *a2 = a + c.ax_begin[j + 2];
      const double u0 = b1[j], u1 = b1[j + 1], u2 = b1[j + 2];
      for (int e = 0; e < count; ++e) {
        double& r = rhs[rows[e]];
        r -= a0[e] * u0;
        r -= a1[e] * u1;
        r -= a2[e] * u2;
      }
    }
    return;
  }
  for (int j = 0; j < n; ++j) {
    const double u = b1[j];
    for (sunindextype k = c.ax_begin[j]; k < colptr[j + 1]; ++k) rhs[rowind[k] - n] -= a[k] * u;
  }
}

int setup(SUNLinearSolver LS, SUNMatrix A) {
  SchurLdl& c = *content(LS);
  const sunindextype* colptr = SUNSparseMatrix_IndexPointers(A);
  const double* a = SUNSparseMatrix_Data(A);
  const int n = c.n;
  const CscPattern& kp = c.sys->mechanical().stiffness_pattern();
  const auto& m = c.sys->mechanical().mass();
  c.gamma = -a[colptr[n]];  // A(0, n) = -gamma
  double* s = c.S.valuePtr();
  for (int j = 0; j < n; ++j) {
    const int begin = c.ax_begin[j];
    for (int k = kp.colptr[j]; k < kp.colptr[j + 1]; ++k)
      s[k] = m[kp.rowind[k]] * c.gamma * a[begin + (k - kp.colptr[j])];
  }
  for (int j = 0; j < n; ++j) s[c.diag[j]] += m[j] * a[colptr[n + j] + 1];  // M A_vv
  ++c.counts.setups;
  c.factorised = false;
  c.radius = jacobi_radius(c, c.options.cg_max_radius);
  c.try_cg = c.radius >= 0.0;
  c.last_flag = c.try_cg ? SUNLS_SUCCESS : factorise(c);
  return c.last_flag;
}

int solve(SUNLinearSolver LS, SUNMatrix A, N_Vector x, N_Vector b, realtype /*tol*/) {
  SchurLdl& c = *content(LS);
  const int n = c.n;
  const double* a = SUNSparseMatrix_Data(A);
  const sunindextype* colptr = SUNSparseMatrix_IndexPointers(A);
  const sunindextype* rowind = SUNSparseMatrix_IndexValues(A);
  const double* bb = N_VGetArrayPointer(b);
  double* xx = N_VGetArrayPointer(x);
  const auto& m = c.sys->mechanical().mass();
  // rhs = M (b2 - A_vx b1)
  for (int i = 0; i < n; ++i) c.rhs[i] = bb[n + i];
  subtract_ax_product(c, a, colptr, rowind, bb);
  for (int i = 0; i < n; ++i) c.rhs[i] *= m[i];
  Eigen::Map<Eigen::VectorXd> r(c.rhs.data(), n), x2(c.x2.data(), n);
  if (!c.factorised && c.try_cg && cg_solve(c, r, x2)) {
    ++c.counts.cg_solves;
  } else {
    if (!c.factorised && factorise(c) != SUNLS_SUCCESS) return c.last_flag = SUNLS_PACKAGE_FAIL_REC;
    try {
      c.factor.solve(r, x2);
    } catch (const std::exception&) {  // CHOLMOD out of memory: not through SUNDIALS' C frames
      return c.last_flag = SUNLS_PACKAGE_FAIL_UNREC;
    }
  }
  for (int i = 0; i < n; ++i) {
    xx[n + i] = c.x2[i];
    xx[i] = bb[i] + c.gamma * c.x2[i];
  }
  c.last_flag = SUNLS_SUCCESS;
  return SUNLS_SUCCESS;
}

sunindextype last_flag(SUNLinearSolver LS) { return content(LS)->last_flag; }

int free_solver(SUNLinearSolver LS) {
  if (!LS) return SUNLS_SUCCESS;
  delete content(LS);
  LS->content = nullptr;
  SUNLinSolFreeEmpty(LS);
  return SUNLS_SUCCESS;
}

}  // namespace

bool is_schur_ldl_solver(SUNLinearSolver LS) {
  return LS && LS->ops && LS->ops->solve == solve && LS->content;
}

SchurCounts schur_counts(SUNLinearSolver LS) {
  const SchurLdl& c = *content(LS);
  SchurCounts counts = c.counts;
  counts.node_columns = c.node_columns;
  return counts;
}

const SymmetricFactor& schur_factor(SUNLinearSolver LS) { return content(LS)->factor; }

SUNLinearSolver make_schur_ldl_solver(SUNContext ctx, const FirstOrderSystem& sys,
                                      const SchurOptions& options) {
  if (!(options.cg_max_radius >= 0.0 && options.cg_max_radius < 1.0))
    throw std::invalid_argument("SchurOptions::cg_max_radius must be in [0, 1)");
  // The content first, the SUNDIALS object last: nothing leaks if a step throws or fails.
  auto c = std::make_unique<SchurLdl>(options);
  c->sys = &sys;
  c->n = sys.size() / 2;
  const int n = c->n;
  const CscPattern& jp = sys.jacobian_pattern();
  const CscPattern& kp = sys.mechanical().stiffness_pattern();
  c->ax_begin.resize(n);
  for (int j = 0; j < n; ++j) c->ax_begin[j] = jp.colptr[j] + 1;  // after the zero diagonal
  c->rhs.resize(n);
  c->x2.resize(n);
  for (Eigen::VectorXd* v : {&c->inv_diag, &c->r, &c->z, &c->p, &c->q}) v->resize(n);
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(kp.nnz());
  for (int j = 0; j < n; ++j)
    for (int k = kp.colptr[j]; k < kp.colptr[j + 1]; ++k) trip.emplace_back(kp.rowind[k], j, 1.0);
  c->S.resize(n, n);
  c->S.setFromTriplets(trip.begin(), trip.end());
  c->S.makeCompressed();
  // The value array of S is filled in kp's order: the two patterns must coincide.
  for (int k = 0; k < kp.nnz(); ++k)
    if (c->S.innerIndexPtr()[k] != kp.rowind[k]) return nullptr;
  c->diag.resize(n);
  for (int j = 0; j < n; ++j) c->diag[j] = kp.find(j, j);
  c->node_columns = options.node_columns && has_node_triples(kp);
  c->factor.analyze(c->S);

  SUNLinearSolver LS = SUNLinSolNewEmpty(ctx);
  if (!LS) return nullptr;
  LS->content = c.release();
  LS->ops->gettype = get_type;
  LS->ops->getid = get_id;
  LS->ops->initialize = initialize;
  LS->ops->setup = setup;
  LS->ops->solve = solve;
  LS->ops->lastflag = last_flag;
  LS->ops->free = free_solver;
  return LS;
}

}  // namespace knitsim::detail
