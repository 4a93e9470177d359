// METIS and the OpenMP runtime for the statically linked CHOLMOD, loaded on first use
// (src/core/on_demand.hpp), like its BLAS (solvers/blas_on_demand.cpp).
//
// CHOLMOD's archive calls METIS (its nested-dissection ordering, tried by cholmod_analyze only
// where AMD's fill is large) and libgomp (the OpenMP loops of its supernodal code). Nothing else
// in knitsim calls either, and the block LDL^T, the default below 33 000 unknowns, calls
// neither: linked at start-up they were two more libraries for the dynamic loader at every run,
// and libgomp's constructor read the environment, /sys/devices/system/cpu/possible and the CPU
// affinity before main. These forwarders load libmetis.so.5 and libgomp.so.1, the libraries the
// dynamic linker would have chosen, on their first call, so the orderings and the OpenMP loops
// run the same code.
//
// METIS: Debian's libmetis-dev (metis.h) is not needed to build knitsim, so the two prototypes
// are written here; every argument is a pointer (idx_t* with Debian's 32-bit idx_t) and the
// result an int, so the forwarding does not depend on idx_t's width.
// OpenMP: the three entry points GCC's code in CHOLMOD's archive calls (nm -u libcholmod.a).
#include <cstdint>

#include "src/core/on_demand.hpp"

namespace {
using metis_idx = std::int32_t;
}

#define KNITSIM_METIS(NAME)                                                             \
  KNITSIM_FORWARD_ON_DEMAND(                                                            \
      "libmetis.so.5", "CHOLMOD's METIS ordering; Debian package libmetis5", int, NAME, \
      (metis_idx * nvtxs, metis_idx * xadj, metis_idx * adjncy, metis_idx * vwgt,       \
       metis_idx * options, metis_idx * out1, metis_idx * out2),                        \
      (nvtxs, xadj, adjncy, vwgt, options, out1, out2))

// METIS_NodeND(nvtxs, xadj, adjncy, vwgt, options, perm, iperm)
KNITSIM_METIS(METIS_NodeND)
// METIS_ComputeVertexSeparator(nvtxs, xadj, adjncy, vwgt, options, sepsize, part)
KNITSIM_METIS(METIS_ComputeVertexSeparator)

#define KNITSIM_GOMP(RETURN, NAME, PARAMS, ARGS)                                                  \
  KNITSIM_FORWARD_ON_DEMAND("libgomp.so.1",                                                       \
                            "CHOLMOD's OpenMP loops; Debian package libgomp1 (with gcc)", RETURN, \
                            NAME, PARAMS, ARGS)

KNITSIM_GOMP(void, GOMP_parallel,
             (void (*fn)(void*), void* data, unsigned num_threads, unsigned flags),
             (fn, data, num_threads, flags))
KNITSIM_GOMP(int, omp_get_num_threads, (), ())
KNITSIM_GOMP(int, omp_get_thread_num, (), ())
