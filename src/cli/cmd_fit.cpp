// knitsim fit (docs/fitting.md): the drape model's parameters fitted to a target with the ICA
// (src/fit/drape_fit.hpp), or with `--optimizer lm` by multi-start Levenberg-Marquardt on analytic
// equilibrium sensitivities (src/fit/lm_fit.hpp; outputs: see run_lm_fit), and the fitted drape.
//
// Order of work: parse; load the scene (--set applied), read and check the target (its matching
// scene must be present and valid), check the ICA options and the integrator; create and probe
// --out; only then fit. Bad input therefore writes nothing (exit 2).
// Outputs in --out:
//   summary.json   params {stiffness, damping, elongation_limit, natural_length, topology},
//                  objective (Eq. 5, percent), evaluations, failed_evaluations, status,
//                  message, wall_seconds, best_country, history [{decade, best, mean,
//                  empires, evaluations}], scene, target, integrator, ica options, bounds,
//                  units (every field: docs/summary_json.md)
//   history.csv    decade,best,mean,empires,evaluations (imperialist costs, paper 1 Fig. 13)
//   drape/         the fitted drape re-run (write_drape_outputs: summary.json, nodes.csv,
//                  drape.vtk, drape.png unless --no-pictures, manifest.json) plus edges.csv
//                  (its measured edges) and target_edges.csv (the target's, as fitted)
//   manifest.json
//   ica_checkpoint.json  {config, state}: the ICA's whole state (IcaState) after the latest
//                  decade, rewritten atomically after every decade; `--resume` continues from
//                  it (kept after the fit: resuming a finished fit only rewrites the outputs)
// Resume: `knitsim fit ... --out DIR --resume` continues the fit whose checkpoint is in DIR,
// bit-identical to an uninterrupted run (best country, objective, history, counts). The
// checkpoint's config (base scene parameters and run options, the target file's content,
// optimizer, --integrator as given, bounds, ICA options except --jobs) must equal this run's,
// else exit 2 naming the first difference; without a checkpoint in DIR the fit starts afresh
// (so a job script may always pass --resume).
// Ctrl-C or SIGTERM during an ICA fit ends it at the end of the current decade (the drapes in
// flight finish, so the checkpoint stays whole): summary.json (status "interrupted", the best
// country so far, fitted_drape_status "not_run"), history.csv and manifest.json are written, no
// drape/, and the exit code is 128 + signal; `--resume` then finishes the fit, bit-identical to
// an uninterrupted one. A second signal kills at once (src/cli/interrupt.hpp).
// Exit 3 (after writing) when every evaluation failed or the fitted drape's re-run does not
// reach equilibrium.
// model.kind = material: the material parameters in material units, the box from the fit.* keys
// and their flags (--membrane-wale-min ...), outputs as src/cli/cmd_fit_material.hpp says; no
// checkpoint (--resume is refused).
#include <CLI/CLI.hpp>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/cmd_fit_material.hpp"
#include "src/cli/commands.hpp"
#include "src/fit/drape_fit.hpp"
#include "src/fit/lm_fit.hpp"
#include "src/fit/material_fit.hpp"
#include "src/fit/targets.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/fit_outputs.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/measure/measurement.hpp"
#include "src/parallel/work_units.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

struct FitArgs {
  std::string scene;
  std::vector<std::string> sets;
  std::string target;
  std::string optimizer = "ica";  // ica | lm (src/fit/lm_fit.hpp)
  DrapeLmOptions lm;
  std::string integrator;  // empty: default_integrator()
  // Tighter than the drape default: at 1e-6 some countries stall at residual ~4e-8 and would
  // be scored as failures (src/fit/drape_fit.hpp).
  double rtol = 1e-8;
  double atol = IntegratorOptions{}.atol;
  double velocity_atol = IntegratorOptions{}.velocity_atol;
  IcaOptions ica;
  std::string out;
  bool resume = false;
  bool quiet = false;
  bool no_pictures = false;  // the fitted drape without drape.png
  std::vector<std::string> ignored;  // flags given that the chosen optimizer does not read
  // The material fit's box and fitted parameters given as flags (--membrane-wale-min ...,
  // --fit-parameters; rows fit.* of the key table): flag -> text, applied as --set of the row's
  // key after the scene's own, so the command line wins.
  std::map<std::string, std::string> box_flags;
};

