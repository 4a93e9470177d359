// libFuzzer target: the knit scene parser (TOML knit scene, inline or file chart) and the knit's
// start (tests/fuzz/fuzz_inputs.hpp). Built with -DKNITSIM_FUZZ=ON (clang); run by ./test.sh --fuzz.
#include <cstddef>
#include <cstdint>
#include <string>

#include "tests/fuzz/fuzz_inputs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  knitsim::fuzz::check_knit_scene_input(std::string(reinterpret_cast<const char*>(data), size));
  return 0;
}
