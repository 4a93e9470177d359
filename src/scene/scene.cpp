#include "src/scene/scene.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "models/mirror_reduced.hpp"
#include "solvers/equilibrium_check.hpp"
#include "src/base/files.hpp"
#include "src/base/text.hpp"

namespace knitsim {

namespace {

enum class Kind { Number, Integer, Text };

// One scene key: where its value goes, its unit and what it means (`knitsim list keys`).
// Number keys expose the field (its accepted range is stated once, by the validators); Integer
// and Text keys parse and check their own value and throw `accepted` (e.g. "one of a, b, c")
// when it does not fit.
struct Key {
  std::string name;
  Kind kind;
  std::function<double&(Scene&)> number;                // Kind::Number
  std::function<bool(Scene&, const std::string&)> set;  // Integer, Text: false = bad
  std::string accepted;                                 // Integer, Text
  std::function<std::string(const Scene&)> get;         // Integer, Text: the value as text
  std::string unit;                                     // "" for text keys and pure numbers
  std::string meaning;                                  // one sentence
};

bool is_name(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '-';
  });
}

const std::vector<Key>& keys() {
  static const std::vector<Key> table = [] {
    std::vector<Key> k;
    auto number = [&k](const char* name, std::function<double&(Scene&)> field, const char* unit,
                       const char* meaning) {
      k.push_back({name, Kind::Number, std::move(field), nullptr, "", nullptr, unit, meaning});
    };
    auto other = [&k](const char* name, Kind kind,
                      std::function<bool(Scene&, const std::string&)> set, const char* accepted,
                      std::function<std::string(const Scene&)> get, const char* meaning) {
      k.push_back({name, kind, nullptr, std::move(set), accepted, std::move(get), "", meaning});
    };
    // A text key naming one of a few values of the DrapeParams member `field`: (name, value).
    auto choice = [&other](const char* name, auto field, auto values, const char* meaning) {
      std::string accepted = "one of ";
      for (std::size_t i = 0; i < values.size(); ++i)
        accepted += (i > 0 ? ", " : "") + values[i].first;
      other(
          name, Kind::Text,
          [field, values](Scene& s, const std::string& v) {
            for (const auto& [text, value] : values)
              if (v == text) return (s.params.*field = value, true);
            return false;
          },
          accepted.c_str(),
          [field, values](const Scene& s) {
            for (const auto& [text, value] : values)
              if (s.params.*field == value) return text;
            return std::string("?");
          },
          meaning);
    };
    other(
        "scene.name", Kind::Text,
        [](Scene& s, const std::string& v) { return is_name(v) ? (s.name = v, true) : false; },
        "a non-empty name of letters, digits, _ and -", [](const Scene& s) { return s.name; },
        "the label in outputs (default: the built-in name or the file's stem)");
    number("fabric.width", [](Scene& s) -> double& { return s.params.width; }, "m",
           "side W of the square sample; the model's side is n L0 with n = round(W / L0)");
    number("fabric.areal_density", [](Scene& s) -> double& { return s.params.areal_density; },
           "g/m^2", "mass per area, spread over the particles");
    number("model.stiffness", [](Scene& s) -> double& { return s.params.stiffness; }, "N/m",
           "spring constant k of every spring (Table 3 box of the fits: 500..1200)");
    number("model.damping", [](Scene& s) -> double& { return s.params.damping; }, "N s/m",
           "damping c, absolute and per particle (not scaled with the mesh); does not change "
           "the equilibrium, only the path to it (fit box 10..20)");
    number("model.elongation_limit",
           [](Scene& s) -> double& { return s.params.elongation_limit; }, "%",
           "largest spring strain before the limit acts (0 = off; fit box 5..20); inactive when "
           "the drape's max strain stays below it");
    number("model.natural_length", [](Scene& s) -> double& { return s.params.natural_length; },
           "m", "rest length L0 of a structural spring; sets the mesh, n = round(W / L0) cells "
           "per side (fit box 0.04..0.06)");
    choice("model.topology", &DrapeParams::topology,
           std::vector<std::pair<std::string, char>>{{"a", 'a'}, {"b", 'b'}, {"c", 'c'}},
           "springs per particle: a = structural + shear + bending, b = structural + shear, "
           "c = structural + bending (structural: to the 4 neighbours at L0; shear: the 2 "
           "diagonals at 1.41 L0; bending: to the second neighbours at 2 L0)");
    number("model.perturbation", [](Scene& s) -> double& { return s.params.perturbation; }, "m",
           "amplitude of a seeded out-of-plane perturbation of the flat start (breaks symmetry)");
    other(
        "model.seed", Kind::Integer,
        [](Scene& s, const std::string& v) {
          auto digit = [](unsigned char c) { return std::isdigit(c) != 0; };
          if (v.empty() || !std::all_of(v.begin(), v.end(), digit)) return false;
          errno = 0;
          const unsigned long long u = std::strtoull(v.c_str(), nullptr, 10);
          if (errno == ERANGE || u > UINT_MAX) return false;
          s.params.seed = static_cast<unsigned>(u);
          return true;
        },
        "an integer in 0..4294967295", [](const Scene& s) { return std::to_string(s.params.seed); },
        "seed of the perturbation");
    choice("model.symmetry", &DrapeParams::symmetry,
           std::vector<std::pair<std::string, DrapeSymmetry>>{{"auto", DrapeSymmetry::Auto},
                                                              {"none", DrapeSymmetry::None},
                                                              {"half", DrapeSymmetry::Half},
                                                              {"quarter", DrapeSymmetry::Quarter},
                                                              {"eighth", DrapeSymmetry::Eighth}},
           "integrate one mirror part of the sheet and unfold it (half: mirror x = W/2; quarter, "
           "eighth: four_corner only); auto = the largest the scene allows, certified on the "
           "whole sheet");
    choice("pins.layout", &DrapeParams::layout,
           std::vector<std::pair<std::string, PinLayout>>{{"four_corner", PinLayout::FourCorner},
                                                          {"two_corner", PinLayout::TwoCorner}},
           "four_corner: hung from its 4 corners (paper 1, Fig. 12); two_corner: from the 2 "
           "corners of one edge (Fig. 11)");
    number("pins.span", [](Scene& s) -> double& { return s.params.pin_span; }, "1",
           "two_corner: final pin distance / model width; below 1 the pins move inward");
    number("pins.move_time", [](Scene& s) -> double& { return s.params.pin_move_time; }, "s",
           "duration of that pin move");
    number("run.t_max", [](Scene& s) -> double& { return s.options.t_max; }, "s",
           "end time if no equilibrium is reached (status time_limit, exit 3)");
    number("run.equilibrium_tol", [](Scene& s) -> double& { return s.options.equilibrium_tol; },
           "1", "static residual (force / mean particle weight) below which the stop is tested");
    number("run.position_tol", [](Scene& s) -> double& { return s.options.position_tol; }, "m",
           "the stop: Newton correction |K^-1 F| below this (docs/numerics.md)");
    return k;
  }();
  return table;
}

