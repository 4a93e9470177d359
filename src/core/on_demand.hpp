// Functions of a shared library that the binary does not link: the library is loaded on the
// first call of one of them (dlopen), so a run that never calls it never maps it.
//
// Why: the dynamic loader's start-up cost grows with every library mapped and relocated. The
// BLAS under CHOLMOD's supernodal back end (solvers/blas_on_demand.cpp) and cairo
// (src/render/cairo_on_demand.cpp) are needed only by large factorisations and by pictures, so
// each is called through forwarders defined with KNITSIM_FORWARD_ON_DEMAND below: C functions of
// the library's own names and prototypes, which the code calling the library uses unchanged.
// The library is looked up by its soname, as the dynamic linker would have found it at start-up
// (Debian's alternatives included), so the code that runs is the same.
//
// Failure mode: a library or function that cannot be loaded is a broken installation (run.sh
// installs every library): the process ends (abort) after one line on stderr naming the
// library, the function, what needed it and the loader's message.
#pragma once

namespace knitsim {

// The address of `function` in `library` ("libcairo.so.2"), loading the library (RTLD_NOW |
// RTLD_LOCAL, kept until the process ends) if it is not loaded yet. `needed_for` says what for,
// and which Debian package provides it, in the message of a failure. Thread-safe.
void* function_on_demand(const char* library, const char* function, const char* needed_for);

}  // namespace knitsim

// Defines the C function NAME, of type RETURN NAME PARAMS, as a forwarder to NAME of LIBRARY
// (looked up on its first call, then called directly). Use at global scope, after including the
// library's header: a prototype that differs from the header's does not compile.
#define KNITSIM_FORWARD_ON_DEMAND(LIBRARY, NEEDED_FOR, RETURN, NAME, PARAMS, ARGS) \
  extern "C" RETURN NAME PARAMS {                                                  \
    static const auto real = reinterpret_cast<RETURN(*) PARAMS>(                   \
        ::knitsim::function_on_demand(LIBRARY, #NAME, NEEDED_FOR));                \
    return real ARGS;                                                              \
  }
