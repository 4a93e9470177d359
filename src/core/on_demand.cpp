#include "src/core/on_demand.hpp"

#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>

namespace knitsim {

void* function_on_demand(const char* library, const char* function, const char* needed_for) {
  // dlopen of a library that is already loaded only counts a reference: cheap, and each
  // forwarder asks once.
  void* handle = dlopen(library, RTLD_NOW | RTLD_LOCAL);
  void* address = handle != nullptr ? dlsym(handle, function) : nullptr;
  if (address == nullptr) {
    std::fprintf(stderr, "knitsim: cannot load %s from %s (%s): %s\n", function, library,
                 needed_for, dlerror());
    std::abort();
  }
  return address;
}

}  // namespace knitsim
