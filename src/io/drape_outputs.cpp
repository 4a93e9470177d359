#include "src/io/drape_outputs.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/io/run_state.hpp"
#include "src/io/vtk.hpp"
#include "src/measure/measurement.hpp"
#include "src/render/render.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace fs = std::filesystem;

std::string linear_algebra_summary(const RunStats& s) {
  std::string line;
  if (s.factorisations > 0 && s.factor_flops > 0.0)
    line = std::to_string(s.factorisations) + " symmetric factorisations (" + s.factorization +
           (s.factorization == "supernodal" ? " LL^T, " : " LDL^T, ") +
           format_number(s.factor_flops, 3) + " flops each, " +
           format_number(s.factor_flops * static_cast<double>(s.factorisations) / 1e9, 3) +
           " GFlop in all)";
  if (s.lin_iters > 0)
    line += (line.empty() ? "" : "; ") + std::to_string(s.lin_iters) + " Krylov iterations";
  return line;
}

std::string certificate_summary(const RunStats& s) {
  return s.certificate.empty() ? std::string("none") : s.certificate;
}

std::string steps_summary(const RunStats& s) {
  return std::to_string(s.steps) + " (RHS " + std::to_string(s.rhs_evals) + ", Jac " +
         std::to_string(s.jac_evals) + ", LS setups " + std::to_string(s.lin_setups) + ")";
}

std::string residual_summary(const RunStats& s, double position_tol) {
  const std::string r = format_number(s.residual, 3);
  if (s.certificate.empty()) return r + " (the stop did not pass: no Newton correction)";
  if (s.residual_decided) return r + " (the stiffness is singular: the residual decided the stop)";
  return r + " (Newton correction " + format_number(s.newton_step, 3) + " m, tol " +
         format_number(position_tol, 3) + " m)";
}

std::vector<std::vector<std::string>> run_rows(const RunStats& s, double position_tol,
                                               const std::string& t_note) {
  std::vector<std::vector<std::string>> rows = {
      {"integrator", s.integrator},
      {"status", std::string(to_string(s.status)) + " (" + s.message + ")"},
      {"certificate", certificate_summary(s)},
      {"t_final", format_number(s.t_final, 6) + " s" + t_note},
      {"steps", steps_summary(s)}};
  if (const std::string la = linear_algebra_summary(s); !la.empty())
    rows.push_back({"linear algebra", la});
  rows.push_back({"residual", residual_summary(s, position_tol)});
  return rows;
}

nlohmann::json summary_units(const nlohmann::json& model) {
  nlohmann::json units = {
      {"t_start, t_final", "s"},
      {"dt", "s: the fixed step of euler, verlet, implicit-euler; 0 for adaptive integrators"},
      {"dt_estimated, dt_predicted",
       "s: stability limits of the explicit methods (docs/numerics.md)"},
      {"wall_seconds, cpu_seconds", "s (cpu: this process, all threads)"},
      {"factor_flops",
       "floating-point operations of one symmetric factorisation (CHOLMOD's count)"},
      {"factor_nonzeros", "entries of one factor L"},
      {"steps, rhs_evals, jac_evals, lin_setups, lin_iters, nonlin_iters, factorisations",
       "counts"}};
  units.update(model);
  return units;
}

std::vector<std::string> field_names(const nlohmann::json& object) {
  std::vector<std::string> names;
  for (const auto& item : object.items()) names.push_back(item.key());
  return names;
}

nlohmann::json parameter_units(KeyModel model, const nlohmann::json& params,
                               const nlohmann::json& options, const std::string& options_name) {
  return {{"params", units_text(model, field_names(params))},
          {options_name, units_text(KeyModel::Both, field_names(options))}};
}

