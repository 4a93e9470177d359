// knitsim fit on a scene with model.kind = material (docs/fitting.md, "The material model"): the
// material parameters fitted in material units with LM (default for this model's callers: the
// same --optimizer flag) or the ICA, the identifiability of what the edges determine, and the
// fitted drape (src/fit/material_fit.hpp).
// Outputs in --out: summary.json (model "material", optimizer, status, message, params with the
// unit in each name, fitted, bounds, objective, evaluations, failed_evaluations,
// identifiability {combinations, parameters, sigma, determined}, warnings, scene, target,
// integrator, wall_seconds, units), drape/ (the fitted drape as knitsim drape writes it, plus
// edges.csv and target_edges.csv), manifest.json. Exit 3 (after writing) when no start
// evaluated or the fitted drape's re-run does not reach equilibrium.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "src/fit/targets.hpp"
#include "src/scene/fit_options.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

struct MaterialFitCommand {
  std::string optimizer;  // lm | ica
  std::string target;     // the file, for the messages and summary.json
  std::vector<std::string> sets;
  std::string integrator;
  LmStartOptions starts;
  LmOptions lm;
  IcaOptions ica;
  bool quiet = false;
};

void run_material_fit_command(const Scene& base, const Target& target,
                              const MaterialFitCommand& args, const std::filesystem::path& dir);

}  // namespace knitsim