// The fit.* rows of the key table that have a flag (the material fit's box).
std::vector<const Key*> box_rows() {
  std::vector<const Key*> rows;
  for (const Key& k : key_table())
    if (k.name.rfind("fit.", 0) == 0 && !k.flag.empty()) rows.push_back(&k);
  return rows;
}

// The scene with the box flags applied: a bad value is refused under its flag.
Scene load_fit_scene(const FitArgs& args) {
  std::vector<std::string> sets = args.sets;
  std::vector<std::pair<std::string, std::string>> names;
  for (const Key* k : box_rows()) {
    const auto given = args.box_flags.find(k->flag);
    if (given == args.box_flags.end()) continue;
    sets.push_back(k->name + "=" + given->second);
    names.emplace_back(k->name, k->flag);
  }
  try {
    return load_scene(args.scene, sets);
  } catch (const std::invalid_argument& e) {
    rethrow_with_flag_names(e, names);
  }
}

constexpr const char* kLmOptionGroup = "LM options (--optimizer lm)";

// The flags of --help group `group` given on the command line, in their help order.
std::vector<std::string> given_flags(CLI::App* cmd, const std::string& group) {
  std::vector<std::string> given;
  for (const CLI::Option* opt :
       cmd->get_options([&](CLI::Option* o) { return o->get_group() == group && o->count() > 0; }))
    given.push_back(opt->get_name());
  return given;
}

// One warning for flags the run will not read, and for a stability-limited integrator, whose
// every drape of the fit takes minutes (warned, not refused: the paper's own method).
void warn_about_fit(const FitArgs& args, const std::string& integrator) {
  if (!args.ignored.empty()) {
    std::string list;
    for (const std::string& flag : args.ignored) list += (list.empty() ? "" : ", ") + flag;
    warn(list + (args.ignored.size() == 1 ? " is" : " are") + " not read by --optimizer " +
         args.optimizer);
  }
  if (make_integrator(integrator)->info().explicit_method)
    warn("--integrator " + integrator +
         ": stability-limited, so each drape of the fit takes minutes (four_corner with euler: "
         "~10 min), against milliseconds with cvode-bdf or static");
}

// One warning when every edge of the target that can tell hangs above its pins (sags_upward):
// lab data with z growing downward (image rows), which the fit would chase to a box corner.
// Called before the fit and again after its result table, where a reader of the result looks.
void warn_if_upside_down(const DrapeFitProblem& problem, const std::string& target) {
  int upward = 0, counted = 0;
  for (const EdgeFit& edge : problem.measured())
    if (const std::optional<bool> up = sags_upward(edge, problem.target_scene()))
      ++counted, upward += *up ? 1 : 0;
  if (counted > 0 && upward == counted)
    warn("--target " + target + ": every edge of " + problem.target_scene() +
         " hangs above its pins; lab z must grow upward (negate image rows; docs/fitting.md)");
}

// One line on stdout: the fitted natural length also sets the mesh (n = round(W / L0) cells per
// side) and the model sheet's side n L0, so a fitted L0 is a fitted mesh (docs/fitting.md).
std::string mesh_note(const Scene& base, const DrapeParams& fitted) {
  const int n = fitted.cells(), n0 = base.params.cells();
  return "note: the fitted natural_length " + format_number(fitted.natural_length, 6) +
         " m also sets the mesh: n = round(fabric.width / L0) = " + std::to_string(n) +
         " cells per side, a model sheet of n L0 = " +
         format_number(n * fitted.natural_length, 4) + " m (the base scene: " +
         std::to_string(n0) + " cells, " + format_number(n0 * base.params.natural_length, 4) +
         " m)\n";
}

