// What a knit run integrates (docs/knit.md, "Running a chart"): a stitch chart, the knit
// parameters and the run options, made from a knit Scene (src/scene/scene.hpp: knit_scene for
// `knitsim knit --chart`, load_knit_scene for `--scene`) once its chart is read.
//
// Failure modes: bad input throws std::invalid_argument with one line naming the flag or key
// ("--chart FILE: cannot read the file: ...", "knit.chart = \"FILE\" (SCENE): cannot read the
// file: ...", "FILE: chart row 2 (line 2), column 3: ...").
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "models/knit_loops.hpp"
#include "solvers/integrator.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

struct KnitScene {
  std::string name = "knit";  // labels the outputs (scene.name)
  std::string chart_file;     // where the chart was read (summary.json chart_file): the path
                              // given, or the scene file for an inline chart
  KnitChart chart;
  KnitParams params;
  IntegratorOptions options;
  int frames = 4;  // captured states, >= 1 (src/scene/frame_recorder.hpp)
  YarnKnitParams yarn;  // knit.model and the yarn-level model's keys
};

// The chart of a knit scene: the file scene.chart, or the text scene.chart_text.
KnitChart read_knit_chart(const Scene& scene);

// The run's scene: `scene`'s name, knit parameters and run options with its chart, read.
KnitScene make_knit_scene(const Scene& scene, KnitChart chart, int frames);

// What a knit run integrates, as state.json's model (SavedRun::model, knitsim knit --continue):
// the chart, one string of stitch letters per course from the bottom, and the knit.* keys of
// `scene` under their names (a text key at its default is left out unless it is knit.network, so
// that state files written before it existed still match; the chart keys are the letters).
// True for the keys only the yarn-level model reads (yarn.*, knit.stitch_length, ...).
bool yarn_model_key(const std::string& key);

nlohmann::json knit_model_keys(const KnitChart& chart, const Scene& scene);

}  // namespace knitsim
