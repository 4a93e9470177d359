#include "src/scene/material_run.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace knitsim {

MaterialDrapeResult run_material_drape(const Scene& scene, const std::string& integrator,
                                       RunObserver* observer) {
  scene.validate();
  if (scene.material.kind != DrapeModelKind::Material)
    throw std::logic_error("run_material_drape: model.kind is not material");
  auto integ = make_integrator(integrator);
  MaterialDrapeResult r;
  auto sheet = std::make_shared<const MaterialSheet>(scene.material.sheet(scene.params));
  r.sheet = sheet;
  const MaterialSheet& s = *sheet;
  r.stats = run_to_equilibrium(s, *integ, scene.options, r.state_x, r.state_v, observer, 0.0);
  const double* x = r.state_x.data();
  const int nv = s.vertex_count();
  r.positions.resize(nv);
  r.rest.resize(nv);
  for (int v = 0; v < nv; ++v) {
    r.positions[v] = s.position(x, v);
    r.rest[v] = s.rest_position(v);
  }
  r.energy = s.potential_energy(r.stats.t_final, x);
  const int nx = s.nx(), ny = s.ny();
  double worst = 0.0;
  for (int i = 0; i <= ny; ++i)
    for (int j = 0; j <= nx; ++j) {
      const Vec3 p = r.positions[s.vertex(i, j)];
      if (j < nx) worst = std::max(worst, norm(r.positions[s.vertex(i, j + 1)] - p) / s.hx() - 1.0);
      if (i < ny) worst = std::max(worst, norm(r.positions[s.vertex(i + 1, j)] - p) / s.hy() - 1.0);
      if (!std::isfinite(p.x + p.y + p.z)) worst = std::numeric_limits<double>::quiet_NaN();
    }
  r.max_strain = worst;
  if (scene.material.clamps == ClampLayout::Corners) {
    double z = 0.0;
    int count = 0;
    for (int i : {ny / 2, (ny + 1) / 2})
      for (int j : {nx / 2, (nx + 1) / 2}) z += r.positions[s.vertex(i, j)].z, ++count;
    r.centre_sag = -z / count;  // the clamps stay at z = 0
  } else {
    // The jaw's line: its last clamped row (the row nearest the tip whose vertices are held).
    int jaw = 0;
    while (jaw + 1 <= ny && s.free_index(s.vertex(jaw + 1, 0)) < 0) ++jaw;
    Vec3 tip{}, before{};
    for (int j = 0; j <= nx; ++j) {
      tip = tip + r.positions[s.vertex(ny, j)];
      before = before + r.positions[s.vertex(ny - 1, j)];
    }
    tip = (1.0 / (nx + 1)) * tip;
    before = (1.0 / (nx + 1)) * before;
    const double y0 = jaw * s.hy();
    const double deg = 180.0 / M_PI;
    r.tip_run = tip.y - y0;
    r.tip_drop = -tip.z;
    r.chord_angle_deg = std::atan2(r.tip_drop, r.tip_run) * deg;
    r.tip_slope_deg = std::atan2(before.z - tip.z, tip.y - before.y) * deg;
    r.centre_sag = r.tip_drop;
  }
  return r;
}

std::string material_limit_violation(const MaterialDrapeResult& r) {
  const MaterialSheetParams& p = r.sheet->params();
  if (!std::isfinite(r.max_strain) || !std::isfinite(r.centre_sag))
    return "the final state is not finite";
  if (r.centre_sag > std::max(p.width, p.length))
    return "the sag exceeds the sheet's size (" + std::to_string(r.centre_sag) + " m)";
  return "";
}

}  // namespace knitsim
