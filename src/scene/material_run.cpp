#include "src/scene/material_run.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "src/scene/whole_sheet_check.hpp"

namespace knitsim {

namespace {

// The mirrors model.symmetry asks for (auto: the largest the sheet has); throws
// std::invalid_argument with one line where the sheet lacks one.
SheetMirrors requested_mirrors(const MaterialSheet& s, DrapeSymmetry symmetry) {
  SheetMirrors m;
  switch (symmetry) {
    case DrapeSymmetry::Auto:
      return largest_mirrors(s);
    case DrapeSymmetry::None:
      return m;
    case DrapeSymmetry::Half:
      m.x = true;
      if (!sheet_lacks(s, m).empty() && sheet_lacks(s, SheetMirrors{false, true, false}).empty())
        m = SheetMirrors{false, true, false};
      break;
    case DrapeSymmetry::Quarter:
      m.x = m.y = true;
      break;
    case DrapeSymmetry::Eighth:
      m.x = m.y = m.diagonal = true;
      break;
  }
  if (const std::string why = sheet_lacks(s, m); !why.empty())
    throw std::invalid_argument(std::string("model.symmetry = ") + to_string(symmetry) + ": " +
                                why + " (use a smaller group, auto or none)");
  return m;
}

}  // namespace

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
  r.mirrors = requested_mirrors(s, scene.params.symmetry);
  std::unique_ptr<MirroredSheet> reduced;
  std::vector<double> q, qv;
  if (r.mirrors.order() > 1) {
    reduced = std::make_unique<MirroredSheet>(sheet, r.mirrors);
    try {
      r.stats = run_to_equilibrium(*reduced, *integ, scene.options, q, qv, observer, 0.0);
    } catch (const std::invalid_argument&) {
      // auto: an integrator option that needs the whole sheet (cvode-bdf-gmres's block-Jacobi
      // preconditioner) refuses the reduction at its start: run whole instead (as paper 1's).
      if (scene.params.symmetry != DrapeSymmetry::Auto) throw;
      reduced.reset();
      r.mirrors = SheetMirrors{};
    }
  }
  if (reduced) {
    r.integrated_dof = reduced->dof();
    r.state_x.assign(s.dof(), 0.0);
    r.state_v.assign(s.dof(), 0.0);
    reduced->unfold(q.data(), r.state_x.data());
    if (scene.params.symmetry == DrapeSymmetry::Auto && r.stats.status == RunStatus::Equilibrium) {
      r.whole_sheet_checked = true;
      if (continue_on_whole_sheet(s, *integ, scene.options, observer, 0.0,
                                  symmetry_name(r.mirrors),
                                  r.state_x, r.state_v, r.stats)) {
        r.mirrors = SheetMirrors{};
        r.integrated_dof = s.dof();
      }
    }
  } else {
    r.stats = run_to_equilibrium(s, *integ, scene.options, r.state_x, r.state_v, observer, 0.0);
    r.integrated_dof = s.dof();
  }
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
  // Distance of a rest point from the nearest clamp rectangle.
  const auto from_clamps = [&s](double x0, double y0) {
    double d = std::numeric_limits<double>::infinity();
    for (const SheetPatch& c : s.params().patches) {
      const double dx = std::max({c.x0 - x0, 0.0, x0 - c.x1});
      const double dy = std::max({c.y0 - y0, 0.0, y0 - c.y1});
      d = std::min(d, std::hypot(dx, dy));
    }
    return d;
  };
  const double away = scene.material.clamp_size;
  double worst = 0.0, worst_away = 0.0;
  auto segment = [&](int a, int b, double h) {
    const double e = norm(r.positions[b] - r.positions[a]) / h - 1.0;
    worst = std::max(worst, e);
    const Vec3 m = 0.5 * (r.rest[a] + r.rest[b]);
    if (from_clamps(m.x, m.y) >= away * (1.0 - 1e-9)) worst_away = std::max(worst_away, e);
  };
  bool finite = true;
  for (int i = 0; i <= ny; ++i)
    for (int j = 0; j <= nx; ++j) {
      const Vec3 p = r.positions[s.vertex(i, j)];
      if (j < nx) segment(s.vertex(i, j), s.vertex(i, j + 1), s.hx());
      if (i < ny) segment(s.vertex(i, j), s.vertex(i + 1, j), s.hy());
      finite = finite && std::isfinite(p.x + p.y + p.z);
    }
  r.max_strain = finite ? worst : std::numeric_limits<double>::quiet_NaN();
  r.max_strain_away = finite ? worst_away : std::numeric_limits<double>::quiet_NaN();
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

const char* symmetry_name(SheetMirrors m) {
  const int order = m.order();
  return order == 8 ? "eighth" : order == 4 ? "quarter" : order == 2 ? "half" : "none";
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