// Scene keys of a fit's base scene that matter and are not fitted: a scene file that leaves
// them out runs sample 1's values, said in one note.
const std::vector<std::string> kFitBaseKeys = {"fabric.width", "fabric.areal_density",
                                               "pins.layout"};

constexpr const char* kCheckpointFile = "ica_checkpoint.json";

// What a checkpoint must have been made with to be resumed by this run (see the header).
nlohmann::json checkpoint_config(const FitArgs& args, const Scene& base,
                                 const DrapeFitOptions& options) {
  nlohmann::json ica = ica_json(args.ica);
  ica.erase("jobs");  // the result does not depend on it
  std::ifstream in(args.target, std::ios::binary);
  std::ostringstream target;
  target << in.rdbuf();
  return {{"scene", base.name},
          {"base_params", to_json(base.params)},
          {"run_options", to_json(base.options)},
          {"target_file_content", target.str()},
          {"optimizer", args.optimizer},
          {"integrator", args.integrator},
          {"bounds", bounds_json(options.bounds)},
          {"ica", ica}};
}

// The state saved in `path` by a fit with `config`; null when there is no such file.
std::shared_ptr<const IcaState> read_checkpoint(const std::filesystem::path& path,
                                                const nlohmann::json& config) {
  std::ifstream in(path);
  if (!in) return nullptr;
  const std::string where = "--resume: " + path.string();
  const nlohmann::json saved = nlohmann::json::parse(in, nullptr, false);
  if (saved.is_discarded() || !saved.contains("config") || !saved.contains("state"))
    throw std::invalid_argument(where + ": not a knitsim fit checkpoint");
  // Compared as written and read back, as the saved one was.
  const nlohmann::json now = nlohmann::json::parse(config.dump());
  if (saved.at("config") != now)
    throw std::invalid_argument(where + " is of a fit with other settings (first difference: " +
                                first_config_difference(saved.at("config"), now) +
                                "); give the same options, or drop --resume to start afresh");
  try {
    return std::make_shared<const IcaState>(ica_state_from_json(saved.at("state")));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + ": " + e.what());
  }
}

// The one line under the LM fit's table saying why the parameters with no standard error are
// not determined: k and L0 enter the edges only as k / L0 at a fixed mesh; a parameter whose
// column of sensitivities is zero does not move the equilibrium at all (the damping never; the
// elongation limit while no spring reaches it).
std::string not_determined_line(const DrapeIdentifiability& id, double max_strain,
                                const DrapeParams& p) {
  std::vector<std::string> why;
  const auto& par = id.parameters;
  if (!std::isfinite(par[0].standard_error) && !std::isfinite(par[3].standard_error) &&
      std::isfinite(par[0].conditional_standard_error))
    why.push_back("stiffness and natural_length enter the edges only as k / L0 at a fixed mesh");
  if (!std::isfinite(par[1].conditional_standard_error))
    why.push_back("damping does not enter the equilibrium");
  if (!std::isfinite(par[2].conditional_standard_error))
    why.push_back("the elongation limit " + format_number(p.elongation_limit, 4) +
                  " % is not reached (max strain " + format_number(100.0 * max_strain, 3) +
                  " %), so it does not act");
  if (why.empty()) return "";
  std::string line = "not determined by the edges: ";
  for (size_t i = 0; i < why.size(); ++i) line += (i ? "; " : "") + why[i];
  return line + " (docs/fitting.md)\n";
}

// The fitted drape, re-run (deterministic: the same run the fit scored) and measured against
// the target, as drape/ holds it.
struct FittedDrape {
  Scene scene;
  DrapeResult result;
  DrapeReport report;
};

FittedDrape rerun_fitted_drape(const DrapeFitProblem& problem, const std::vector<double>& best_x) {
  Scene scene = problem.scene_of(best_x);
  DrapeResult result = run_drape(scene, problem.integrator());
  DrapeReport report = drape_report(scene, result, &problem.measured());
  return {std::move(scene), std::move(result), std::move(report)};
}

