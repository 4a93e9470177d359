// Plumbing shared by the SUNDIALS integrators (cvode.cpp, arkode.cpp, static_newton.cpp).
// Internal to solvers/: nothing outside this folder includes SUNDIALS.
//
// Ownership. Every SUNDIALS handle is owned by a unique_ptr with a deleter that calls the
// matching free function (SUNContext_Free, N_VDestroy, SUNMatDestroy, SUNLinSolFree,
// SUNNonlinSolFree, CVodeFree, ARKStepFree, ERKStepFree, KINFree). Objects that reference one
// another must be destroyed in reverse order of creation: integrator memory first, then
// solvers, matrices, vectors and the context last. Classes that hold them declare them in
// creation order so the compiler-generated destructor gets that right.
//
// Errors (docs/reliability.md). `check` is the one place a SUNDIALS return flag is
// checked: a negative flag during set-up throws SundialsError carrying the call and the
// flag's name. During stepping a negative flag becomes a failed Integrator::Step whose
// message names the call, the flag and the time (`step_failure`) -- never an exception.
// Exceptions never cross a SUNDIALS callback: every callback body runs inside `guarded`,
// which maps any exception to -1 (unrecoverable); a non-finite value in an RHS or Jacobian
// maps to +1 (recoverable: the integrator retries with a smaller step and reports a flag
// such as CV_REPTD_RHSFUNC_ERR if that keeps failing). SUNDIALS' own error messages go to an
// ErrorLog (not stderr) and are appended to failure messages.
//
// Sparse matrices. SUNDIALS' sparse SUNMatrix here is CSC (CSC_MAT), the same storage order
// as CscPattern (src/core/sparse.hpp), with 64-bit indices. The pattern is copied into the
// matrix's index arrays once (`make_csc_matrix`). CVODE and ARKODE call SUNMatZero before
// a user Jacobian function, which wipes the index arrays too, so the matrix-based
// integrators supply a linear-system function instead (CVodeSetLinSysFn /
// ARKStepSetLinSysFn): NewtonMatrix keeps the Jacobian values of the last evaluation and
// writes A = I - gamma J straight into the fixed pattern (every diagonal entry is in the
// pattern, so no O(n^2) SUNMatScaleAddI insertion and no saved-Jacobian copy). KINSOL has no
// linear-system hook and zeroes its matrix before each Jacobian call, so its callback
// re-writes the pattern (`write_csc_pattern`, O(nnz)) before the values.
#pragma once

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>

#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "solvers/integrator.hpp"
#include "src/core/first_order.hpp"
#include "src/core/sparse.hpp"

namespace knitsim::sun {

// ---- errors ---------------------------------------------------------------------------

// A SUNDIALS call failed during set-up. what() = "<call>: <FLAG_NAME> (<flag>)[: detail]".
class SundialsError : public std::runtime_error {
 public:
  SundialsError(const std::string& call, int flag, const std::string& flag_name,
                const std::string& detail);
  int flag() const { return flag_; }
  const std::string& flag_name() const { return flag_name_; }

