// knitsim repro (docs/commands.md): paper 1's Tables 4 and 6, the Taguchi tuning, Fig. 13 and the
// fitted drapes' pictures, on the synthetic targets (src/repro/repro.hpp has what is computed and
// written).
//
//   knitsim repro table4|table6|taguchi|fig13|all [--preset quick|paper] [--jobs J] [--out DIR]
//                 [--resume] [--targets DIR] [--optimizer ica|lm|ica,lm] [overrides of the
//                 preset: --samples --sets --runs --decades --countries --imperialists
//                 --replicates --seed] [--four-corner-symmetry none|quarter|eighth]
//                 [--integrator NAME]
//                 [--no-pictures]
//
// --optimizer: the optimizers of Tables 4 and 6 (default ica); lm adds table4_lm.csv,
// table6_lm.csv and lm_vs_ica.csv (src/repro/repro.hpp); Taguchi and Fig. 13 always use the ICA.
//
// Targets: read from --targets DIR (<set>_sample<s>.csv, written by `knitsim targets`), by
// default the source tree's paper_repro/data/targets as configured at build time
// (KNITSIM_TARGETS_DIR); a file that is not there is generated in memory by
// make_synthetic_target with the same defaults (bit for bit what `knitsim targets` commits), so
// the command works from anywhere, only slower. An explicit --targets must exist.
// Order of work: parse, apply the preset and the overrides, validate, read the committed
// targets; only then create --out. Bad input therefore writes nothing (exit 2).
// --resume continues an interrupted run in the same --out from its checkpoints (fits.jsonl,
// taguchi.jsonl); the options must be the same (else exit 2).
// --jobs J: threads; J fits run at once, each on one thread (the results do not depend on it).
// Under MPI (mpirun -np N knitsim repro ...) the units are spread over the ranks; --out is then
// required.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/commands.hpp"
#include "src/paper/paper_data.hpp"
#include "src/parallel/work_units.hpp"
#include "src/repro/repro.hpp"

#ifndef KNITSIM_TARGETS_DIR
#define KNITSIM_TARGETS_DIR ""
#endif