[[noreturn]] void unknown_key(const std::string& key, const std::string& where) {
  throw std::invalid_argument(unknown_key_message(key, scene_keys()) + where);
}

const Key& find_key(const std::string& name, const std::string& where) {
  for (const Key& k : keys())
    if (k.name == name) return k;
  unknown_key(name, where);
}

// The accepted values of a key, for type errors. For numbers the range is asked from the
// validators (with the field set to NaN), so it is stated in one place.
std::string accepted(const Key& key) {
  if (key.kind != Kind::Number) return key.accepted;
  Scene probe;
  key.number(probe) = std::numeric_limits<double>::quiet_NaN();
  try {
    probe.validate();
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    const std::string marker = ": must be ";
    const size_t at = msg.find(marker);
    if (at != std::string::npos) return "a number " + msg.substr(at + marker.size());
  }
  return "a finite number";
}

[[noreturn]] void bad_value(const Key& key, const std::string& shown, const std::string& where) {
  throw std::invalid_argument(key.name + " = " + printable(shown) + ": must be " + accepted(key) +
                              where);
}

// Sets a Number key; NaN and inf are type errors.
void set_number(Scene& scene, const Key& key, double value, const std::string& shown,
                const std::string& where) {
  if (!std::isfinite(value)) bad_value(key, shown, where);
  key.number(scene) = value;
}

