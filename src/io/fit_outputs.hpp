// What `knitsim fit` writes (docs/commands.md, docs/summary_json.md): the fit's summary.json, its
// table (history.csv of the ICA, starts.csv of the LM fit), the fitted drape's drape/ folder and
// manifest.json, made here once for the command (src/cli/cmd_fit.cpp) and the Python module's
// knitsim.fit (src/python/fit_call.hpp) alike; and the JSON pieces the fit's checkpoint shares.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "src/base/table.hpp"
#include "src/fit/drape_fit.hpp"
#include "src/fit/lm_fit.hpp"
#include "src/io/drape_outputs.hpp"

namespace knitsim {

// summary.json's `units` of a fit: what each number is measured in (lm: the LM fit's fields).
nlohmann::json fit_units(bool lm);
// The fitted parameters {stiffness, damping, elongation_limit, natural_length, topology as text}.
nlohmann::json params_json(const DrapeParams& p);
// The ICA options as summary.json and the checkpoint record them: to_json(o) with seed and jobs.
nlohmann::json ica_json(const IcaOptions& o);
// The search box {gene: [lower, upper]}, genes as drape_gene_names().
nlohmann::json bounds_json(const DrapeFitBounds& b);

// A fit's outputs before they are written.
struct FitReport {
  nlohmann::json settings;  // what was asked: summary.json's first fields, manifest.json's options
  nlohmann::json summary;   // summary.json: settings, then the outcome and `units`
  std::string table_file;   // "history.csv" (ICA) or "starts.csv" (LM)
  // history.csv: decade, best, mean, empires, evaluations; starts.csv: topology, cells,
  // screened, predicted, refined, status, evaluations, objective and the continuous genes.
  Table table;
};

// The report of the ICA fit `fit` of `problem`, whose base scene is `base` (as given to the
// problem), asked with the --set overrides `sets` and the target file `target` (as given).
// `fitted_drape` is the fitted drape's re-run, nullptr where it was not run (a fit cut short:
// fitted_drape_status "not_run"); resumed_from_decade >= 0 records a resumed fit's start.
FitReport ica_fit_report(const Scene& base, const std::vector<std::string>& sets,
                         const std::string& target, const DrapeFitProblem& problem,
                         const DrapeFitResult& fit, const DrapeResult* fitted_drape,
                         int resumed_from_decade = -1);

// The same for the LM fit `fit` run with `lm` (its seed as used); `fitted_drape` nullptr where
// no start was evaluated (fit.ok false: no params, objective or fitted drape in the summary).
FitReport lm_fit_report(const Scene& base, const std::vector<std::string>& sets,
                        const std::string& target, const DrapeFitProblem& problem,
                        const DrapeLmOptions& lm, const DrapeLmResult& fit,
                        const DrapeResult* fitted_drape);

// The fitted drape as drape/ holds it: the best country's scene, its run, the run's report
// against `target` (the target scene's measured edges, DrapeFitProblem::measured()).
struct FittedDrapeOutputs {
  const Scene& scene;
  const DrapeResult& result;
  const DrapeReport& report;
  const std::vector<EdgeFit>& target;
};

// Writes into `dir` (made by make_output_dir): the report's table, drape/ (write_drape_outputs
// with the target: summary.json, nodes.csv, edges.csv, target_edges.csv, drape.vtk, drape.png
// unless picture = false, state.json, manifest.json) unless `drape` is nullptr, summary.json,
// and manifest.json last (finish_output_folder). Not the ICA's checkpoint: the command writes
// it after every decade.
void write_fit_outputs(const std::filesystem::path& dir, const FitReport& report,
                       const FittedDrapeOutputs* drape, bool picture = true);

}  // namespace knitsim
