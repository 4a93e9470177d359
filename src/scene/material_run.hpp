// One drape of the material model (model.kind = material; docs/material_drape.md): the scene's
// MaterialSheet (or its mirror reduction, model.symmetry) run to equilibrium with the named integrator, and what its reports show.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "models/material_sheet.hpp"
#include "solvers/integrator.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

struct MaterialDrapeResult {
  std::shared_ptr<const MaterialSheet> sheet;
  RunStats stats;
  std::vector<Vec3> positions;  // every vertex (clamped ones at rest) at t_final, m
  std::vector<Vec3> rest;       // every vertex at t = 0, m
  std::vector<double> state_x, state_v;  // the integrated unknowns at t_final
  // The mirrors the run integrated by (model.symmetry resolved: auto takes the largest group
  // the sheet has, sheet_lacks; none after a whole-sheet continuation), the unknowns it
  // integrated, and whether auto's reduced equilibrium was certified on the whole sheet.
  SheetMirrors mirrors;
  int integrated_dof = 0;
  bool whole_sheet_checked = false;
  double energy = 0.0;      // J: the potential energy at t_final (membrane + bending + gravity)
  double max_strain = 0.0;  // largest (l - h) / h of a grid-line segment (rows and columns)
  // The same over the segments whose rest midpoint is at least clamps.size from every clamp:
  // the peak at a clamp's corner is a singularity of the continuum (docs/material_drape.md).
  double max_strain_away = 0.0;
  // clamps.layout = corners: the clamps' height (0) minus the centre's (the mean of the 1, 2 or
  // 4 vertices nearest the sheet's centre), m.
  double centre_sag = 0.0;
  // clamps.layout = edge (Peirce's cantilever): the tip (the mean of the free end's row)
  // relative to the jaw's line: run along the strip, drop below it (m); the chord from the
  // jaw's line to the tip below the horizontal and the tip's slope (the last segment's), deg.
  double tip_run = 0.0, tip_drop = 0.0, chord_angle_deg = 0.0, tip_slope_deg = 0.0;
};

// Validates `scene` (model.kind must be material), builds its sheet, runs it from the flat
// sheet at rest (throws std::invalid_argument for an unknown integrator, an option the run
// refuses, or a model.symmetry whose mirror the sheet lacks) and measures the result; a run
// that does not reach equilibrium is a status. model.symmetry: none runs the whole sheet; half
// (the x mirror, else the y mirror), quarter (x and y) and eighth (and the diagonal) run the
// MirroredSheet; auto the largest group the sheet has, its equilibrium then certified on the
// whole sheet as paper 1's auto (continue_on_whole_sheet, src/scene/whole_sheet_check.hpp);
// an integrator option that needs the whole sheet then runs it whole.
MaterialDrapeResult run_material_drape(const Scene& scene, const std::string& integrator,
                                       RunObserver* observer = nullptr);

// The mirror group's name as model.symmetry spells it: none, half, quarter or eighth.
const char* symmetry_name(SheetMirrors m);

// A figure of the result outside what the model stands for ("" if none): not finite, or a sag
// or drop larger than the sheet (status outside_model_limits, docs/reliability.md).
std::string material_limit_violation(const MaterialDrapeResult& r);

}  // namespace knitsim
