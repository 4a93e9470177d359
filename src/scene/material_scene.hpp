// The material model's part of a drape scene (model.kind = material; docs/material_drape.md):
// its keys (mesh.cells, fabric.length, material.*, clamps.*) and how they make a MaterialSheet.
// fabric.width and fabric.areal_density are shared with paper 1's model (DrapeParams).
//
// Clamps: `corners` holds a square patch of side clamps.size at each of the four corners (the
// four_corner drape with clamps of a size); `edge` holds the strip's y = 0 end over a jaw of
// depth clamps.size and leaves clamps.overhang free beyond it (Peirce's cantilever: the strip
// runs along the wales, y, so the overhang bends with B_w). With `edge` the mesh is laid so that
// the jaw's line falls on a row: n_o = max(2, round(cells overhang / width)) cells on the
// overhang, h_y = overhang / n_o, and the jaw holds 1 + max(1, round(size / h_y)) rows;
// fabric.length is not used (the strip is the jaw plus the overhang).
// Units: SI (m, N/m, N m, 1/s); areal density g/m^2 as paper 1's model.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "models/drape_grid.hpp"
#include "models/material_sheet.hpp"

namespace knitsim {

enum class DrapeModelKind { Paper, Material };
enum class ClampLayout { Corners, Edge };
const char* to_string(DrapeModelKind k);  // paper | material
const char* to_string(ClampLayout c);     // corners | edge

struct MaterialScene {
  DrapeModelKind kind = DrapeModelKind::Paper;  // model.kind
  int cells = 20;                 // mesh.cells: cells along the width, [2, 2000]
  double length = 0.0;            // fabric.length, m along the wales (y); 0 = the width
  double membrane_wale = 1000.0;  // material.membrane_wale, N/m (A_w)
  double membrane_course = 1000.0;  // material.membrane_course, N/m (A_c)
  double membrane_shear = 300.0;  // material.membrane_shear, N/m (A_s)
  double poisson = 0.3;           // material.poisson, nu_cw
  double bending_wale = 1e-5;     // material.bending_wale, N m (B_w)
  double bending_course = 1e-5;   // material.bending_course, N m (B_c)
  double damping = 1e5;           // material.damping, 1/s (mass-proportional rate)
  ClampLayout clamps = ClampLayout::Corners;  // clamps.layout
  double clamp_size = 0.05;       // clamps.size, m
  double overhang = 0.04;         // clamps.overhang, m (edge)

  // Ranges of every field (InvalidField named by its scene key); where kind = material also
  // what depends on the paper's shared keys (`params`: width, symmetry): the clamps fit the
  // sheet, and model.symmetry = eighth only on an isotropic sheet (A_w = A_c, B_w = B_c: an
  // anisotropic sheet has no diagonal mirror; the sheet's other mirrors are checked on the
  // sheet by run_material_drape).
  void validate(const DrapeParams& params) const;
  // The sheet this scene makes (validated first).
  MaterialSheetParams sheet(const DrapeParams& params) const;
};

// summary.json's and manifest.json's `params` of a material run: every material key by name with
// its unit in the name (overhang_m, bending_wale_Nm, ...).
nlohmann::json material_params_json(const MaterialScene& m, const DrapeParams& params);

}  // namespace knitsim
