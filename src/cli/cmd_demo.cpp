// knitsim demo: what ./run.sh runs until the paper reproduction exists.
//
// 1. The built-in scenes four_corner and two_corner with the default integrator, each into its
//    own subfolder with the drape outputs (summary.json, nodes.csv, drape.vtk, drape.png,
//    manifest.json).
// 2. Every registered integrator on four_corner, each capped at kComparisonWallCap seconds of
//    wall time (the explicit and non-stiff methods need minutes to hours here and end with
//    status wall_limit: that is the measurement), compared by cost and by the largest
//    particle distance from the reference run (cvode-bdf, or the first integrator registered).
// 3. report.md (tables and picture links), comparison.csv (full precision), manifest.json.
// Exit status 3 if a scene run of step 1 did not reach equilibrium (everything is still written).
// Ctrl-C or SIGTERM (src/cli/interrupt.hpp) ends the current run within about a second, skips
// the rest, writes the report of the runs so far and exits 128 + the signal.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/commands.hpp"
#include "src/cli/interrupt.hpp"
#include "src/core/stop_request.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/io/progress.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

namespace fs = std::filesystem;

constexpr double kComparisonWallCap = 15.0;  // s of wall time per integrator in step 2

const std::vector<std::string> kScenes = {"four_corner", "two_corner"};
const std::string kComparisonScene = "four_corner";

// Empty if a signal arrived during the run's set-up (StopRequested): no state, no row.
std::optional<DrapeResult> run_with_progress(const Scene& scene, const std::string& integrator) {
  ProgressLine progress(scene.name + " " + integrator, scene.options.equilibrium_tol);
  try {
    return run_drape(scene, integrator, &progress);
  } catch (const StopRequested&) {
    return std::nullopt;
  }
}

std::string one_line(const std::string& scene, const RunStats& s) {
  return scene + "  " + s.integrator + "  " + to_string(s.status) +
         "  t = " + format_number(s.t_final, 4) + " s  steps " + std::to_string(s.steps) +
         "  wall " + format_number(1e3 * s.wall_seconds, 4) + " ms";
}

double max_distance(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double d = 0.0;
  for (size_t k = 0; k < a.size(); ++k) d = std::max(d, norm(a[k] - b[k]));
  return d;
}

struct DemoArgs {
  std::string out;
  double wall_cap = kComparisonWallCap;  // s, --max-wall
};

