// The reproduction of paper 1 (Mozafary & Payvandy 2017; docs/fitting.md): Tables 4 and 6,
// the Taguchi tuning of the ICA (Table 1, Fig. 10), the convergence plot (Fig. 13) and the
// pictures of the fitted drapes (Tables 5 and 7), on the synthetic targets of
// src/fit/synthetic_targets.hpp, side by side with the paper's numbers (src/paper/paper_data.hpp).
//
// Work (every independent unit goes through run_work_units, src/parallel/work_units.hpp:
// checkpoint, --resume, MPI):
//   fit unit "fit/<set>/s<sample>/run<r>": one ICA fit (src/fit/drape_fit.hpp) of the four_corner
//     scene of that sample (Table 2 areal density, rtol 1e-8) to the target <set>_sample<s>.
//   lm unit "lm/<set>/s<sample>" (with --optimizer lm): one multi-start Levenberg-Marquardt fit
//     (src/fit/lm_fit.hpp, fit_drape_lm) of the same scene to the same target; on twin it adds a
//     fit of k alone with L0 and the topology held at the true values ("k at the true L0": the
//     edges determine k only through k / L0, experiments/identifiability/README.md).
//   Both write the same result fields (best_x, objective, evaluations, failed_evaluations,
//   status, seed, wall_seconds, cpu_seconds); the units differ only in the optimizer call.
//   taguchi unit "taguchi/<set>/s<sample>/e<NN>/r<k>": one ICA fit of the Taguchi sample with the
//     options of L27 experiment NN (levels of paper Table 1 on the columns of
//     default_l27_columns(), ica_table1_options), replicate k.
// Seeds: unit_seed(seed, key) -- a hash of the base seed and the unit's key (which names set,
// sample and run), so a result depends neither on the order of the units, nor on the number of
// ranks or threads, nor on a resume. The ICA itself is bit-identical for any number of jobs.
// After the units (rank 0 only), per optimizer: per (set, sample) the best run (lowest error;
// ties: lowest run index) gives Table 4; its parameters, applied unchanged to the sample's
// two_corner scene, give Table 6; the fitted drapes are re-run for the pictures. Taguchi and
// Fig. 13 are studies of the ICA and always use it.
//
// Outputs in the output folder:
//   table4.csv   set, sample, runs, best_run, fitted stiffness (N/m), damping (N s/m),
//                elongation_limit (%), natural_length (m), topology, error (Eq. 5, %); the
//                spread over the runs' best countries (<param>_min, <param>_max, topologies:
//                the letters found), error_max; evaluations, failed_evaluations; the paper's
//                Table 4 values (paper_*); for twin the true values (= the paper's) and the
//                relative recovery errors stiffness_rel_error, natural_length_rel_error
//                ((fit - true) / true); empty cells where a column does not apply.
//   table6.csv   set, sample, the applied parameters, table4_error, error (two_corner, %),
//                drape_status, paper_table4_error, paper_error (Table 6).
//   table4_lm.csv, table6_lm.csv (--optimizer lm): the same columns for the LM fits (runs = 1)
//                plus cpu_seconds (of the fit; CPU time differs between runs, so the ICA
//                tables, which must compare byte for byte across ranks, leave it out).
//   lm_vs_ica.csv (both optimizers): per set and sample the LM and ICA errors, drape
//                evaluations (ICA: all its runs) and CPU seconds, evaluations ratio ICA / LM,
//                lm_not_worse (LM error <= ICA's best); on twin the LM recovery of k / L0, k
//                and L0, and of k at the true L0 ((fit - true) / true).
//   taguchi_responses.csv (run, A..G levels, y1..yr: final ICA cost, %),
//   taguchi_sn.csv, taguchi_effects.csv, taguchi_anova.csv (src/fit/taguchi.hpp tables).
//   fig13.csv    run (best|median), decade, best, mean (imperialist costs, %); fig13.png.
//   pictures/<set>_s<sample>_<scene>[_lm]/  write_drape_outputs of each fitted drape.
//   report.md, manifest.json, checkpoint files fits.jsonl / taguchi.jsonl.
//
// Failure modes: bad options throw std::invalid_argument naming the field (validate); a
// committed target file that does not parse throws std::invalid_argument; a target that must be
// generated and does not settle leaves its samples without a fit (their rows say why); a unit
// whose fit throws is reported in the tables as an error row (status column).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "models/drape_grid.hpp"
#include "src/fit/ica.hpp"
#include "src/fit/lm_fit.hpp"
#include "src/fit/synthetic_targets.hpp"
#include "src/fit/targets.hpp"

