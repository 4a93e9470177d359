// Drape scenes (docs/scenes.md): a DrapeParams set plus the run options (docs/equilibrium.md),
// loaded from a built-in name or a TOML file, with `--set key=value` overrides, and run to
// equilibrium.
//
// Scene file (TOML), keys and units exactly as in models/scenes/four_corner.toml; every key is
// optional (defaults: DrapeParams / IntegratorOptions, i.e. sample 1 hung from four corners):
//   [scene]  name (text; default: the built-in name or the file's stem)
//   [fabric] width (m), areal_density (g/m^2)
//   [model]  stiffness (N/m), damping (N s/m), elongation_limit (percent),
//            natural_length (m), topology (a|b|c), perturbation (m), seed (integer >= 0),
//            symmetry (none|half|quarter|eighth: integrate one half of the grid, or one
//            quarter or eighth of four_corner, unfolded after)
//   [pins]   layout (four_corner|two_corner), span (fraction of the width), move_time (s)
//   [run]    t_max (s), equilibrium_tol (static residual, dimensionless: the stop where the
//            stiffness is singular, and max(1e-4, it) the residual below which the stop is
//            tested), position_tol (m: the stop in positions where the stiffness is positive
//            definite; both solvers/integrator.hpp)
// Line 2 of a scene file is a comment that describes it in one line (`knitsim list scenes`).
//
// Every parameter a user can set is one row of one table (key_table() below): its scene key
// and/or command-line flag, unit, default, accepted values, meaning and the model it applies to.
// Validation messages, the run options' flags (src/cli/cli_options.cpp), `knitsim list keys`,
// summary.json's options and docs/reference/scene_keys.md all come from it (docs/architecture.md,
// "Adding a parameter").
//
// Failure modes: every bad input throws std::invalid_argument with one line naming the key as
// the user wrote it (scene key, or the command-line flag for the run options):
//   "model.stifness: unknown key; did you mean model.stiffness?"
//   "model.stiffness = abc: must be a number > 0 N/m"      (wrong type, NaN, inf)
//   "model.stiffness = -5: must be > 0 N/m"                 (range, from DrapeParams::validate)
//   "scene: cannot read FILE: <reason>",  "scene FILE: TOML syntax error at line L, column C: ..."
#pragma once

#include <any>
#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "models/drape_grid.hpp"
#include "models/knit_loops.hpp"
#include "models/yarn_knit.hpp"
#include "solvers/integrator.hpp"
#include "src/base/table.hpp"
#include "src/core/invalid_field.hpp"
#include "src/core/vec3.hpp"
#include "src/scene/fit_options.hpp"
#include "src/scene/material_scene.hpp"

namespace knitsim {

// The built-in scene files as (name, TOML text), compiled into the binary from
// models/scenes/*.toml by src/scene/embed_scenes.cmake (defined in the generated
// builtin_scenes.cpp).
const std::vector<std::pair<std::string, std::string>>& builtin_scenes();

struct Scene {
  std::string name = "four_corner";  // scene.name
  std::string source = "built-in";   // "built-in" or the file path it was read from
  DrapeParams params;
  // The material model's keys (model.kind = material; src/scene/material_scene.hpp): used
  // with fabric.width and fabric.areal_density from `params` when kind is material.
  MaterialScene material;
  // The material model's fit: its search box and fitted parameters (fit.* keys; knitsim fit).
  MaterialFitBox fit_box;
  // Run options: the scene sets t_max and equilibrium_tol ([run]); the command line may set
  // the integrator's tolerances, step and caps. Everything else keeps its default.
  IntegratorOptions options;
  // The knit model (knitsim knit): its parameters (knit.* keys) and stitch chart file.
  KnitParams knit;
  // knit.model and the yarn-level model's keys (knit.model = yarn: yarn.*, knit.stitch_length,
  // ...; models/yarn_knit.hpp, docs/yarn_model.md).
  YarnKnitParams yarn;
  std::string chart;
  std::string chart_text;  // the chart inline (knit.chart_text); a knit scene has one of the two
  // The keys the scene file or a --set gave, in that order (a key may repeat): every other
  // key has its default, sample 1's value (`knitsim list keys`).
  std::vector<std::string> keys_given;
  // Each given key's value as the user typed it (the last one given), and each run flag's
  // (by flag: "--rtol"), for messages.
  std::map<std::string, std::string> typed;