void run(const DemoArgs& args) {
  const std::string& out = args.out;
  const double wall_cap = args.wall_cap;
  const InterruptScope interrupt;  // first: a signal once the folder is locked keeps the rows
  const fs::path dir = make_output_dir(out, "demo");
  const std::string integrator = default_integrator();
  bool all_settled = true;
  const auto stopped = [&] { return interrupt.signal() != 0; };

  Table scenes;
  scenes.columns = {"scene",    "integrator", "status",         "t_final (s)", "steps",
                    "residual", "sag (cm)",   "max strain (%)", "wall (ms)",   "picture"};
  std::string pictures;
  for (const std::string& name : kScenes) {
    if (stopped()) break;
    Scene scene = load_scene(name);
    scene.options.interrupt = interrupt.flag();
    const std::optional<DrapeResult> run = run_with_progress(scene, integrator);
    if (!run) break;
    const DrapeResult& r = *run;
    fs::create_directories(dir / name);
    write_drape_outputs(dir / name, scene, r);
    const RunStats& s = r.stats;
    all_settled = all_settled && s.status == RunStatus::Equilibrium;
    scenes.rows.push_back({name, s.integrator, to_string(s.status), format_number(s.t_final),
                           std::to_string(s.steps), format_number(s.residual, 2),
                           format_number(100 * r.centre_sag), format_number(100 * r.max_strain, 3),
                           format_number(1e3 * s.wall_seconds),
                           "[drape.png](" + name + "/drape.png)"});
    pictures += "### " + name + "\n\n![" + name + "](" + name + "/drape.png)\n\n";
    std::cout << one_line(name, s) << std::endl;
  }

  Scene scene = load_scene(kComparisonScene);
  scene.options.max_wall_seconds = wall_cap;
  scene.options.interrupt = interrupt.flag();
  std::vector<RunStats> stats;
  std::vector<std::vector<Vec3>> positions;
  for (const IntegratorInfo& info : integrator_catalog()) {
    if (stopped()) break;
    std::optional<DrapeResult> run = run_with_progress(scene, info.name);
    if (!run) break;
    DrapeResult& r = *run;
    std::cout << one_line(scene.name, r.stats) << std::endl;
    stats.push_back(r.stats);
    positions.push_back(std::move(r.positions));
  }
  size_t ref = 0;
  for (size_t k = 0; k < stats.size(); ++k)
    if (stats[k].integrator == "cvode-bdf") ref = k;
  const std::string ref_name = stats.empty() ? "" : stats[ref].integrator;

  Table csv, md;
  csv.columns = {"integrator", "status",     "t_final",  "steps",   "rhs_evals",
                 "jac_evals",  "lin_setups", "residual", "wall_ms", "max_dx_m"};
  md.columns = {
      "integrator", "status",    "t_final (s)", "steps",     "RHS evals",
      "Jac evals",  "LS setups", "residual",    "wall (ms)", "max abs dx vs " + ref_name + " (m)"};
  for (size_t k = 0; k < stats.size(); ++k) {
    const RunStats& s = stats[k];
    const double dx = max_distance(positions[k], positions[ref]);
    csv.rows.push_back({s.integrator, to_string(s.status), format_number(s.t_final, 17),
                        std::to_string(s.steps), std::to_string(s.rhs_evals),
                        std::to_string(s.jac_evals), std::to_string(s.lin_setups),
                        format_number(s.residual, 17), format_number(1e3 * s.wall_seconds, 17),
                        format_number(dx, 17)});
    md.rows.push_back(
        {s.integrator, to_string(s.status), format_number(s.t_final), std::to_string(s.steps),
         std::to_string(s.rhs_evals), std::to_string(s.jac_evals), std::to_string(s.lin_setups),
         format_number(s.residual, 2), format_number(1e3 * s.wall_seconds), format_number(dx, 2)});
  }
  write_file_atomic(dir / "comparison.csv", csv.csv());

  std::ostringstream report;
  report << "# knitsim demo\n\n"
         << "Built-in scenes (sample 1 of paper 1, Tables 2 and 4: k = 852 N/m, c = 12 N s/m, "
            "L0 = 4.9 cm, topology a, 41.65 g/m^2) run from the flat state to equilibrium "
            "(the stop of docs/equilibrium.md) with "
         << integrator << ". Each folder holds summary.json, nodes.csv, drape.vtk, drape.png "
         << "and manifest.json.\n\n"
         << scenes.markdown() << "\n"
         << pictures << "## Integrator comparison on " << kComparisonScene << "\n\n"
         << "Every registered integrator on the same scene and the same equilibrium criterion, "
         << "each capped at " << format_number(wall_cap) << " s of wall time "
         << "(status wall_limit: it had not settled by then). max abs dx: the largest distance "
         << "of any particle from its position in the " << ref_name << " run. Raw numbers: "
         << "comparison.csv.\n\n"
         << md.markdown();
  if (stopped())
    report << "\n**Interrupted** by " << interrupt.signal_name()
           << ": the runs after the one marked `interrupted` were skipped.\n";
  write_file_atomic(dir / "report.md", report.str());

  nlohmann::json integrators = nlohmann::json::array();
  for (const RunStats& s : stats) integrators.push_back(s.integrator);
  finish_output_folder(dir, manifest({{"command", "demo"},
                                      {"scenes", kScenes},
                                      {"scene_integrator", integrator},
                                      {"comparison_scene", kComparisonScene},
                                      {"comparison_integrators", integrators},
                                      {"comparison_wall_cap_s", wall_cap},
                                      {"options", to_json(scene.options)}}));

  std::cout << "\n" << md.text() << "\nreport: " << (dir / "report.md").string() << std::endl;
  if (stopped()) {
    std::cerr << "knitsim demo: interrupted by " << interrupt.signal_name()
              << "; the report of the runs so far is in " << (dir / "report.md").string()
              << std::endl;
    throw CLI::RuntimeError(interrupt.exit_code());
  }
  if (!all_settled) throw CLI::RuntimeError(3);
}

}  // namespace

void register_demo_command(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "demo", "Built-in scenes and an integrator comparison, with a Markdown report");
  cmd->add_option("--out", args->out,
                  "Output folder (default: a fresh out/demo-<YYYYmmdd-HHMMSS>)");
  cmd->add_option("--max-wall", args->wall_cap,
                  "Wall-clock cap per integrator of the comparison, s (the explicit and non-stiff "
                  "methods take most of a full run's minute)")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e6));
  cmd->callback([args] { run(*args); });
}

}  // namespace knitsim
