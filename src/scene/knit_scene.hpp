// A knit scene (docs/knit.md, "Running a chart"): a stitch chart, the knit parameters and the run
// options -- what a knit run integrates and how -- read from a chart file (knitsim knit --chart)
// or a scene file (--scene: TOML, the chart by path or inline, knit and run keys).
//
// Failure modes: bad input throws std::invalid_argument with one line naming the flag or key
// ("--chart FILE: cannot read the file: ...", "knit.chart = FILE (SCENE line 3): cannot read the
// file: ...", "FILE: chart row 2 (line 2), column 3: ...").
#pragma once

#include <string>
#include <vector>

#include "models/knit_loops.hpp"
#include "solvers/integrator.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

struct KnitScene {
  std::string name = "knit";  // labels the outputs: scene.name, else the chart file's stem
  std::string chart_file;     // where the chart was read (summary.json chart_file): the path
                              // given, or the scene file for an inline chart
  KnitChart chart;
  KnitParams params;
  IntegratorOptions options;
  int frames = 4;  // captured states, >= 1 (src/scene/frame_recorder.hpp)
};

// --chart FILE: a scene of that chart and nothing else (every key at its default).
KnitScene knit_scene_of_chart(const std::string& chart_path);

// --scene FILE: the chart by path (knit.chart, relative to the scene file's folder) or inline
// (knit.chart_text; exactly one of them), scene.name, and the file's other entries as
// "key=value" assignments, inserted at the front of `assignments` (before the command line's
// --set ones) for the knit keys to apply. A file longer than kMaxSceneFileBytes is refused.
KnitScene read_knit_scene(const std::string& path, std::vector<std::string>& assignments);

}  // namespace knitsim
