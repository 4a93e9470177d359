#include "src/cli/cmd_knit_cell.hpp"

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/interrupt.hpp"
#include "src/io/json.hpp"
#include "src/io/progress.hpp"
#include "src/io/yarn_cell_outputs.hpp"
#include "src/scene/yarn_cell_run.hpp"

namespace knitsim {

void run_knit_cell(const KnitScene& scene, const std::string& integrator, const std::string& out,
                   bool quiet, const std::string& continue_from) {
  if (scene.yarn.model != KnitModelKind::Yarn)
    throw std::invalid_argument(
        "knit.boundary = periodic: applies to knit.model = yarn only (one of network, yarn)");
  if (scene.params.pins != KnitPins::None || !scene.params.clamps.empty() || scene.params.gravity)
    throw std::invalid_argument(
        "knit.boundary = periodic has no edge to hold: knit.pins, knit.clamps and knit.gravity "
        "apply to knit.boundary = swatch only");
  if (!continue_from.empty())
    throw std::invalid_argument(
        "--continue: not for knit.boundary = periodic (a cell run is "
        "short: run it again)");
  const double e = scene.yarn.cell_strain;
  check_cell_strain(e);
  auto start = std::make_shared<const YarnCellStart>(
      build_yarn_cell_start(scene.chart, scene.params, scene.yarn));  // validates the keys
  const InterruptScope interrupt;
  IntegratorOptions options = scene.options;
  options.interrupt = interrupt.flag();
  bool created = false;
  const std::filesystem::path dir = make_output_dir(out, "knit-" + scene.name, &created);
  const YarnCellRun run = [&] {
    ProgressLine progress(scene.name + " cell " + integrator, options.equilibrium_tol, !quiet);
    return run_yarn_cell(start, integrator, options, &progress);
  }();
  std::unique_ptr<YarnCellPull> pull;
  if (scene.yarn.cell_pull != 0 && run.stats.status == RunStatus::Equilibrium)
    pull = std::make_unique<YarnCellPull>(
        pull_yarn_cell(start, integrator, options, run.end, scene.yarn.cell_pull == 1, e));
  write_yarn_cell_outputs(dir, run, integrator,
                          {{"chart", scene.chart_file},
                           {"integrator", integrator},
                           {"boundary", "periodic"},
                           {"cell_pull", scene.yarn.cell_pull},
                           {"cell_strain", e},
                           {"options", to_json(scene.options)}},
                          pull.get());
  if (!quiet) {
    Table t;
    t.columns = {"knit cell", scene.name + " (" + scene.chart_file + ")"};
    t.rows = {
        {"repeat", std::to_string(start->repeat.wales) + " wales x " +
                       std::to_string(start->repeat.courses) + " courses, " +
                       std::to_string(run.dof) + " dof"},
        {"status", std::string(to_string(run.stats.status)) + " (" + run.stats.message + ")"},
        {"steps", std::to_string(run.stats.steps) + " in " + std::to_string(run.stages.size()) +
                      " stages, " + format_number(run.stats.cpu_seconds, 3) + " s CPU"},
        {"relaxed", format_number(run.courses_per_cm, 4) + " courses/cm, " +
                        format_number(run.wales_per_cm, 4) +
                        " wales/cm at l = " + format_number(run.stitch_length * 1e3, 4) + " mm"},
        {"constants", "K_c " + format_number(run.k_c, 3) + ", K_w " + format_number(run.k_w, 3) +
                          ", K_s " + format_number(run.k_s, 3) + ", R " + format_number(run.r, 3)},
        {"clearance", "min " + format_number(run.clearance_min_over_d, 3) + " d over " +
                          std::to_string(run.clearance_checks) + " checks, end " +
                          format_number(run.clearance_end_over_d, 3) + " d"},
        {"outputs", dir.string() + "/"}};
    if (pull && !pull->strain.empty())
      t.rows.insert(
          t.rows.end() - 1,
          {"pull", std::string(pull->along_courses ? "along the courses" : "along the wales") +
                       " to " + format_number(pull->strain.back(), 3) + ": " +
                       format_number(pull->force_per_width.back(), 4) + " N/m, lateral strain " +
                       format_number(pull->lateral_strain.back(), 3) + ", " +
                       to_string(pull->status.back())});
    std::cout << t.text() << std::flush;
  }
  RunStats stats = run.stats;  // a pull step that did not settle ends the run with its status
  if (pull && !pull->status.empty() && pull->status.back() != RunStatus::Equilibrium)
    stats.status = pull->status.back();
  exit_with_run_status("knit", stats, interrupt, dir.string());
}

}  // namespace knitsim