 private:
  int flag_;
  std::string flag_name_;
};

// A module's flag-to-name function (CVodeGetReturnFlagName, ARKStepGetReturnFlagName,
// ERKStepGetReturnFlagName, KINGetReturnFlagName); nullptr for calls that have none.
using FlagNameFn = char* (*)(long int);

// The name of `flag` (SUNDIALS returns a malloc'ed string; it is freed here).
std::string flag_name(int flag, FlagNameFn name);

// SUNDIALS' error and warning messages of one integrator, kept instead of printed.
struct ErrorLog {
  std::array<char, 512> last{};  // the most recent message, NUL-terminated
  void clear() { last[0] = '\0'; }
};
// Error handler for CVodeSetErrHandlerFn / ARKStepSetErrHandlerFn / ERKStepSetErrHandlerFn /
// KINSetErrHandlerFn; user data = ErrorLog*.
void record_error(int error_code, const char* module, const char* function, char* msg, void* log);

// The one flag check for set-up: throws SundialsError if flag < 0. `log` (optional) adds
// SUNDIALS' own message.
void check(int flag, const char* call, FlagNameFn name, const ErrorLog* log = nullptr);
// The one check for constructors that return a handle: throws SundialsError if null.
template <class T>
T* check_created(T* handle, const char* call) {
  if (handle == nullptr) throw SundialsError(call, 0, "NULL", "creation failed");
  return handle;
}

// The message of a failed step: "<call>: <FLAG_NAME> at t = <t> s[: <SUNDIALS message>]".
std::string step_failure(const char* call, int flag, FlagNameFn name, double t,
                         const ErrorLog& log);

// Runs a callback body; any exception becomes -1 (unrecoverable), so none crosses SUNDIALS.
template <class Body>
int guarded(Body&& body) noexcept {
  try {
    return body();
  } catch (...) {
    return -1;
  }
}

// 0 if all n values are finite, 1 (SUNDIALS "recoverable") otherwise; -1 (unrecoverable: the
// step fails at once, the state stays the last accepted one) once a stop was requested
// (src/core/stop_request.hpp), so that a Newton iteration of a large system does not run on.
// Every right-hand side and Jacobian callback ends with it.
int finite_or_recoverable(const double* values, long n);

// ---- RAII owners ----------------------------------------------------------------------

struct ContextDeleter {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
struct LinearSolverDeleter {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct NonlinearSolverDeleter {
  void operator()(SUNNonlinearSolver s) const { SUNNonlinSolFree(s); }
};
template <void (*Free)(void**)>
struct MemoryDeleter {
  void operator()(void* mem) const { Free(&mem); }
};

using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextDeleter>;
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;
using MatrixPtr = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter>;
using LinearSolverPtr =
    std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverDeleter>;
using NonlinearSolverPtr =
    std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, NonlinearSolverDeleter>;
using CvodeMemPtr = std::unique_ptr<void, MemoryDeleter<CVodeFree>>;
using ArkStepMemPtr = std::unique_ptr<void, MemoryDeleter<ARKStepFree>>;
using ErkStepMemPtr = std::unique_ptr<void, MemoryDeleter<ERKStepFree>>;
using KinsolMemPtr = std::unique_ptr<void, MemoryDeleter<KINFree>>;

ContextPtr make_context();
// A serial vector of length n that owns its data (zero-initialised).
VectorPtr make_vector(long n, SUNContext ctx);
// A serial vector that wraps caller-owned data (not freed by the vector).
VectorPtr wrap_vector(double* data, long n, SUNContext ctx);
inline double* vec_data(N_Vector v) { return NV_DATA_S(v); }

// ---- sparse matrices ------------------------------------------------------------------

// Copies the pattern into A's index arrays (A: CSC, same shape, nnz >= pattern.nnz()).
void write_csc_pattern(const CscPattern& pattern, SUNMatrix A);
// A CSC SUNMatrix with `pattern` written once; values zero.
MatrixPtr make_csc_matrix(const CscPattern& pattern, SUNContext ctx);
// KLU sparse LU on A (CSC) with AMD fill-reducing ordering, not SUNDIALS' default COLAMD: every
// matrix factored here (I - gamma J and K = M Ax) is structurally symmetric, which AMD orders
// with less work (docs/numerics.md, "Linear algebra"). The symbolic analysis is done at the
// first set-up and kept; later set-ups refactor numerically.
LinearSolverPtr make_klu(N_Vector y, SUNMatrix A, SUNContext ctx);
// The Newton linear solver chosen by opt.newton_solver for A = I - gamma J in `fo`'s pattern:
// KLU, or the symmetric Schur-complement solver (schur_ldl_solver.hpp) factorising with
// opt.factorization.
LinearSolverPtr make_newton_solver(const IntegratorOptions& opt, const FirstOrderSystem& fo,
                                   N_Vector y, SUNMatrix A, SUNContext ctx);
// After lin_setups and lin_iters are filled: sets st.factorisations (= lin_setups, or the
// Schur solver's own count), adds the Schur solver's CG iterations to lin_iters and sets
// st.factorization and st.ldl_fallbacks from it.
void add_newton_solver_counts(SUNLinearSolver ls, RunStats& st);

// ---- Newton matrix of the first-order system ------------------------------------------

enum class MatrixKind { SparseCsc, Dense };

// A = I - gamma J for FirstOrderSystem's 2n x 2n Jacobian J, assembled into a SUNMatrix:
// CSC with J's pattern (fixed, written once) or dense column-major (small systems only).
// The Jacobian values of the last evaluation are kept, so a set-up that may re-use J
// (SUNDIALS' jok) only re-scales. No allocation after construction.
class NewtonMatrix {
 public:
  NewtonMatrix(const FirstOrderSystem& fo, MatrixKind kind, SUNContext ctx);
  SUNMatrix get() const { return A_.get(); }
  // Writes A = I - gamma J; J is re-evaluated at (t, y) unless reuse_jacobian (and a
  // previous evaluation exists). Sets *jacobian_current to whether J was evaluated now.
  // Returns 0, or 1 (recoverable) if J is not finite.
  int assemble(double t, const double* y, bool reuse_jacobian, double gamma,
               bool* jacobian_current);

 private:
  const FirstOrderSystem& fo_;
  MatrixKind kind_;
  MatrixPtr A_;
  std::vector<double> jac_;     // J values in fo.jacobian_pattern() order
  std::vector<long> diagonal_;  // CSC: position of entry (j, j) in the pattern
  bool have_jacobian_ = false;
};

// ---- the ODE as SUNDIALS sees it ------------------------------------------------------

// user_data of the CVODE and ARKODE callbacks: the first-order system y' = f(t, y),
// y = [x; v] (2n), with its Newton matrix when the method is matrix-based.
struct OdeProblem {
  explicit OdeProblem(const FirstOrderSystem& system) : fo(system) {}
  virtual ~OdeProblem() = default;
  const FirstOrderSystem& fo;
  NewtonMatrix* newton = nullptr;
};

// y' = f(t, y) (CVRhsFn and ARKRhsFn have this signature); user_data = OdeProblem*.
int ode_rhs(double t, N_Vector y, N_Vector ydot, void* user_data);

// The state as an owned 2n vector [x0; v0].
VectorPtr make_state(const double* x0, const double* v0, int n, SUNContext ctx);

// The per-component absolute tolerances of y = [x; v] (IntegratorOptions::velocity_atol): the
// 2n vector [atol (n positions, m); velocity_atol (n velocities, m/s)], or null when
// velocity_atol is 0 -- then the caller sets the scalar pair (rtol, atol). For
// CVodeSVtolerances / ARKStepSVtolerances / ERKStepSVtolerances, which copy the vector (it may
// be freed right after the call).
VectorPtr absolute_tolerances(const IntegratorOptions& opt, int n, SUNContext ctx);

}  // namespace knitsim::sun
