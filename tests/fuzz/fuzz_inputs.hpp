// The fuzzed entry points (tests/fuzz/fuzz_*.cpp, libFuzzer) and their oracle, shared with the
// normal suite (tests/test_fuzz_regressions.cpp replays tests/fuzz/corpus/ and
// tests/fuzz/regressions/ through the same functions).
//
// Each check feeds one input to a parser the command line reaches with user files:
//   scene   load_scene_text (TOML scene, docs/scenes.md), then, if accepted and small, the grid;
//   chart   parse_knit_chart (docs/knit.md), then, if accepted and small, the model and its
//           type-value points and centrelines at rest;
//   target  parse_target_csv (src/fit/targets.hpp), then every scene's edge fits;
//   state   parse_run_state (src/io/output.hpp: the state.json of drape|knit --continue), then
//           what it holds (finite, x and v of one size);
//   set     the --set overrides of knitsim drape (one key=value per line of the input, given to
//           load_scene on four_corner in order), then, if accepted and small, the grid;
//   knit_scene  load_knit_scene_text (TOML knit scene, docs/knit.md), its inline chart, the
//           validation knitsim knit makes, then, if small, start_knit (model and initial state).
// Oracle: the parser either accepts the input or throws std::invalid_argument with one
// non-empty line (docs/reliability.md: one clear line naming the bad input). Once it has accepted, the
// later stages must succeed (validation promised they would) and give finite numbers. Anything
// else -- another exception, a multi-line message, a non-finite result -- throws
// FuzzFinding; crashes, UB, leaks and hangs are caught by the sanitizers and libFuzzer.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace knitsim::fuzz {

struct FuzzFinding : std::logic_error {
  using std::logic_error::logic_error;
};

// The rejection half of the oracle: throws FuzzFinding for an empty or multi-line message.
void check_rejection_message(const std::string& message);

void check_scene_input(const std::string& text);
void check_chart_input(const std::string& text);
void check_target_input(const std::string& text);
void check_state_input(const std::string& text);
void check_set_input(const std::string& text);
void check_knit_scene_input(const std::string& text);

// The fuzz targets by name (the folder names under tests/fuzz/corpus and regressions).
struct FuzzEntry {
  const char* name;
  void (*check)(const std::string& text);
};
const std::vector<FuzzEntry>& fuzz_entries();

}  // namespace knitsim::fuzz
