// knitsim.drape without Python: the one entry point the Python module (module.cpp) and the C++
// benchmark (experiments/python/drape_loop.cpp) call, so that what the benchmark measures beside
// the module is the module's own overhead. It does what `knitsim drape` does before and after
// its run (src/cli/cmd_drape.cpp), on the same functions: load_scene with the overrides, the run
// options, the integrator's name, --target; run_drape; drape_report (the measured edges and
// summary.json). It writes nothing; write_drape_call writes the command's files.
//
// Thread safety: calls on different threads share nothing (each owns its scene, result and
// cancel flag); the process-wide interrupt flag of the command line (src/cli/interrupt.hpp) is
// not used: a call is cancelled through its own `cancel`.
//
// Failure modes: bad input throws std::invalid_argument with the command line's one-line message
// ("model.stiffness = -5: must be > 0 N/m", "--rtol = 0: ...", "--integrator = X: ..."); a run
// that ends in any status but equilibrium (interrupted, diverged, ...) is a status in
// result.stats, not an exception.
#pragma once

#include <atomic>
#include <string>
#include <utility>
#include <vector>

#include "src/io/drape_outputs.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

struct DrapeRequest {
  std::string scene = "four_corner";   // a built-in name or a TOML path (--scene)
  std::vector<std::string> overrides;  // "key=value", each as --set takes it
  std::string integrator;              // "" = default_integrator() (--integrator)
  // The run options by the command line's flag names without "--" and with "_" for "-"
  // ("rtol", "max_wall", "newton_solver", ...: run_option_flags()), values as text.
  std::vector<std::pair<std::string, std::string>> run_options;
  std::string target;  // target edges CSV (--target); "" = none
};

struct DrapeCall {
  Scene scene;
  std::string integrator;
  DrapeResult result;
  bool has_target = false;
  std::vector<EdgeFit> target_edges;  // the target scene's edges (has_target)
  DrapeReport report;                 // measured edges and summary.json
};

// The run option names DrapeRequest::run_options takes, as (name, its flag): ("rtol", "--rtol").
const std::vector<std::pair<std::string, std::string>>& run_option_flags();
// Sets the run option `name` (a name of run_option_flags()) of `o` from its text; throws
// std::invalid_argument ("--rtol = x: must be a number", or the names for an unknown one).
void apply_run_option(IntegratorOptions& o, const std::string& name, const std::string& value);

// Checks the whole request (throws std::invalid_argument), runs it with `cancel` as its interrupt
// flag (may be nullptr) and `observer` (may be nullptr), and measures the result.
DrapeCall drape_call(const DrapeRequest& request, const std::atomic<bool>* cancel = nullptr,
                     RunObserver* observer = nullptr);

// Writes the files `knitsim drape --out folder` writes (write_drape_outputs; drape.png unless
// picture = false) into `folder`, made as --out makes it (make_output_dir), and removes a stale
// steps.csv as drape without --step-history does. Returns the folder's path.
std::string write_drape_call(const DrapeCall& call, const std::string& folder, bool picture = true);

}  // namespace knitsim