// Sets `key` from text (a --set value, or a TOML string or integer).
void set_from_text(Scene& scene, const Key& key, const std::string& text, const std::string& shown,
                   const std::string& where) {
  if (key.kind == Kind::Number) {
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size()) bad_value(key, shown, where);
    set_number(scene, key, value, shown, where);
  } else if (!key.set(scene, text)) {
    bad_value(key, shown, where);
  }
}

std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

void apply_override(Scene& scene, const std::string& assignment) {
  const size_t eq = assignment.find('=');
  if (eq == std::string::npos)
    throw std::invalid_argument("--set " + printable(assignment) + ": expected key=value, e.g. " +
                                "model.stiffness=900");
  const std::string name = trim(assignment.substr(0, eq));
  std::string value = trim(assignment.substr(eq + 1));
  const Key& key = find_key(name, "");
  if (key.kind == Kind::Text && value.size() >= 2 && value.front() == '"' && value.back() == '"')
    value = value.substr(1, value.size() - 2);
  set_from_text(scene, key, value, value, "");
  scene.keys_given.push_back(key.name);
}

// A TOML value as it appears in the file, for messages.
std::string shown(const toml::node& node) {
  std::ostringstream os;
  node.visit([&os](const auto& v) { os << v; });
  return os.str();
}

void apply_toml(Scene& scene, const std::string& text, const std::string& source) {
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << "scene " << source << ": TOML syntax error at line " << e.source().begin.line
       << ", column " << e.source().begin.column << ": " << printable(std::string(e.description()));
    throw std::invalid_argument(os.str());
  }
  auto where = [&source](const toml::node& node) {
    return " (" + source + " line " + std::to_string(node.source().begin.line) + ")";
  };
  for (const auto& [section, section_node] : root) {
    const std::string section_name(section.str());
    const toml::table* table = section_node.as_table();
    if (!table) unknown_key(section_name, where(section_node));
    for (const auto& [name, node] : *table) {
      const std::string full = section_name + "." + std::string(name.str());
      const Key& key = find_key(full, where(node));
      if (key.kind == Kind::Number && node.is_number()) {
        // An integer beyond 2^53 has no exact double, so toml++'s value<double>() is empty:
        // take the nearest double, and let the key's range check judge it.
        const double v = node.is_integer() ? static_cast<double>(node.as_integer()->get())
                                           : node.as_floating_point()->get();
        set_number(scene, key, v, shown(node), where(node));
      } else if (key.kind == Kind::Integer && node.is_integer()) {
        set_from_text(scene, key, shown(node), shown(node), where(node));
      } else if (key.kind == Kind::Text && node.is_string()) {
        set_from_text(scene, key, node.value<std::string>().value(), shown(node), where(node));
      } else {
        bad_value(key, shown(node), where(node));
      }
      scene.keys_given.push_back(key.name);
    }
  }
}

[[noreturn]] void unreadable(const std::string& path, const std::string& reason) {
  std::string msg = "scene: cannot read " + path + ": " + reason;
  if (path.find('/') == std::string::npos && path.find('.') == std::string::npos) {
    msg += " (built-in scenes:";
    for (const auto& s : builtin_scenes()) msg += " " + s.first;
    msg += ")";
  }
  throw std::invalid_argument(msg);
}

}  // namespace

void Scene::validate() const {
  params.validate();
  try {
    options.validate();
  } catch (const std::invalid_argument& e) {
    // IntegratorOptions names its fields; the user wrote a scene key or a command-line flag.
    rethrow_renamed(e, run_option_names());
  }
}

Scene load_scene_text(const std::string& text, const std::string& name, const std::string& source,
                      const std::vector<std::string>& overrides) {
  Scene scene;
  scene.name = name;
  scene.source = source;
  apply_toml(scene, text, source == "built-in" ? "built-in " + name : source);
  for (const std::string& o : overrides) apply_override(scene, o);
  scene.validate();
  return scene;
}

Scene load_scene(const std::string& name_or_path, const std::vector<std::string>& overrides) {
  const auto& builtins = builtin_scenes();
  const auto builtin = std::find_if(builtins.begin(), builtins.end(),
                                    [&](const auto& s) { return s.first == name_or_path; });
  if (builtin != builtins.end())
    return load_scene_text(builtin->second, builtin->first, "built-in", overrides);
  std::string text, why;
  if (!read_input_file(name_or_path, kMaxSceneFileBytes, text, why)) unreadable(name_or_path, why);
  const std::string stem = std::filesystem::path(name_or_path).stem().string();
  return load_scene_text(text, is_name(stem) ? stem : "scene", name_or_path, overrides);
}

