#include "src/io/yarn_cell_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "src/base/files.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"

namespace knitsim {

namespace {

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; }

}  // namespace

nlohmann::json yarn_cell_summary(const YarnCellRun& run, const std::string& integrator,
                                 const YarnCellPull* pull) {
  const YarnCellStart& st = *run.start;
  const YarnParams& p = st.params.yarn;
  nlohmann::json change = nlohmann::json::array(), knitted = nlohmann::json::array();
  double worst = 0.0;
  for (std::size_t c = 0; c < run.course_end.size(); ++c) {
    const double x = run.course_end[c] / run.course_knitted[c] - 1.0;
    change.push_back(number_or_null(x));
    knitted.push_back(run.course_knitted[c]);
    if (!(std::abs(x) <= worst)) worst = std::abs(x);
  }
  nlohmann::json stages = nlohmann::json::array();
  for (const YarnCellRun::Stage& s : run.stages)
    stages.push_back({{"status", to_string(s.status)},
                      {"steps", s.steps},
                      {"residual", number_or_null(s.residual)},
                      {"cpu_seconds", s.cpu_seconds},
                      {"wall_seconds", s.wall_seconds},
                      {"width_m", s.width},
                      {"height_m", s.height}});
  std::vector<std::string> rows;
  for (int c = st.repeat.courses - 1; c >= 0; --c) {
    std::string row;
    for (int w = 0; w < st.repeat.wales; ++w) row += static_cast<char>(st.repeat.at(w, c));
    rows.push_back(row);
  }
  // Per course (bottom first), per wale: the loop's vertices (the start's arc fractions of its
  // cell, sinker to sinker; the start is uniform in arc), their extents and the yarn's straightness
  // (chord over arc length: a float lying straight is near 1).
  nlohmann::json loops = nlohmann::json::array();
  for (std::size_t c = 0; c < run.end.courses.size() && c < st.cell_start.size(); ++c) {
    const std::vector<Vec3>& v = run.end.courses[c];
    const int n = static_cast<int>(v.size());
    double total = 0.0;
    for (double l : st.cell_start[c]) total += l;
    nlohmann::json row = nlohmann::json::array();
    double before = 0.0;
    for (std::size_t i = 0; i < st.cell_start[c].size(); ++i) {
      const int k0 = static_cast<int>(std::lround(n * before / total));
      before += st.cell_start[c][i];
      const int k1 = static_cast<int>(std::lround(n * before / total));
      // vertex k1 of the last wale is vertex 0 shifted by the period W
      auto at = [&](int k) { return k < n ? v[k] : v[k - n] + Vec3{run.end.width, 0.0, 0.0}; };
      Vec3 lo = at(k0), hi = at(k0);
      double arc = 0.0, z = 0.0;
      for (int k = k0; k < k1; ++k) z += at(k).z / std::max(1, k1 - k0);
      for (int k = k0 + 1; k <= k1; ++k) {
        const Vec3 a = at(k);
        lo = {std::min(lo.x, a.x), std::min(lo.y, a.y), std::min(lo.z, a.z)};
        hi = {std::max(hi.x, a.x), std::max(hi.y, a.y), std::max(hi.z, a.z)};
        arc += norm(a - at(k - 1));
      }
      row.push_back({{"stitch", std::string(1, static_cast<char>(st.repeat.at(
                                                   static_cast<int>(i), static_cast<int>(c))))},
                     {"height_m", hi.y - lo.y},
                     {"width_m", hi.x - lo.x},
                     {"depth_m", hi.z - lo.z},
                     {"z_mean_m", z},
                     {"length_m", arc},
                     {"straightness", arc > 0.0 ? norm(at(k1) - at(k0)) / arc : 0.0}});
    }
    loops.push_back(row);
  }
  const double d = st.d;
  nlohmann::json cell = {{"repeat", rows},
                         {"loops", loops},
                         {"wales", st.repeat.wales},
                         {"courses", st.repeat.courses},
                         {"width_m", run.end.width},
                         {"height_m", run.end.height},
                         {"start_width_m", st.width},
                         {"start_height_m", st.height},
                         {"courses_per_cm", run.courses_per_cm},
                         {"wales_per_cm", run.wales_per_cm},
                         {"stitch_length_m", run.stitch_length},
                         {"tightness_factor", std::sqrt(p.tex) / (run.stitch_length * 1e3)},
                         {"K_c", run.k_c},
                         {"K_w", run.k_w},
                         {"K_s", run.k_s},
                         {"R", run.r},
                         {"clearance_min_over_d", number_or_null(run.clearance_min_over_d)},
                         {"clearance_start_over_d", number_or_null(run.clearance_start_over_d)},
                         {"clearance_end_over_d", number_or_null(run.clearance_end_over_d)},
                         {"clearance_checks", run.clearance_checks},
                         {"course_length_knitted_m", knitted},
                         {"course_length_change", change},
                         {"course_length_change_max", number_or_null(worst)},
                         {"dE_dW_N", number_or_null(run.size_gradient[0])},
                         {"dE_dH_N", number_or_null(run.size_gradient[1])},
                         {"status", to_string(run.stats.status)},
                         {"message", run.stats.message},
                         {"steps", run.stats.steps},
                         {"cpu_seconds", run.stats.cpu_seconds},
                         {"wall_seconds", run.stats.wall_seconds},
                         {"stages", stages},
                         {"dof", run.dof},
                         {"edges_per_wale", st.params.vertices_per_loop},
                         {"start_loop_radius_over_d", st.r / d}};
  nlohmann::json pulled = nullptr;
  if (pull) {
    nlohmann::json status = nlohmann::json::array();
    for (RunStatus s : pull->status) status.push_back(to_string(s));
    pulled = {{"direction", pull->along_courses ? "course" : "wale"},
              {"strain", pull->strain},
              {"reaction_N", pull->reaction},
              {"force_per_width_N_per_m", pull->force_per_width},
              {"lateral_strain", pull->lateral_strain},
              {"status", status},
              {"steps", pull->steps},
              {"cpu_seconds", pull->cpu_seconds}};
  }
  return {{"command", "knit"},
          {"pull", pulled},
          {"model", "yarn"},
          {"boundary", "periodic"},
          {"integrator", integrator},
          {"status", to_string(run.stats.status)},
          {"cell", cell},
          {"yarn_model",
           {{"diameter_m", d},
            {"tex", p.tex},
            {"fibre_density", p.fibre_density},
            {"packing_fraction", p.packing_fraction},
            {"tensile_modulus", p.tensile_modulus},
            {"stretch_stiffness_N", p.stretch_stiffness()},
            {"bending_rigidity", p.bending_rigidity},
            {"relaxation_time", p.relaxation_time},
            {"contact_stiffness", p.contact_kappa()}}},
          {"units",
           {{"cell",
             "width_m, height_m, stitch_length_m, course_length_knitted_m m; "
             "courses_per_cm, wales_per_cm 1/cm; loops (per course, bottom first, per "
             "wale: its yarn, sinker to sinker) height_m, width_m, depth_m, z_mean_m, "
             "length_m m, straightness (chord / length) 1; K_c, K_w, K_s, R, tightness_factor "
             "(sqrt(tex) / l in mm) 1; clearance_*_over_d d; course_length_change "
             "relative; dE_dW_N, dE_dH_N N per cell; cpu_seconds, wall_seconds s"},
            {"pull",
             "strain, lateral_strain 1; reaction_N N per cell; force_per_width_N_per_m "
             "N/m (per rest width: H0 along the courses, W0 along the wales)"}}}};
}