namespace knitsim {

enum class ReproTask { Table4, Table6, Taguchi, Fig13, All };
const char* to_string(ReproTask task);
// "table4" | "table6" | "taguchi" | "fig13" | "all"; std::invalid_argument otherwise.
ReproTask repro_task_from_name(const std::string& name);

// The optimizer of the Table 4 fits: the paper's ICA, or Levenberg-Marquardt (src/fit/lm_fit.hpp).
enum class ReproOptimizer { Ica, Lm };
const char* to_string(ReproOptimizer optimizer);
// "ica" | "lm"; std::invalid_argument "optimizers = X: accepted ica|lm" otherwise.
ReproOptimizer repro_optimizer_from_name(const std::string& name);
// none | quarter | eighth (ReproOptions::four_corner_symmetry); else std::invalid_argument.
DrapeSymmetry four_corner_symmetry_from_name(const std::string& name);

// CPU seconds of one four_corner drape with the paper's explicit Euler at its stability limit:
// 1.23e8 steps x 4.94 us (experiments/benchmark/README.md, "Drape scenes").
constexpr double kEulerCpuSecondsPerFourCornerDrape = 607.0;

struct ReproOptions {
  std::string preset = "quick";  // the preset these values came from (recorded)
  ReproTask task = ReproTask::All;
  std::vector<int> samples = {1, 2, 3, 4, 5, 6, 7, 8, 9};  // Tables 4 and 6, each 1..9
  std::vector<SyntheticSet> sets = {SyntheticSet::Twin, SyntheticSet::Cross};
  // Optimizers of Tables 4 and 6, each at most once; lm only for the tasks table4|table6|all.
  std::vector<ReproOptimizer> optimizers = {ReproOptimizer::Ica};
  int runs = 10;      // ICA runs per (set, sample), the best kept (paper: 10); >= 1
  IcaOptions ica;     // each fit's budget (default: Taguchi-best A3 B3 C1 D2 E1 F2 G2);
                      // ica.seed and ica.jobs are set per unit
  int jobs = 1;       // threads: units (fits) run this many at once, each on one thread
  DrapeLmOptions lm;  // each LM fit (one per (set, sample)); lm.seed is replaced per unit
  // Fig. 13: the runs of this (set, sample) (the same units as Table 4's when it is included).
  SyntheticSet fig13_set = SyntheticSet::Cross;
  int fig13_sample = 1;
  // Taguchi: L27 x replicates fits of one sample, factor levels of Table 1 except that factor
  // A (decades) takes taguchi_decades (paper: 10, 20, 40).
  SyntheticSet taguchi_set = SyntheticSet::Cross;
  int taguchi_sample = 1;
  int taguchi_replicates = 3;  // >= 1 (the paper does not say; 3 is our choice)
  std::array<int, 3> taguchi_decades = {10, 20, 40};
  std::uint64_t seed = 2017;  // base seed of every unit (unit_seed)
  // Integrator of every fit drape and picture; empty: repro_default_integrator().
  std::string integrator;
  // model.symmetry of every four_corner fit and drape (none | quarter | eighth): the ICA and LM
  // fits are all on four_corner (Table 6 evaluates their parameters on two_corner, which stays
  // whole), and the eighth is the exact restriction of the full equations to the symmetric
  // states the scene reaches (models/mirror_reduced.hpp). Default eighth: the same fits for a
  // fraction of the whole sheet's CPU, up to the lottery of failed evaluations
  // (paper_repro/README.md, "The eighth", has the figures).
  DrapeSymmetry four_corner_symmetry = DrapeSymmetry::Eighth;
  double rtol = 1e-8;  // of every drape (as knitsim fit, src/fit/drape_fit.hpp)
  // Committed targets <dir>/<set>_sample<s>.csv; a missing file is generated in memory with
  // make_synthetic_target(sample, set, synthetic). Empty: generate all.
  std::string targets_dir;
  SyntheticOptions synthetic;
  bool pictures = true;  // write pictures/ (Tables 5 and 7)
  bool progress = true;  // progress lines (stderr on a terminal; stage lines on stdout)

