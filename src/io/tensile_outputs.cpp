#include "src/io/tensile_outputs.hpp"

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/render/plot.hpp"

namespace knitsim {

namespace fs = std::filesystem;

std::string tensile_csv(const TensileResult& r) {
  std::string out =
      "step,strain,displacement_m,force_N,force_per_width_N_per_m,lateral_strain,energy_J,status,"
      "newton_steps,reaction_fixed_x_N,reaction_fixed_y_N,reaction_moving_x_N,"
      "reaction_moving_y_N\n";
  for (const TensileStep& s : r.steps) {
    out += std::to_string(s.step);
    for (double v : {s.strain, s.displacement, s.force, s.force_per_width, s.lateral_strain,
                     s.energy}) {
      out += ',';
      append_number(out, v);
    }
    out += ',' + s.status + ',' + std::to_string(s.stats.steps);
    for (const Vec3& q : s.reactions) {
      out += ',';
      append_number(out, q.x);
      out += ',';
      append_number(out, q.y);
    }
    out += '\n';
  }
  return out;
}

nlohmann::json tensile_summary(const KnitScene& scene, const TensileOptions& o,
                               const TensileResult& r) {
  nlohmann::json steps = nlohmann::json::array();
  long newton = 0;
  for (const TensileStep& s : r.steps) {
    nlohmann::json reactions = nlohmann::json::array();
    for (const Vec3& q : s.reactions) reactions.push_back({q.x, q.y, q.z});
    steps.push_back({{"step", s.step},
                     {"strain", s.strain},
                     {"force_N", s.force},
                     {"status", s.status},
                     {"newton_steps", s.stats.steps},
                     {"factorisations", s.stats.factorisations},
                     {"stop_factorisations", s.stats.stop_factorisations},
                     {"cpu_seconds", s.stats.cpu_seconds},
                     {"certificate", s.stats.certificate},
                     {"saddle_escapes", s.stats.saddle_escapes},
                     {"reactions_N", reactions}});
    newton += s.stats.steps;
  }
  const bool stiff = r.steps.size() > 1 && r.steps[1].strain > 0.0;
  const int run = static_cast<int>(r.steps.size()) - 1;
  return {{"chart", scene.name},
          {"chart_file", scene.chart_file},
          {"direction", o.direction},
          {"steps", o.steps},
          {"strain", o.strain},
          {"gauge_ratio", o.gauge_ratio},
          {"unload", o.unload},
          {"specimen_wales", r.specimen.wales},
          {"specimen_courses", r.specimen.courses},
          {"gauge_m", r.gauge},
          {"width_m", r.width},
          {"clamps", {r.model.clamps[0].name, r.model.clamps[1].name}},
          {"status", r.complete ? "complete" : r.steps.back().status},
          {"steps_run", run},
          {"newton_steps", newton},
          {"newton_steps_per_step", run > 0 ? static_cast<double>(newton) / run : 0.0},
          {"initial_stiffness_N_per_m",
           stiff ? nlohmann::json((r.steps[1].force_per_width - r.steps[0].force_per_width) /
                                  r.steps[1].strain)
                 : nlohmann::json(nullptr)},
          {"initial_poisson_ratio",
           stiff ? nlohmann::json(-(r.steps[1].lateral_strain - r.steps[0].lateral_strain) /
                                  r.steps[1].strain)
                 : nlohmann::json(nullptr)},
          {"cpu_seconds", r.cpu_seconds},
          {"wall_seconds", r.wall_seconds},
          {"per_step", steps},
          {"options", to_json(scene.options)},
          {"units",
           {{"strain", "1"},
            {"force_N", "N"},
            {"force_per_width", "N/m"},
            {"gauge_m", "m"},
            {"width_m", "m"},
            {"initial_stiffness_N_per_m",
             "N/m (force per rest width per unit strain, steps 0 to 1)"},
            {"reactions_N", "N, the force each clamp (fixed, moving) exerts on the fabric"}}}};
}

void write_tensile_outputs(const fs::path& dir, const KnitScene& scene, const TensileOptions& o,
                           const TensileResult& r, bool pictures) {
  write_file_atomic(dir / "tensile.csv", tensile_csv(r));
  if (pictures && r.steps.size() > 1) {
    LinePlot plot;
    plot.title = scene.name + ": tensile test along the " + o.direction + "s (" +
                 std::to_string(r.specimen.wales) + " wales x " +
                 std::to_string(r.specimen.courses) + " courses)";
    plot.x_label = "strain";
    plot.y_label = "force per width, N/m";
    PlotSeries load{"loading", {}, {}, {0.12, 0.35, 0.70}, false, true};
    PlotSeries unload{"unloading", {}, {}, {0.80, 0.25, 0.15}, true, true};
    for (std::size_t k = 0; k < r.steps.size(); ++k) {
      PlotSeries& s = static_cast<int>(k) <= o.steps ? load : unload;
      if (static_cast<int>(k) > o.steps && unload.x.empty())
        unload.x.push_back(r.steps[k - 1].strain), unload.y.push_back(r.steps[k - 1].force_per_width);
      s.x.push_back(r.steps[k].strain);
      s.y.push_back(r.steps[k].force_per_width);
    }
    plot.series.push_back(load);
    if (!unload.x.empty()) plot.series.push_back(unload);
    render_line_plot_png((dir / "tensile.png").string(), plot);
  } else {
    remove_stale_output(dir / "tensile.png");
  }
  write_json_atomic(dir / "summary.json", tensile_summary(scene, o, r));
  finish_output_folder(dir, manifest({{"chart", scene.chart_file},
                                      {"direction", o.direction},
                                      {"steps", o.steps},
                                      {"strain", o.strain},
                                      {"gauge_ratio", o.gauge_ratio},
                                      {"unload", o.unload},
                                      {"options", to_json(scene.options)}}));
}

}  // namespace knitsim
