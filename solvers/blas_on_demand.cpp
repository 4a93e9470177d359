// BLAS and LAPACK for the statically linked CHOLMOD, loaded on first use (dlopen).
//
// CHOLMOD's supernodal back end (solvers/symmetric_factor.hpp, from 33 000 unknowns) is the only
// caller of BLAS in knitsim. Linked at start-up, the BLAS (Debian's OpenBLAS with libgfortran)
// cost every run ~5 ms of the dynamic loader's time, so CHOLMOD is linked statically and the
// twelve routines its supernodal code calls are defined here: each loads libblas.so.3 or
// liblapack.so.3 on its first call and forwards to the routine of that name there. These are
// the libraries the dynamic linker would have chosen (Debian's alternatives: OpenBLAS from
// libopenblas0-serial, which run.sh installs), so the factorisations are the same.
// Prototypes are CHOLMOD's own (cholmod_blas.h), so a mismatch does not compile.
// Failure mode: without the library the process aborts with a message naming it.
#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>

extern "C" {
#include <cholmod_blas.h>
}

namespace {

void* open_library(const char* name) {
  void* handle = dlopen(name, RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    std::fprintf(stderr,
                 "knitsim: cannot load %s for CHOLMOD's supernodal factorisation (Debian: "
                 "libopenblas0-serial): %s\n",
                 name, dlerror());
    std::abort();
  }
  return handle;
}

void* blas() {
  static void* const handle = open_library("libblas.so.3");
  return handle;
}
void* lapack() {
  static void* const handle = open_library("liblapack.so.3");
  return handle;
}

template <typename Fn>
Fn routine(void* library, const char* name) {
  void* address = dlsym(library, name);
  if (address == nullptr) {
    std::fprintf(stderr, "knitsim: %s is not in the BLAS/LAPACK library: %s\n", name, dlerror());
    std::abort();
  }
  return reinterpret_cast<Fn>(address);
}

}  // namespace

// NAME(PARAMS) looked up once in LIBRARY() and called with ARGS.
#define KNITSIM_FORWARD(LIBRARY, NAME, PARAMS, ARGS)                            \
  extern "C" void NAME PARAMS {                                                 \
    static const auto real = routine<void(*) PARAMS>(LIBRARY(), #NAME);         \
    real ARGS;                                                                  \
  }

KNITSIM_FORWARD(blas, dgemv_,
                (char* trans, BLAS_INT* m, BLAS_INT* n, double* alpha, double* A, BLAS_INT* lda,
                 double* X, BLAS_INT* incx, double* beta, double* Y, BLAS_INT* incy),
                (trans, m, n, alpha, A, lda, X, incx, beta, Y, incy))
KNITSIM_FORWARD(blas, zgemv_,
                (char* trans, BLAS_INT* m, BLAS_INT* n, double* alpha, double* A, BLAS_INT* lda,
                 double* X, BLAS_INT* incx, double* beta, double* Y, BLAS_INT* incy),
                (trans, m, n, alpha, A, lda, X, incx, beta, Y, incy))
KNITSIM_FORWARD(blas, dtrsv_,
                (char* uplo, char* trans, char* diag, BLAS_INT* n, double* A, BLAS_INT* lda,
                 double* X, BLAS_INT* incx),
                (uplo, trans, diag, n, A, lda, X, incx))
KNITSIM_FORWARD(blas, ztrsv_,
                (char* uplo, char* trans, char* diag, BLAS_INT* n, double* A, BLAS_INT* lda,
                 double* X, BLAS_INT* incx),
                (uplo, trans, diag, n, A, lda, X, incx))
KNITSIM_FORWARD(blas, dtrsm_,
                (char* side, char* uplo, char* transa, char* diag, BLAS_INT* m, BLAS_INT* n,
                 double* alpha, double* A, BLAS_INT* lda, double* B, BLAS_INT* ldb),
                (side, uplo, transa, diag, m, n, alpha, A, lda, B, ldb))
KNITSIM_FORWARD(blas, ztrsm_,
                (char* side, char* uplo, char* transa, char* diag, BLAS_INT* m, BLAS_INT* n,
                 double* alpha, double* A, BLAS_INT* lda, double* B, BLAS_INT* ldb),
                (side, uplo, transa, diag, m, n, alpha, A, lda, B, ldb))
KNITSIM_FORWARD(blas, dgemm_,
                (char* transa, char* transb, BLAS_INT* m, BLAS_INT* n, BLAS_INT* k, double* alpha,
                 double* A, BLAS_INT* lda, double* B, BLAS_INT* ldb, double* beta, double* C,
                 BLAS_INT* ldc),
                (transa, transb, m, n, k, alpha, A, lda, B, ldb, beta, C, ldc))
KNITSIM_FORWARD(blas, zgemm_,
                (char* transa, char* transb, BLAS_INT* m, BLAS_INT* n, BLAS_INT* k, double* alpha,
                 double* A, BLAS_INT* lda, double* B, BLAS_INT* ldb, double* beta, double* C,
                 BLAS_INT* ldc),
                (transa, transb, m, n, k, alpha, A, lda, B, ldb, beta, C, ldc))
KNITSIM_FORWARD(blas, dsyrk_,
                (char* uplo, char* trans, BLAS_INT* n, BLAS_INT* k, double* alpha, double* A,
                 BLAS_INT* lda, double* beta, double* C, BLAS_INT* ldc),
                (uplo, trans, n, k, alpha, A, lda, beta, C, ldc))
KNITSIM_FORWARD(blas, zherk_,
                (char* uplo, char* trans, BLAS_INT* n, BLAS_INT* k, double* alpha, double* A,
                 BLAS_INT* lda, double* beta, double* C, BLAS_INT* ldc),
                (uplo, trans, n, k, alpha, A, lda, beta, C, ldc))
KNITSIM_FORWARD(lapack, dpotrf_,
                (char* uplo, BLAS_INT* n, double* A, BLAS_INT* lda, BLAS_INT* info),
                (uplo, n, A, lda, info))
KNITSIM_FORWARD(lapack, zpotrf_,
                (char* uplo, BLAS_INT* n, double* A, BLAS_INT* lda, BLAS_INT* info),
                (uplo, n, A, lda, info))
