#include "src/io/fit_outputs.hpp"

#include <cmath>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

nlohmann::json fit_units(bool lm) {
  const std::vector<std::string> genes(drape_gene_names().begin(),
                                       drape_gene_names().begin() + kDrapeContinuous);
  nlohmann::json u = {
      {"params, base_params, bounds, best_country",
       units_text(KeyModel::Drape, genes) +
           "; the topology gene u in [0, 3) (best_country's last entry, bounds.topology)"},
      {"run_options", units_text(KeyModel::Both, field_names(to_json(IntegratorOptions{})))},
      {"objective", "%: the Eq. 5 error of the fitted drape's edges against the target"},
      {"wall_seconds, cpu_seconds", "s"},
      {"evaluations, failed_evaluations", "counts of drapes"}};
  if (lm) {
    u["standard_errors, conditional_standard_errors"] = "the unit of each parameter (params)";
    u["identifiability"] =
        "sigma 1: the standard deviation of the Eq. 5 residuals (a fraction: the objective is "
        "100 x their rms); stiffness_over_length_relative_error 1: a fraction; "
        "condition_number 1; correlation_stiffness_natural_length 1";
    u["starts"] = "screened, predicted, objective %; x as best_country";
  } else {
    u["history"] = "best, mean %: the imperialists' Eq. 5 costs per decade";
  }
  return u;
}

nlohmann::json params_json(const DrapeParams& p) {
  return {{"stiffness", p.stiffness},
          {"damping", p.damping},
          {"elongation_limit", p.elongation_limit},
          {"natural_length", p.natural_length},
          {"topology", std::string(1, p.topology)}};
}

nlohmann::json ica_json(const IcaOptions& o) {
  nlohmann::json j = to_json(o);
  j["seed"] = o.seed;
  j["jobs"] = o.jobs;
  return j;
}

nlohmann::json bounds_json(const DrapeFitBounds& b) {
  nlohmann::json bounds = nlohmann::json::object();
  for (int g = 0; g < kDrapeGenes; ++g) bounds[drape_gene_names()[g]] = {b.lower[g], b.upper[g]};
  return bounds;
}

namespace {

Table history_table(const DrapeFitResult& fit) {
  Table history;
  history.columns = {"decade", "best", "mean", "empires", "evaluations"};
  for (const IcaDecade& d : fit.history)
    history.rows.push_back({std::to_string(d.decade), format_number(d.best_cost, 17),
                            format_number(d.mean_cost, 17), std::to_string(d.empires),
                            std::to_string(d.evaluations)});
  return history;
}

nlohmann::json history_json(const DrapeFitResult& fit) {
  nlohmann::json history = nlohmann::json::array();
  for (const IcaDecade& d : fit.history)
    history.push_back({{"decade", d.decade},
                       {"best", d.best_cost},
                       {"mean", d.mean_cost},
                       {"empires", d.empires},
                       {"evaluations", d.evaluations}});
  return history;
}

}  // namespace

FitReport ica_fit_report(const Scene& base, const std::vector<std::string>& sets,
                         const std::string& target, const DrapeFitProblem& problem,
                         const DrapeFitResult& fit, const DrapeResult* fitted_drape,
                         int resumed_from_decade) {
  FitReport report;
  report.settings = {{"scene", base.name},
                     {"scene_source", base.source},
                     {"sets", sets},
                     {"target", target},
                     {"target_scene", problem.target_scene()},
                     {"optimizer", "ica"},
                     {"integrator", problem.integrator()},
                     {"ica", ica_json(problem.options().ica)},
                     {"bounds", bounds_json(problem.options().bounds)},
                     {"base_params", to_json(base.params)},
                     {"run_options", to_json(base.options)}};
  nlohmann::json& summary = report.summary = report.settings;
  summary["params"] = params_json(fit.params);
  summary["objective"] = fit.objective;
  summary["evaluations"] = fit.evaluations;
  summary["failed_evaluations"] = fit.failed_evaluations;
  summary["status"] = to_string(fit.status);
  summary["message"] = fit.message;
  summary["wall_seconds"] = fit.wall_seconds;
  summary["best_country"] = fit.best_x;
  summary["history"] = history_json(fit);
  summary["fitted_drape_status"] =
      fitted_drape ? std::string(to_string(fitted_drape->stats.status)) : "not_run";
  if (resumed_from_decade >= 0) summary["resumed_from_decade"] = resumed_from_decade;
  summary["units"] = fit_units(false);
  report.table_file = "history.csv";
  report.table = history_table(fit);
  return report;
}

