// Small knit scenes for the tests of clamps, loads and the tensile test: a plain chart's text and
// a KnitScene of a chart with given parameters.
#pragma once

#include <string>

#include "models/knit_loops.hpp"
#include "src/scene/knit_scene.hpp"

namespace knitsim::test {

// `courses` rows of `wales` knits.
inline std::string plain(int wales, int courses) {
  std::string s;
  for (int j = 0; j < courses; ++j) s += std::string(wales, 'K') + "\n";
  return s;
}

inline KnitScene scene_of(const std::string& chart, const KnitParams& p) {
  KnitScene s;
  s.name = "test";
  s.chart = parse_knit_chart(chart);
  s.params = p;
  return s;
}

}  // namespace knitsim::test
