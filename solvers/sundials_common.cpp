#include "solvers/sundials_common.hpp"

#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "solvers/schur_ldl_solver.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim::sun {

namespace {

std::string with_detail(const std::string& head, const std::string& detail) {
  return detail.empty() ? head : head + ": " + detail;
}

}  // namespace

SundialsError::SundialsError(const std::string& call, int flag, const std::string& name,
                             const std::string& detail)
    : std::runtime_error(
          with_detail(call + ": " + name + " (" + std::to_string(flag) + ")", detail)),
      flag_(flag),
      flag_name_(name) {}

std::string flag_name(int flag, FlagNameFn name) {
  if (name == nullptr) return "flag " + std::to_string(flag);
  char* s = name(flag);
  if (s == nullptr) return "flag " + std::to_string(flag);
  std::string out(s);
  std::free(s);
  return out;
}

void record_error(int /*error_code*/, const char* module, const char* function, char* msg,
                  void* log) {
  auto* l = static_cast<ErrorLog*>(log);
  std::snprintf(l->last.data(), l->last.size(), "[%s] %s: %s", module ? module : "?",
                function ? function : "?", msg ? msg : "");
}

void check(int flag, const char* call, FlagNameFn name, const ErrorLog* log) {
  if (flag >= 0) return;
  throw SundialsError(call, flag, flag_name(flag, name), log ? log->last.data() : "");
}

std::string step_failure(const char* call, int flag, FlagNameFn name, double t,
                         const ErrorLog& log) {
  std::ostringstream os;
  os << call << ": " << flag_name(flag, name) << " at t = " << t << " s";
  return with_detail(os.str(), log.last.data());
}

int finite_or_recoverable(const double* values, long n) {
  if (stop_requested()) return -1;
  for (long i = 0; i < n; ++i)
    if (!std::isfinite(values[i])) return 1;
  return 0;
}

ContextPtr make_context() {
  SUNContext ctx = nullptr;
  check(SUNContext_Create(nullptr, &ctx), "SUNContext_Create", nullptr);
  return ContextPtr(ctx);
}

