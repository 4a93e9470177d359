// The parts of the reproduction (src/repro/repro.hpp) that its own files share: the work units,
// the best fits of a sample and the tables made of them. Not for use outside src/repro/.
#pragma once

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "src/base/table.hpp"
#include "src/fit/drape_fit.hpp"
#include "src/parallel/work_units.hpp"
#include "src/repro/repro.hpp"
#include "src/scene/scene.hpp"

namespace knitsim::repro_internal {

// ---- targets (repro_targets.cpp) ----------------------------------------------------------------

// The (set, sample) pairs a reproduction needs.
std::vector<std::pair<SyntheticSet, int>> needed_targets(const ReproOptions& o);

// ---- work units (repro_units.cpp) -------------------------------------------------------------

// CPU seconds of this process (std::clock).
double cpu_now();
// CPU seconds of the calling thread.
double thread_cpu_now();
// The built-in scene `scene` with the sample's areal density and the reproduction's rtol (and
// on four_corner its symmetry reduction).
Scene sample_scene(const std::string& scene, int sample, const ReproOptions& o);
DrapeFitOptions fit_options(const ReproOptions& o, const IcaOptions& ica);

// How one fit is made: the optimizer and its options (seeds already set for the unit).
struct FitMethod {
  ReproOptimizer optimizer = ReproOptimizer::Ica;
  IcaOptions ica;  // the ICA's; also the DrapeFitProblem's options
  DrapeLmOptions lm;
};
// One fit of the sample's four_corner scene to `target` by `m`: the unit result
// (src/repro/repro.hpp).
nlohmann::json fit_unit(const ReproOptions& o, const Target& target, SyntheticSet set, int sample,
                        const FitMethod& m);
// A fit unit before it runs.
struct FitSpec {
  std::string key;  // fit_key or taguchi_key
  const Target* target = nullptr;
  SyntheticSet set = SyntheticSet::Twin;
  int sample = 0;
  FitMethod method;  // seeds set; its ica.jobs is fit_work_units'
};
// The work units of `specs` (fit_unit each). o.jobs threads run o.jobs units at once
// (WorkUnitOptions::threads), each fit on one thread; a unit alone runs its ICA on all of them.
// Neither changes a result (the ICA is bit-identical for any number of jobs).
std::vector<WorkUnit> fit_work_units(const ReproOptions& o, std::vector<FitSpec> specs);
// "fit/<set>/s<sample>/run<NN>" (ICA) or "lm/<set>/s<sample>" (one LM fit per sample).
std::string fit_key(ReproOptimizer optimizer, SyntheticSet set, int sample, int run);
// "taguchi/<set>/s<sample>/e<NN>/r<k>".
std::string taguchi_key(const ReproOptions& o, int experiment, int replicate);
// Levels 1..3 of factors A..G in L27 experiment e (0..26).
std::array<int, 7> experiment_levels(int e);
// The ICA options of L27 experiment e (paper Table 1 levels; decades from the preset).
IcaOptions taguchi_ica(const ReproOptions& o, int e);
// A unit result without an error.
inline bool ok(const nlohmann::json& unit) { return !unit.contains("error"); }

// ---- the fits of a sample and their tables (repro_tables.cpp) -----------------------------------

// The runs of one (optimizer, set, sample) and the best of them.
struct SampleFits {
  ReproOptimizer optimizer = ReproOptimizer::Ica;
  SyntheticSet set = SyntheticSet::Twin;
  int sample = 0;
  std::vector<nlohmann::json> runs;  // unit results in run order
  int best = -1;      // index of the lowest error among runs without error; -1 if none
  std::string error;  // the first unit error, if every run failed

  long evaluations() const {  // drape evaluations of the good runs
    long n = 0;
    for (const nlohmann::json& r : runs)
      if (ok(r)) n += r["evaluations"].get<long>();
    return n;
  }
  double cpu_seconds() const {  // CPU seconds of the good runs
    double t = 0.0;
    for (const nlohmann::json& r : runs)
      if (ok(r)) t += r["cpu_seconds"].get<double>();
    return t;
  }
  std::vector<double> best_x() const {  // best >= 0
    return runs[best]["best_x"].get<std::vector<double>>();
  }

  std::vector<int> by_objective() const {  // indices of the good runs, best first
    std::vector<int> idx;
    for (size_t r = 0; r < runs.size(); ++r)
      if (ok(runs[r])) idx.push_back(static_cast<int>(r));
    std::stable_sort(idx.begin(), idx.end(), [&](int a, int b) {
      return runs[a]["objective"].get<double>() < runs[b]["objective"].get<double>();
    });
    return idx;
  }
};

// A table cell: format_number(v, digits).
std::string cell(double v, int digits = 6);
// Table 4 of `fits` (src/repro/repro.hpp); cpu_column: a last column cpu_seconds (all runs).
Table table4(const std::vector<SampleFits>& fits, bool cpu_column);
// The mean over samples of (max - min) / box width of each continuous parameter.
std::array<double, 4> mean_spread(const Table& t4, SyntheticSet set);
// Table 4 as a compact markdown table for the report.
std::string table4_markdown(const Table& t4, SyntheticSet set);
// The fits of optimizer m that Tables 4 and 6 show (not a Fig. 13-only sample).
std::vector<SampleFits> table_fits(const std::vector<SampleFits>& fits, const ReproOptions& o,
                                   ReproOptimizer m);
// File-name suffix of an optimizer's outputs: "" for the ICA (the paper's), "_lm" for LM.
std::string suffix(ReproOptimizer m);
// Table 6 of `fits` (src/repro/repro.hpp): the best parameters re-run on two_corner, with the
// pictures under dir/pictures when o.pictures. LM adds evaluations and cpu_seconds of the
// four_corner fit.
Table make_table6(const std::vector<SampleFits>& fits, const ReproOptions& o,
                  const ReproTargets& targets, const std::filesystem::path& dir, ReproOptimizer m);
// LM next to the ICA (when it ran) and the paper, per (set, sample): lm_vs_ica.csv
// (src/repro/repro.hpp). t6: the two_corner errors per optimizer (empty tables when not run).
Table lm_vs_ica(const std::vector<SampleFits>& lm, const std::vector<SampleFits>& ica,
                const Table& lm_t6, const Table& ica_t6);
// lm_vs_ica of one set as a compact markdown table, and the target's tally on twin.
std::string lm_vs_ica_markdown(const Table& t, SyntheticSet set);
// Markdown rows of the four_corner pictures of `fits` (re-run; written under dir/pictures).
std::string four_corner_pictures(const std::vector<SampleFits>& fits, const ReproOptions& o,
                                 const ReproTargets& targets, const std::filesystem::path& dir,
                                 ReproOptimizer m, bool two_corner);

}  // namespace knitsim::repro_internal
