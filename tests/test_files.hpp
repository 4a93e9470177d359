// Files of the source tree that several tests read.
#pragma once

#include <catch2/catch.hpp>
#include <fstream>
#include <sstream>
#include <string>

namespace knitsim::test {

// The text of models/charts/<name> (KNITSIM_CHARTS, set per test in tests/CMakeLists.txt).
inline std::string chart_file(const std::string& name) {
  std::ifstream in(std::string(KNITSIM_CHARTS) + "/" + name);
  REQUIRE(in.good());
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace knitsim::test
