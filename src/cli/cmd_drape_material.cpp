#include "src/cli/cmd_drape_material.hpp"

#include <CLI/CLI.hpp>
#include <iostream>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/interrupt.hpp"
#include "src/core/stop_request.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/material_outputs.hpp"
#include "src/io/progress.hpp"
#include "src/io/step_log.hpp"

namespace knitsim {

namespace {

std::string human_summary(const Scene& scene, const MaterialDrapeResult& r,
                          const std::string& dir) {
  const RunStats& s = r.stats;
  const MaterialSheet& sheet = *r.sheet;
  Table t;
  t.columns = {"drape", scene.name + " (" + scene.source + ", model.kind = material)"};
  t.rows = {{"mesh", std::to_string(sheet.nx()) + " x " + std::to_string(sheet.ny()) +
                         " cells, " + std::to_string(sheet.vertex_count()) + " vertices, " +
                         std::to_string(sheet.dof()) + " dof" +
                         (r.integrated_dof != sheet.dof()
                              ? " (" + std::to_string(r.integrated_dof) + " integrated: " +
                                    symmetry_name(r.mirrors) +
                                    (r.whole_sheet_checked ? ", certified on the whole sheet" : "") +
                                    ")"
                              : "")}};
  const auto run = run_rows(s, scene.options.position_tol);
  t.rows.insert(t.rows.end(), run.begin(), run.end());
  if (scene.material.clamps == ClampLayout::Corners) {
    t.rows.push_back({"centre sag", format_number(100 * r.centre_sag, 5) + " cm"});
  } else {
    t.rows.push_back({"tip drop", format_number(1e3 * r.tip_drop, 5) + " mm (run " +
                                      format_number(1e3 * r.tip_run, 5) + " mm)"});
    t.rows.push_back({"chord angle", format_number(r.chord_angle_deg, 5) + " deg (tip slope " +
                                         format_number(r.tip_slope_deg, 4) + " deg)"});
  }
  t.rows.insert(t.rows.end(), {{"max strain", format_number(100 * r.max_strain, 3) + " % (" +
                                                  format_number(100 * r.max_strain_away, 3) +
                                                  " % away from the clamps)"},
                               {"energy", format_number(r.energy, 6) + " J"},
                               {"wall", format_number(1e3 * s.wall_seconds, 4) + " ms"},
                               {"outputs", dir + "/"}});
  return t.text();
}

}  // namespace

void run_material_drape_command(Scene& scene, const std::string& integrator,
                                const MaterialDrapeCommand& args) {
  if (!args.continue_from.empty())
    throw std::invalid_argument(
        "--continue: not available with model.kind = material (it runs from the flat sheet)");
  if (!args.target.empty())
    throw std::invalid_argument(
        "--target: the Eq. 5 edges are paper 1's (model.kind = paper); not available with "
        "model.kind = material");
  std::unique_ptr<Integrator> integ = make_integrator(integrator);
  const InterruptScope interrupt;
  scene.options.interrupt = interrupt.flag();
  bool created = false;
  const std::filesystem::path dir = make_output_dir(args.out, "drape-" + scene.name, &created);
  warn_about_run("material.damping", scene.material.damping, integ->info(), args.flags,
                 scene.options.t_max);
  // A scene file that leaves material keys out runs them at the defaults: illustrative values,
  // not a measured fabric; say so once (as paper 1's scenes note sample 1's values).
  const std::vector<std::string> missing = keys_not_given(
      scene, {"fabric.width", "fabric.areal_density", "material.membrane_wale",
              "material.membrane_course", "material.membrane_shear", "material.poisson",
              "material.bending_wale", "material.bending_course", "clamps.layout", "clamps.size"});
  if (scene.source != "built-in" && !missing.empty()) {
    std::string list;
    for (const std::string& key : missing)
      list += (list.empty() ? "" : ", ") + key + " = " + scene_key_value(scene, key);
    note(scene.source + " leaves " + list +
         " at the defaults (illustrative, not a measured fabric; knitsim list keys)");
  }
  std::string steps_csv;
  MaterialDrapeResult result = [&] {
    ProgressLine progress(scene.name + " " + integrator, scene.options.equilibrium_tol,
                          !args.quiet);
    StepLog steps(&progress);
    RunObserver* observer = args.step_history ? static_cast<RunObserver*>(&steps) : &progress;
    try {
      MaterialDrapeResult r = run_material_drape(scene, integrator, observer);
      steps_csv = steps.csv();
      return r;
    } catch (const std::invalid_argument& e) {
      refuse_at_run_start(e, dir, created);
    } catch (const StopRequested&) {
      interrupt.end_during_setup("drape", dir, created);
    }
  }();
  if (const std::string limits = material_limit_violation(result);
      result.stats.status == RunStatus::Equilibrium && !limits.empty()) {
    result.stats.status = RunStatus::OutsideModelLimits;
    result.stats.message = limits + " (the solver's stop passed: " + result.stats.message + ")";
    warn("the equilibrium is outside the model's limits: " + limits +
         "; status outside_model_limits (docs/reliability.md)");
  }
  if (args.step_history)
    write_file_atomic(dir / "steps.csv", steps_csv);
  else
    remove_stale_output(dir / "steps.csv");
  write_material_outputs(dir, scene, result);
  if (!args.quiet) std::cout << human_summary(scene, result, dir.string()) << std::flush;
  const RunStatus status = result.stats.status;
  if (status == RunStatus::Equilibrium) return;
  // As exit_with_run_status, without its --continue hint (not available on this model).
  if (status == RunStatus::Interrupted || status == RunStatus::StepLimit ||
      status == RunStatus::WallLimit)
    std::cerr << "knitsim drape: "
              << (status == RunStatus::Interrupted
                      ? std::string("interrupted by ") + interrupt.signal_name()
                  : status == RunStatus::StepLimit ? std::string("stopped by --max-steps")
                                                   : std::string("stopped by --max-wall"))
              << " at t = " << result.stats.t_final << " s; outputs written to " << dir.string()
              << "/" << std::endl;
  throw CLI::RuntimeError(status == RunStatus::Interrupted ? interrupt.exit_code() : 3);
}

}  // namespace knitsim
