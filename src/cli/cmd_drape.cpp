// knitsim drape (docs/commands.md): one scene run to equilibrium, with its outputs.
//
// Order of work: parse, load the scene and apply --set, check the run options and the
// integrator name, create and probe --out; only then run and write. Bad input therefore writes
// nothing (exit 2); a run that ends in any status but equilibrium still writes its outputs and
// exits 3 -- or 128 + the signal (130, 143) when Ctrl-C or SIGTERM stopped it (status
// interrupted, src/cli/interrupt.hpp). --continue DIR starts from the state.json of an earlier run
// (read and checked with the other input, before --out is made).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/cmd_drape_material.hpp"
#include "src/cli/commands.hpp"
#include "src/cli/interrupt.hpp"
#include "src/core/stop_request.hpp"
#include "src/fit/targets.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/progress.hpp"
#include "src/io/run_state.hpp"
#include "src/io/step_log.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

struct DrapeArgs {
  std::string scene = "four_corner";
  std::vector<std::string> sets;
  std::string integrator;     // empty: default_integrator()
  IntegratorOptions options;  // only the fields add_run_options binds are taken from here
  std::map<std::string, std::string> typed;  // those flags' values as typed (messages)
  std::string out;
  std::string target;
  bool step_history = false;
  bool quiet = false;
  bool no_pictures = false;
  std::string continue_from;  // --continue DIR
};

std::string human_summary(const Scene& scene, const DrapeResult& r, const std::string& dir) {
  const RunStats& s = r.stats;
  const int side = r.grid.n + 1;
  Table t;
  t.columns = {"drape", scene.name + " (" + scene.source + ")"};
  t.rows = {
      {"grid", std::to_string(side) + " x " + std::to_string(side) + " particles, " +
                   std::to_string(r.grid.network.spec().springs.size()) + " springs, " +
                   std::to_string(r.grid.network.dof()) + " dof" +
                   (r.integrated_dof != r.grid.network.dof()
                        ? " (" + std::to_string(r.integrated_dof) +
                              " integrated: " + to_string(r.symmetry) +
                              (r.whole_sheet_checked ? ", certified on the whole sheet" : "") + ")"
                        : std::string())}};
  const auto run = run_rows(s, scene.options.position_tol);
  t.rows.insert(t.rows.end(), run.begin(), run.end());
  t.rows.insert(t.rows.end(), {{"centre sag", format_number(100 * r.centre_sag, 4) + " cm"},
                               {"max strain", format_number(100 * r.max_strain, 3) + " %"},
                               {"wall", format_number(1e3 * s.wall_seconds, 4) + " ms"},
                               {"outputs", dir + "/"}});
  return t.text();
}

