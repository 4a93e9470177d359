// knitsim tensile: a quasi-static tensile test of a stitch chart or knit scene (the driver:
// src/scene/tensile_run.hpp; the outputs: src/io/tensile_outputs.hpp; docs/knit.md, "Under
// load").
//
// Order of work, as knit's: parse the flags, read the chart and the keys, check the parameters
// and the test's options, and only then create --out, run and write. Bad input writes nothing
// and exits 2; a test whose every step reached equilibrium exits 0, one that stopped at a step
// that did not exits 3 with the curve so far written (status in summary.json and tensile.csv).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/commands.hpp"
#include "src/io/knit_outputs.hpp"
#include "src/io/tensile_outputs.hpp"
#include "src/scene/knit_run.hpp"
#include "src/scene/knit_scene.hpp"
#include "src/scene/tensile_run.hpp"

namespace knitsim {

namespace {

namespace fs = std::filesystem;

struct TensileArgs {
  std::string chart, scene, out;
  std::vector<std::string> sets;
  TensileOptions test;
  IntegratorOptions options;
  std::map<std::string, std::string> typed;
  bool quiet = false, no_pictures = false;
};

std::string human_summary(const TensileResult& r, const std::string& dir) {
  Table t;
  t.columns = {"step", "strain", "force N/m", "lateral strain", "Newton", "status"};
  for (const TensileStep& s : r.steps)
    t.rows.push_back({std::to_string(s.step), format_number(s.strain, 4),
                      format_number(s.force_per_width, 5), format_number(s.lateral_strain, 4),
                      std::to_string(s.stats.steps), s.status});
  return t.text() + "specimen " + std::to_string(r.specimen.wales) + " wales x " +
         std::to_string(r.specimen.courses) + " courses, gauge " +
         format_number(r.gauge * 1e3, 4) + " mm, width " + format_number(r.width * 1e3, 4) +
         " mm; " + format_number(r.cpu_seconds, 3) + " s CPU in the steps; outputs " + dir + "/\n";
}

void run(const TensileArgs& args) {
  if (args.chart.empty() == args.scene.empty())
    throw std::invalid_argument(args.chart.empty() ? "--chart or --scene is required"
                                                   : "--chart and --scene: give one of them");
  Scene input;
  KnitChart chart;
  if (args.scene.empty()) {
    chart = read_knit_chart(knit_scene(args.chart, {}));
    input = knit_scene(args.chart, args.sets);
  } else {
    input = load_knit_scene(args.scene, args.sets);
    chart = read_knit_chart(input);
  }
  copy_run_flags(args.options, input.options);
  input.typed.insert(args.typed.begin(), args.typed.end());
  input.validate();
  args.test.validate();
  KnitScene scene = make_knit_scene(input, std::move(chart), 1);
  // The specimen and its clamps are checked before the folder is made (nothing written).
  tensile_specimen(scene.chart, args.test, scene.params);
  if (scene.params.pins != KnitPins::None || !scene.params.clamps.empty())
    throw std::invalid_argument(
        std::string(scene.params.pins != KnitPins::None ? "knit.pins" : "knit.clamps") +
        ": tensile clamps the specimen itself (--direction); leave knit.pins and knit.clamps "
        "unset");
  if (!scene.params.point_forces.empty() || scene.params.load_steps > 0)
    throw std::invalid_argument(
        std::string(scene.params.load_steps > 0 ? "knit.load_steps" : "knit.forces") +
        ": tensile steps its own clamp (--steps) and applies no force; leave it unset");

  bool created = false;
  const fs::path dir = make_output_dir(args.out, "tensile-" + scene.name, &created);
  const nlohmann::json keys = knit_model_keys(scene.chart, input);
  auto write_step = [&](const TensileResult& r, int step, const std::vector<double>& v) {
    const TensileResult::Kept& kept = r.kept.back();
    char name[32];
    std::snprintf(name, sizeof name, "step_%03d", step);
    fs::create_directories(dir / name);
    KnitScene at = scene;
    at.chart = r.specimen;
    KnitResult kr{r.model, kept.stats, 0.0, kept.x, v, kept.positions, {}, {}, nullptr, {}};
    // The yarn measures of this state alone (a knit run's are over its whole run).
    const YarnPolylines rest_lines = yarn_polylines(r.model, r.model.rest_positions());
    const YarnPolylines lines = yarn_polylines(r.model, kept.positions);
    KnitMeasures& ms = kr.measures;
    ms.rest_clearance = yarn_clearance(r.model, rest_lines).over_r;
    ms.min_clearance = yarn_clearance(r.model, lines);
    ms.end_clearance = ms.min_clearance.over_r;
    ms.measured_states = 1;
    ms.crossings = check_crossings(designed_crossings(r.model, rest_lines), lines);
    write_knit_outputs(dir / name, at, kr, keys, !args.no_pictures);
  };
  const TensileResult result = [&]() -> TensileResult {
    try {
      return run_tensile(scene, args.test, nullptr, write_step);
    } catch (const std::invalid_argument& e) {
      refuse_at_run_start(e, dir, created);
    }
  }();
  write_tensile_outputs(dir, scene, args.test, result, !args.no_pictures);
  if (!args.quiet) std::cout << human_summary(result, dir.string()) << std::flush;
  if (!result.complete) {
    std::cerr << "knitsim tensile: step " << result.steps.back().step << " ended "
              << result.steps.back().status << "; the curve so far is in " << dir.string()
              << "/tensile.csv\n";
    std::exit(3);
  }
}

}  // namespace

void register_tensile_command(CLI::App& app) {
  auto args = std::make_shared<TensileArgs>();
  CLI::App* cmd = app.add_subcommand(
      "tensile",
      "Quasi-static tensile test of a stitch chart (docs/knit.md, \"Under load\"): a strip of "
      "the chart clamped at two opposite edges, one edge moved in equal steps, each step's "
      "equilibrium certified; writes tensile.csv, tensile.png, step_NNN/ (the knit outputs of "
      "a few steps), summary.json and manifest.json into --out");
  cmd->add_option("--chart", args->chart, "Stitch chart file (K knit, T tuck, M miss)");
  cmd->add_option("--scene", args->scene, "Knit scene file (docs/knit.md), instead of --chart");
  cmd->add_option("--set", args->sets,
                  "Override a knit or run key, e.g. knit.contact=0 (repeatable; `knitsim list "
                  "keys`); knit.pins and knit.clamps are the test's own")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--direction", args->test.direction,
                  "Pull along the wales (wale: bottom edge held, top edge moved) or the courses "
                  "(course: left edge held, right edge moved)")
      ->capture_default_str();
  cmd->add_option("--steps", args->test.steps, "Equal loading steps, 1 to 100000")
      ->capture_default_str();
  cmd->add_option("--strain", args->test.strain,
                  "Engineering strain of the clamp distance at the last step, in (0, 1]")
      ->capture_default_str();
  cmd->add_option("--gauge-ratio", args->test.gauge_ratio,
                  "Clamp distance / width of the strip, in (0, 100]: the chart's extent along "
                  "the pull is kept, its columns (rows) repeated or cut across it")
      ->capture_default_str();
  cmd->add_flag("--unload", args->test.unload, "Unload back to 0 along the same steps");
  cmd->add_option("--outputs", args->test.outputs,
                  "Steps whose knit outputs are written into step_NNN/ (spread to the last), 0 to "
                  "1000")
      ->capture_default_str();
  add_run_options(cmd, args->options, &args->typed);
  cmd->add_option("--out", args->out,
                  "Output folder (default: a fresh out/tensile-<chart>-<YYYYmmdd-HHMMSS>)");
  cmd->add_flag("--no-pictures", args->no_pictures, "Skip tensile.png and the steps' PNGs");
  cmd->add_flag("--quiet", args->quiet, "No summary on stdout");
  cmd->callback([args] { run(*args); });
}

}  // namespace knitsim
