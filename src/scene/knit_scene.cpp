#include "src/scene/knit_scene.hpp"

#include <stdexcept>
#include <string>
#include <vector>
#include <utility>

#include "src/base/files.hpp"
#include "src/base/text.hpp"

namespace knitsim {

KnitChart read_knit_chart(const Scene& scene) {
  const bool command_line = scene.source == "command line";  // knit_scene: --chart
  if (scene.chart.empty()) {
    try {
      return parse_knit_chart(scene.chart_text, scene.yarn.periodic);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("knit.chart_text (" + printable(scene.source) + "): " + e.what());
    }
  }
  // 4 million points (KnitParams::max_points) are ~4 MB of letters: a larger file is refused.
  constexpr std::size_t kMaxChartFileBytes = std::size_t{16} << 20;
  std::string text, why;
  if (!read_input_file(scene.chart, kMaxChartFileBytes, text, why)) {
    const auto typed = scene.typed.find("knit.chart");
    // The path as typed, on one line: a TOML multi-line string may hold newlines.
    throw std::invalid_argument(
        printable(command_line ? "--chart " + scene.chart
                               : "knit.chart = " +
                                     (typed != scene.typed.end() ? typed->second : scene.chart) +
                                     " (" + scene.source + ")") +
        ": cannot read the file: " + why);
  }
  try {
    return parse_knit_chart(text, scene.yarn.periodic);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(printable(scene.chart) + ": " + e.what());
  }
}

KnitScene make_knit_scene(const Scene& scene, KnitChart chart, int frames) {
  return {scene.name,   scene.chart.empty() ? scene.source : scene.chart,
          std::move(chart), scene.knit, scene.options, frames, scene.yarn};
}

bool yarn_model_key(const std::string& key) {
  return key.rfind("yarn.", 0) == 0 || key == "knit.stitch_length" || key == "knit.tuck_length" ||
         key == "knit.miss_length" || key == "knit.yarn_vertices" || key == "knit.yarn_ramp" ||
         key == "knit.boundary" || key == "knit.cell_pull" || key == "knit.cell_strain";
}

nlohmann::json knit_model_keys(const KnitChart& chart, const Scene& scene) {
  nlohmann::json keys = nlohmann::json::object();
  std::vector<std::string> courses;
  for (int c = 0; c < chart.courses; ++c) {
    std::string row;
    for (int w = 0; w < chart.wales; ++w) row += static_cast<char>(chart.at(w, c));
    courses.push_back(row);
  }
  keys["chart"] = courses;
  Scene defaults;
  for (const Key& k : key_table()) {
    if (k.model != KeyModel::Knit || k.name == "knit.chart" || k.name == "knit.chart_text")
      continue;  // the chart is "chart", as its letters
    if (yarn_model_key(k.name) && scene.yarn.model != KnitModelKind::Yarn)
      continue;  // the yarn model's keys only for it (earlier state files still match)
    if (k.number)
      keys[k.name] = k.number(const_cast<Scene&>(scene));  // read only
    else if (k.name == "knit.network" || k.get(scene) != k.get(defaults))
      keys[k.name] = k.get(scene);
  }
  return keys;
}

}  // namespace knitsim
