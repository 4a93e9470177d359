#include "src/repro/repro.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <stdexcept>

#include "solvers/integrator.hpp"
#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/fit/drape_fit.hpp"
#include "src/fit/taguchi.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/measure/measurement.hpp"
#include "src/paper/paper_data.hpp"
#include "src/parallel/work_units.hpp"
#include "src/render/plot.hpp"
#include "src/repro/repro_internal.hpp"
#include "src/scene/scene.hpp"
namespace knitsim {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace repro_internal;

namespace {

void print_stage(const ReproOptions& o, const std::string& line) {
  if (o.progress) std::cout << line << "\n" << std::flush;
}

struct Timer {
  std::chrono::steady_clock::time_point wall0 = std::chrono::steady_clock::now();
  double cpu0 = cpu_now();
  double wall() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  }
  double cpu() const { return cpu_now() - cpu0; }
};

// Paper protocol's drape count: the Table 4 fits and the Taguchi L27 (four_corner drapes).
long paper_drape_estimate() {
  const ReproOptions p = repro_preset("paper");
  long n =
      static_cast<long>(p.sets.size() * p.samples.size()) * p.runs * ica_evaluation_estimate(p.ica);
  for (int e = 0; e < kL27Runs; ++e)
    n += p.taguchi_replicates * ica_evaluation_estimate(taguchi_ica(p, e));
  return n;
}

json options_json(const ReproOptions& o) {
  json sets = json::array();
  for (SyntheticSet s : o.sets) sets.push_back(to_string(s));
  json optimizer_names = json::array();
  for (ReproOptimizer m : o.optimizers) optimizer_names.push_back(to_string(m));
  return {{"preset", o.preset},
          {"task", to_string(o.task)},
          {"samples", o.samples},
          {"sets", sets},
          {"optimizers", optimizer_names},
          {"runs", o.runs},
          {"lm", to_json(o.lm)},
          {"ica", to_json(o.ica)},  // without seed and jobs: units carry their own seeds
          {"fig13", {{"set", to_string(o.fig13_set)}, {"sample", o.fig13_sample}}},
          {"taguchi",
           {{"set", to_string(o.taguchi_set)},
            {"sample", o.taguchi_sample},
            {"replicates", o.taguchi_replicates},
            {"decades_levels", o.taguchi_decades}}},
          {"seed", o.seed},
          {"integrator", repro_integrator(o)},
          {"rtol", o.rtol},
          {"four_corner_symmetry", to_string(o.four_corner_symmetry)},
          {"synthetic",
           {{"noise_mm", o.synthetic.noise_mm},
            {"photos", o.synthetic.photos},
            {"seed", o.synthetic.seed}}}};
}

// Which parts of the reproduction a task runs.
struct ReproParts {
  bool tables = false;  // Tables 4 and 6 (and the LM comparison)
  bool table6 = false;
  bool fig13 = false;
  bool taguchi = false;
};

ReproParts parts_of(ReproTask task) {
  const bool all = task == ReproTask::All;
  ReproParts p;
  p.tables = task == ReproTask::Table4 || task == ReproTask::Table6 || all;
  p.table6 = task == ReproTask::Table6 || all;
  p.fig13 = task == ReproTask::Fig13 || all;
  p.taguchi = task == ReproTask::Taguchi || all;
  return p;
}

// Where each target came from, keyed "<set>_sample<s>": the manifest's and the report's list.
json target_provenance(const ReproOptions& o, const ReproTargets& targets) {
  json provenance = json::object();
  for (const auto& [set, sample] : needed_targets(o))
    provenance[std::string(to_string(set)) + "_sample" + std::to_string(sample)] =
        targets.provenance(set, sample);
  return provenance;
}

// The fits of one (optimizer, set, sample): its runs.
struct FitJob {
  ReproOptimizer optimizer;
  SyntheticSet set;
  int sample;
  int runs;  // ICA: o.runs; LM: 1 (deterministic)
};

// The fits Tables 4 and 6 show, then Fig. 13's sample when no table fit covers it.
std::vector<FitJob> fit_jobs(const ReproOptions& o, const ReproParts& parts) {
  std::vector<FitJob> jobs;
  const auto has_job = [&](ReproOptimizer m, SyntheticSet set, int sample) {
    return std::any_of(jobs.begin(), jobs.end(), [&](const FitJob& j) {
      return j.optimizer == m && j.set == set && j.sample == sample;
    });
  };
  if (parts.tables)
    for (ReproOptimizer m : o.optimizers)
      for (SyntheticSet set : o.sets)
        for (int s : o.samples) jobs.push_back({m, set, s, m == ReproOptimizer::Ica ? o.runs : 1});
  if (parts.fig13 && !has_job(ReproOptimizer::Ica, o.fig13_set, o.fig13_sample))
    jobs.push_back({ReproOptimizer::Ica, o.fig13_set, o.fig13_sample, o.runs});
  return jobs;
}

// The work units' shared settings; their checkpoint is <name>.jsonl in the output folder
// (src/parallel/work_units.hpp).
WorkUnitOptions unit_options(const ReproOptions& o, const fs::path& dir, const json& config,
                             bool resume, const std::string& name) {
  WorkUnitOptions wo;
  wo.checkpoint = (dir / name).string();
  wo.resume = resume;
  wo.config = config;
  wo.progress = o.progress;
  wo.label = "repro " + name.substr(0, name.find('.'));  // "repro fits"
  wo.threads = o.jobs;
  return wo;
}

// Runs the fits of `jobs` whose target is available: their unit results in job and run order.
std::vector<json> run_fits(const ReproOptions& o, const std::vector<FitJob>& jobs,
                           const ReproTargets& targets, const WorkUnitOptions& wo, bool root) {
  std::vector<FitSpec> specs;
  int ica_runs = 0, lm_fits = 0;
  for (const FitJob& j : jobs)
    for (int r = 0; r < j.runs && targets.available(j.set, j.sample); ++r) {
      const std::string key = fit_key(j.optimizer, j.set, j.sample, r);
      FitMethod m{j.optimizer, o.ica, o.lm};
      m.ica.seed = m.lm.seed = unit_seed(o.seed, key);
      (j.optimizer == ReproOptimizer::Ica ? ica_runs : lm_fits) += 1;
      specs.push_back({key, &targets.get(j.set, j.sample), j.set, j.sample, m});
    }
  const std::vector<WorkUnit> units = fit_work_units(o, std::move(specs));
  if (units.empty()) return {};
  if (root)
    print_stage(o, "fits: " + std::to_string(ica_runs) + " ICA runs (" + std::to_string(o.runs) +
                       " per set x sample, ~" + std::to_string(ica_evaluation_estimate(o.ica)) +
                       " drapes per run), " + std::to_string(lm_fits) + " LM fits");
  return run_work_units(units, wo);
}

// Runs the Taguchi L27 (o.taguchi_replicates ICA fits per experiment) when its target is
// available: the unit results, experiment by experiment; none without the target.
std::vector<json> run_taguchi(const ReproOptions& o, const ReproTargets& targets,
                              const WorkUnitOptions& wo, bool root) {
  if (!targets.available(o.taguchi_set, o.taguchi_sample)) return {};
  std::vector<FitSpec> specs;
  const Target* target = &targets.get(o.taguchi_set, o.taguchi_sample);
  long drapes = 0;
  for (int e = 0; e < kL27Runs; ++e)
    for (int k = 0; k < o.taguchi_replicates; ++k) {
      const std::string key = taguchi_key(o, e, k);
      IcaOptions ica = taguchi_ica(o, e);
      ica.seed = unit_seed(o.seed, key);
      drapes += ica_evaluation_estimate(ica);
      const FitMethod m{ReproOptimizer::Ica, ica, o.lm};
      specs.push_back({key, target, o.taguchi_set, o.taguchi_sample, m});
    }
  if (root)
    print_stage(o, "taguchi: L27 x " + std::to_string(o.taguchi_replicates) + " ICA runs on " +
                       to_string(o.taguchi_set) + "_sample" + std::to_string(o.taguchi_sample) +
                       ", ~" + std::to_string(drapes) + " drapes");
  return run_work_units(fit_work_units(o, std::move(specs)), wo);
}

// The fit results grouped per job, each with its best run; a job without its target carries
// the target's provenance as its error.
std::vector<SampleFits> group_fits(const std::vector<FitJob>& jobs,
                                   const std::vector<json>& fit_results,
                                   const ReproTargets& targets) {
  std::vector<SampleFits> fits;
  size_t next = 0;  // the next result in fit_results
  for (const FitJob& j : jobs) {
    SampleFits f;
    f.optimizer = j.optimizer;
    f.set = j.set;
    f.sample = j.sample;
    if (!targets.available(f.set, f.sample))
      f.error = "target " + targets.provenance(f.set, f.sample);
    for (int r = 0; r < j.runs && targets.available(f.set, f.sample); ++r) {
      const json& u = fit_results[next++];
      f.runs.push_back(u);
      if (!ok(u) && f.error.empty()) f.error = u["error"].get<std::string>();
    }
    const std::vector<int> good = f.by_objective();
    f.best = good.empty() ? -1 : good.front();
    fits.push_back(f);
  }
  return fits;
}

// Adds the drapes and CPU seconds of the good units among `results` to the summary.
void add_fit_cost(ReproSummary& summary, const std::vector<json>& results) {
  for (const json& u : results)
    if (ok(u)) {
      summary.fit_drapes += u["evaluations"].get<long>();
      summary.fit_cpu_seconds += u["cpu_seconds"].get<double>();
    }
}

// The report (report.md) as it is written, and the files written beside it.
struct ReproReport {
  const ReproOptions& o;
  const fs::path& dir;
  ReproSummary& summary;
  std::ostringstream text;