nlohmann::json drape_summary(const Scene& scene, const DrapeResult& r) {
  const SpringNetwork& net = r.grid.network;
  nlohmann::json j = to_json(r.stats);
  j["scene"] = scene.name;
  j["source"] = scene.source;
  j["grid"] = {{"n", r.grid.n},
               {"particles", net.particle_count()},
               {"pinned", net.spec().pinned.size()},
               {"springs", net.spec().springs.size()},
               {"dof", net.dof()},
               {"integrated_dof", r.integrated_dof}};
  j["t_start"] = r.t_start;
  j["symmetry"] = to_string(r.symmetry);  // the reduction that ran (model.symmetry resolved)
  j["whole_sheet_certified"] = r.whole_sheet_checked;
  // A diverged (runaway) state's figures mean nothing, a non-finite one is none: null; figures
  // past the model's own limits are flagged (model_limits), whatever the status.
  const bool meaningful = r.stats.status != RunStatus::Diverged;
  const auto figure = [meaningful](double v) {
    return meaningful && std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  };
  j["max_strain"] = figure(r.max_strain);
  j["centre_sag_m"] = figure(r.centre_sag);
  if (const std::string why = drape_limit_violation(scene.params, r.max_strain, r.centre_sag);
      !why.empty())
    j["model_limits"] = why;
  j["params"] = to_json(scene.params);
  j["options"] = to_json(scene.options);
  j["units"] = summary_units(
      {{"residual, residual_floor",
        "1: the static residual (docs/equilibrium.md), max over free particles of |spring force + "
        "weight| "
        "/ mean particle weight; residual_floor: its round-off bound"},
       {"centre_sag_m", "m"},
       {"max_strain", "1: (L - L0) / L0 of the most stretched spring, a fraction (stdout: %)"},
       {"objective", "%: the Eq. 5 error against --target"},
       {"edge_coefficients",
        "1: p0..p4 of d(s) = sum p_i s^i, s and d lengths divided by the "
        "edge's reference length (edges.csv; src/measure/measurement.hpp)"}});
  j["units"].update(parameter_units(KeyModel::Drape, j["params"], j["options"]));
  return j;
}

namespace {

// drape.png: the oblique view of the final state, pins marked, parameters in the caption.
void write_drape_picture(const fs::path& path, const Scene& scene, const DrapeResult& r,
                         const std::vector<std::array<int, 4>>& quads) {
  const DrapeGrid& g = r.grid;
  const int side = g.n + 1;
  MeshScene mesh;
  mesh.points = r.positions;
  mesh.quads = quads;
  mesh.markers = g.network.spec().pinned;
  RenderView view;
  // The equilibrium solver's t stays where the pins stop (0 for fixed pins): no time to show.
  view.title = scene.name + ": " + to_string(r.stats.status) +
               (r.stats.certificate.empty() ? "" : " (" + r.stats.certificate + ")") + " by " +
               r.stats.integrator +
               (r.stats.t_final > 0.0 ? " at t = " + format_number(r.stats.t_final, 4) + " s" : "");
  const DrapeParams& p = scene.params;
  view.caption = {"k = " + format_number(p.stiffness) + " N/m, c = " + format_number(p.damping) +
                      " N s/m, L0 = " + format_number(100 * p.natural_length) + " cm, topology " +
                      std::string(1, p.topology) + ", " + format_number(p.areal_density) + " g/m^2",
                  std::to_string(side) + " x " + std::to_string(side) + " particles, centre sag " +
                      format_number(100 * r.centre_sag, 3) + " cm, max strain " +
                      format_number(100 * r.max_strain, 3) + " %, residual " +
                      format_number(r.stats.residual, 2)};
  write_file_atomic_with(path, [&](const std::string& tmp) { render_mesh_png(tmp, mesh, view); });
}

}  // namespace

DrapeReport drape_report(const Scene& scene, const DrapeResult& r,
                         const std::vector<EdgeFit>* target) {
  DrapeReport report{{}, drape_summary(scene, r)};
  nlohmann::json& summary = report.summary;
  std::vector<EdgeFit>& edges = report.edges;
  const bool finite = std::all_of(r.positions.begin(), r.positions.end(), is_finite);
  // The edges of a run that stopped early (a flat sheet, a diverged one) may not be measurable
  // (fit_polynomial needs 5 distinct abscissae): the outputs are still written, with the reason.
  if (finite) {
    try {
      edges = measure_edges(r.grid, r.positions);
    } catch (const std::invalid_argument& e) {
      summary["edges_error"] = e.what();
    }
  }
  if (!edges.empty()) {
    nlohmann::json coefficients = nlohmann::json::object();
    for (const EdgeFit& e : edges)
      coefficients[e.name] = std::vector<double>(e.coefficients.begin(), e.coefficients.end());
    summary["edge_coefficients"] = coefficients;
    if (target) {
      summary["objective"] = objective(*target, edges);
      nlohmann::json target_coefficients = nlohmann::json::object();
      for (const EdgeFit& e : *target)
        target_coefficients[e.name] =
            std::vector<double>(e.coefficients.begin(), e.coefficients.end());
      summary["target_edge_coefficients"] = target_coefficients;
    }
  }
  return report;
}

