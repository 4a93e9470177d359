#include "src/scene/material_scene.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "src/core/invalid_field.hpp"

namespace knitsim {

const char* to_string(DrapeModelKind k) { return k == DrapeModelKind::Paper ? "paper" : "material"; }
const char* to_string(ClampLayout c) { return c == ClampLayout::Corners ? "corners" : "edge"; }

namespace {

void positive(const char* key, double v, double hi, const char* unit) {
  if (!(v > 0.0 && v <= hi)) {
    std::ostringstream os;
    os << "must be in (0, " << hi << "] " << unit;
    bad_field(key, v, os.str());
  }
}

// Cells on the overhang of an edge clamp, and the jaw's rows beyond the first.
void edge_mesh(const MaterialScene& m, double width, int& overhang_cells, int& jaw_cells) {
  overhang_cells = std::max(2, static_cast<int>(std::lround(m.cells * m.overhang / width)));
  const double hy = m.overhang / overhang_cells;
  jaw_cells = std::max(1, static_cast<int>(std::lround(m.clamp_size / hy)));
}

}  // namespace

void MaterialScene::validate(const DrapeParams& params) const {
  if (!(cells >= 2 && cells <= 2000)) bad_field("mesh.cells", cells, "must be in [2, 2000]");
  if (!(length >= 0.0 && length <= 100.0))
    bad_field("fabric.length", length, "must be in [0, 100] m (0 = the width: a square)");
  positive("material.membrane_wale", membrane_wale, 1e9, "N/m");
  positive("material.membrane_course", membrane_course, 1e9, "N/m");
  positive("material.membrane_shear", membrane_shear, 1e9, "N/m");
  if (!(std::abs(poisson) < 0.99))
    bad_field("material.poisson", poisson,
              "must be in (-0.99, 0.99) (and poisson^2 A_w / A_c < 1)");
  if (poisson * poisson * membrane_wale / membrane_course >= 1.0) {
    std::ostringstream os;
    os << "must satisfy poisson^2 x membrane_wale / membrane_course < 1 (here "
       << poisson * poisson * membrane_wale / membrane_course << ")";
    bad_field("material.poisson", poisson, os.str());
  }
  positive("material.bending_wale", bending_wale, 1.0, "N m");
  positive("material.bending_course", bending_course, 1.0, "N m");
  if (!(damping >= 0.0 && damping <= 1e9))
    bad_field("material.damping", damping, "must be in [0, 1e9] 1/s");
  positive("clamps.size", clamp_size, 100.0, "m");
  positive("clamps.overhang", overhang, 100.0, "m");
  if (kind != DrapeModelKind::Material) return;
  // The diagonal mirror (an eighth) needs an isotropic sheet; the rest of what a mirror needs
  // (symmetric clamps, a square mesh) is checked on the sheet itself (sheet_lacks).
  if (params.symmetry == DrapeSymmetry::Eighth &&
      !(membrane_wale == membrane_course && bending_wale == bending_course))
    throw std::invalid_argument(
        "model.symmetry = eighth: the sheet has no diagonal mirror (it needs "
        "material.membrane_wale = material.membrane_course and material.bending_wale = "
        "material.bending_course; use quarter or auto)");
  const double width = params.width, len = length > 0.0 ? length : width;
  if (clamps == ClampLayout::Corners && !(2.0 * clamp_size < std::min(width, len))) {
    std::ostringstream os;
    os << "must be < half the sheet's shorter side, " << 0.5 * std::min(width, len)
       << " m (clamps.layout = corners)";
    bad_field("clamps.size", clamp_size, os.str());
  }
  if (clamps == ClampLayout::Corners && !(clamp_size >= width / cells * (1.0 - 1e-9))) {
    std::ostringstream os;
    os << "must be >= one cell, fabric.width / mesh.cells = " << width / cells
       << " m (a clamp holds the slope: 2 x 2 vertices at least)";
    bad_field("clamps.size", clamp_size, os.str());
  }
  if (clamps == ClampLayout::Edge) {
    int no = 0, nj = 0;
    edge_mesh(*this, width, no, nj);
    if (no + nj > 20000)
      bad_field("mesh.cells", cells, "must give at most 20000 cells along the strip");
  } else if (std::lround(cells * len / width) > 20000) {
    bad_field("mesh.cells", cells, "must give at most 20000 cells along the length");
  }
}

MaterialSheetParams MaterialScene::sheet(const DrapeParams& params) const {
  validate(params);
  MaterialSheetParams s;
  s.width = params.width;
  s.areal_density = params.areal_density;
  s.cells = cells;
  s.membrane_wale = membrane_wale;
  s.membrane_course = membrane_course;
  s.membrane_shear = membrane_shear;
  s.poisson_cw = poisson;
  s.bending_wale = bending_wale;
  s.bending_course = bending_course;
  s.damping_rate = damping;
  if (clamps == ClampLayout::Edge) {
    int no = 0, nj = 0;
    edge_mesh(*this, params.width, no, nj);
    const double hy = overhang / no;
    s.cells_length = no + nj;
    s.length = overhang + nj * hy;
    s.patches.push_back({0.0, 0.0, params.width, nj * hy});
  } else {
    s.length = length > 0.0 ? length : params.width;
    const double a = clamp_size, w = s.width, l = s.length;
    s.patches = {{0.0, 0.0, a, a}, {w - a, 0.0, w, a}, {0.0, l - a, a, l}, {w - a, l - a, w, l}};
  }
  return s;
}

nlohmann::json material_params_json(const MaterialScene& m, const DrapeParams& p) {
  nlohmann::json j = {{"kind", to_string(m.kind)},
                      {"width_m", p.width},
                      {"areal_density_g_m2", p.areal_density},
                      {"cells", m.cells},
                      {"membrane_wale_N_m", m.membrane_wale},
                      {"membrane_course_N_m", m.membrane_course},
                      {"membrane_shear_N_m", m.membrane_shear},
                      {"poisson", m.poisson},
                      {"bending_wale_Nm", m.bending_wale},
                      {"bending_course_Nm", m.bending_course},
                      {"damping_per_s", m.damping},
                      {"clamps", to_string(m.clamps)},
                      {"clamp_size_m", m.clamp_size}};
  if (m.clamps == ClampLayout::Edge)
    j["overhang_m"] = m.overhang;
  else
    j["length_m"] = m.length > 0.0 ? m.length : p.width;
  return j;
}

}  // namespace knitsim