namespace knitsim {

namespace {

struct ReproArgs {
  std::string task;
  std::string preset = "quick";
  int jobs = 1;
  std::string out;
  bool resume = false;
  std::string targets;
  std::string samples;
  std::vector<std::string> sets;
  std::vector<std::string> optimizers;
  int runs = 0, decades = 0, countries = 0, imperialists = 0, replicates = 0;
  std::uint64_t seed = 0;
  std::string four_corner_symmetry;
  std::string integrator;
  bool no_pictures = false;
  bool quiet = false;
};

void run(const ReproArgs& a, const CLI::App& cmd) {
  ReproOptions o = repro_preset(a.preset);
  o.task = repro_task_from_name(a.task);
  o.jobs = a.jobs;
  if (cmd.count("--samples")) o.samples = parse_sample_list(a.samples);
  if (cmd.count("--sets")) {
    o.sets.clear();
    for (const std::string& s : a.sets) o.sets.push_back(synthetic_set_from_name(s));
  }
  if (cmd.count("--runs")) o.runs = a.runs;
  if (cmd.count("--decades")) o.ica.decades = a.decades;
  if (cmd.count("--countries")) o.ica.countries = a.countries;
  if (cmd.count("--imperialists")) o.ica.imperialists = a.imperialists;
  if (cmd.count("--replicates")) o.taguchi_replicates = a.replicates;
  if (cmd.count("--seed")) o.seed = a.seed;
  if (cmd.count("--integrator")) o.integrator = a.integrator;
  o.pictures = !a.no_pictures;
  o.progress = !a.quiet;
  if (cmd.count("--targets")) {
    if (!std::filesystem::is_directory(a.targets))
      throw std::invalid_argument("--targets = " + a.targets + ": not a folder");
    o.targets_dir = a.targets;
  } else if (std::filesystem::is_directory(KNITSIM_TARGETS_DIR)) {
    o.targets_dir = KNITSIM_TARGETS_DIR;
  }
  try {
    if (cmd.count("--four-corner-symmetry"))
      o.four_corner_symmetry = four_corner_symmetry_from_name(a.four_corner_symmetry);
    if (cmd.count("--optimizer")) {
      o.optimizers.clear();
      for (const std::string& m : a.optimizers)
        o.optimizers.push_back(repro_optimizer_from_name(m));
    }
    o.validate();
  } catch (const std::invalid_argument& e) {
    rethrow_with_flag_names(e, {{"taguchi_replicates", "--replicates"},
                                {"four_corner_symmetry", "--four-corner-symmetry"},
                                {"integrator", "--integrator"},
                                {"optimizers", "--optimizer"},
                                {"runs", "--runs"},
                                {"samples", "--samples"},
                                {"sets", "--sets"}});
  }
  if (a.resume && a.out.empty())
    throw std::invalid_argument("--resume: needs --out, the folder of the interrupted run");
  if (process_count() > 1 && a.out.empty())
    throw std::invalid_argument("--out: required under MPI (every rank must use one folder)");
  // Rank 0 decides (under mpirun it would otherwise find the checkpoint it has just begun).
  std::string refusal;
  if (process_rank() == 0) try {
      refuse_fresh_start_over_checkpoint(a.out, repro_checkpoint_files(), a.resume);
    } catch (const std::invalid_argument& e) {
      refusal = e.what();
    }
  broadcast(refusal);
  if (!refusal.empty()) throw std::invalid_argument(refusal);
  ReproTargets targets(o);
  std::filesystem::path dir;
  if (process_rank() == 0)
    dir = make_output_dir(a.out, "repro-" + a.task);
  else
    dir = a.out;

  const ReproSummary s = run_repro(o, targets, dir, a.resume);
  if (process_rank() != 0 || a.quiet) return;
  std::cout << "\nwrote " << dir.string() << "/: ";
  for (size_t i = 0; i < s.files.size(); ++i) std::cout << (i ? ", " : "") << s.files[i];
  std::cout << "\nrepro " << a.task << " --preset " << a.preset << ": "
            << format_number(s.wall_seconds, 3) << " s wall, " << format_number(s.cpu_seconds, 3)
            << " s CPU (" << s.fit_drapes << " fit drapes, " << format_number(s.cpu_per_drape, 3)
            << " s CPU each)\n"
            << "estimate for --preset paper (" << s.paper_drapes
            << " drapes): " << format_number(s.paper_cpu_estimate / 3600.0, 3)
            << " CPU h; with the paper's explicit Euler: "
            << format_number(s.paper_euler_cpu_estimate / (3600.0 * 24.0 * 365.0), 3)
            << " CPU years\n";
}

}  // namespace

void register_repro_command(CLI::App& app) {
  auto args = std::make_shared<ReproArgs>();
  CLI::App* cmd = app.add_subcommand(
      "repro",
      "Reproduce paper 1: Tables 4 and 6, the Taguchi tuning, Fig. 13 and the fitted drapes, on "
      "the synthetic targets; writes CSV tables, pictures, report.md and manifest.json into "
      "--out");
  cmd->add_option("task", args->task, "table4|table6|taguchi|fig13|all")->required();
  cmd->add_option("--preset", args->preset,
                  "quick (reduced budget, ~5 s with 2 jobs) | paper (the paper's protocol; "
                  "Tables 4 + 6: ~1 min with 2 jobs)")
      ->capture_default_str();
  cmd->add_option("--jobs", args->jobs,
                  "Threads: fits run this many at once (results do not depend on it)")
      ->capture_default_str();
  cmd->add_option("--out", args->out,
                  "Output folder (default: a fresh out/repro-<task>-<YYYYmmdd-HHMMSS>)");
  cmd->add_flag("--resume", args->resume,
                "Continue an interrupted run in --out from its checkpoints");
  cmd->add_option("--targets", args->targets,
                  "Folder of committed targets <set>_sample<s>.csv (default: the source tree's "
                  "paper_repro/data/targets; missing files are generated)");
  // One string, parsed by parse_sample_list: a CLI11 delimiter would split "2,5-7" into
  // three values and refuse them.
  cmd->add_option("--samples", args->samples, "Override: samples of Tables 4/6, e.g. 1-9 or 2,5-7");
  cmd->add_option("--sets", args->sets, "Override: target sets, twin,cross")->delimiter(',');
  cmd->add_option("--optimizer", args->optimizers,
                  "Optimizers of Tables 4 and 6: ica (default), lm (multi-start "
                  "Levenberg-Marquardt, src/fit/lm_fit.hpp) or ica,lm (LM next to the ICA)")
      ->delimiter(',');
  cmd->add_option("--runs", args->runs, "Override: ICA runs per sample (best kept)");
  cmd->add_option("--decades", args->decades, "Override: ICA decades per fit");
  cmd->add_option("--countries", args->countries, "Override: ICA countries per fit");
  cmd->add_option("--imperialists", args->imperialists, "Override: ICA imperialists per fit");
  cmd->add_option("--replicates", args->replicates, "Override: Taguchi replicates per run");
  add_seed_option(cmd, args->seed, "Override: base seed of every unit (default 2017)");
  cmd->add_option("--four-corner-symmetry", args->four_corner_symmetry,
                  "Integrate every four_corner fit and drape on this symmetry reduction: none | "
                  "quarter | eighth (default; the exact restriction to the symmetric states, "
                  "models/mirror_reduced.hpp); two_corner stays whole");
  cmd->add_option("--integrator", args->integrator,
                  "Integrator of every fit drape and picture (knitsim list integrators; default "
                  "equilibrium, the state the damped dynamics reach, found without integrating "
                  "the transient); part of the checkpoints' settings");
  cmd->add_flag("--no-pictures", args->no_pictures, "Skip the fitted drapes' pictures");
  cmd->add_flag("--quiet", args->quiet, "Nothing on stdout");
  cmd->callback([args, cmd] { run(*args, *cmd); });
}

}  // namespace knitsim