void write_drape_outputs(const fs::path& dir, const Scene& scene, const DrapeResult& r,
                         const std::vector<EdgeFit>* target, bool picture) {
  write_drape_outputs(dir, scene, r, drape_report(scene, r, target), target, picture);
}

void write_drape_outputs(const fs::path& dir, const Scene& scene, const DrapeResult& r,
                         const DrapeReport& report, const std::vector<EdgeFit>* target,
                         bool picture) {
  const DrapeGrid& g = r.grid;
  const int side = g.n + 1;
  std::vector<int> pinned(r.positions.size(), 0);
  for (int p : g.network.spec().pinned) pinned[p] = 1;

  const nlohmann::json& summary = report.summary;
  const std::vector<EdgeFit>& edges = report.edges;
  if (edges.empty()) remove_stale_output(dir / "edges.csv");
  if (!edges.empty())
    write_file_atomic_with(dir / "edges.csv",
                           [&](const std::string& tmp) { write_edges_csv(edges, tmp); });
  if (target)
    write_file_atomic_with(dir / "target_edges.csv",
                           [&](const std::string& tmp) { write_edges_csv(*target, tmp); });
  else
    remove_stale_output(dir / "target_edges.csv");
  write_json_atomic(dir / "summary.json", summary);

  // %.17g, as a stream at precision 17 wrote them, through std::to_chars.
  std::string nodes = "id,i,j,x,y,z,pinned\n";
  nodes.reserve(nodes.size() + 96 * r.positions.size());
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      const int id = g.index(i, j);
      const Vec3& p = r.positions[id];
      for (const int k : {id, i, j}) append_integer(nodes, k), nodes += ',';
      for (const double c : {p.x, p.y, p.z}) append_general(nodes, c, 17), nodes += ',';
      append_integer(nodes, pinned[id]);
      nodes += '\n';
    }
  write_file_atomic(dir / "nodes.csv", nodes);

  write_run_state(dir, {"drape",
                        {r.stats.t_final, r.state_x, r.state_v},
                        r.stats.integrator,
                        r.stats.dt,
                        drape_model_keys(scene.params)});

  std::vector<std::array<int, 4>> quads;
  for (int i = 0; i < g.n; ++i)
    for (int j = 0; j < g.n; ++j)
      quads.push_back({g.index(i, j), g.index(i, j + 1), g.index(i + 1, j + 1), g.index(i + 1, j)});

  VtkPolyData vtk;
  vtk.title = "knitsim drape " + scene.name + " (" + r.stats.integrator + ", " +
              to_string(r.stats.status) + ", t = " + format_number(r.stats.t_final, 6) + " s)";
  vtk.points = r.positions;
  for (const auto& q : quads) vtk.cells.emplace_back(q.begin(), q.end());
  vtk.point_ints.push_back({"pinned", pinned});
  std::vector<Vec3> displacement(r.positions.size());
  for (size_t k = 0; k < displacement.size(); ++k) displacement[k] = r.positions[k] - r.rest[k];
  vtk.point_vectors.push_back({"displacement", displacement});
  write_file_atomic(dir / "drape.vtk", to_vtk(vtk));

  if (picture)
    write_drape_picture(dir / "drape.png", scene, r, quads);
  else
    remove_stale_output(dir / "drape.png");
  finish_output_folder(dir, manifest({{"scene", scene.name},
                                      {"source", scene.source},
                                      {"integrator", r.stats.integrator},
                                      {"params", to_json(scene.params)},
                                      {"options", to_json(scene.options)}}));
}

}  // namespace knitsim