// The fit's files in dir (write_fit_outputs), drape/ where the fitted drape was re-run.
void write_fit(const std::filesystem::path& dir, const FitReport& report,
               const DrapeFitProblem& problem, const std::optional<FittedDrape>& drape,
               bool picture) {
  if (!drape) return write_fit_outputs(dir, report, nullptr, picture);
  const FittedDrapeOutputs outputs{drape->scene, drape->result, drape->report, problem.measured()};
  write_fit_outputs(dir, report, &outputs, picture);
}

// --optimizer lm: the multi-start Levenberg-Marquardt fit and its outputs in dir: summary.json
// (the ICA's fields params, objective, evaluations, failed_evaluations, status, message,
// wall_seconds, best_country, plus cpu_seconds, standard_errors, identifiability and starts),
// starts.csv (one row per start), drape/ and manifest.json. Exit 3 as for the ICA.
void run_lm_fit(const FitArgs& args, const Scene& base, const DrapeFitProblem& problem,
                const std::filesystem::path& dir) {
  if (!args.quiet)
    std::cout << "fitting " << base.name << " to " << args.target << " (scene "
              << problem.target_scene()
              << ") with Levenberg-Marquardt: " << args.lm.starts_per_bracket
              << " start(s) per topology and n bracket, " << args.lm.refine
              << " refined with <= " << args.lm.lm.max_evaluations << " evaluations each, "
              << problem.integrator() << "\n"
              << std::flush;
  DrapeLmOptions lm = args.lm;
  lm.seed = args.ica.seed;  // --seed draws the random starts too
  const DrapeLmResult fit = fit_drape_lm(problem, lm);
  std::optional<FittedDrape> drape;
  if (fit.ok) drape.emplace(rerun_fitted_drape(problem, fit.best_x));
  const FitReport report = lm_fit_report(base, args.sets, args.target, problem, lm, fit,
                                         drape ? &drape->result : nullptr);
  write_fit(dir, report, problem, drape, !args.no_pictures);
  const bool drape_ok = drape && drape->result.stats.status == RunStatus::Equilibrium;
  const double max_strain = drape ? drape->result.max_strain : 0.0;
  const DrapeIdentifiability& id = fit.identifiability;
  if (!args.quiet) {
    std::cout << report.table.text() << "\nstatus: " << fit.message << "\n";
    // What the edges determine first: k / L0 (with the topology and n, chosen by the
    // screening); then the parameters one by one, whose standard errors are infinite where the
    // data cannot separate them, and one line saying why.
    Table t;
    t.columns = {"parameter", "fitted", "standard error", "if the others were known"};
    const char* units[kDrapeContinuous] = {" N/m", " N s/m", " %", " m"};
    auto error = [](double v, const char* unit) {
      return std::isfinite(v) ? format_number(v, 3) + unit : "none";
    };
    if (fit.ok)
      t.rows.push_back({"k / L0 (determined)",
                        format_number(fit.params.stiffness / fit.params.natural_length, 6) +
                            " N/m^2",
                        format_number(100.0 * id.ratio_relative_error, 3) + " %", ""});
    t.rows.push_back({"topology", fit.ok ? std::string(1, fit.params.topology) : "-", "", ""});
    if (fit.ok) t.rows.push_back({"cells per side n", std::to_string(fit.params.cells()), "", ""});
    for (int g = 0; g < kDrapeContinuous && fit.ok; ++g)
      t.rows.push_back({drape_gene_names()[g], format_number(fit.best_x[g], 6) + units[g],
                        error(id.parameters[g].standard_error, units[g]),
                        error(id.parameters[g].conditional_standard_error, units[g])});
    t.rows.push_back({"objective", format_number(fit.objective, 6) + " %", "", ""});
    t.rows.push_back({"evaluations", std::to_string(fit.evaluations), "", ""});
    t.rows.push_back({"cpu", format_number(fit.cpu_seconds, 4) + " s", "", ""});
    t.rows.push_back({"outputs", dir.string() + "/", "", ""});
    std::cout << t.text();
    if (fit.ok) std::cout << not_determined_line(id, max_strain, fit.params) << mesh_note(base, fit.params);
    std::cout << std::flush;
    warn_if_upside_down(problem, args.target);
  }
  if (!fit.ok || !drape_ok) throw CLI::RuntimeError(3);
}