  // DrapeParams::validate, IntegratorOptions::validate and KnitParams::validate, each bad field
  // named as the user writes it (run.t_max, --rtol, --max-wall, ...) with its value as typed;
  // and knit.network = paper refused beside an explicit knit.stabiliser, knit.bending or
  // knit.contact > 0 (paper 2's network has none of them).
  void validate() const;
};

// Which model a key applies to: the drape (paper 1), the knit (paper 2), both (the run), or the
// fitting commands (fit, optimize, repro, targets: their flags only).
enum class KeyModel { Drape, Knit, Both, Fit };
const char* to_string(KeyModel model);  // "drape", "knit", "both", "fit"

// One row of the parameter table: everything the program says or does about one parameter.
struct Key {
  enum class Kind { Number, Integer, Text };
  std::string name;   // scene file / --set key, "model.stiffness"; "" for a flag-only option
  std::string flag;   // command-line flag, "--rtol"; "" for none
  std::string field;  // the name its validate() throws under (InvalidField::field()), and
                      // summary.json's name of an IntegratorOptions field
  KeyModel model = KeyModel::Drape;
  Kind kind = Kind::Number;
  std::string unit;     // "" for text keys and pure numbers ("1" shown for ratios)
  std::string meaning;  // one sentence (`knitsim list keys`); a flag's --help text
  // summary.json's name of the value where it is not the key's last part (pins.span: pin_span)
  // or, for an IntegratorOptions row, its field; "" otherwise (summary_name()).
  std::string summary;
  // Number keys: the field in a Scene (its accepted range is stated once, by the validators).
  std::function<double&(Scene&)> number;
  // Integer and Text keys: parse and store (false = not accepted), read back, what is accepted.
  std::function<bool(Scene&, const std::string&)> set;
  std::function<std::string(const Scene&)> get;
  std::string accepted;
  // IntegratorOptions rows: the field, for the flags, copy_run_flags and summary.json.
  std::variant<std::monostate, double IntegratorOptions::*, int IntegratorOptions::*,
               long IntegratorOptions::*>
      option;
  std::vector<std::string> choices;  // named IntegratorOptions values (--factorization ...)
  std::function<bool(IntegratorOptions&, const std::string&)> set_option;
  std::function<std::string(const IntegratorOptions&)> get_option;
  // Rows of the fitting commands' flags (src/scene/fit_options.hpp): the field as a pointer to
  // member `T S::*` of its options struct S (the commands bind the flag to it), its default as
  // text, and S::validate() run with the field out of every range (NaN; -1 for an integer),
  // from which the range is read as for the other rows.
  std::any member;
  std::function<std::string()> default_value;
  std::function<void()> probe_range;

