#include "src/io/material_outputs.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/io/vtk.hpp"

namespace knitsim {

namespace fs = std::filesystem;

nlohmann::json material_summary(const Scene& scene, const MaterialDrapeResult& r) {
  const MaterialSheet& s = *r.sheet;
  nlohmann::json j = to_json(r.stats);
  j["scene"] = scene.name;
  j["source"] = scene.source;
  j["model"] = "material";
  int clamped = 0;
  for (int v = 0; v < s.vertex_count(); ++v) clamped += s.free_index(v) < 0;
  j["mesh"] = {{"cells_x", s.nx()}, {"cells_y", s.ny()},     {"hx_m", s.hx()},
               {"hy_m", s.hy()},    {"vertices", s.vertex_count()}, {"clamped", clamped},
               {"dof", s.dof()}, {"integrated_dof", r.integrated_dof}};
  // The mirrors the run integrated by (model.symmetry resolved), as paper 1's drapes say it.
  j["symmetry"] = symmetry_name(r.mirrors);
  if (r.mirrors.order() == 2) j["mirror"] = r.mirrors.x ? "x" : "y";
  j["whole_sheet_certified"] = r.whole_sheet_checked;
  const bool meaningful = r.stats.status != RunStatus::Diverged;
  const auto figure = [meaningful](double v) {
    return meaningful && std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  };
  j["energy_J"] = figure(r.energy);
  j["max_strain"] = figure(r.max_strain);
  j["max_strain_away_from_clamps"] = figure(r.max_strain_away);
  if (scene.material.clamps == ClampLayout::Corners) {
    j["centre_sag_m"] = figure(r.centre_sag);
  } else {
    j["tip_run_m"] = figure(r.tip_run);
    j["tip_drop_m"] = figure(r.tip_drop);
    j["chord_angle_deg"] = figure(r.chord_angle_deg);
    j["tip_slope_deg"] = figure(r.tip_slope_deg);
  }
  if (const std::string why = material_limit_violation(r); !why.empty()) j["model_limits"] = why;
  j["params"] = material_params_json(scene.material, scene.params);
  j["options"] = to_json(scene.options);
  j["units"] = summary_units(
      {{"residual, residual_floor",
        "1: the static residual, max over free vertices of |net force| / mean vertex weight; "
        "residual_floor: its round-off bound"},
       {"energy_J", "J: potential energy (membrane + bending + gravity) at t_final"},
       {"max_strain", "1: largest (l - h) / h of a grid-line segment, a fraction"},
       {"max_strain_away_from_clamps",
        "1: the same over segments at least clamps.size from every clamp"},
       {"centre_sag_m, tip_run_m, tip_drop_m", "m"},
       {"chord_angle_deg, tip_slope_deg", "degrees below the horizontal"},
       {"mesh", "cells, m (hx_m, hy_m), counts"},
       {"symmetry", "the mirror group integrated (none, half, quarter, eighth); mirror: a half's"},
       {"params", "the unit is in each name: _m, _N_m (N/m), _Nm (N m), _g_m2, _per_s"}});
  j["units"]["options"] = units_text(KeyModel::Both, field_names(j["options"]));
  return j;
}

void write_material_outputs(const fs::path& dir, const Scene& scene,
                            const MaterialDrapeResult& r) {
  const MaterialSheet& s = *r.sheet;
  for (const char* stale : {"edges.csv", "target_edges.csv", "drape.png", "state.json"})
    remove_stale_output(dir / stale);
  write_json_atomic(dir / "summary.json", material_summary(scene, r));
  std::vector<int> clamped(r.positions.size(), 0);
  std::string nodes = "id,i,j,x,y,z,clamped\n";
  for (int i = 0; i <= s.ny(); ++i)
    for (int j = 0; j <= s.nx(); ++j) {
      const int id = s.vertex(i, j);
      clamped[id] = s.free_index(id) < 0;
      const Vec3& p = r.positions[id];
      for (const int k : {id, i, j}) append_integer(nodes, k), nodes += ',';
      for (const double c : {p.x, p.y, p.z}) append_general(nodes, c, 17), nodes += ',';
      append_integer(nodes, clamped[id]);
      nodes += '\n';
    }
  write_file_atomic(dir / "nodes.csv", nodes);
  VtkPolyData vtk;
  vtk.title = "knitsim drape " + scene.name + " (material, " + r.stats.integrator + ", " +
              to_string(r.stats.status) + ")";
  vtk.points = r.positions;
  for (int i = 0; i < s.ny(); ++i)
    for (int j = 0; j < s.nx(); ++j)
      vtk.cells.push_back(
          {s.vertex(i, j), s.vertex(i, j + 1), s.vertex(i + 1, j + 1), s.vertex(i + 1, j)});
  vtk.point_ints.push_back({"clamped", clamped});
  std::vector<Vec3> displacement(r.positions.size());
  for (size_t k = 0; k < displacement.size(); ++k) displacement[k] = r.positions[k] - r.rest[k];
  vtk.point_vectors.push_back({"displacement", displacement});
  write_file_atomic(dir / "drape.vtk", to_vtk(vtk));
  finish_output_folder(dir, manifest({{"scene", scene.name},
                                      {"source", scene.source},
                                      {"integrator", r.stats.integrator},
                                      {"params", material_params_json(scene.material, scene.params)},
                                      {"options", to_json(scene.options)}}));
}

}  // namespace knitsim