// The ICA fit's first lines: what is fitted to what, with which budget, and where a resumed fit
// goes on from.
void print_ica_start(const FitArgs& args, const Scene& base, const DrapeFitProblem& problem,
                     const std::shared_ptr<const IcaState>& resumed_from,
                     const std::filesystem::path& dir) {
  std::cout << "fitting " << base.name << " to " << args.target << " (scene "
            << problem.target_scene() << ", " << problem.measured().size()
            << " edges) with the ICA: " << args.ica.countries << " countries, "
            << args.ica.imperialists << " imperialists, " << args.ica.decades << " decades, seed "
            << args.ica.seed << ", jobs " << args.ica.jobs << ", " << problem.integrator() << "\n";
  if (args.resume)
    std::cout << (resumed_from ? "resuming from decade " + std::to_string(resumed_from->decade) +
                                     " of " + std::to_string(args.ica.decades)
                               : std::string("no checkpoint: starting afresh"))
              << " (" << (dir / kCheckpointFile).string() << ")\n";
  std::cout << std::flush;
}

// The ICA fit's console report: the history, the status and the fitted parameters.
// With the fitted drape (a finished fit), also LM's line on what the edges do not determine,
// from the sensitivities at the best country (one more drape, not counted in the fit's).
void print_ica_result(const FitArgs& args, const Scene& base, const DrapeFitProblem& problem,
                      const DrapeFitResult& fit, const Table& history,
                      const std::filesystem::path& dir, const DrapeResult* drape) {
  std::cout << history.text() << "\nstatus: " << fit.message << "\n";
  Table t;
  t.columns = {"parameter", "fitted"};
  t.rows = {{"stiffness", format_number(fit.params.stiffness, 6) + " N/m"},
            {"damping", format_number(fit.params.damping, 6) + " N s/m"},
            {"elongation_limit", format_number(fit.params.elongation_limit, 6) + " %"},
            {"natural_length", format_number(fit.params.natural_length, 6) + " m"},
            {"topology", std::string(1, fit.params.topology)},
            {"objective", format_number(fit.objective, 6) + " %"},
            {"evaluations", std::to_string(fit.evaluations) + " (" +
                                std::to_string(fit.failed_evaluations) + " failed)"},
            {"wall", format_number(fit.wall_seconds, 4) + " s"},
            {"outputs", dir.string() + "/"}};
  std::cout << t.text() << mesh_note(base, fit.params);
  if (drape && drape->stats.status == RunStatus::Equilibrium) {
    const DrapeResiduals at = drape_residuals(problem, fit.best_x, args.lm.polish);
    if (!at.failed)
      std::cout << not_determined_line(identifiability(at, fit.best_x), drape->max_strain,
                                       fit.params);
  }
  std::cout << std::flush;
  warn_if_upside_down(problem, args.target);
}

