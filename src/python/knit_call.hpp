// knitsim.knit without Python: what `knitsim knit` does before and after its run
// (src/cli/cmd_knit.cpp), on the same functions: the chart (--chart) or knit scene (--scene) with
// the overrides, the run options, the integrator's name and its default velocity tolerance;
// run_knit; the textile measures, the end state's centrelines and summary.json (knit_summary).
// It writes nothing; write_knit_call writes the command's files (write_knit_outputs).
//
// Thread safety and failure modes as drape_call's (drape_call.hpp): each call owns its scene,
// result and cancel flag; bad input throws std::invalid_argument with the command line's one-line
// message (a bad chart: "FILE: chart row R (line L), column C: ..."); a run that ends in any
// status but equilibrium is a status in result.stats.
#pragma once

#include <atomic>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "src/geometry/nurbs.hpp"
#include "src/measure/knit_measures.hpp"
#include "src/scene/knit_run.hpp"
#include "src/scene/knit_scene.hpp"

namespace knitsim {

struct KnitRequest {
  std::string chart_or_scene;          // a chart file (--chart) or, ending in .toml, a knit scene
  std::vector<std::string> overrides;  // "key=value", each as --set takes it
  std::string integrator;              // "" = default_knit_integrator(...) (--integrator)
  // The run options by name (run_option_flags(), drape_call.hpp), values as text.
  std::vector<std::pair<std::string, std::string>> run_options;
  int frames = 4;  // --frames
};

// True where `path` names a knit scene (a .toml file) rather than a chart.
bool is_knit_scene_path(const std::string& path);
// The chart and the scene of a knit call (a chart file or a .toml knit scene, with the --set
// overrides), read as the commands read them: the chart before the overrides apply.
KnitChart read_knit_input(const std::string& chart_or_scene,
                          const std::vector<std::string>& overrides, Scene& input);

struct KnitCall {
  KnitScene scene;
  nlohmann::json model_keys;  // state.json's model (knit_model_keys)
  std::unique_ptr<KnitResult> result;
  std::optional<TextileMeasures> textile;  // none for an end state that is not finite
  std::vector<CurveSamples> centerlines;   // the courses' at the end (none if not finite)
  std::string stitches_csv;                // stitches.csv's text ("" without textile)
  nlohmann::json summary;                  // summary.json
};

// Checks the whole request (throws std::invalid_argument), runs it with `cancel` as its interrupt
// flag (may be nullptr) and `observer` (may be nullptr), and measures the result.
std::shared_ptr<KnitCall> knit_call(const KnitRequest& request,
                                    const std::atomic<bool>* cancel = nullptr,
                                    RunObserver* observer = nullptr);

// Writes the files `knitsim knit --out folder` writes (write_knit_outputs; the PNGs unless
// picture = false) into `folder`, made as --out makes it, and removes a stale steps.csv as knit
// without --step-history does. Returns the folder's path.
std::string write_knit_call(const KnitCall& call, const std::string& folder, bool pictures = true);

}  // namespace knitsim