namespace {

// N_VWrmsNorm for serial vectors, sqrt(sum (x_i w_i)^2 / n), with four partial sums: SUNDIALS'
// own loop has one accumulator, so each element waits for the previous add, and the integrators
// call the norm many times per step (error test, Newton convergence, order selection,
// stability-limit detection). The sum's order differs from SUNDIALS', so the norm may differ
// from SUNDIALS' own in the last bit. SUNDIALS' fused vector operations
// (N_VEnableFusedOps_Serial) stay off: they were slower. Figures: docs/numerics.md, "Linear
// algebra".
double wrms_norm(N_Vector x, N_Vector w) {
  const long n = N_VGetLength_Serial(x);
  const double* xd = N_VGetArrayPointer(x);
  const double* wd = N_VGetArrayPointer(w);
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  long i = 0;
  for (; i + 4 <= n; i += 4)
    for (int k = 0; k < 4; ++k) {
      const double p = xd[i + k] * wd[i + k];
      s[k] += p * p;
    }
  for (; i < n; ++i) s[0] += (xd[i] * wd[i]) * (xd[i] * wd[i]);
  return std::sqrt(((s[0] + s[1]) + (s[2] + s[3])) / static_cast<double>(n));
}

// The element-wise operations of the serial N_Vector, compiled with knitsim's flags: Debian's
// libsundials is built without optimisation, and these loops are a large share of an implicit
// integrator's instructions (docs/numerics.md, "Linear algebra"). Each computes exactly what
// SUNDIALS' own does, case for case (N_VLinearSum's special cases round differently: c (x + y)
// is not c x + c y), so results are bit-identical; the loops only get compiled properly. z may
// alias x or y, as in SUNDIALS.
long length(N_Vector v) { return N_VGetLength_Serial(v); }
double* data(N_Vector v) { return N_VGetArrayPointer_Serial(v); }

template <class F>
void map_into(N_Vector z, N_Vector x, F f) {  // z_i = f(x_i)
  const long n = length(z);
  const double* xd = data(x);
  double* zd = data(z);
  for (long i = 0; i < n; ++i) zd[i] = f(xd[i]);
}

template <class F>
void map_into(N_Vector z, N_Vector x, N_Vector y, F f) {  // z_i = f(x_i, y_i)
  const long n = length(z);
  const double* xd = data(x);
  const double* yd = data(y);
  double* zd = data(z);
  for (long i = 0; i < n; ++i) zd[i] = f(xd[i], yd[i]);
}

void linear_sum(double a, N_Vector x, double b, N_Vector y, N_Vector z) {
  // y += a x and x += b y in place: SUNDIALS' axpy, which adds or subtracts for a = +-1.
  const auto axpy = [](double c, N_Vector u, N_Vector w) {
    if (c == 1.0)
      map_into(w, w, u, [](double wi, double ui) { return wi + ui; });
    else if (c == -1.0)
      map_into(w, w, u, [](double wi, double ui) { return wi - ui; });
    else
      map_into(w, w, u, [c](double wi, double ui) { return wi + c * ui; });
  };
  if (b == 1.0 && z == y) return axpy(a, x, y);
  if (a == 1.0 && z == x) return axpy(b, y, x);
  if (a == 1.0 && b == 1.0) return map_into(z, x, y, [](double u, double w) { return u + w; });
  if ((a == 1.0 && b == -1.0) || (a == -1.0 && b == 1.0)) {
    N_Vector plus = a == 1.0 ? x : y, minus = a == 1.0 ? y : x;
    return map_into(z, plus, minus, [](double u, double w) { return u - w; });
  }
  if (a == 1.0 || b == 1.0) {  // c u + w, u the vector scaled by the coefficient that is not 1
    const double c = a == 1.0 ? b : a;
    N_Vector u = a == 1.0 ? y : x, w = a == 1.0 ? x : y;
    return map_into(z, u, w, [c](double ui, double wi) { return c * ui + wi; });
  }
  if (a == -1.0 || b == -1.0) {  // c u - w
    const double c = a == -1.0 ? b : a;
    N_Vector u = a == -1.0 ? y : x, w = a == -1.0 ? x : y;
    return map_into(z, u, w, [c](double ui, double wi) { return c * ui - wi; });
  }
  if (a == b) return map_into(z, x, y, [a](double u, double w) { return a * (u + w); });
  if (a == -b) return map_into(z, x, y, [a](double u, double w) { return a * (u - w); });
  map_into(z, x, y, [a, b](double u, double w) { return a * u + b * w; });
}

void scale(double c, N_Vector x, N_Vector z) {
  if (c == 1.0 && z != x) return map_into(z, x, [](double u) { return u; });
  if (c == -1.0 && z != x) return map_into(z, x, [](double u) { return -u; });
  map_into(z, x, [c](double u) { return c * u; });
}

void constant(double c, N_Vector z) {
  map_into(z, z, [c](double) { return c; });
}
void prod(N_Vector x, N_Vector y, N_Vector z) {
  map_into(z, x, y, [](double u, double w) { return u * w; });
}
void quotient(N_Vector x, N_Vector y, N_Vector z) {
  map_into(z, x, y, [](double u, double w) { return u / w; });
}
void absolute(N_Vector x, N_Vector z) {
  map_into(z, x, [](double u) { return std::fabs(u); });
}
void reciprocal(N_Vector x, N_Vector z) {
  map_into(z, x, [](double u) { return 1.0 / u; });
}
void add_const(N_Vector x, double b, N_Vector z) {
  map_into(z, x, [b](double u) { return u + b; });
}
void compare(double c, N_Vector x, N_Vector z) {
  map_into(z, x, [c](double u) { return std::fabs(u) >= c ? 1.0 : 0.0; });
}
double max_norm(N_Vector x) {
  const long n = length(x);
  const double* xd = data(x);
  double m = 0.0;
  for (long i = 0; i < n; ++i) m = std::fabs(xd[i]) > m ? std::fabs(xd[i]) : m;
  return m;
}
double dot(N_Vector x, N_Vector y) {  // in SUNDIALS' order (one accumulator): the same sum
  const long n = length(x);
  const double* xd = data(x);
  const double* yd = data(y);
  double s = 0.0;
  for (long i = 0; i < n; ++i) s += xd[i] * yd[i];
  return s;
}

// Installs the operations above (and wrms_norm) on `v`; clones (the integrators' work vectors)
// inherit them.
N_Vector with_compiled_ops(N_Vector v) {
  v->ops->nvwrmsnorm = wrms_norm;
  v->ops->nvlinearsum = linear_sum;
  v->ops->nvscale = scale;
  v->ops->nvconst = constant;
  v->ops->nvprod = prod;
  v->ops->nvdiv = quotient;
  v->ops->nvabs = absolute;
  v->ops->nvinv = reciprocal;
  v->ops->nvaddconst = add_const;
  v->ops->nvcompare = compare;
  v->ops->nvmaxnorm = max_norm;
  v->ops->nvmaxnormlocal = max_norm;
  v->ops->nvdotprod = dot;
  v->ops->nvdotprodlocal = dot;
  return v;
}

}  // namespace

