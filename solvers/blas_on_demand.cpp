// BLAS and LAPACK for the statically linked CHOLMOD, loaded on first use (src/core/on_demand.hpp).
//
// CHOLMOD's supernodal back end (solvers/symmetric_factor.hpp, from 33 000 unknowns) is the only
// caller of BLAS in knitsim. Linked at start-up, the BLAS (Debian's OpenBLAS with libgfortran)
// would add to every run's start-up (experiments/benchmark/README.md, "Process start"), so
// CHOLMOD is linked statically and the twelve routines its supernodal code calls are defined
// here: each loads libblas.so.3 or liblapack.so.3 on its first call and forwards to the routine
// of that name there. These are the libraries the dynamic linker would have chosen (Debian's
// alternatives: OpenBLAS from libopenblas0-serial, which run.sh installs), so the
// factorisations are the same.
// Prototypes are CHOLMOD's own (cholmod_blas.h), so a mismatch does not compile.
extern "C" {
#include <cholmod_blas.h>
}

#include "src/core/on_demand.hpp"
#include "src/core/stop_request.hpp"

#define KNITSIM_FORWARD(LIBRARY, NAME, PARAMS, ARGS)                              \
  KNITSIM_FORWARD_ON_DEMAND(LIBRARY,                                              \
                            "CHOLMOD's supernodal factorisation; Debian package " \
                            "libopenblas0-serial",                                \
                            void, NAME, PARAMS, ARGS)

KNITSIM_FORWARD("libblas.so.3", dgemv_,
                (char* trans, BLAS_INT* m, BLAS_INT* n, double* alpha, double* A, BLAS_INT* lda,
                 double* X, BLAS_INT* incx, double* beta, double* Y, BLAS_INT* incy),
                (trans, m, n, alpha, A, lda, X, incx, beta, Y, incy))
KNITSIM_FORWARD("libblas.so.3", zgemv_,
                (char* trans, BLAS_INT* m, BLAS_INT* n, double* alpha, double* A, BLAS_INT* lda,
                 double* X, BLAS_INT* incx, double* beta, double* Y, BLAS_INT* incy),
                (trans, m, n, alpha, A, lda, X, incx, beta, Y, incy))
KNITSIM_FORWARD("libblas.so.3", dtrsv_,
                (char* uplo, char* trans, char* diag, BLAS_INT* n, double* A, BLAS_INT* lda,
                 double* X, BLAS_INT* incx),
                (uplo, trans, diag, n, A, lda, X, incx))
KNITSIM_FORWARD("libblas.so.3", ztrsv_,
                (char* uplo, char* trans, char* diag, BLAS_INT* n, double* A, BLAS_INT* lda,
                 double* X, BLAS_INT* incx),
                (uplo, trans, diag, n, A, lda, X, incx))
KNITSIM_FORWARD("libblas.so.3", dtrsm_,
                (char* side, char* uplo, char* transa, char* diag, BLAS_INT* m, BLAS_INT* n,
                 double* alpha, double* A, BLAS_INT* lda, double* B, BLAS_INT* ldb),
                (side, uplo, transa, diag, m, n, alpha, A, lda, B, ldb))
KNITSIM_FORWARD("libblas.so.3", ztrsm_,
                (char* side, char* uplo, char* transa, char* diag, BLAS_INT* m, BLAS_INT* n,
                 double* alpha, double* A, BLAS_INT* lda, double* B, BLAS_INT* ldb),
                (side, uplo, transa, diag, m, n, alpha, A, lda, B, ldb))
KNITSIM_FORWARD("libblas.so.3", dgemm_,
                (char* transa, char* transb, BLAS_INT* m, BLAS_INT* n, BLAS_INT* k, double* alpha,
                 double* A, BLAS_INT* lda, double* B, BLAS_INT* ldb, double* beta, double* C,
                 BLAS_INT* ldc),
                (transa, transb, m, n, k, alpha, A, lda, B, ldb, beta, C, ldc))
KNITSIM_FORWARD("libblas.so.3", zgemm_,
                (char* transa, char* transb, BLAS_INT* m, BLAS_INT* n, BLAS_INT* k, double* alpha,
                 double* A, BLAS_INT* lda, double* B, BLAS_INT* ldb, double* beta, double* C,
                 BLAS_INT* ldc),
                (transa, transb, m, n, k, alpha, A, lda, B, ldb, beta, C, ldc))
KNITSIM_FORWARD("libblas.so.3", dsyrk_,
                (char* uplo, char* trans, BLAS_INT* n, BLAS_INT* k, double* alpha, double* A,
                 BLAS_INT* lda, double* beta, double* C, BLAS_INT* ldc),
                (uplo, trans, n, k, alpha, A, lda, beta, C, ldc))
KNITSIM_FORWARD("libblas.so.3", zherk_,
                (char* uplo, char* trans, BLAS_INT* n, BLAS_INT* k, double* alpha, double* A,
                 BLAS_INT* lda, double* beta, double* C, BLAS_INT* ldc),
                (uplo, trans, n, k, alpha, A, lda, beta, C, ldc))
// dpotrf_ factors each supernode's diagonal block. Once a stop is requested
// (src/core/stop_request.hpp) it reports that block's first pivot not positive (info = 1)
// without factoring it: CHOLMOD then returns at once, not positive definite, and
// SymmetricFactor::factorize reports the factorisation failed -- a factorisation of minutes
// ends at its next supernode instead of running on.
extern "C" void dpotrf_(char* uplo, BLAS_INT* n, double* A, BLAS_INT* lda, BLAS_INT* info) {
  using Real = void (*)(char*, BLAS_INT*, double*, BLAS_INT*, BLAS_INT*);
  static const auto real = reinterpret_cast<Real>(::knitsim::function_on_demand(
      "liblapack.so.3", "dpotrf_",
      "CHOLMOD's supernodal factorisation; Debian package libopenblas0-serial"));
  if (::knitsim::stop_requested()) {
    *info = 1;
    return;
  }
  real(uplo, n, A, lda, info);
}
KNITSIM_FORWARD("liblapack.so.3", zpotrf_,
                (char* uplo, BLAS_INT* n, double* A, BLAS_INT* lda, BLAS_INT* info),
                (uplo, n, A, lda, info))