void run(const DrapeArgs& args) {
  Scene scene = load_scene(args.scene, args.sets);
  copy_run_flags(args.options, scene.options);
  scene.typed.insert(args.typed.begin(), args.typed.end());
  scene.validate();

  const std::string integrator = args.integrator.empty() ? default_integrator() : args.integrator;
  std::unique_ptr<Integrator> integ;
  try {
    integ = make_integrator(integrator);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--") + e.what());  // "--integrator = X: ..."
  }

  if (scene.material.kind == DrapeModelKind::Material)  // its own run and outputs
    return run_material_drape_command(
        scene, integrator,
        {args.out, args.target, args.continue_from, args.step_history, args.quiet, args.options});

  std::optional<RunState> from;
  if (!args.continue_from.empty())
    from = continue_state(args.continue_from, "drape", drape_model_keys(scene.params),
                          "--scene and --set", integrator, scene.options);

  // --target: read, checked and fitted before the output folder is made.
  std::vector<EdgeFit> target_edges;
  if (!args.target.empty()) {
    const Target target = read_target_csv(args.target);
    try {
      target_edges = fit_target_scene(target.scene(target_scene_name(scene)));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("--target " + args.target + ": " + e.what());
    }
  }

  // The handlers first: a signal once the folder is locked ends the run with its outputs.
  const InterruptScope interrupt;
  scene.options.interrupt = interrupt.flag();
  bool created = false;
  const std::filesystem::path dir = make_output_dir(args.out, "drape-" + scene.name, &created);
  warn_about_run("model.damping", scene.params.damping, integ->info(), args.options,
                 scene.options.t_max);
  note_keys_not_given(scene, physical_scene_keys());
  std::string steps_csv;
  DrapeResult result = [&] {
    ProgressLine progress(scene.name + " " + integrator, scene.options.equilibrium_tol,
                          !args.quiet);
    StepLog steps(&progress);
    RunObserver* observer = args.step_history ? static_cast<RunObserver*>(&steps) : &progress;
    try {
      DrapeResult r = run_drape(scene, integrator, observer, from ? &*from : nullptr);
      steps_csv = steps.csv();
      return r;
    } catch (const std::invalid_argument& e) {  // an option the model refuses at the start
      refuse_at_run_start(e, dir, created);
    } catch (const StopRequested&) {  // a signal while the grid was built
      interrupt.end_during_setup("drape", dir, created);
    }
  }();
  // An equilibrium that breaks the model's own limits is not reported as one (exit 3).
  const std::string limits =
      drape_limit_violation(scene.params, result.max_strain, result.centre_sag);
  if (result.stats.status == RunStatus::Equilibrium && !limits.empty()) {
    result.stats.status = RunStatus::OutsideModelLimits;
    result.stats.message = limits + " (the solver's stop passed: " + result.stats.message + ")";
    warn("the equilibrium is outside the model's limits: " + limits +
         "; status outside_model_limits (docs/reliability.md)");
  }
  if (args.step_history)  // before the outputs' manifest.json, the last file (files.hpp)
    write_file_atomic(dir / "steps.csv", steps_csv);
  else
    remove_stale_output(dir / "steps.csv");
  write_drape_outputs(dir, scene, result, args.target.empty() ? nullptr : &target_edges,
                      !args.no_pictures);
  if (!args.quiet) std::cout << human_summary(scene, result, dir.string()) << std::flush;
  exit_with_run_status("drape", result.stats, interrupt, dir.string());
}

}  // namespace

void register_drape_command(CLI::App& app) {
  auto args = std::make_shared<DrapeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "drape",
      "Hang a fabric (paper 1) and run it to equilibrium; writes summary.json, "
      "nodes.csv, edges.csv, drape.vtk, drape.png, state.json and manifest.json into "
      "--out");
  cmd->add_option("--scene", args->scene,
                  "Built-in scene (four_corner, two_corner, two_corner_slack; cantilever, "
                  "four_corner_material: model.kind = material) or a TOML file")
      ->capture_default_str();
  cmd->add_option("--set", args->sets,
                  "Override a scene key, e.g. model.stiffness=900 (repeatable: one key=value "
                  "per --set)")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--integrator", args->integrator,
                  "Integrator (knitsim list integrators); default equilibrium (the state the "
                  "damped dynamics reach, found without integrating the transient)");
  add_run_options(cmd, args->options, &args->typed);
  cmd->add_option("--out", args->out,
                  "Output folder (default: a fresh out/drape-<scene>-<YYYYmmdd-HHMMSS>)");
  cmd->add_option("--target", args->target,
                  "Target edges (CSV; format: docs/fitting.md): adds the Eq. 5 objective and both "
                  "sets of edge coefficients to summary.json and writes target_edges.csv");
  cmd->add_flag("--no-pictures", args->no_pictures,
                "Skip drape.png (its rendering costs about as much as a four_corner solve)");
  add_history_and_continue_options(cmd, args->step_history, args->continue_from, "scene and --set");
  cmd->add_flag("--quiet", args->quiet, "No progress line and no summary on stdout");
  std::string keys;
  for (const std::string& key : scene_keys()) keys += (keys.empty() ? "" : ", ") + key;
  cmd->footer(
      "Scene keys (TOML sections of a scene file, or --set section.key=value; units, defaults "
      "and accepted values: knitsim list keys; docs/scenes.md):\n  " +
      keys +
      "\nmodel.topology, the springs of each particle: a = structural + shear + bending, "
      "b = structural + shear, c = structural + bending.\nA scene file sets only the keys it "
      "names; the rest keep sample 1's values (a note on stderr lists the physical ones).");
  cmd->callback([args] { run(*args); });
}

}  // namespace knitsim
