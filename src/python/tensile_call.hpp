// knitsim.tensile without Python: what `knitsim tensile` does before and after its run
// (src/cli/cmd_tensile.cpp), on the same functions: the chart or knit scene with the overrides
// and run options, the test's options checked (TensileOptions::validate), the specimen and its
// clamps checked; run_tensile; tensile.csv's text and summary.json (tensile_summary). It writes
// nothing; write_tensile_call writes the command's files but the kept steps' step_NNN/ folders
// (their knit outputs need the model in that step's state, which only the run itself holds).
//
// Thread safety and failure modes as drape_call's (drape_call.hpp): each call owns its scene,
// result and cancel flag; bad input throws std::invalid_argument with the command line's one-line
// message ("--steps = 0: ..."); a step that does not reach equilibrium (interrupted included)
// ends the test with its status in the last step, the curve so far kept.
#pragma once

#include <atomic>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "src/scene/knit_scene.hpp"
#include "src/scene/tensile_run.hpp"

namespace knitsim {

struct TensileRequest {
  std::string chart_or_scene;          // a chart file (--chart) or, ending in .toml, a knit scene
  std::vector<std::string> overrides;  // "key=value", each as --set takes it
  // The run options by name (run_option_flags(), drape_call.hpp), values as text.
  std::vector<std::pair<std::string, std::string>> run_options;
  TensileOptions test;  // --direction, --steps, --strain, --gauge-ratio, --unload, --outputs
};

struct TensileCall {
  KnitScene scene;
  TensileOptions test;
  TensileResult result;
  std::string csv;         // tensile.csv's text
  nlohmann::json summary;  // summary.json
};

// Checks the whole request (throws std::invalid_argument), runs the test with `cancel` as its
// interrupt flag (may be nullptr) and `observer` (may be nullptr).
std::shared_ptr<TensileCall> tensile_call(const TensileRequest& request,
                                          const std::atomic<bool>* cancel = nullptr,
                                          RunObserver* observer = nullptr);

// Writes tensile.csv, tensile.png (unless pictures = false), summary.json and manifest.json, as
// `knitsim tensile --out folder` does, into `folder`, made as --out makes it (no step_NNN/).
// Returns the folder's path.
std::string write_tensile_call(const TensileCall& call, const std::string& folder,
                               bool pictures = true);

}  // namespace knitsim