FitReport lm_fit_report(const Scene& base, const std::vector<std::string>& sets,
                        const std::string& target, const DrapeFitProblem& problem,
                        const DrapeLmOptions& lm, const DrapeLmResult& fit,
                        const DrapeResult* fitted_drape) {
  auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; };
  FitReport report;
  report.table_file = "starts.csv";
  Table& starts = report.table;
  starts.columns = {"topology", "cells",  "screened",    "predicted",
                    "refined",  "status", "evaluations", "objective"};
  for (int g = 0; g < kDrapeContinuous; ++g) starts.columns.push_back(drape_gene_names()[g]);
  nlohmann::json starts_json = nlohmann::json::array();
  for (const DrapeLmStart& s : fit.starts) {
    const std::string status = s.refined ? to_string(s.lm.status) : "screened";
    const int evaluations = s.refined ? s.lm.evaluations : 1;
    starts.rows.push_back({std::string(1, s.topology), std::to_string(s.cells),
                           format_number(s.screened, 6), format_number(s.predicted, 6),
                           s.refined ? "1" : "0", status, std::to_string(evaluations),
                           format_number(s.objective, 17)});
    for (int g = 0; g < kDrapeContinuous; ++g)
      starts.rows.back().push_back(format_number(s.x[g], 17));
    starts_json.push_back({{"topology", std::string(1, s.topology)},
                           {"cells", s.cells},
                           {"x0", s.x0},
                           {"x", s.x},
                           {"screened", finite_or_null(s.screened)},
                           {"predicted", finite_or_null(s.predicted)},
                           {"refined", s.refined},
                           {"objective", finite_or_null(s.objective)},
                           {"status", status},
                           {"evaluations", evaluations}});
  }
  const DrapeIdentifiability& id = fit.identifiability;
  nlohmann::json se = nlohmann::json::object(), cse = nlohmann::json::object();
  for (int g = 0; g < kDrapeContinuous; ++g) {
    se[drape_gene_names()[g]] = finite_or_null(id.parameters[g].standard_error);
    cse[drape_gene_names()[g]] = finite_or_null(id.parameters[g].conditional_standard_error);
  }
  report.settings = {{"scene", base.name},
                     {"scene_source", base.source},
                     {"sets", sets},
                     {"target", target},
                     {"target_scene", problem.target_scene()},
                     {"optimizer", "lm"},
                     {"integrator", problem.integrator()},
                     {"lm", to_json(lm)},
                     {"bounds", bounds_json(problem.options().bounds)},
                     {"base_params", to_json(base.params)},
                     {"run_options", to_json(base.options)}};
  nlohmann::json& summary = report.summary = report.settings;
  if (fit.ok) {
    summary["params"] = params_json(fit.params);
    summary["objective"] = fit.objective;
    summary["best_country"] = fit.best_x;
    if (fitted_drape) summary["fitted_drape_status"] = to_string(fitted_drape->stats.status);
  }
  summary["evaluations"] = fit.evaluations;
  summary["failed_evaluations"] = fit.failed_evaluations;
  summary["status"] = fit.ok ? "converged" : "all_failed";
  summary["message"] = fit.message;
  summary["wall_seconds"] = fit.wall_seconds;
  summary["cpu_seconds"] = fit.cpu_seconds;
  summary["standard_errors"] = se;
  summary["conditional_standard_errors"] = cse;
  summary["identifiability"] = {
      {"condition_number", finite_or_null(id.condition_number)},
      {"rank", id.rank},
      {"residuals", id.residuals},
      {"sigma", id.sigma},
      {"correlation_stiffness_natural_length", finite_or_null(id.correlation_stiffness_length)},
      {"stiffness_over_length_relative_error", finite_or_null(id.ratio_relative_error)}};
  summary["starts"] = starts_json;
  summary["units"] = fit_units(true);
  return report;
}

void write_fit_outputs(const std::filesystem::path& dir, const FitReport& report,
                       const FittedDrapeOutputs* drape, bool picture) {
  write_file_atomic(dir / report.table_file, report.table.csv());
  if (drape) {
    const std::filesystem::path drape_dir = dir / "drape";
    std::filesystem::create_directories(drape_dir);
    write_drape_outputs(drape_dir, drape->scene, drape->result, drape->report, &drape->target,
                        picture);
  }
  write_json_atomic(dir / "summary.json", report.summary);
  finish_output_folder(dir, manifest(report.settings));
}

}  // namespace knitsim
