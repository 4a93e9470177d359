#include "src/cli/cmd_fit_material.hpp"

#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/fit/material_fit.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/io/material_outputs.hpp"

namespace knitsim {

namespace {

// A parameter's name with its unit, as summary.json's params name them (bending_wale_Nm).
std::string with_unit(int g) {
  const std::string unit = material_gene_units()[g];
  const std::string suffix = unit == "N/m" ? "_N_m" : unit == "N m" ? "_Nm" : "";
  return std::string(material_gene_names()[g]) + suffix;
}

nlohmann::json summary_of(const Scene& base, const MaterialFitCommand& args,
                          const MaterialFitProblem& problem, const MaterialFitResult& fit,
                          const MaterialDrapeResult* drape) {
  nlohmann::json params = nlohmann::json::object(), bounds = nlohmann::json::object();
  nlohmann::json fitted = nlohmann::json::array();
  for (int g = 0; g < kMaterialGenes; ++g) params[with_unit(g)] = fit.parameters[g];
  for (int g : problem.fitted()) {
    fitted.push_back(material_gene_names()[g]);
    bounds[with_unit(g)] = {base.fit_box.lower(g), base.fit_box.upper(g)};
  }
  nlohmann::json combinations = nlohmann::json::array(), errors = nlohmann::json::object();
  const MaterialIdentifiability& id = fit.identifiability;
  for (const MaterialDetermined& c : id.combinations) {
    nlohmann::json w = nlohmann::json::object();
    for (size_t a = 0; a < c.combination.size(); ++a)
      w[material_gene_names()[problem.fitted()[a]]] = c.combination[a];
    combinations.push_back({{"singular_value", c.singular_value},
                            {"ln_weights", w},
                            {"edge_change_percent_for_10_percent", c.edge_change_percent},
                            {"determined", c.determined}});
  }
  for (size_t a = 0; a < id.parameters.size(); ++a) {
    const MaterialParameterError& e = id.parameters[a];
    auto finite = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    errors[material_gene_names()[problem.fitted()[a]]] = {
        {"value", e.value},
        {"relative_standard_error", finite(e.relative_standard_error)},
        {"conditional_relative_error", finite(e.conditional_relative_error)},
        {"on_bound", e.on_bound}};
  }
  return {{"model", "material"},
          {"optimizer", fit.optimizer},
          {"status", fit.ok ? "ok" : "failed"},
          {"message", fit.message},
          {"params", params},
          {"fitted", fitted},
          {"bounds", bounds},
          {"objective", fit.ok ? nlohmann::json(fit.objective) : nlohmann::json()},
          {"evaluations", fit.evaluations},
          {"failed_evaluations", fit.failed_evaluations},
          {"identifiability",
           {{"combinations", combinations},
            {"parameters", errors},
            {"sigma", id.sigma},
            {"determined", id.determined},
            {"determined_threshold_percent", MaterialIdentifiability::kDeterminedPercent}}},
          {"warnings", fit.warnings},
          {"fitted_drape_status",
           drape ? nlohmann::json(to_string(drape->stats.status)) : nlohmann::json("not_run")},
          {"scene", base.name},
          {"sets", args.sets},
          {"target", args.target},
          {"integrator", problem.integrator()},
          {"wall_seconds", fit.wall_seconds},
          {"units",
           {{"params", "membrane_* N/m; poisson 1; bending_* N m"},
            {"objective", "percent (Eq. 5)"},
            {"relative_standard_error", "of ln p (poisson: absolute)"},
            {"wall_seconds", "s"}}}};
}

}  // namespace

void run_material_fit_command(const Scene& base, const Target& target,
                              const MaterialFitCommand& args, const std::filesystem::path& dir) {
  const MaterialFitProblem problem(base, target, args.integrator);
  if (!args.quiet)
    std::cout << "fitting " << base.name << " (material model, " << base.material.cells
              << " cells) to " << args.target << " (scene four_corner, "
              << problem.measured().size() << " edges) with "
              << (args.optimizer == "lm" ? "Levenberg-Marquardt" : "the ICA") << ", "
              << problem.integrator() << "; fitted: " << base.fit_box.parameters << "\n"
              << std::flush;
  const MaterialFitResult fit = args.optimizer == "lm"
                                    ? fit_material_lm(problem, args.starts, args.lm, args.ica.seed)
                                    : fit_material_ica(problem, args.ica);
  std::optional<MaterialDrapeResult> drape;
  Scene fitted_scene = with_material_parameters(base, fit.parameters);
  if (fit.ok) drape.emplace(run_material_drape(fitted_scene, problem.integrator()));
  const std::filesystem::path drape_dir = dir / "drape";
  if (drape) {
    std::filesystem::create_directories(drape_dir);
    write_material_outputs(drape_dir, fitted_scene, *drape);
    if (drape->stats.status == RunStatus::Equilibrium)
      write_edges_csv(measure_material_edges(*drape->sheet, drape->positions),
                      (drape_dir / "edges.csv").string());
    write_edges_csv(problem.measured(), (drape_dir / "target_edges.csv").string());
  }
  write_json_atomic(dir / "summary.json",
                    summary_of(base, args, problem, fit, drape ? &*drape : nullptr));
  finish_output_folder(dir, manifest({{"optimizer", args.optimizer},
                                      {"integrator", problem.integrator()},
                                      {"target", args.target},
                                      {"scene", base.name},
                                      {"sets", args.sets},
                                      {"fit_parameters", base.fit_box.parameters}}));
  if (!args.quiet) {
    Table t;
    t.columns = {"parameter", "fitted", "box", "relative standard error",
                 "if the others were known"};
    auto rel = [](double v) {
      return std::isfinite(v) ? format_number(100.0 * v, 3) + " %" : "none";
    };
    for (int g = 0; g < kMaterialGenes; ++g) {
      std::vector<std::string> row = {
          material_gene_names()[g],
          format_number(fit.parameters[g], 5) + " " + material_gene_units()[g], "held (scene)", "",
          ""};
      for (size_t a = 0; a < problem.fitted().size() && fit.ok; ++a)
        if (problem.fitted()[a] == g) {
          row[2] = format_number(base.fit_box.lower(g), 3) + " .. " +
                   format_number(base.fit_box.upper(g), 3);
          row[3] = rel(fit.identifiability.parameters[a].relative_standard_error);
          row[4] = rel(fit.identifiability.parameters[a].conditional_relative_error);
        }
      t.rows.push_back(row);
    }
    t.rows.push_back(
        {"objective", fit.ok ? format_number(fit.objective, 6) + " %" : "-", "", "", ""});
    t.rows.push_back({"evaluations",
                      std::to_string(fit.evaluations) + " (" +
                          std::to_string(fit.failed_evaluations) + " failed)",
                      "", "", ""});
    t.rows.push_back({"wall", format_number(fit.wall_seconds, 4) + " s", "", "", ""});
    t.rows.push_back({"outputs", dir.string() + "/", "", "", ""});
    std::cout << "status: " << fit.message << "\n" << t.text();
    MaterialFitResult shown = fit;
    shown.warnings.clear();  // on stderr, below
    std::cout << identifiability_text(problem, shown) << std::flush;
  }
  for (const std::string& w : fit.warnings) warn(w);
  if (!fit.ok || !drape || drape->stats.status != RunStatus::Equilibrium)
    throw CLI::RuntimeError(3);
}

}  // namespace knitsim
