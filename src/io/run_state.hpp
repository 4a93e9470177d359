// state.json, what `knitsim drape|knit --continue DIR` starts from: the integrated state at the
// end of a run and what a continuation must match.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "models/drape_grid.hpp"
#include "solvers/integrator.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

// What `--continue DIR` starts from: DIR/state.json, the integrated state at t_final of a drape
// or knit run with what a continuation must match.
struct SavedRun {
  std::string command;  // "drape" or "knit": the command that wrote it
  RunState state;       // t_final, and x, v: the integrated unknowns
  std::string integrator;
  double dt = 0.0;       // the run's fixed step (euler, verlet, implicit-euler), else 0
  nlohmann::json model;  // {"model.stiffness": 852, ...}: what was integrated, keyed as the user
                         // sets it (--set keys; "chart" for the knit chart)
};
// A drape's SavedRun::model: to_json(params) with its keys as --set names them ("model.KEY",
// "fabric.width", "pins.layout", ...).
nlohmann::json drape_model_keys(const DrapeParams& params);
// Writes DIR/state.json (format "knitsim run state 2", shortest round-trip decimals); if x, v
// or t is not finite there is nothing to continue from, and an earlier run's state.json in DIR
// is removed (--continue would start from it).
void write_run_state(const std::filesystem::path& dir, const SavedRun& saved);
// The text of a state.json written by `command`: throws std::invalid_argument (one line) naming
// what is missing or malformed (x, v not finite or not integrated_dof long, t or dt negative),
// or that another command or format wrote it. Fuzzed (tests/fuzz/fuzz_state.cpp).
SavedRun parse_run_state(const std::string& text, const std::string& command);
// Reads DIR/state.json (at most 256 MiB) with parse_run_state; the message names the file.
SavedRun read_run_state(const std::filesystem::path& dir, const std::string& command);
// --continue DIR of `command`: the saved state, checked against this run -- `model` (keyed as
// SavedRun::model) must equal the saved one key by key (the message names the first that differs,
// "model.stiffness = 900 here, 852 in the run being continued; give the same <same_what>"), the
// folder must hold one whole run (output_folder_complete, src/base/files.hpp), its
// t must be below options.t_max ("raise run.t_max"). A fixed-step run continued by the same
// integrator keeps the saved step unless options.dt is set, so an interrupted euler run
// continues on the same step sequence. Throws std::invalid_argument (one line, starting
// "--continue"). The caller checks the state's size against what it integrates.
RunState continue_state(const std::string& dir, const std::string& command,
                        const nlohmann::json& model, const std::string& same_what,
                        const std::string& integrator, IntegratorOptions& options);

}  // namespace knitsim
