#include "src/io/run_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/io/json.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace fs = std::filesystem;

namespace {

// state.json's "format": bump the number if the layout changes.
constexpr const char* kRunStateFormat = "knitsim run state 2";

bool all_finite(const std::vector<double>& a) {
  return std::all_of(a.begin(), a.end(), [](double d) { return std::isfinite(d); });
}

}  // namespace

void write_run_state(const fs::path& dir, const SavedRun& saved) {
  if (!all_finite(saved.state.x) || !all_finite(saved.state.v) || !std::isfinite(saved.state.t)) {
    remove_stale_output(dir / "state.json");  // an earlier run's would be continued instead
    return;
  }
  write_json_atomic(dir / "state.json", {{"format", kRunStateFormat},
                                         {"command", saved.command},
                                         {"integrator", saved.integrator},
                                         {"dt", saved.dt},
                                         {"model", saved.model},
                                         {"t", saved.state.t},
                                         {"integrated_dof", saved.state.x.size()},
                                         {"x", saved.state.x},
                                         {"v", saved.state.v}});
}

namespace {

// The fields of to_json(DrapeParams) whose --set key is not "model.<field>". parse_run_state
// also reads them keyed "model.<field>" (state files of earlier builds) and renames them, so
// that a refusal names the key --set knows.
const std::vector<std::pair<std::string, std::string>>& drape_fields_set_elsewhere() {
  static const std::vector<std::pair<std::string, std::string>> fields = {
      {"width", "fabric.width"},
      {"areal_density", "fabric.areal_density"},
      {"layout", "pins.layout"},
      {"pin_span", "pins.span"},
      {"pin_move_time", "pins.move_time"}};
  return fields;
}

}  // namespace

SavedRun parse_run_state(const std::string& text, const std::string& command) {
  SavedRun saved;
  // A byte JSON text cannot hold (a control character outside a string's escapes): binary data,
  // which the parser would report as "unexpected end of input" at a NUL.
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 && c != '\t' && c != '\n' && c != '\r') {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", c);
      throw std::invalid_argument("not a JSON file: byte " + std::to_string(i + 1) + " is " + hex +
                                  ", a control character (binary data?)");
    }
  }
  try {
    const nlohmann::json state = nlohmann::json::parse(text);
    if (!state.is_object() || !state.contains("format") || state.at("format") != kRunStateFormat)
      throw std::invalid_argument("format is not \"" + std::string(kRunStateFormat) +
                                  "\" (not a state file of this knitsim version)");
    saved.command = state.at("command").get<std::string>();
    if (saved.command != command)
      throw std::invalid_argument("the state of a knitsim " + printable(saved.command) +
                                  " run; this is knitsim " + command);
    saved.state.t = state.at("t").get<double>();
    if (!(saved.state.t >= 0.0) || !std::isfinite(saved.state.t))
      throw std::invalid_argument("t = " + format_number(saved.state.t) +
                                  ": must be >= 0 s and finite");
    saved.state.x = state.at("x").get<std::vector<double>>();
    saved.state.v = state.at("v").get<std::vector<double>>();
    const size_t n = state.at("integrated_dof").get<size_t>();
    if (saved.state.x.size() != n || saved.state.v.size() != n)
      throw std::invalid_argument("x and v must hold integrated_dof = " + std::to_string(n) +
                                  " numbers each");
    if (!all_finite(saved.state.x) || !all_finite(saved.state.v))
      throw std::invalid_argument("x and v must be finite");
    saved.integrator = state.at("integrator").get<std::string>();
    saved.dt = state.at("dt").get<double>();
    if (!(saved.dt >= 0.0) || !std::isfinite(saved.dt))
      throw std::invalid_argument("dt = " + format_number(saved.dt) +
                                  ": must be >= 0 s and finite");
    saved.model = state.at("model");
    if (!saved.model.is_object()) throw std::invalid_argument("model is not an object");
    if (command == "drape")  // an earlier build's keys: "model.width" for fabric.width, ...
      for (const auto& [field, set_key] : drape_fields_set_elsewhere()) {
        const auto old = saved.model.find("model." + field);
        if (old == saved.model.end() || saved.model.contains(set_key)) continue;
        saved.model[set_key] = *old;
        saved.model.erase(old);
      }
  } catch (const nlohmann::json::exception& e) {
    // Without the library's "[json.exception.parse_error.101] " tag: what went wrong, where.
    std::string what = e.what();
    if (what.rfind("[json.exception.", 0) == 0 && what.find("] ") != std::string::npos)
      what.erase(0, what.find("] ") + 2);
    throw std::invalid_argument("not a valid state file: " + printable(what));
  }
  return saved;
}

