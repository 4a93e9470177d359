// What a material drape writes (model.kind = material; docs/material_drape.md, "Outputs"):
// summary.json, nodes.csv, drape.vtk, manifest.json.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

#include "src/scene/material_run.hpp"

namespace knitsim {

// summary.json: the run's RunStats, scene, source, model "material", the mesh, the measures
// (energy_J, max_strain, max_strain_away_from_clamps; corners: centre_sag_m; edge: tip_run_m, tip_drop_m, chord_angle_deg,
// tip_slope_deg), params (material_params_json: overhang_m, bending_wale_Nm, ...), options,
// units; and model_limits where a figure is outside them.
nlohmann::json material_summary(const Scene& scene, const MaterialDrapeResult& r);

// Writes summary.json, nodes.csv (id,i,j,x,y,z,clamped; every vertex at t_final, m),
// drape.vtk (the grid's quads, point data `clamped` and `displacement`, m) and, last,
// manifest.json into `dir` (which must exist); removes the paper model's other outputs
// (edges.csv, target_edges.csv, drape.png, state.json) from a reused folder.
void write_material_outputs(const std::filesystem::path& dir, const Scene& scene,
                            const MaterialDrapeResult& r);

}  // namespace knitsim
