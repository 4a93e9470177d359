// knitsim knit: a stitch chart's interlacing-point network (paper 2) run to its steady state
// (src/scene/knit_run.hpp), its outputs written by src/io/knit_outputs.hpp. What the outputs,
// the frames, the networks and the velocity tolerance mean: docs/knit.md.
//
// Order of work, as drape's: parse the flags, read the chart and the keys (--chart and --set, or
// the knit scene --scene and --set), check the parameters, the run options and the integrator
// name, build the model, read --continue; only then create --out, run and write. Bad input (a bad
// chart: one line naming row and column) therefore writes nothing and exits 2; a run that ends in
// any status but equilibrium still writes everything and exits 3 -- or 128 + the signal (130, 143)
// when Ctrl-C or SIGTERM stopped it (status interrupted, src/cli/interrupt.hpp).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/cmd_knit_cell.hpp"
#include "src/cli/commands.hpp"
#include "src/core/stop_request.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/knit_load_outputs.hpp"
#include "src/io/knit_outputs.hpp"
#include "src/io/progress.hpp"
#include "src/io/run_state.hpp"
#include "src/io/step_log.hpp"
#include "src/scene/knit_run.hpp"
#include "src/scene/knit_scene.hpp"

namespace knitsim {

namespace {

namespace fs = std::filesystem;

struct KnitArgs {
  std::string chart;
  std::string scene;  // --scene FILE, a knit scene (or --chart)
  std::vector<std::string> sets;
  std::string integrator;     // empty: default_knit_integrator()
  IntegratorOptions options;  // only the fields add_run_options binds are taken from here
  std::map<std::string, std::string> typed;  // those flags' values as typed (messages)
  bool velocity_atol_given = false;          // --velocity-atol on the command line
  int frames = 4;
  std::string out;
  bool step_history = false;
  bool quiet = false;
  bool no_pictures = false;
  std::string continue_from;  // --continue DIR
};

// The warnings before a run: no damping, --dt to an adaptive method (as drape's), and the knit's
// own (knit_run_warnings).
void warn_before_run(const KnitScene& scene, const std::string& integrator,
                     const IntegratorInfo& info, const IntegratorOptions& flags) {
  warn_about_run("knit.damping", scene.params.damping, info, flags, scene.options.t_max);
  for (const std::string& w : knit_run_warnings(scene.params, integrator, info)) warn(w);
}

std::string human_summary(const KnitScene& scene, const KnitResult& r, const std::string& dir) {
  const RunStats& s = r.stats;
  const KnitMeasures& m = r.measures;
  Table t;
  t.columns = {"knit", scene.name + " (" + scene.chart_file + ")"};
  t.rows = {{"chart", std::to_string(scene.chart.wales) + " wales x " +
                          std::to_string(scene.chart.courses) + " courses, " +
                          std::to_string(r.model.points.size()) + " points, " +
                          std::to_string(r.model.network.spec().springs.size()) + " springs"}};
  const auto run =
      run_rows(s, scene.options.position_tol,
               s.t_final > r.t_start || s.steps == 0 ? "" : " (its steps do not advance t)");
  t.rows.insert(t.rows.end(), run.begin(), run.end());
  t.rows.insert(
      t.rows.end(),
      {{"max displacement", format_number(max_displacement_over_r(r.model, r.positions), 4) + " r"},
       {"clearance", "min " + format_number(m.min_clearance.over_r, 3) + " r over the run (" +
                         std::to_string(m.measured_states) + " states, to " +
                         format_number(m.min_resolution, 2) + " r), end " +
                         format_number(m.end_clearance, 3) + " r, rest " +
                         format_number(m.rest_clearance, 3) + " r"},
       {"crossings", std::to_string(m.crossings.designed) + " designed, " +
                         std::to_string(m.crossings.changed) + " changed over/under"},
       {"wall", format_number(1e3 * s.wall_seconds, 4) + " ms"}});
  if (!r.model.clamps.empty()) {  // each clamp's reaction, and their balance with the weight
    std::string text;
    Vec3 balance = knit_weight(r.model);
    for (const ClampReaction& c : knit_clamp_reactions(r.model, s.t_final, r.x)) {
      text += (text.empty() ? "" : "; ") + c.name + " (" + format_number(c.reaction.x, 4) + ", " +
              format_number(c.reaction.y, 4) + ") N";
      balance = balance + c.reaction;
    }
    t.rows.push_back({"reactions", text + "; with the weight they sum to (" +
                                       format_number(balance.x, 3) + ", " +
                                       format_number(balance.y, 3) + ") N"});
  }
  if (!r.load_steps.empty()) {  // a run under load: the balance with the applied loads
    const KnitLoadStep& last = r.load_steps.back();
    t.rows.push_back({"load steps", std::to_string(r.load_steps.size()) + " of " +
                                        std::to_string(std::max(1, scene.params.load_steps)) +
                                        " (loads.csv), load " + format_number(last.load, 4)});
    t.rows.push_back({"balance", knit_balance_text(last.balance)});
  }
  t.rows.push_back({"outputs", dir + "/"});
  return t.text();
}

void run(const KnitArgs& args) {
  if (args.chart.empty() == args.scene.empty())
    throw std::invalid_argument(args.chart.empty() ? "--chart or --scene is required"
                                                   : "--chart and --scene: give one of them");
  Scene input;  // the keys as given: the knit's, the run's
  KnitChart chart;
  if (args.scene.empty()) {  // --chart: the chart is read before the --set keys apply
    Scene bare = knit_scene(args.chart, {});
    try {
      chart = read_knit_chart(bare);
    } catch (const std::invalid_argument&) {
      // A periodic cell's repeat has no edge: read without the edge rules if the keys ask for
      // one (knit.boundary = periodic); else, or if the keys are bad, the chart's error first.
      bool periodic = false;
      try {
        periodic = knit_scene(args.chart, args.sets).yarn.periodic;
      } catch (const std::exception&) {
      }
      if (!periodic) throw;
      bare.yarn.periodic = true;
      chart = read_knit_chart(bare);
    }
    input = knit_scene(args.chart, args.sets);
  } else {
    input = load_knit_scene(args.scene, args.sets);
    chart = read_knit_chart(input);
  }
  const std::string inputs = args.scene.empty() ? "--chart and --set" : "--scene and --set";
  copy_run_flags(args.options, input.options);
  input.typed.insert(args.typed.begin(), args.typed.end());
  const std::string integrator = args.integrator.empty()
                                     ? default_knit_integrator(input.knit.yarn_contact())
                                     : args.integrator;
  std::unique_ptr<Integrator> integ;
  try {
    integ = make_integrator(integrator);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--") + e.what());  // "--integrator = X: ..."
  }
  if (!args.velocity_atol_given)
    set_default_knit_velocity_atol(input.options, input.knit, integ->info());
  input.validate();  // run.t_max, --rtol, knit.* ...
  if (args.frames < 1)
    throw std::invalid_argument("--frames = " + std::to_string(args.frames) + ": must be >= 1");
  KnitScene scene = make_knit_scene(input, std::move(chart), args.frames);
  if (scene.yarn.periodic)  // a cell of an endless fabric (src/cli/cmd_knit_cell.hpp)
    return run_knit_cell(scene, integrator, args.out, args.quiet, args.continue_from);
  KnitStart start = start_knit(scene);  // validates the parameters
  if (!args.continue_from.empty()) {
    const RunState from =
        continue_state(args.continue_from, "knit", knit_model_keys(scene.chart, input), inputs,
                       integrator, scene.options);
    try {
      continue_knit(start, from);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("--continue " + args.continue_from + ": " + e.what());
    }
  }

  // The handlers first: a signal once the folder is locked ends the run with its outputs.
  const InterruptScope interrupt;
  scene.options.interrupt = interrupt.flag();
  bool created = false;
  const fs::path dir = make_output_dir(args.out, "knit-" + scene.name, &created);
  warn_before_run(scene, integrator, integ->info(), args.options);
  std::string steps_csv;
  const KnitResult result = [&] {
    ProgressLine progress(scene.name + " " + integrator, scene.options.equilibrium_tol,
                          !args.quiet);
    StepLog steps(&progress);
    RunObserver* observer = args.step_history ? static_cast<RunObserver*>(&steps) : &progress;
    try {
      KnitResult r = run_knit(std::move(start), scene, integrator, observer);
      steps_csv = steps.csv();
      return r;
    } catch (const std::invalid_argument& e) {  // an option the model refuses at the start
      refuse_at_run_start(e, dir, created);
    } catch (const StopRequested&) {  // a signal during the integrator's set-up
      interrupt.end_during_setup("knit", dir, created);
    }
  }();
  if (args.step_history)
    write_file_atomic(dir / "steps.csv", steps_csv);
  else
    remove_stale_output(dir / "steps.csv");
  write_knit_outputs(dir, scene, result, knit_model_keys(scene.chart, input), !args.no_pictures);
  if (const std::string w = knit_overlap_warning(result.measures); !w.empty()) warn(w);
  if (!args.quiet) std::cout << human_summary(scene, result, dir.string()) << std::flush;
  exit_with_run_status("knit", result.stats, interrupt, dir.string());
}

}  // namespace

void register_knit_command(CLI::App& app) {
  auto args = std::make_shared<KnitArgs>();
  CLI::App* cmd = app.add_subcommand(
      "knit",
      "Run a stitch chart's interlacing-point network (paper 2) to its steady state; writes "
      "points.csv, typevalue.csv, centerlines.csv/.vtk, before/after.png, frames/, summary.json, "
      "state.json and manifest.json into --out");
  cmd->add_option("--chart", args->chart, "Stitch chart file (K knit, T tuck, M miss)");
  cmd->add_option("--scene", args->scene,
                  "Knit scene file (TOML: the chart by path or inline, knit and run keys; "
                  "docs/knit.md), instead of --chart");
  std::string keys;  // the knit's and the run's keys (key_table), a text key with its values
  for (const Key& k : key_table()) {
    if (k.name.empty() || k.model == KeyModel::Drape) continue;
    std::string values;
    for (const std::string& c : k.choices) values += (values.empty() ? " (" : " | ") + c;
    keys += (keys.empty() ? "" : ", ") + k.name + values + (values.empty() ? "" : ")");
  }
  cmd->add_option("--set", args->sets,
                  "Override a parameter, e.g. knit.network=paper (repeatable); keys " + keys)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--integrator", args->integrator,
                  "Integrator (knitsim list integrators); default equilibrium with yarn contact "
                  "(knit.contact > 0, the default), else cvode-bdf");
  CLI::Option* velocity_atol = add_run_options(cmd, args->options, &args->typed);
  velocity_atol->description(velocity_atol->get_description() +
                             "; not given: 0.001 (stabilised network), or 0 (paper network)");
  cmd->add_option("--frames", args->frames,
                  "Captured frames (the start to the last residual check), >= 1")
      ->capture_default_str();
  cmd->add_option("--out", args->out,
                  "Output folder (default: a fresh out/knit-<chart>-<YYYYmmdd-HHMMSS>)");
  cmd->add_flag("--no-pictures", args->no_pictures,
                "Skip before.png, after.png and the frames' PNGs (the CSV and VTK files stay)");
  add_history_and_continue_options(cmd, args->step_history, args->continue_from,
                                   "--chart and --set");
  cmd->add_flag("--quiet", args->quiet, "No progress line and no summary on stdout");
  cmd->callback([args, velocity_atol] {
    args->velocity_atol_given = velocity_atol->count() > 0;
    run(*args);
  });
}

}  // namespace knitsim