  const std::string& label() const { return name.empty() ? flag : name; }  // as messages name it
};

// The table, in `knitsim list keys` order. Rows with neither key nor flag are IntegratorOptions
// fields no user sets (dt_safety, check_every, runaway_position): summary.json still shows them.
// The fitting commands' rows are appended by append_fit_option_rows (src/scene/fit_options.hpp).
const std::vector<Key>& key_table();
// The row with this flag (std::logic_error if none: a programming error).
const Key& key_of_flag(const std::string& flag);
// What the validators accept for a number or integer row, "must be" dropped ("in [0, 1]",
// ">= 1"), asked from them with the field out of every range; "" where they state none.
std::string key_range(const Key& key);

// Rethrows a validation error in the user's words: the field renamed to its key or flag, and the
// value as `scene` records it typed (when it still reads back as the value refused). Anything
// that is not an InvalidField of a row is rethrown unchanged.
[[noreturn]] void rethrow_as_typed(const std::invalid_argument& e, const Scene* scene = nullptr);

// Loads a built-in scene (by name) or a scene file (any other argument is a path), applies the
// "key=value" overrides in order, and validates the result. A file longer than
// kMaxSceneFileBytes is refused unread ("scene: cannot read FILE: larger than ...").
Scene load_scene(const std::string& name_or_path, const std::vector<std::string>& overrides = {});
constexpr std::size_t kMaxSceneFileBytes = std::size_t{1} << 20;  // scene files are ~1 kB

// The same from the TOML text itself: `name` is the default scene.name, `source` the file path
// ("built-in" for a built-in scene) as messages show it. load_scene reads, then calls this.
Scene load_scene_text(const std::string& text, const std::string& name, const std::string& source,
                      const std::vector<std::string>& overrides = {});

// The knit's scene from `knitsim knit --chart CHART --set ...`: the knit's defaults (KnitParams,
// IntegratorOptions) with the overrides, keys of the knit and the run only, applied in order.
// Not validated (the command validates once it has its flags: Scene::validate).
Scene knit_scene(const std::string& chart, const std::vector<std::string>& overrides);

// A knit scene file (knitsim knit --scene; docs/knit.md, "Running a chart"): the knit's
// defaults with the file's knit and run keys, then the overrides. knit.chart is taken relative
// to the file's folder; the scene's name is the chart file's stem (the scene file's for an
// inline chart). Exactly one of knit.chart and knit.chart_text (std::invalid_argument
// otherwise). Not validated, as knit_scene.
Scene load_knit_scene(const std::string& path, const std::vector<std::string>& overrides = {});
// The same from the TOML text itself, `path` standing for the file it came from (messages, the
// chart's folder, the name). load_knit_scene reads, then calls this.
Scene load_knit_scene_text(const std::string& text, const std::string& path,
                           const std::vector<std::string>& overrides = {});

// The scene keys of `model`'s scenes (its own and the run's), dotted ("model.stiffness"), in
// file order.
std::vector<std::string> scene_keys(KeyModel model = KeyModel::Drape);

// Every row with a key or a flag: the key (or flag), the model it applies to, its unit ("-" for
// text keys, "1" for ratios), default (sample 1, four corners; the knit's defaults), accepted
// values (from the same validators that refuse bad input) and meaning: what `knitsim list keys`
// prints and docs/reference/scene_keys.md is generated from.
Table scene_key_table();
// The value of scene key `name` in `scene` as text, with its unit ("852 N/m", "a").
std::string scene_key_value(const Scene& scene, const std::string& name);
// summary.json's name of a row's value: Key::summary if set, an IntegratorOptions row's field
// (t_max, krylov_eps_lin), else the key's last part (model.stiffness: stiffness).
std::string summary_name(const Key& key);
// summary.json's `units` text of a block of values written under the rows' summary names
// (`fields`: params' or options' names), from the rows of `model` exactly (Drape, Knit: the
// params; Both: the run options): every field with a unit, grouped by unit in the table's order,
// "width, natural_length, perturbation m; areal_density g/m^2; ...". Fields of text rows, and
// names no row of `model` has, are left out.
std::string units_text(KeyModel model, const std::vector<std::string>& fields);
// The keys of `among` that neither the scene file nor a --set gave (Scene::keys_given).
std::vector<std::string> keys_not_given(const Scene& scene, const std::vector<std::string>& among);

// The one-line description of a scene file: its line 2 without the leading "#".
std::string scene_description(const std::string& toml_text);

// The integrator of drape, fit, repro and demo's first row: `equilibrium`, the solver for the
// state the damped dynamics reach (solvers/equilibrium_solver.cpp).
std::string default_integrator();

// One drape run and the quantities every report of it shows.
struct DrapeResult {
  DrapeGrid grid;               // the full model; particle (i, j) = grid.index(i, j)
  int integrated_dof = 0;       // dof integrated: the grid's, or its reduction's (symmetry)
  RunStats stats;               // status, counters, residual, wall time
  std::vector<Vec3> positions;  // all particles (pins included) at stats.t_final, m
  std::vector<Vec3> rest;       // all particles at t = 0, m
  double max_strain = 0.0;      // largest spring strain (L - L0)/L0 at t_final
  double centre_sag = 0.0;      // m: mean pin height minus the height of the grid centre (the
                                // mean of the 1 or 4 particles nearest to it), at t_final
  // The integrated state at t_final (integrated_dof unknowns each; the reduction's where
  // model.symmetry is set): what `knitsim drape --continue` starts from (state.json).
  std::vector<double> state_x, state_v;
  double t_start = 0.0;  // s: where the run began (0, or the t of the state it continued from)
  // The reduction that ran (model.symmetry = auto resolved; none after a whole-sheet restart),
  // and whether the whole sheet's K was checked at the unfolded state (auto only).
  DrapeSymmetry symmetry = DrapeSymmetry::None;
  bool whole_sheet_checked = false;
};

// Where a run continues from (knitsim drape|knit --continue): the integrated state (x, v) at
// time t of an earlier run.
struct RunState {
  double t = 0.0;
  std::vector<double> x, v;
};

// Builds the grid of `scene`, runs it from the flat state with run_to_equilibrium and the named
// integrator (throws std::invalid_argument for an unknown name), and measures the result.
// With model.symmetry = half | quarter | eighth the run integrates make_drape_reduced(grid) and
// unfolds its final state onto the full grid, so positions, edges and outputs always see the full
// sheet. A run that does not reach equilibrium is a status in result.stats, not an exception.
// With `from` the run starts at from->t from that state instead of the flat sheet at rest; its
// size must be the integrated dof (std::invalid_argument otherwise).
DrapeResult run_drape(const Scene& scene, const std::string& integrator,
                      RunObserver* observer = nullptr, const RunState* from = nullptr);

// The target scene (src/fit/targets.hpp) a scene's edges are compared with: the one its pins imply
// (four_corner; two_corner; two_corner_slack when pins.span < 1), whatever the scene's name.
std::string target_scene_name(const Scene& scene);

}  // namespace knitsim