  // A file written by someone else under dir, listed in the summary.
  void keep(const std::string& name) { summary.files.push_back(name); }
  // Writes dir/name and lists it.
  void write(const std::string& name, const std::string& contents) {
    write_file_atomic(dir / name, contents);
    keep(name);
  }
};

// The fits of optimizer m that the tables show; none when m did not run.
const std::vector<SampleFits>& shown_fits(
    const std::map<ReproOptimizer, std::vector<SampleFits>>& shown, ReproOptimizer m) {
  static const std::vector<SampleFits> none;
  const auto it = shown.find(m);
  return it == shown.end() ? none : it->second;
}

// The report's title, what the targets are, the budget and where each target came from.
void report_header(ReproReport& r, const json& provenance) {
  const ReproOptions& o = r.o;
  r.text << "# knitsim repro " << to_string(o.task) << " --preset " << o.preset << "\n\n"
         << "Paper 1 (Mozafary & Payvandy 2017) reproduced on synthetic targets "
            "(paper_repro/data/README.md): "
            "**twin** = the model itself at the paper's Table 4 parameters plus 0.5 mm noise "
            "(can the ICA recover known parameters?), **cross** = the same fabric on a 3x finer "
            "grid plus noise (a real model error, as the paper's photographs have). The paper's "
            "numbers come from its real fabrics, so they are context, not an answer key.\n\n"
         << "Budget: " << o.runs << " ICA runs per sample (best kept), " << o.ica.countries
         << " countries, " << o.ica.imperialists << " imperialists, " << o.ica.decades
         << " decades, beta " << o.ica.beta << ", gamma " << o.ica.gamma << ", revolution "
         << o.ica.revolution_rate << ", xi " << o.ica.xi << "; base seed " << o.seed
         << "; integrator " << repro_integrator(o) << ", rtol " << format_number(o.rtol)
         << "; four_corner integrated "
         << (o.four_corner_symmetry == DrapeSymmetry::None
                 ? std::string("whole")
                 : std::string("on the ") + to_string(o.four_corner_symmetry) + " (model.symmetry)")
         << ".\n\nTargets:\n\n";
  for (const auto& [key, source] : provenance.items())
    r.text << "- " << key << ": " << source.get<std::string>() << "\n";
  r.text << "\n";
}

// table4[_lm].csv per optimizer; the ICA's Table 4 in the report, set by set.
void report_table4(ReproReport& r, const std::map<ReproOptimizer, std::vector<SampleFits>>& shown) {
  const ReproOptions& o = r.o;
  for (const auto& [m, f] : shown) {
    const Table t4 = table4(f, m == ReproOptimizer::Lm);
    r.write("table4" + suffix(m) + ".csv", t4.csv());
    if (m != ReproOptimizer::Ica) continue;
    r.text << "## Table 4: four_corner fits\n\nOurs next to the paper's Table 4 (values in "
              "parentheses). Spread = min-max over the "
           << o.runs
           << " runs' best countries: a parameter the edges do not determine spreads over its "
              "box.\n\n";
    for (SyntheticSet set : o.sets) {
      const std::array<double, 4> spread = mean_spread(t4, set);
      r.text << "### " << to_string(set) << "\n\n"
             << table4_markdown(t4, set) << "\nMean spread over the runs as a fraction of the "
             << "Table 3 box: stiffness " << format_number(spread[0], 2) << ", damping "
             << format_number(spread[1], 2) << ", elongation " << format_number(spread[2], 2)
             << ", natural length " << format_number(spread[3], 2) << ".\n\n";
    }
    r.text
        << "Reading: damping only sets how fast the sheet settles and the elongation limit "
           "only acts on springs stretched beyond it, so neither changes the equilibrium the "
           "edges measure: their fitted values are arbitrary within the box (wide spread), "
           "while stiffness and natural length are determined only together: at a fixed "
           "grid size n = round(W / L0) the edges depend on k / L0 alone (src/fit/sensitivity.hpp, "
           "experiments/identifiability/README.md), so the fit identifies k / L0, n and the "
           "topology, and k and L0 slide together along a valley of equal error. On twin the "
           "recovery errors of k and L0 are in the columns stiffness_rel_error, "
           "natural_length_rel_error of table4.csv; with a reduced budget (quick preset) the "
           "ICA is also far from converged.\n\n";
  }
}

// Re-runs the shown fits on two_corner: table6[_lm].csv per optimizer, the ICA's in the report.
// Returns the tables per optimizer.
std::map<ReproOptimizer, Table> report_table6(
    ReproReport& r, const std::map<ReproOptimizer, std::vector<SampleFits>>& shown,
    const ReproTargets& targets) {
  print_stage(r.o, "table6: applying the four_corner fits to two_corner");
  std::map<ReproOptimizer, Table> t6s;
  for (const auto& [m, f] : shown) {
    const Table t6 = make_table6(f, r.o, targets, r.dir, m);
    t6s[m] = t6;
    r.write("table6" + suffix(m) + ".csv", t6.csv());
    if (m != ReproOptimizer::Ica) continue;
    Table md;
    md.columns = {"set", "sample", "4-corner error % ours (paper)", "2-corner error % ours (paper)",
                  "status"};
    for (const auto& row : t6.rows)
      md.rows.push_back(
          {row[0], row[1],
           (row[7].empty() ? "-" : format_number(std::stod(row[7]), 3)) + " (" + row[10] + ")",
           (row[8].empty() ? "-" : format_number(std::stod(row[8]), 3)) + " (" + row[11] + ")",
           row[9]});
    r.text << "## Table 6: the four_corner parameters applied unchanged to two_corner\n\n"
           << md.markdown()
           << "\nReading: the two_corner scene loads the fabric differently (hanging from two "
              "pins, large in-plane strains), so it also tests what the four_corner fit could "
              "not see. On twin the true parameters reproduce both scenes up to the noise, so a "
              "two_corner error well above the four_corner one points at a parameter the "
              "four_corner edges left undetermined.\n\n";
  }
  return t6s;
}

// lm_vs_ica.csv and its section: LM next to the ICA (when it ran) and the paper.
void report_lm_vs_ica(ReproReport& r,
                      const std::map<ReproOptimizer, std::vector<SampleFits>>& shown,
                      const std::map<ReproOptimizer, Table>& t6s) {
  const ReproOptions& o = r.o;
  const auto t6_of = [&](ReproOptimizer m) {
    const auto it = t6s.find(m);
    return it == t6s.end() ? Table() : it->second;  // empty without table6
  };
  const Table cmp = lm_vs_ica(shown_fits(shown, ReproOptimizer::Lm),
                              shown_fits(shown, ReproOptimizer::Ica), t6_of(ReproOptimizer::Lm),
                              t6_of(ReproOptimizer::Ica));
  r.write("lm_vs_ica.csv", cmp.csv());
  r.text << "## Tables 4 and 6 with Levenberg-Marquardt, next to the ICA and the paper\n\n"
         << "One LM fit per sample (src/fit/lm_fit.hpp: every topology x grid-size bracket "
            "screened once, the "
         << o.lm.refine << " best refined with <= " << o.lm.lm.max_evaluations
         << " evaluations each); ICA: the best of " << o.runs
         << " runs, its drapes counted over all runs (table4_lm.csv, table6_lm.csv, "
            "lm_vs_ica.csv). k at true L0: k fitted by LM with L0 and the topology held at "
            "the twin's true values.\n\n";
  for (SyntheticSet set : o.sets)
    r.text << "### " << to_string(set) << "\n\n" << lm_vs_ica_markdown(cmp, set);
  r.text << "Reading: the edges determine k / L0, the grid size n and the topology, not k and "
            "L0 separately (experiments/identifiability/README.md), so the twin's k and L0 "
            "errors measure where on the valley of equal error the fit stopped; k at the true "
            "L0 shows how well k / L0 is pinned by these noisy edges.\n\n";
}

// Pictures of the fitted drapes (paper Tables 5 and 7), re-run under dir/pictures.
void report_pictures(ReproReport& r,
                     const std::map<ReproOptimizer, std::vector<SampleFits>>& shown,
                     const ReproTargets& targets, bool two_corner) {
  print_stage(r.o, "pictures: re-running the fitted four_corner drapes");
  r.text << "## Pictures (paper Tables 5 and 7)\n\n| optimizer | set | sample | four_corner | "
            "two_corner |\n|---|---|---|---|---|\n";
  for (const auto& [m, f] : shown)
    r.text << four_corner_pictures(f, r.o, targets, r.dir, m, two_corner);
  r.text << "\n";
  r.keep("pictures/");
}

// Fig. 13: the ICA's convergence on its sample, best and median run (fig13.csv, fig13.png).
void report_fig13(ReproReport& r, const std::vector<SampleFits>& fits) {
  const ReproOptions& o = r.o;
  const auto it = std::find_if(fits.begin(), fits.end(), [&](const SampleFits& f) {
    return f.optimizer == ReproOptimizer::Ica && f.set == o.fig13_set &&
           f.sample == o.fig13_sample;
  });
  const std::vector<int> order = it->by_objective();
  Table csv;
  csv.columns = {"curve", "run", "decade", "best", "mean"};
  LinePlot plot;
  plot.log_y = true;
  plot.title = std::string("ICA convergence, ") + to_string(o.fig13_set) + " sample " +
               std::to_string(o.fig13_sample) + " (paper Fig. 13)";
  plot.x_label = "decade";
  plot.y_label = "imperialist cost (Eq. 5 error, %)";
  std::vector<std::pair<std::string, int>> curves;
  if (!order.empty()) curves.push_back({"best", order.front()});
  if (order.size() >= 3) curves.push_back({"median", order[(order.size() - 1) / 2]});
  for (const auto& [name, run] : curves) {
    PlotSeries best, mean;
    best.label = name + " run (" + std::to_string(run) + "): best";
    mean.label = name + " run (" + std::to_string(run) + "): mean";
    best.color = {0.12, 0.35, 0.70};
    mean.color = {0.85, 0.40, 0.10};
    best.dashed = mean.dashed = name != "best";
    const json& h = it->runs[run]["history"];
    for (size_t d = 0; d < h.size(); ++d) {
      const double b = h[d][0].get<double>(), m = h[d][1].get<double>();
      csv.rows.push_back({name, std::to_string(run), std::to_string(d), cell(b, 17), cell(m, 17)});
      best.x.push_back(static_cast<double>(d));
      best.y.push_back(b);
      mean.x.push_back(static_cast<double>(d));
      mean.y.push_back(m);
    }
    plot.series.push_back(best);
    plot.series.push_back(mean);
  }
  r.write("fig13.csv", csv.csv());
  r.text << "## Fig. 13: convergence\n\n";
  if (curves.empty()) {
    r.text << "Every run failed: no curve.\n\n";
    return;
  }
  render_line_plot_png((r.dir / "fig13.png").string(), plot);
  r.keep("fig13.png");
  r.text << "![](fig13.png)\n\nBest and mean imperialist cost per decade of the best run"
         << (curves.size() > 1 ? " (solid) and the median run (dashed)" : "") << " of "
         << to_string(o.fig13_set) << " sample " << o.fig13_sample
         << " (fig13.csv). As in the paper, the mean approaches the best as the empires "
            "collapse onto one region.\n\n";
}

// The Taguchi L27's responses, and when every fit succeeded its S/N, effects and ANOVA.
void report_taguchi(ReproReport& r, const std::vector<json>& taguchi_results) {
  const ReproOptions& o = r.o;
  Table responses;
  responses.columns = {"run", "A", "B", "C", "D", "E", "F", "G"};
  for (int k = 0; k < o.taguchi_replicates; ++k)
    responses.columns.push_back("y" + std::to_string(k + 1));
  std::vector<std::vector<double>> y(kL27Runs);
  std::string failure;
  for (int e = 0; e < kL27Runs; ++e) {
    std::vector<std::string> row = {std::to_string(e + 1)};
    for (int l : experiment_levels(e)) row.push_back(std::to_string(l));
    for (int k = 0; k < o.taguchi_replicates; ++k) {
      const json& u = taguchi_results[e * o.taguchi_replicates + k];
      if (ok(u)) {
        y[e].push_back(u["objective"].get<double>());
        row.push_back(cell(y[e].back(), 17));
      } else {
        if (failure.empty()) failure = u["error"].get<std::string>();
        row.push_back("");
      }
    }
    responses.rows.push_back(row);
  }
  r.write("taguchi_responses.csv", responses.csv());
  r.text << "## Taguchi L27 (paper Table 1, Fig. 10)\n\n"
         << kL27Runs << " experiments x " << o.taguchi_replicates << " replicate(s), ICA fits "
         << "of " << to_string(o.taguchi_set) << " sample " << o.taguchi_sample
         << "; factor A (decades) levels " << o.taguchi_decades[0] << "/" << o.taguchi_decades[1]
         << "/" << o.taguchi_decades[2]
         << " (paper 10/20/40), the other factors at Table 1's levels (B countries, C "
            "imperialists, read swapped). Response = final cost (Eq. 5 error, %); "
            "smaller-the-better S/N.\n\n";
  if (!failure.empty()) {
    r.text << "Not analysed: a fit failed (" << failure << ").\n\n";
    return;
  }
  const TaguchiAnalysis a = analyze_l27(y);
  r.write("taguchi_sn.csv", taguchi_sn_table(a).csv());
  r.write("taguchi_effects.csv", taguchi_effects_table(a).csv());
  r.write("taguchi_anova.csv", taguchi_anova_table(a).csv());
  r.text << taguchi_effects_table(a).markdown() << "\nChosen levels: **" << a.optimal_levels()
         << "**; paper: **A3 B3 C1 D2 E1 F2 G2**.\n\n"
         << "Reading: A (decades) and B (countries) buy more evaluations, so their best "
            "level is the largest budget unless the runs have converged; the other factors' "
            "effects are small next to the run-to-run noise of one replicate (see "
            "taguchi_anova.csv: F against the unassigned columns), so their chosen levels "
            "are not a robust finding at this budget.\n\n";
}

// The run's cost and the paper preset's estimate: the summary's timings and the report's last
// section.
void report_cost(ReproReport& r, const Timer& timer) {
  ReproSummary& summary = r.summary;
  summary.wall_seconds = timer.wall();
  summary.cpu_seconds = timer.cpu();
  summary.cpu_per_drape =
      summary.fit_drapes > 0 ? summary.fit_cpu_seconds / summary.fit_drapes : 0.0;
  summary.paper_drapes = paper_drape_estimate();
  summary.paper_cpu_estimate = summary.paper_drapes * summary.cpu_per_drape;
  summary.paper_euler_cpu_estimate = summary.paper_drapes * kEulerCpuSecondsPerFourCornerDrape;
  r.text << "## Cost\n\nThis run: " << format_number(summary.wall_seconds, 3) << " s wall, "
         << format_number(summary.cpu_seconds, 3) << " s CPU; " << summary.fit_drapes
         << " four_corner drapes in the fits at " << format_number(summary.cpu_per_drape, 3)
         << " s CPU each.\n\nEstimate of `--preset paper` (Tables 4+6 and Taguchi, ~"
         << summary.paper_drapes << " four_corner drapes, lower bound from the ICA budgets): "
         << format_number(summary.paper_cpu_estimate / 3600.0, 3)
         << " CPU hours with this integrator; with the paper's explicit Euler ("
         << kEulerCpuSecondsPerFourCornerDrape
         << " s CPU per four_corner drape, experiments/benchmark/README.md): "
         << format_number(summary.paper_euler_cpu_estimate / 3600.0 / 24.0 / 365.0, 3)
         << " CPU years.\n";
}

// manifest.json: the configuration and the cost.
void write_manifest(ReproReport& r, const json& config) {
  const ReproSummary& s = r.summary;
  json m = manifest(config);
  m["cost"] = {{"wall_seconds", s.wall_seconds},
               {"cpu_seconds", s.cpu_seconds},
               {"fit_drapes", s.fit_drapes},
               {"fit_cpu_seconds", s.fit_cpu_seconds},
               {"cpu_per_drape", s.cpu_per_drape},
               {"paper_drapes_estimate", s.paper_drapes},
               {"paper_cpu_seconds_estimate", s.paper_cpu_estimate},
               {"paper_euler_cpu_seconds_estimate", s.paper_euler_cpu_estimate}};
  finish_output_folder(r.dir, m);
  r.keep("manifest.json");
}

}  // namespace