std::string scene_key_value(const Scene& scene, const std::string& name) {
  const Key& key = find_key(name, "");
  if (key.kind != Kind::Number) return key.get(scene);
  const double v = key.number(const_cast<Scene&>(scene));  // read only
  return format_number(v, 6) + (key.unit.empty() || key.unit == "1" ? "" : " " + key.unit);
}

std::vector<std::string> keys_not_given(const Scene& scene,
                                        const std::vector<std::string>& among) {
  std::vector<std::string> missing;
  for (const std::string& name : among)
    if (std::find(scene.keys_given.begin(), scene.keys_given.end(), name) ==
        scene.keys_given.end())
      missing.push_back(name);
  return missing;
}

Table scene_key_table() {
  const Scene defaults;
  Table t;
  t.columns = {"key", "unit", "default", "accepted", "meaning"};
  for (const Key& k : keys()) {
    const std::string value =
        k.kind == Kind::Number ? format_number(k.number(const_cast<Scene&>(defaults)), 6)
                               : k.get(defaults);
    std::string range = accepted(k);
    if (k.kind == Kind::Number && range.rfind("a number ", 0) == 0) range.erase(0, 9);
    t.rows.push_back({k.name, k.unit.empty() ? "-" : k.unit, value, range, k.meaning});
  }
  return t;
}

std::vector<std::string> scene_keys() {
  std::vector<std::string> names;
  for (const Key& k : keys()) names.push_back(k.name);
  return names;
}

std::string scene_description(const std::string& toml_text) {
  std::istringstream in(toml_text);
  std::string line;
  std::getline(in, line);
  if (!std::getline(in, line)) return "";
  const size_t hash = line.find('#');
  return hash == std::string::npos ? "" : trim(line.substr(hash + 1));
}

std::string default_integrator() { return "equilibrium"; }

std::string default_knit_integrator() { return "cvode-bdf"; }

namespace {

// The largest mirror group of the grid and its start: eighth, quarter, half, or none (a
// perturbed start, two_corner for quarter and eighth, a topology without the diagonal mirror).
DrapeSymmetry largest_symmetry(const DrapeGrid& grid) {
  for (DrapeSymmetry s : {DrapeSymmetry::Eighth, DrapeSymmetry::Quarter, DrapeSymmetry::Half}) {
    try {
      (void)make_drape_reduced(grid, s);
      return s;
    } catch (const std::invalid_argument&) {
    }
  }
  return DrapeSymmetry::None;
}

// model.symmetry = auto: the reduced model cannot see the antisymmetric modes, so its unfolded
// equilibrium is certified on the whole sheet. Where the whole sheet's K has a negative pivot,
// the state is moved 1 mm along the most negative mode (largest component positive) and the
// whole sheet runs on from there; the certificate is the whole sheet's either way.
void certify_whole_sheet(const Scene& scene, const SpringNetwork& net, Integrator& integ,
                         RunObserver* observer, std::vector<double>& x, DrapeResult& r) {
  const double t = r.stats.t_final;
  detail::StiffnessProbe probe(net, scene.options.factorization);
  const detail::StiffnessProbe::Result p = probe.probe(t, x.data());
  r.whole_sheet_checked = true;
  if (p.factored && !p.singular && p.negative_pivots == 0) {
    r.stats.min_eigenvalue = p.min_eigenvalue;  // the whole sheet's, not the reduction's
    r.stats.eigenvalue_threshold = p.threshold;
    return;
  }
  probe.leave_saddle(t, x.data(), 1e-3);  // m; a singular sheet runs on as it is
  std::vector<double> v(x.size(), 0.0);
  IntegratorOptions options = scene.options;
  const RunStats reduced = r.stats;
  r.stats = run_to_equilibrium(net, integ, options, x, v, observer, t);
  add_counters(r.stats, reduced);
  r.stats.message += "; the " + std::string(to_string(r.symmetry)) +
                     "'s equilibrium is not a minimum of the whole sheet: continued on it";
  r.symmetry = DrapeSymmetry::None;
  r.state_x = x;
  r.state_v = v;
  r.integrated_dof = net.dof();
}

}  // namespace

