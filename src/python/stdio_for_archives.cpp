// The C library's stdout and stderr as the module's own hidden variables.
//
// Debian's CHOLMOD and CAMD archives (libsuitesparse-dev, compiled as position-independent
// executable code) reach stdout and stderr -- in their print routines -- PC-relative, as an
// executable may, where the variables are copied into it at start-up. A shared object cannot
// bind that to the C library's variables ("relocation R_X86_64_PC32 against symbol `stdout'
// can not be used when making a shared object"), so the module defines its own, hidden (the
// static link binds the archives' references to them), holding the C library's FILE pointers,
// copied when the module is loaded.
#include <dlfcn.h>

#include <utility>

struct _IO_FILE;

extern "C" {
__attribute__((visibility("hidden"))) _IO_FILE* stdout = nullptr;
__attribute__((visibility("hidden"))) _IO_FILE* stderr = nullptr;
}

namespace {

__attribute__((constructor)) void copy_stdio() {
  for (auto [name, into] : {std::pair{"stdout", &stdout}, std::pair{"stderr", &stderr}})
    if (void* real = dlsym(RTLD_DEFAULT, name)) *into = *static_cast<_IO_FILE**>(real);
}

}  // namespace