ReproSummary run_repro(const ReproOptions& o, ReproTargets& targets, const fs::path& dir,
                       bool resume) {
  const Timer timer;
  const ReproParts parts = parts_of(o.task);
  const bool root = process_rank() == 0;
  targets.generate_missing(o.progress && root);

  json config = options_json(o);
  const json provenance = target_provenance(o, targets);
  config["targets"] = provenance;

  // Every rank computes its share of the units; rank 0 alone writes.
  const std::vector<FitJob> jobs = fit_jobs(o, parts);
  const std::vector<json> fit_results =
      run_fits(o, jobs, targets, unit_options(o, dir, config, resume, repro_checkpoint_files()[0]),
               root);
  const std::vector<json> taguchi_results =
      parts.taguchi ? run_taguchi(o, targets,
                                  unit_options(o, dir, config, resume, repro_checkpoint_files()[1]),
                                  root)
                    : std::vector<json>{};
  ReproSummary summary;
  if (!root) return summary;

  const std::vector<SampleFits> fits = group_fits(jobs, fit_results, targets);
  add_fit_cost(summary, fit_results);
  add_fit_cost(summary, taguchi_results);

  ReproReport report{o, dir, summary, {}};
  report_header(report, provenance);
  std::map<ReproOptimizer, std::vector<SampleFits>> shown;  // the fits Tables 4 and 6 show
  if (parts.tables)
    for (ReproOptimizer m : o.optimizers) shown[m] = table_fits(fits, o, m);
  report_table4(report, shown);
  const std::map<ReproOptimizer, Table> t6s =
      parts.table6 ? report_table6(report, shown, targets) : std::map<ReproOptimizer, Table>{};
  if (shown.count(ReproOptimizer::Lm)) report_lm_vs_ica(report, shown, t6s);
  if (o.pictures && !shown.empty()) report_pictures(report, shown, targets, parts.table6);
  if (parts.fig13) report_fig13(report, fits);
  if (parts.taguchi && !targets.available(o.taguchi_set, o.taguchi_sample))
    report.text << "## Taguchi L27\n\nNot run: target " << to_string(o.taguchi_set) << "_sample"
                << o.taguchi_sample << " " << targets.provenance(o.taguchi_set, o.taguchi_sample)
                << "\n\n";
  if (parts.taguchi && !taguchi_results.empty()) report_taguchi(report, taguchi_results);

  report_cost(report, timer);
  report.write("report.md", report.text.str());
  write_manifest(report, config);
  return summary;
}

}  // namespace knitsim
