// knitsim.fit without Python: the ICA drape fit as `knitsim fit` runs it (src/cli/cmd_fit.cpp,
// the ICA optimizer), on the same functions: load_scene with the overrides, rtol 1e-8 unless
// given, read_target_csv, DrapeFitProblem, fit_drape; then the fitted drape re-run and measured
// (drape_report against the target), as fit's drape/ folder holds it; the fit's summary.json
// and history.csv by the command's own function (src/io/fit_outputs.hpp). Writes nothing until
// write_fit_call; no checkpoint (a fit cut short is not resumed from Python).
//
// Failure modes: bad input throws std::invalid_argument with the command line's one-line message
// (the ICA's options renamed to their flags, "--countries = 1: ..."); every evaluation failing is
// the status all_failed, not an exception.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "src/fit/drape_fit.hpp"
#include "src/io/fit_outputs.hpp"
#include "src/python/drape_call.hpp"

namespace knitsim {

struct FitRequest {
  std::string scene = "four_corner";   // base scene (--scene)
  std::vector<std::string> overrides;  // --set
  std::string target;                  // --target (required)
  std::string integrator;              // "" = default_integrator()
  // By flag name without "--", "_" for "-": rtol, atol, velocity_atol, seed, jobs, decades,
  // countries, imperialists, beta, gamma, revolution, xi, stop_one_empire (fit_option_flags()).
  std::vector<std::pair<std::string, std::string>> options;
  // The search box by gene (drape_gene_names()): (gene, lower, upper); the rest keep Table 3's.
  std::vector<std::tuple<std::string, double, double>> bounds;
};

struct FitCall {
  DrapeFitResult fit;
  std::string integrator;
  std::string target_scene;
  // The fitted drape, re-run (not for a fit cut short, whose best country is provisional).
  std::shared_ptr<DrapeCall> drape;
  FitReport report;  // summary.json, history.csv and the manifest's options, as the command's
};

// (name, flag) of the options FitRequest::options takes.
const std::vector<std::pair<std::string, std::string>>& fit_option_flags();

// `stop`, when set, is asked after every decade (on the calling thread): true ends the fit there
// with status interrupted.
FitCall fit_call(const FitRequest& request, const std::function<bool()>& stop = nullptr);

// Writes the files `knitsim fit --out folder` writes but the checkpoint (write_fit_outputs:
// history.csv, drape/ with drape.png unless picture = false, summary.json, manifest.json) into
// `folder`, made as --out makes it (make_output_dir). Returns the folder's path.
std::string write_fit_call(const FitCall& call, const std::string& folder, bool picture = true);

}  // namespace knitsim