void write_yarn_cell_outputs(const std::filesystem::path& dir, const YarnCellRun& run,
                             const std::string& integrator, const nlohmann::json& options,
                             const YarnCellPull* pull) {
  write_json_atomic(dir / "summary.json", yarn_cell_summary(run, integrator, pull));
  if (pull) {
    std::ostringstream p;
    p.precision(10);
    p << "step,strain,reaction_N,force_per_width_N_per_m,lateral_strain,status,steps\n";
    for (std::size_t k = 0; k < pull->strain.size(); ++k)
      p << k << ',' << pull->strain[k] << ',' << pull->reaction[k] << ','
        << pull->force_per_width[k] << ',' << pull->lateral_strain[k] << ','
        << to_string(pull->status[k]) << ',' << pull->steps[k] << '\n';
    write_file_atomic(dir / "cell_pull.csv", p.str());
  }
  std::ostringstream csv;
  csv.precision(10);
  csv << "course,vertex,x_m,y_m,z_m\n";
  for (std::size_t c = 0; c < run.end.courses.size(); ++c)
    for (std::size_t k = 0; k < run.end.courses[c].size(); ++k) {
      const Vec3& v = run.end.courses[c][k];
      csv << c << ',' << k << ',' << v.x << ',' << v.y << ',' << v.z << '\n';
    }
  write_file_atomic(dir / "cell_yarn.csv", csv.str());
  finish_output_folder(dir, manifest(options));
}

}  // namespace knitsim