SavedRun read_run_state(const fs::path& dir, const std::string& command) {
  // Capped like the other inputs: 256 MiB holds the state of a 1000 x 1000 grid.
  constexpr std::size_t kMaxStateFileBytes = std::size_t{256} << 20;
  const fs::path path = dir / "state.json";
  std::string text, why;
  if (!read_input_file(path.string(), kMaxStateFileBytes, text, why))
    throw std::invalid_argument(
        path.string() + ": " + why +
        (fs::exists(dir / "summary.json")
             ? " (that run's final state was not finite, or it predates state.json)"
             : " (not the output folder of a knitsim " + command + " run)"));
  try {
    return parse_run_state(text, command);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path.string() + ": " + e.what());
  }
}

nlohmann::json drape_model_keys(const DrapeParams& params) {
  nlohmann::json keys = nlohmann::json::object();
  const nlohmann::json fields = to_json(params);  // items() must not outlive its object
  for (const auto& [field, value] : fields.items()) {
    std::string key = "model." + field;
    for (const auto& [elsewhere, set_key] : drape_fields_set_elsewhere())
      if (field == elsewhere) key = set_key;
    keys[key] = value;
  }
  return keys;
}

RunState continue_state(const std::string& dir, const std::string& command,
                        const nlohmann::json& model, const std::string& same_what,
                        const std::string& integrator, IntegratorOptions& options) {
  const std::string where = "--continue " + dir + ": ";
  SavedRun saved;
  try {
    saved = read_run_state(dir, command);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--continue: " + std::string(e.what()));
  }
  // The files of one run only: a rerun stopped while writing may have left its summary beside
  // the earlier run's state (src/base/files.hpp, finish_output_folder).
  if (std::string why; !output_folder_complete(dir, why))
    throw std::invalid_argument("--continue: " + why + "; run it again");
  for (const auto& [key, value] : model.items())
    if (!saved.model.contains(key) || saved.model.at(key) != value) {
      const std::string here = value.dump(),
                        there = saved.model.contains(key) ? saved.model.at(key).dump() : "absent";
      const std::string differ = here.size() + there.size() <= 80
                                     ? key + " = " + here + " here, " + there + " in"
                                     : key + " differs from";  // e.g. a chart: not one line
      throw std::invalid_argument(where + differ + " the run being continued; give the same " +
                                  same_what);
    }
  // A key kept only where it differs from its default (a text key such as knit.pins) is absent
  // here when this run takes the default: one the saved run kept differs from it.
  for (const auto& [key, value] : saved.model.items())
    if (!model.contains(key))
      throw std::invalid_argument(where + key + " = " + value.dump().substr(0, 40) +
                                  " in the run being continued, the default here; give the same " +
                                  same_what);
  if (!(saved.state.t < options.t_max))
    throw std::invalid_argument(where + "that run stopped at t = " + format_number(saved.state.t) +
                                " s, not below run.t_max = " + format_number(options.t_max) +
                                " s; raise run.t_max");
  if (options.dt == 0.0 && saved.dt > 0.0 && integrator == saved.integrator) options.dt = saved.dt;
  return saved.state;
}

}  // namespace knitsim
