// libFuzzer target: the state.json parser and what follows it (tests/fuzz/fuzz_inputs.hpp). Built
// with -DKNITSIM_FUZZ=ON (clang); run by ./test.sh --fuzz.
#include <cstddef>
#include <cstdint>
#include <string>

#include "tests/fuzz/fuzz_inputs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  knitsim::fuzz::check_state_input(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
