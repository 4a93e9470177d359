// What a drape run writes (docs/commands.md, docs/reference/outputs.md): summary.json, nodes.csv,
// drape.vtk, drape.png, edges.csv, state.json, manifest.json; and the parts of a run's summary
// that the knit run shares.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solvers/integrator.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

// The "linear algebra" line of drape's and knit's summaries: "125 symmetric factorisations
// (block LDL^T, 2.12e+09 flops each, 265 GFlop in all)", followed by "; 2401 Krylov iterations"
// where the run iterated (lin_iters: GMRES, or CG between factorisations); "" where it did
// neither (the explicit methods; KLU, whose factorisations are not costed). `static`'s count
// includes the few KLU factorisations of K (the same pattern) of its Newton polish.
std::string linear_algebra_summary(const RunStats& s);

// The "steps" line of drape's and knit's summaries: "14 (RHS 23, Jac 23, LS setups 14)".
std::string steps_summary(const RunStats& s);

// The "certificate" and "residual" lines of drape's and knit's summaries: the certificate, or
// "none" where the stop did not pass; the static residual with the stop's own figure beside it
// (the Newton correction and position_tol, m), or that the residual decided (a singular
// stiffness), or that the stop did not pass.
std::string certificate_summary(const RunStats& s);
std::string residual_summary(const RunStats& s, double position_tol);

// The rows a run's console table shares (drape, material drape, knit): integrator, status,
// certificate, t_final (followed by t_note), steps, linear algebra (where there is any) and
// residual, each as {label, text}.
std::vector<std::vector<std::string>> run_rows(const RunStats& s, double position_tol,
                                               const std::string& t_note = "");

// summary.json's "units": what each number of a run summary is measured in, for a reader
// without the source. `model` maps the model's own numbers (drape or knit: the residual's
// scale, centre_sag_m, params, ...) to their units; times, steps and cost figures are shared.
nlohmann::json summary_units(const nlohmann::json& model);
// The units of a summary's parameter blocks, from the rows of the parameter table (units_text,
// src/scene/scene.hpp): {"params": of `params`' fields, by the rows of `model` (drape or knit),
// "options": of `options`' fields (IntegratorOptions), or under `options_name`}.
nlohmann::json parameter_units(KeyModel model, const nlohmann::json& params,
                               const nlohmann::json& options,
                               const std::string& options_name = "options");
// The field names of a JSON object, in its order.
std::vector<std::string> field_names(const nlohmann::json& object);

// summary.json: scene, source, status, message, integrator, t_final, residual, wall time, all
// RunStats counters, grid size and counts, max strain, centre sag, params, options.
nlohmann::json drape_summary(const Scene& scene, const DrapeResult& result);

// Writes into `dir` (which must exist): summary.json, nodes.csv (id,i,j,x,y,z,pinned; all
// particles at t_final, m), drape.vtk (the grid's quads, point data `pinned` and
// `displacement` = position - rest position, m), state.json (write_run_state: the integrated
// unknowns at t_final; omitted if not finite), manifest.json (options: scene, integrator,
// params, run options), edges.csv (the measured edges, docs/fitting.md) when the final state is finite
// and measurable (else summary.json's `edges_error` says why), and drape.png (render_mesh_png,
// oblique view) unless picture = false (`--no-pictures`, for sweeps: docs/performance.md).
// With `target` (the measured edges of the matching target scene, e.g. fit_target_scene(...)),
// summary.json also gets `objective` (Eq. 5, %) and the per-edge coefficients of both, and
// target_edges.csv is written. edges.csv, target_edges.csv and drape.png, when not written, are
// removed from a reused folder (remove_stale_output).
void write_drape_outputs(const std::filesystem::path& dir, const Scene& scene,
                         const DrapeResult& result, const std::vector<EdgeFit>* target = nullptr,
                         bool picture = true);

// What write_drape_outputs derives from a run before it writes: the measured edges (empty where
// the final state is not finite or not measurable) and summary.json as written (drape_summary
// with edge_coefficients or edges_error, and with `target` the objective and the target's
// coefficients). The Python module returns both without writing.
struct DrapeReport {
  std::vector<EdgeFit> edges;
  nlohmann::json summary;
};
DrapeReport drape_report(const Scene& scene, const DrapeResult& result,
                         const std::vector<EdgeFit>* target = nullptr);
// write_drape_outputs with the report already made (the same files, byte for byte).
void write_drape_outputs(const std::filesystem::path& dir, const Scene& scene,
                         const DrapeResult& result, const DrapeReport& report,
                         const std::vector<EdgeFit>* target = nullptr, bool picture = true);

}  // namespace knitsim
