// libFuzzer target: drape's --set overrides, one per line (tests/fuzz/fuzz_inputs.hpp). Built with
// -DKNITSIM_FUZZ=ON (clang); run by ./test.sh --fuzz.
#include <cstddef>
#include <cstdint>
#include <string>

#include "tests/fuzz/fuzz_inputs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  knitsim::fuzz::check_set_input(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
