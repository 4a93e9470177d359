#include "src/scene/knit_scene.hpp"

#include <filesystem>
#include <optional>
#include <stdexcept>

#include "src/base/files.hpp"

namespace knitsim {

namespace {

namespace fs = std::filesystem;

// The chart file at `path`; `what` names it in messages ("--chart FILE", "knit.chart = FILE").
KnitChart read_chart(const std::string& path, const std::string& what) {
  // 4 million points (KnitParams::max_points) are ~4 MB of letters: a larger file is refused.
  constexpr std::size_t kMaxChartFileBytes = std::size_t{16} << 20;
  std::string text, why;
  if (!read_input_file(path, kMaxChartFileBytes, text, why))
    throw std::invalid_argument(what + ": cannot read the file: " + why);
  try {
    return parse_knit_chart(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

}  // namespace

KnitScene knit_scene_of_chart(const std::string& path) {
  KnitScene scene;
  scene.chart = read_chart(path, "--chart " + path);
  scene.chart_file = path;
  scene.name = fs::path(path).stem().string();
  return scene;
}

KnitScene read_knit_scene(const std::string& path, std::vector<std::string>& sets) {
  std::string text, why;
  if (!read_input_file(path, kMaxSceneFileBytes, text, why))
    throw std::invalid_argument("scene: cannot read " + path + ": " + why);
  std::vector<std::string> from_file;
  std::optional<SceneEntry> chart, chart_text, name;
  for (const SceneEntry& e : scene_entries(text, path)) {
    if (e.key == "knit.chart")
      chart = e;
    else if (e.key == "knit.chart_text")
      chart_text = e;
    else if (e.key == "scene.name")
      name = e;
    else
      from_file.push_back(e.key + "=" + e.value);
  }
  const auto where = [&path](const SceneEntry& e) {
    return " (" + path + " line " + std::to_string(e.line) + ")";
  };
  if (chart.has_value() == chart_text.has_value())
    throw std::invalid_argument("scene " + path +
                                ": give one of knit.chart (a chart file, relative to the scene "
                                "file) and knit.chart_text (the chart inline)");
  KnitScene scene;
  if (chart) {
    const fs::path file = fs::path(path).parent_path() / chart->value;
    scene.chart = read_chart(file.string(), "knit.chart = " + chart->value + where(*chart));
    scene.chart_file = file.lexically_normal().string();  // "models/charts/x.chart"
    scene.name = fs::path(chart->value).stem().string();
  } else {
    try {
      scene.chart = parse_knit_chart(chart_text->value);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("knit.chart_text" + where(*chart_text) + ": " + e.what());
    }
    scene.chart_file = path;
    scene.name = fs::path(path).stem().string();
  }
  if (name) {
    if (!is_scene_name(name->value))
      throw std::invalid_argument("scene.name = " + name->value +
                                  ": must be a non-empty name of letters, digits, _ and -" +
                                  where(*name));
    scene.name = name->value;
  }
  sets.insert(sets.begin(), from_file.begin(), from_file.end());
  return scene;
}

}  // namespace knitsim