// The ICA fit, its outputs in dir and its exit: 128 + signal when interrupted (the handlers,
// installed here, are `interrupt`, which the problem's stop_requested reads), 3 when every
// evaluation failed or the fitted drape does not settle.
void run_ica_fit(const FitArgs& args, const Scene& base, const DrapeFitProblem& problem,
                 const std::shared_ptr<const IcaState>& resumed_from,
                 const std::filesystem::path& dir, std::unique_ptr<InterruptScope>& interrupt) {
  if (!args.quiet) print_ica_start(args, base, problem, resumed_from, dir);
  interrupt = std::make_unique<InterruptScope>(InterruptScope::Reach::BetweenUnits);
  const DrapeFitResult fit = fit_drape(problem);
  // Not for a fit cut short, whose best country is provisional.
  std::optional<FittedDrape> drape;
  if (fit.status != IcaStatus::Interrupted) drape.emplace(rerun_fitted_drape(problem, fit.best_x));
  const FitReport report =
      ica_fit_report(base, args.sets, args.target, problem, fit, drape ? &drape->result : nullptr,
                     resumed_from ? resumed_from->decade : -1);
  write_fit(dir, report, problem, drape, !args.no_pictures);
  if (!args.quiet)
    print_ica_result(args, base, problem, fit, report.table, dir, drape ? &drape->result : nullptr);
  if (fit.status == IcaStatus::Interrupted) {
    std::cerr << "knitsim fit: interrupted by " << interrupt->signal_name() << " after decade "
              << fit.history.back().decade << " of " << args.ica.decades
              << "; the best so far is written to " << dir.string()
              << "/; the same command with --resume goes on from there" << std::endl;
    throw CLI::RuntimeError(interrupt->exit_code());
  }
  if (fit.status == IcaStatus::AllFailed || !drape ||
      drape->result.stats.status != RunStatus::Equilibrium)
    throw CLI::RuntimeError(3);
}

// model.kind = material: the material fit (src/cli/cmd_fit_material.hpp); no checkpoint.
void run_material(const FitArgs& args, const Scene& base, const Target& target) {
  if (args.resume) throw std::invalid_argument("--resume: only with model.kind = paper");
  MaterialFitCommand m;
  m.optimizer = args.optimizer;
  m.target = args.target;
  m.sets = args.sets;
  m.integrator = args.integrator;
  m.starts = args.lm;
  m.lm = args.lm.lm;
  m.ica = args.ica;
  m.quiet = args.quiet;
  std::unique_ptr<MaterialFitProblem> check;  // set-up errors before the folder is made
  try {
    check = std::make_unique<MaterialFitProblem>(base, target, args.integrator);
  } catch (const std::invalid_argument& e) {
    rethrow_with_flag_names(e, {{"integrator", "--integrator"}});
  }
  const std::filesystem::path dir = make_output_dir(args.out, "fit-" + base.name);
  if (!args.ignored.empty()) {
    std::string list;
    for (const std::string& flag : args.ignored) list += (list.empty() ? "" : ", ") + flag;
    warn(list + (args.ignored.size() == 1 ? " is" : " are") + " not read by --optimizer " +
         args.optimizer);
  }
  run_material_fit_command(base, target, m, dir);
}

void run(const FitArgs& args) {
  if (args.optimizer != "ica" && args.optimizer != "lm")
    throw std::invalid_argument("--optimizer = " + args.optimizer + ": accepted: ica, lm");
  try {
    args.lm.validate();
  } catch (const std::invalid_argument& e) {
    rethrow_as_typed(e);  // under the flags of the LM rows of key_table()
  }
  Scene base = load_fit_scene(args);
  base.options.rtol = args.rtol;
  base.options.atol = args.atol;
  base.options.velocity_atol = args.velocity_atol;
  base.validate();
  const Target target = read_target_csv(args.target);
  if (base.material.kind == DrapeModelKind::Material) return run_material(args, base, target);
  if (!args.box_flags.empty())
    warn(args.box_flags.begin()->first +
         " is not read with model.kind = paper (paper 1's box is Table 3's; docs/fitting.md)");
  DrapeFitOptions options;
  options.ica = args.ica;
  options.integrator = args.integrator;
  if (args.resume && args.out.empty())
    throw std::invalid_argument("--resume: needs --out, the folder of the fit to continue");
  if (args.resume && args.optimizer != "ica")
    throw std::invalid_argument("--resume: only with --optimizer ica");
  refuse_fresh_start_over_checkpoint(args.out, {kCheckpointFile}, args.resume);
  const nlohmann::json config = checkpoint_config(args, base, options);
  if (args.resume)
    options.ica.resume_from = read_checkpoint(args.out + "/" + kCheckpointFile, config);
  std::filesystem::path dir;  // the output folder, made below once all input is checked
  options.ica.on_decade = [&dir, &config](const IcaState& state) {
    write_file_atomic(dir / kCheckpointFile,
                      nlohmann::json{{"config", config}, {"state", to_json(state)}}.dump() + "\n");
  };
  // Ctrl-C or SIGTERM ends the ICA at the end of its current decade, whose checkpoint is then
  // written; the handlers are installed once the fit starts (the LM fit has none).
  std::unique_ptr<InterruptScope> interrupt;
  options.ica.stop_requested = [&interrupt] { return interrupt && interrupt->signal() != 0; };
  std::unique_ptr<DrapeFitProblem> problem;
  try {
    problem = std::make_unique<DrapeFitProblem>(base, target, options);
  } catch (const std::invalid_argument& e) {
    rethrow_with_flag_names(e, {{"integrator", "--integrator"}});
  }
  dir = make_output_dir(args.out, "fit-" + base.name);
  warn_about_fit(args, problem->integrator());
  note_keys_not_given(base, kFitBaseKeys);
  warn_if_upside_down(*problem, args.target);
  if (args.optimizer == "lm") return run_lm_fit(args, base, *problem, dir);

  run_ica_fit(args, base, *problem, options.ica.resume_from, dir, interrupt);
}

}  // namespace