VectorPtr make_vector(long n, SUNContext ctx) {
  VectorPtr v(check_created(N_VNew_Serial(n, ctx), "N_VNew_Serial"));
  with_compiled_ops(v.get());
  N_VConst(0.0, v.get());
  return v;
}

VectorPtr wrap_vector(double* values, long n, SUNContext ctx) {
  return VectorPtr(
      with_compiled_ops(check_created(N_VMake_Serial(n, values, ctx), "N_VMake_Serial")));
}

VectorPtr make_state(const double* x0, const double* v0, int n, SUNContext ctx) {
  VectorPtr y = make_vector(2L * n, ctx);
  std::copy_n(x0, n, vec_data(y.get()));
  std::copy_n(v0, n, vec_data(y.get()) + n);
  return y;
}

VectorPtr absolute_tolerances(const IntegratorOptions& opt, int n, SUNContext ctx) {
  if (opt.velocity_atol == 0.0) return nullptr;
  VectorPtr atol = make_vector(2L * n, ctx);
  std::fill_n(vec_data(atol.get()), n, opt.atol);
  std::fill_n(vec_data(atol.get()) + n, n, opt.velocity_atol);
  return atol;
}

void write_csc_pattern(const CscPattern& pattern, SUNMatrix A) {
  sunindextype* colptr = SUNSparseMatrix_IndexPointers(A);
  sunindextype* rowind = SUNSparseMatrix_IndexValues(A);
  std::copy(pattern.colptr.begin(), pattern.colptr.end(), colptr);
  std::copy(pattern.rowind.begin(), pattern.rowind.end(), rowind);
}

MatrixPtr make_csc_matrix(const CscPattern& pattern, SUNContext ctx) {
  MatrixPtr A(check_created(
      SUNSparseMatrix(pattern.rows, pattern.cols, std::max(pattern.nnz(), 1), CSC_MAT, ctx),
      "SUNSparseMatrix"));
  write_csc_pattern(pattern, A.get());
  std::fill_n(SUNSparseMatrix_Data(A.get()), SUNSparseMatrix_NNZ(A.get()), 0.0);
  return A;
}

LinearSolverPtr make_klu(N_Vector y, SUNMatrix A, SUNContext ctx) {
  LinearSolverPtr ls(check_created(SUNLinSol_KLU(y, A, ctx), "SUNLinSol_KLU"));
  check(SUNLinSol_KLUSetOrdering(ls.get(), 0 /* AMD */), "SUNLinSol_KLUSetOrdering", nullptr);
  return ls;
}