  // Throws std::invalid_argument "<field> = <value>: accepted range" (samples in 1..9, each
  // once; sets non-empty and distinct; optimizers non-empty and distinct, lm only with
  // table4|table6|all; runs, taguchi_replicates >= 1; taguchi_decades >= 1; rtol in (0, 0.1];
  // four_corner_symmetry none | quarter | eighth;
  // DrapeFitOptions::validate of ica and integrator; lm; synthetic).
  void validate() const;
};

// The integrator repro runs when ReproOptions::integrator is empty: default_integrator(),
// `equilibrium`. Tables 4 and 6 need only each drape's equilibrium, which it finds without
// integrating the transient (solvers/equilibrium_solver.cpp).
std::string repro_default_integrator();
// o.integrator, or repro_default_integrator() if it is empty.
std::string repro_integrator(const ReproOptions& o);

// The presets (std::invalid_argument for another name):
//   paper: the paper's protocol: samples 1-9, twin and cross, 10 runs per sample at the
//          Taguchi-best ICA settings (25 countries, 2 imperialists, 40 decades, beta 1,
//          gamma 0.1, revolution 0.3, xi 0.15), Taguchi with Table 1's levels, 3 replicates.
//   quick: what ./run.sh runs: the same 9 samples and 2 sets, but 2 runs per sample of
//          10 countries x 6 decades (~58 drapes per run instead of ~945); Taguchi with 1
//          replicate and factor A's decades 1/2/4 instead of 10/20/40 (other factors as Table 1).
// Both: the ICA only (optimizers); LM, when chosen, at the DrapeLmOptions defaults.
ReproOptions repro_preset(const std::string& name);

// The seed of a unit: splitmix64 of the base seed mixed with the FNV-1a hash of its key.
std::uint64_t unit_seed(std::uint64_t base, const std::string& key);

// Cost evaluations of one ICA run with these options when no empire collapses (a lower bound):
// countries + decades x colonies, where a run with fewer colonies than imperialists has
// 2 x imperialists countries (src/fit/ica.hpp step 2).
long ica_evaluation_estimate(const IcaOptions& o);

// The targets a reproduction needs, read from the committed files up front (so that a bad file
// is bad input before anything is written) and the rest generated on demand.
class ReproTargets {
 public:
  // Reads every existing <targets_dir>/<set>_sample<s>.csv the options need.
  explicit ReproTargets(const ReproOptions& options);
  // Generates the targets without a committed file (make_synthetic_target; slow for cross). A
  // target whose drapes do not settle is left unavailable (its rows report why); the rest of
  // the reproduction goes on.
  void generate_missing(bool progress);
  bool available(SyntheticSet set, int sample) const;
  // The target of (set, sample); std::logic_error if it is not available.
  const Target& get(SyntheticSet set, int sample) const;
  // "paper_repro/.../twin_sample1.csv", "generated in memory by ..." or "unavailable: why".
  std::string provenance(SyntheticSet set, int sample) const;

 private:
  struct Entry {
    Target target;
    bool loaded = false;
    std::string source;
  };
  SyntheticOptions synthetic_;
  std::map<std::pair<SyntheticSet, int>, Entry> entries_;
  const Entry& entry(SyntheticSet set, int sample) const;
};

struct ReproSummary {
  double wall_seconds = 0.0, cpu_seconds = 0.0;  // the whole reproduction, this process
  long fit_drapes = 0;                    // four_corner drapes evaluated by the fits + Taguchi
  double fit_cpu_seconds = 0.0;           // CPU of those fits (all threads)
  double cpu_per_drape = 0.0;             // fit_cpu_seconds / fit_drapes
  long paper_drapes = 0;                  // estimate of the paper preset (Tables 4+6 + Taguchi)
  double paper_cpu_estimate = 0.0;        // paper_drapes x cpu_per_drape
  double paper_euler_cpu_estimate = 0.0;  // paper_drapes x kEulerCpuSecondsPerFourCornerDrape
  std::vector<std::string> files;         // written, relative to the output folder
};

// The checkpoints run_repro keeps in its folder (JSON lines, src/parallel/work_units.hpp): the
// fits' and the Taguchi experiment's.
inline const std::vector<std::string>& repro_checkpoint_files() {
  static const std::vector<std::string> names = {"fits.jsonl", "taguchi.jsonl"};
  return names;
}

// Runs the reproduction into `dir` (existing, writable); on ranks other than 0 it only computes
// units and returns an empty summary. `options` must be valid.
ReproSummary run_repro(const ReproOptions& options, ReproTargets& targets,
                       const std::filesystem::path& dir, bool resume);

}  // namespace knitsim