void register_fit_command(CLI::App& app) {
  auto args = std::make_shared<FitArgs>();
  IcaOptions& o = args->ica;
  CLI::App* cmd = app.add_subcommand(
      "fit",
      "Fit the drape model's parameters (paper 1: Table 3 box; model.kind = material: material "
      "units, the fit.* box) to a target with the ICA or LM; writes summary.json, the fitted "
      "drape and manifest.json into --out");
  cmd->add_option("--scene", args->scene,
                  "Base scene (four_corner, two_corner, two_corner_slack or a TOML file): "
                  "fabric, pins and run options")
      ->required();
  cmd->add_option("--set", args->sets, "Override a scene key of the base scene (repeatable)")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--target", args->target,
                  "Target edges CSV: normalised points, coefficients or lab points in mm with "
                  "the pins (format and a worked lab example: docs/fitting.md)")
      ->required();
  cmd->add_option("--optimizer", args->optimizer,
                  "Optimiser: ica, or lm (multi-start Levenberg-Marquardt with analytic "
                  "equilibrium sensitivities; src/fit/lm_fit.hpp)")
      ->capture_default_str();
  for (CLI::Option* opt : add_row_flags(cmd, static_cast<LmStartOptions&>(args->lm)))
    opt->group(kLmOptionGroup);
  for (CLI::Option* opt : add_row_flags(cmd, args->lm.lm)) opt->group(kLmOptionGroup);
  cmd->add_option("--integrator", args->integrator,
                  "Integrator of every evaluation (knitsim list integrators); default equilibrium");
  cmd->add_option("--rtol", args->rtol, "Relative tolerance of every drape run (adaptive methods)")
      ->capture_default_str();
  add_atol_options(cmd, args->atol, args->velocity_atol);
  add_ica_options(cmd, o);
  cmd->add_option("--out", args->out,
                  "Output folder (default: a fresh out/fit-<scene>-<YYYYmmdd-HHMMSS>)");
  cmd->add_flag("--resume", args->resume,
                "Continue the interrupted fit in --out from its ica_checkpoint.json (same "
                "options needed; any --jobs); starts afresh if there is none");
  for (const Key* k : box_rows()) {
    const std::string range = key_range(*k);
    cmd->add_option_function<std::string>(
           k->flag, [args, flag = k->flag](const std::string& v) { args->box_flags[flag] = v; },
           k->meaning + " (scene key " + k->name + (range.empty() ? "" : "; " + range) + ")")
        ->group("Material fit (model.kind = material)");
  }
  cmd->add_flag("--no-pictures", args->no_pictures, "Skip the fitted drape's drape.png");
  cmd->add_flag("--quiet", args->quiet, "Nothing on stdout");
  cmd->callback([args, cmd] {
    args->ignored = given_flags(cmd, args->optimizer == "lm" ? kIcaOptionGroup : kLmOptionGroup);
    run(*args);
  });
}

}  // namespace knitsim