LinearSolverPtr make_newton_solver(const IntegratorOptions& opt, const FirstOrderSystem& fo,
                                   N_Vector y, SUNMatrix A, SUNContext ctx) {
  if (opt.newton_solver == IntegratorOptions::NewtonSolver::Klu) return make_klu(y, A, ctx);
  knitsim::detail::SchurOptions options;
  if (opt.newton_solver == IntegratorOptions::NewtonSolver::SchurLdl) options.cg_max_radius = 0.0;
  options.factorization = opt.factorization;
  return LinearSolverPtr(check_created(knitsim::detail::make_schur_ldl_solver(ctx, fo, options),
                                       "make_schur_ldl_solver"));
}

void add_newton_solver_counts(SUNLinearSolver ls, RunStats& st) {
  st.factorisations = st.lin_setups;
  if (!knitsim::detail::is_schur_ldl_solver(ls)) return;
  const knitsim::detail::SchurCounts c = knitsim::detail::schur_counts(ls);
  st.factorisations = c.factorisations;
  st.lin_iters += c.cg_iterations;
  knitsim::detail::schur_factor(ls).fill_stats(st);
}

NewtonMatrix::NewtonMatrix(const FirstOrderSystem& fo, MatrixKind kind, SUNContext ctx)
    : fo_(fo), kind_(kind) {
  const CscPattern& p = fo.jacobian_pattern();
  jac_.assign(p.nnz(), 0.0);
  if (kind == MatrixKind::SparseCsc) {
    A_ = make_csc_matrix(p, ctx);
    diagonal_.resize(p.cols);
    for (int j = 0; j < p.cols; ++j) {
      diagonal_[j] = p.find(j, j);
      if (diagonal_[j] < 0)  // FirstOrderSystem guarantees every diagonal entry
        throw std::logic_error("NewtonMatrix: Jacobian pattern lacks a diagonal entry");
    }
  } else {
    A_ = MatrixPtr(check_created(SUNDenseMatrix(p.rows, p.cols, ctx), "SUNDenseMatrix"));
  }
}

int NewtonMatrix::assemble(double t, const double* y, bool reuse_jacobian, double gamma,
                           bool* jacobian_current) {
  const CscPattern& p = fo_.jacobian_pattern();
  const bool evaluate = !(reuse_jacobian && have_jacobian_);
  if (evaluate) {
    fo_.jacobian_values(t, y, jac_.data());
    have_jacobian_ = true;
    if (finite_or_recoverable(jac_.data(), static_cast<long>(jac_.size())) != 0) {
      have_jacobian_ = false;
      *jacobian_current = false;
      return 1;
    }
  }
  *jacobian_current = evaluate;
  if (kind_ == MatrixKind::SparseCsc) {
    double* a = SUNSparseMatrix_Data(A_.get());
    for (int k = 0; k < p.nnz(); ++k) a[k] = -gamma * jac_[k];
    for (long d : diagonal_) a[d] += 1.0;
  } else {
    double* a = SUNDenseMatrix_Data(A_.get());
    const long rows = p.rows;
    std::fill_n(a, rows * p.cols, 0.0);
    for (int j = 0; j < p.cols; ++j) {
      double* col = a + j * rows;
      for (int k = p.colptr[j]; k < p.colptr[j + 1]; ++k) col[p.rowind[k]] = -gamma * jac_[k];
      col[j] += 1.0;
    }
  }
  return 0;
}

int ode_rhs(double t, N_Vector y, N_Vector ydot, void* user_data) {
  return guarded([&] {
    const auto* problem = static_cast<const OdeProblem*>(user_data);
    problem->fo.rhs(t, vec_data(y), vec_data(ydot));
    return finite_or_recoverable(vec_data(ydot), problem->fo.size());
  });
}

}  // namespace knitsim::sun