DrapeResult run_drape(const Scene& scene, const std::string& integrator, RunObserver* observer,
                      const RunState* from) {
  scene.validate();
  auto integ = make_integrator(integrator);
  DrapeResult r{build_drape_grid(scene.params), 0, RunStats{}, {}, {}, 0.0, 0.0, {}, {}, 0.0};
  const SpringNetwork& net = r.grid.network;
  std::vector<double>& q = r.state_x;
  std::vector<double>& qv = r.state_v;
  const double t0 = from ? from->t : 0.0;
  r.t_start = t0;
  if (from) q = from->x, qv = from->v;
  auto run = [&](const MechanicalSystem& sys) {
    if (from &&
        (static_cast<int>(q.size()) != sys.dof() || static_cast<int>(qv.size()) != sys.dof()))
      throw std::invalid_argument("the state to continue from has " + std::to_string(q.size()) +
                                  " unknowns; this scene integrates " + std::to_string(sys.dof()));
    r.stats = run_to_equilibrium(sys, *integ, scene.options, q, qv, observer, t0);
    r.integrated_dof = sys.dof();
  };
  std::vector<double> x;
  r.symmetry = scene.params.symmetry;
  if (r.symmetry == DrapeSymmetry::Auto)
    r.symmetry = (from && static_cast<int>(from->x.size()) == net.dof())
                     ? DrapeSymmetry::None  // continuing a whole-sheet state
                     : largest_symmetry(r.grid);
  if (r.symmetry != DrapeSymmetry::None) {
    const MirrorReduced reduced = make_drape_reduced(r.grid, r.symmetry);
    try {
      run(reduced);
    } catch (const std::invalid_argument&) {
      // auto: an integrator option that needs the whole sheet (cvode-bdf-gmres's block-Jacobi
      // preconditioner) refuses the reduction at its start: run whole instead.
      if (scene.params.symmetry != DrapeSymmetry::Auto) throw;
      r.symmetry = DrapeSymmetry::None;
      if (from) {
        q = from->x, qv = from->v;
      } else {
        q.clear(), qv.clear();  // the whole sheet's own start
      }
    }
  }
  if (r.symmetry != DrapeSymmetry::None) {
    const MirrorReduced reduced = make_drape_reduced(r.grid, r.symmetry);
    x.resize(net.dof());
    reduced.unfold(q.data(), x.data());
    if (scene.params.symmetry == DrapeSymmetry::Auto && r.stats.status == RunStatus::Equilibrium)
      certify_whole_sheet(scene, net, *integ, observer, x, r);
  } else {
    run(net);
    x = q;
  }
  const double t = r.stats.t_final;
  net.all_positions(t, x.data(), r.positions);
  r.rest = net.spec().positions;
  r.max_strain = net.max_strain(t, x.data());

  const int n = r.grid.n;
  double centre_z = 0.0;
  int count = 0;
  for (int i : {n / 2, (n + 1) / 2})
    for (int j : {n / 2, (n + 1) / 2}) centre_z += r.positions[r.grid.index(i, j)].z, ++count;
  double pin_z = 0.0;
  for (int p : net.spec().pinned) pin_z += r.positions[p].z;
  r.centre_sag = pin_z / net.spec().pinned.size() - centre_z / count;
  return r;
}

std::string target_scene_name(const Scene& scene) {
  if (scene.params.layout == PinLayout::FourCorner) return "four_corner";
  return scene.params.pin_span < 1.0 ? "two_corner_slack" : "two_corner";
}

const std::vector<std::pair<std::string, std::string>>& run_option_names() {
  static const std::vector<std::pair<std::string, std::string>> names = {
      {"t_max", "run.t_max"},
      {"equilibrium_tol", "run.equilibrium_tol"},
      {"position_tol", "run.position_tol"},
      {"rtol", "--rtol"},
      {"atol", "--atol"},
      {"velocity_atol", "--velocity-atol"},
      {"dt", "--dt"},
      {"max_order", "--max-order"},
      {"max_steps", "--max-steps"},
      {"max_wall_seconds", "--max-wall"},
      {"max_restarts", "--max-restarts"},
      {"krylov_dim", "--krylov-dim"},
      {"krylov_eps_lin", "--eps-lin"}};
  return names;
}

}  // namespace knitsim
