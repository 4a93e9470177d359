#include "tests/fuzz/fuzz_inputs.hpp"

#include <cmath>
#include <optional>
#include <vector>

#include "models/drape_grid.hpp"
#include "models/knit_loops.hpp"
#include "src/fit/targets.hpp"
#include "src/io/run_state.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/knit_run.hpp"
#include "src/scene/knit_scene.hpp"
#include "src/scene/scene.hpp"

namespace knitsim::fuzz {

namespace {

// Accepted inputs larger than this are only parsed: building them is what the unit tests and
// the cap checks cover, and it would slow the fuzzer down.
constexpr long kMaxBuiltPoints = 2500;
constexpr long kMaxContactPoints = 30;  // charts built with the default contact (check_chart_input)

// Runs the parser; true if it accepted. A rejection must be std::invalid_argument with one
// non-empty line.
template <class Parse>
bool accepted(Parse&& parse) {
  try {
    parse();
    return true;
  } catch (const std::invalid_argument& e) {
    check_rejection_message(e.what());
    return false;
  }
}

// Runs a stage after the parser accepted: any exception there is a finding.
template <class Stage>
void must_succeed(const char* what, Stage&& stage) {
  try {
    stage();
  } catch (const FuzzFinding&) {
    throw;
  } catch (const std::exception& e) {
    throw FuzzFinding(std::string("accepted input, then ") + what + " threw: " + e.what());
  }
}

void require_finite(double value, const char* what) {
  if (!std::isfinite(value)) throw FuzzFinding(std::string("accepted input, non-finite ") + what);
}

}  // namespace

// The initial state of an accepted model is finite, and so is its static residual there.
void check_initial_state(const SpringNetwork& net) {
  std::vector<double> x(net.dof()), v(net.dof());
  net.initial_state(x.data(), v.data());
  for (double xi : x) require_finite(xi, "initial position");
  require_finite(net.static_residual(0.0, x.data()), "static residual at the start");
}

void check_rejection_message(const std::string& message) {
  if (message.empty()) throw FuzzFinding("rejected with an empty message");
  if (message.find('\n') != std::string::npos)
    throw FuzzFinding("rejected with a message of several lines: " + message);
}

void check_scene_input(const std::string& text) {
  Scene scene;
  if (!accepted([&] { scene = load_scene_text(text, "fuzz", "fuzz.toml"); })) return;
  const long side = scene.params.cells() + 1L;
  if (side * side > kMaxBuiltPoints) return;
  must_succeed("building the grid",
               [&] { check_initial_state(build_drape_grid(scene.params).network); });
}

void check_set_input(const std::string& text) {
  std::vector<std::string> sets;  // one --set per line, as the shell would pass them
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t end = std::min(text.find('\n', begin), text.size());
    sets.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  Scene scene;
  if (!accepted([&] { scene = load_scene("four_corner", sets); })) return;
  const long side = scene.params.cells() + 1L;
  if (side * side > kMaxBuiltPoints) return;
  must_succeed("building the grid",
               [&] { check_initial_state(build_drape_grid(scene.params).network); });
}

void check_chart_input(const std::string& text) {
  KnitChart chart;
  if (!accepted([&] { chart = parse_knit_chart(text); })) return;
  const long points = static_cast<long>(chart.wales) * (chart.courses + 1);  // at most
  if (points > kMaxBuiltPoints) return;
  must_succeed("building the model and its geometry at rest", [&] {
    // The default model (with yarn contact) on small charts; larger ones without contact, whose
    // set-up (the contact's pattern) would take the fuzzing time: with contact on every chart
    // ./test.sh --fuzz ran 106 chart inputs in its minute, with this cap its 2000 in 44 s.
    KnitParams params;
    if (points > kMaxContactPoints) params.contact_ratio = 0.0;
    const KnitModel model = build_knit(chart, params);
    check_initial_state(model.network);
    const std::vector<Vec3> rest = model.rest_positions();
    for (const LoopTypeValues& loop : type_value_points(model, rest))
      for (const Vec3& t : loop.t) require_finite(t.x + t.y + t.z, "type-value point at rest");
    for (const CurveSamples& line : course_centerlines(model, rest))
      for (const Vec3& p : line.points) require_finite(p.x + p.y + p.z, "centreline point");
  });
}

void check_knit_scene_input(const std::string& text) {
  // The scene's folder does not exist, so a knit.chart file under it is refused unread ("cannot
  // read the file"); a chart path that leaves it (absolute, or through "..") is not read at all:
  // the fuzzer reads no file of the machine's. Inline charts (knit.chart_text) are built.
  const std::string folder = "/nonexistent-knitsim-fuzz/";
  Scene input;
  KnitChart chart;
  bool inline_chart = false;
  if (!accepted([&] {
        input = load_knit_scene_text(text, folder + "fuzz.toml");
        inline_chart = input.chart.empty();
        if (inline_chart || input.chart.rfind(folder, 0) == 0) chart = read_knit_chart(input);
        input.validate();
      }))
    return;
  if (!inline_chart) return;
  const long points = static_cast<long>(chart.wales) * (chart.courses + 1);  // at most
  if (points > kMaxBuiltPoints) return;
  // The contact's set-up is slow (check_chart_input): larger charts are built without it.
  if (points > kMaxContactPoints) input.knit.contact_ratio = 0.0;
  KnitScene scene = make_knit_scene(input, chart, 1);
  std::optional<KnitStart> start;
  // start_knit may still refuse the chart for the model (a float too long for the contact,
  // yarns inside the contact's core at rest): one line, as a parser's refusal.
  if (!accepted([&] { start.emplace(start_knit(scene)); })) return;
  must_succeed("checking the knit's start", [&] {
    check_initial_state(start->model.network);
    for (double xi : start->x) require_finite(xi, "initial position");
  });
}

void check_target_input(const std::string& text) {
  Target target;
  if (!accepted([&] { target = parse_target_csv(text, "fuzz.csv"); })) return;
  must_succeed("validating and fitting it", [&] {
    target.validate();
    for (const TargetScene& scene : target.scenes)
      for (const EdgeFit& fit : fit_target_scene(scene))
        for (double c : fit.coefficients) require_finite(c, "edge coefficient");
  });
}

void check_state_input(const std::string& text) {
  SavedRun saved;
  if (!accepted([&] { saved = parse_run_state(text, "drape"); })) return;
  must_succeed("checking what it holds", [&] {
    if (saved.state.x.size() != saved.state.v.size())
      throw FuzzFinding("accepted a state whose x and v differ in size");
    require_finite(saved.state.t, "t");
    require_finite(saved.dt, "dt");
    for (double d : saved.state.x) require_finite(d, "position");
    for (double d : saved.state.v) require_finite(d, "velocity");
    if (!saved.model.is_object()) throw FuzzFinding("accepted a model that is not an object");
  });
}

const std::vector<FuzzEntry>& fuzz_entries() {
  static const std::vector<FuzzEntry> entries = {{"scene", check_scene_input},
                                                 {"chart", check_chart_input},
                                                 {"target", check_target_input},
                                                 {"state", check_state_input},
                                                 {"set", check_set_input},
                                                 {"knit_scene", check_knit_scene_input}};
  return entries;
}

}  // namespace knitsim::fuzz
