#include "src/io/yarn_knit_outputs.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "src/io/json.hpp"

namespace knitsim {

namespace {

nlohmann::json number_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; }

}  // namespace

void add_yarn_knit_summary(const YarnKnitRun& run, std::size_t dof, nlohmann::json& summary) {
  const YarnKnit& y = *run.knit;
  summary["model"] = "yarn";
  summary["dof"] = dof;
  nlohmann::json& b = summary["yarn"];
  if (!b.is_object()) b = nlohmann::json::object();
  b["clearance_min_over_d"] = number_or_null(run.clearance_min_over_d);
  b["clearance_start_over_d"] = number_or_null(run.clearance_start_over_d);
  b["clearance_end_over_d"] = number_or_null(run.clearance_end_over_d);
  b["clearance_checks"] = run.clearance_checks;
  nlohmann::json change = nlohmann::json::array(), knitted = nlohmann::json::array();
  double worst = 0.0;
  for (std::size_t j = 0; j < run.course_end.size(); ++j) {
    const double c = run.course_end[j] / run.course_knitted[j] - 1.0;
    change.push_back(number_or_null(c));
    knitted.push_back(run.course_knitted[j]);
    if (!(std::abs(c) <= worst)) worst = std::abs(c);
  }
  const YarnStructure& st = run.structure_end;
  b["interlocks"] = st.interlocks;
  b["loops_withdrawn"] = st.withdrawn;
  b["interlock_gap_max_over_d"] = number_or_null(st.interlock_gap_max_over_d);
  b["interlock_gap_start_max_over_d"] = number_or_null(run.structure_start.interlock_gap_max_over_d);
  b["structure"] = st.lost() ? "lost" : "kept";
  b["course_length_knitted_m"] = knitted;
  b["course_length_change"] = change;  // end against knitted, relative
  b["course_length_change_max"] = number_or_null(worst);
  nlohmann::json stages = nlohmann::json::array();
  for (const YarnKnitRun::Stage& s : run.stages)
    stages.push_back({{"fraction", s.fraction},
                      {"scale", y.ramp_scale(s.fraction)},
                      {"status", to_string(s.status)},
                      {"steps", s.steps},
                      {"residual", number_or_null(s.residual)},
                      {"cpu_seconds", s.cpu_seconds},
                      {"wall_seconds", s.wall_seconds}});
  const YarnParams& p = y.params.yarn;
  summary["yarn_model"] = {
      {"diameter_m", y.d},
      {"start_loop_radius_m", y.r},
      {"start_loop_radius_over_d", y.r / y.d},
      {"vertices", run.vertices},
      {"free_vertices", run.free_vertices},
      {"edges_per_cell", y.params.vertices_per_loop},
      {"pins", y.pins.size()},
      {"stitch_length_m", y.params.stitch_length},
      {"ramp_stages", stages},
      {"ramp_carries_refused", run.carries_refused},
      {"verlet",
       {{"dt_axial_s", run.verlet.dt_axial},
        {"dt_estimated_s", number_or_null(run.verlet.dt_estimated)},
        {"dt_predicted_s", number_or_null(run.verlet.dt_predicted)},
        {"force_cpu_seconds", run.verlet.force_cpu_seconds},
        {"steps_to_steady_state", number_or_null(run.verlet.steps_to_steady)},
        {"cpu_seconds_to_steady_state",
         number_or_null(run.verlet.steps_to_steady * run.verlet.force_cpu_seconds)}}},
      {"pattern_misses", run.pattern_misses},
      {"tex", p.tex},
      {"fibre_density", p.fibre_density},
      {"packing_fraction", p.packing_fraction},
      {"tensile_modulus", p.tensile_modulus},
      {"stretch_stiffness_N", p.stretch_stiffness()},
      {"bending_rigidity", p.bending_rigidity},
      {"relaxation_time", p.relaxation_time},
      {"contact_stiffness", p.contact_kappa()}};
}

}  // namespace knitsim
