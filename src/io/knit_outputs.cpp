#include "src/io/knit_load_outputs.hpp"
#include "src/io/knit_outputs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <list>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/io/run_state.hpp"
#include "src/io/textile_outputs.hpp"
#include "src/io/vtk.hpp"
#include "src/io/yarn_knit_outputs.hpp"
#include "src/render/render.hpp"

namespace knitsim {

namespace {

namespace fs = std::filesystem;

// One line of fields separated by commas: the integers, then the numbers (shortest exact text).
void append_row(std::string& out, std::initializer_list<long long> ints,
                std::initializer_list<double> numbers) {
  bool first = true;
  for (long long v : ints) {
    if (!first) out += ',';
    append_integer(out, v);
    first = false;
  }
  for (double v : numbers) {
    if (!first) out += ',';
    append_number(out, v);
    first = false;
  }
  out += '\n';
}

// One VTK polyline per course centreline, cell data `course`.
std::string centerlines_vtk(const std::string& title, const std::vector<CurveSamples>& lines) {
  VtkPolyData vtk;
  vtk.title = title;
  vtk.kind = VtkPolyData::Cells::Lines;
  vtk.digits = 0;  // shortest round-trip, as the CSV files
  std::vector<int> course;
  for (const CurveSamples& c : lines) {
    std::vector<int> cell;
    for (const Vec3& p : c.points) {
      cell.push_back(static_cast<int>(vtk.points.size()));
      vtk.points.push_back(p);
    }
    course.push_back(static_cast<int>(vtk.cells.size()));
    vtk.cells.push_back(std::move(cell));
  }
  vtk.cell_ints.push_back({"course", std::move(course)});
  return to_vtk(vtk);
}

// "stabilised network (s 0.1)" or "paper 2's network (a mechanism)".
std::string network_label(const KnitParams& p) {
  return p.mechanism()
             ? "paper 2's network (a mechanism)"
             : "stabilised network (s " + format_number(p.stabiliser_ratio, 3) +
                   (p.out_of_plane_bending()
                        ? ", out-of-plane bending b " + format_number(p.bending_ratio, 3)
                        : std::string()) +
                   (p.yarn_contact() ? ", yarn contact c " + format_number(p.contact_ratio, 3)
                                     : std::string()) +
                   ")";
}

// Front view of the centrelines (z-buffered tubes, render_strokes_png), courses in alternating
// colours, interlacing points as dots.
void render_front(const fs::path& path, const KnitModel& m, const std::vector<Vec3>& pos,
                  const std::vector<CurveSamples>& lines, const std::string& title) {
  std::vector<Stroke> strokes;
  for (size_t j = 0; j < lines.size(); ++j) {
    Stroke s;
    s.points = lines[j].points;
    s.radius = 0.35 * m.params.loop_radius;
    s.color = j % 2 == 0 ? Rgb{0.85, 0.35, 0.20} : Rgb{0.25, 0.45, 0.75};
    strokes.push_back(std::move(s));
  }
  RenderView view;
  view.front_xy = true;
  view.title = title;
  view.caption = {std::to_string(m.chart.wales) + " wales x " + std::to_string(m.chart.courses) +
                  " courses, r = " + format_number(1e3 * m.params.loop_radius, 3) + " mm, " +
                  network_label(m.params)};
  write_file_atomic_with(
      path, [&](const std::string& tmp) { render_strokes_png(tmp, strokes, pos, view); });
}

nlohmann::json params_json(const KnitParams& p) {
  return {{"loop_radius", p.loop_radius},
          {"wale_stiffness", p.wale_stiffness},
          {"course_stiffness", p.course_stiffness},
          {"damping", p.damping},
          {"areal_density", p.areal_density},
          {"stabiliser_ratio", p.stabiliser_ratio},
          {"bending_ratio", p.out_of_plane_bending() ? p.bending_ratio : 0.0},
          {"contact_ratio", p.yarn_contact() ? p.contact_ratio : 0.0},
          {"network", p.mechanism() ? "paper" : "stabilised"}};
}

nlohmann::json measures_json(const KnitMeasures& k) {
  const YarnClearance& c = k.min_clearance;
  return {{"clearance_min_over_r", c.over_r},
          {"clearance_min_t", k.t_min_clearance},
          {"clearance_min_check", k.check_min_clearance},
          {"clearance_min_courses", {c.a.course, c.b.course}},
          {"clearance_min_where", {c.where.x, c.where.y, c.where.z}},
          {"clearance_end_over_r", k.end_clearance},
          {"clearance_rest_over_r", k.rest_clearance},
          {"clearance_measured_states", k.measured_states},
          {"clearance_cpu_seconds", k.measure_cpu_seconds},
          {"clearance_min_resolution_over_r", k.min_resolution},
          {"crossings_designed", k.crossings.designed},
          {"crossings_changed", k.crossings.changed}};
}

// The yarn contact's state at the end of a run (null without contact): its closest points and
// how many pairs touch, and its counters over the run (models/yarn_contact.hpp).
nlohmann::json contact_json(const KnitModel& m, double t, const std::vector<double>& x) {
  if (!m.contact) return nullptr;
  const ContactNetwork& c = *m.contact;
  int touching = 0;
  const double closest = c.min_distance(t, x.data(), &touching);
  return {{"points", c.points().size()},
          {"min_point_distance_over_r", std::isfinite(closest)
                                            ? nlohmann::json(closest / m.params.loop_radius)
                                            : nlohmann::json(nullptr)},
          {"pairs_in_contact", touching},
          {"renewed_yarns", c.refreshes()},
          {"renewals_cut", c.cut_renewals()},
          {"pattern_misses", c.pattern_misses()},
          {"list_rebuilds", c.list_rebuilds()},
          {"list_sweeps", c.list_sweeps()}};
}

// summary.json's `clamps` (a chart with clamps only): each clamp's name, points, displacement
// from rest (m) and reaction (N, the force it exerts on the fabric), and the balance of the
// reactions and the weight (N; zero at an equilibrium, to the residual).
nlohmann::json clamps_json(const KnitModel& m, double t, const std::vector<double>& x) {
  nlohmann::json list = nlohmann::json::array();
  Vec3 sum = knit_weight(m);
  auto vec = [](Vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); };
  for (const ClampReaction& c : knit_clamp_reactions(m, t, x)) {
    list.push_back({{"name", c.name},
                    {"points", c.points},
                    {"displacement_m", vec(c.displacement)},
                    {"reaction_N", vec(c.reaction)}});
    sum = sum + c.reaction;
  }
  return {{"each", list}, {"weight_N", vec(knit_weight(m))}, {"balance_N", vec(sum)}};
}

// summary.json's `units` for a knit run's own numbers (summary_units adds the shared ones; those
// of its params and options come from the parameter table's rows).
nlohmann::json knit_units(const nlohmann::json& params, const nlohmann::json& options) {
  nlohmann::json units = summary_units(
      {{"residual, residual_floor",
        "1: the static residual (docs/equilibrium.md), max over free points of |net force| / "
        "(k_w r), a wale spring stretched by one loop radius (with gravity: or the mean point "
        "weight, the smaller)"},
       {"max_displacement_over_r", "1: largest displacement / loop radius"},
       {"yarn",
        "clearance_*_over_r 1: smallest segment-to-segment distance between yarn centreline "
        "pieces of different courses (or one course, >= pi r apart along it) / loop radius, 2 = "
        "at least 2; clearance_min_t s; clearance_min_check: its residual check (0: the start); "
        "clearance_min_where m; clearance_min_resolution_over_r 1: a dip between measured states "
        "shallower than this can be missed; clearance_cpu_seconds s: the measuring inside the "
        "run, part of stats.cpu_seconds; crossings: designed front-view crossings at rest and "
        "how many changed over/under order at the end"},
       {"fabric", kFabricUnits},
       {"contact",
        "null without yarn contact; min_point_distance_over_r 1: the closest two contact points "
        "at the end / loop radius (null: no pair within reach); pairs_in_contact: pairs closer "
        "than the touching distance r; renewed_yarns, renewals_cut, pattern_misses, "
        "list_rebuilds, list_sweeps: counts over the run (docs/knit.md, Yarn contact)"}});
  units.update(parameter_units(KeyModel::Knit, params, options));
  return units;
}

// The centrelines of each distinct state, computed once (the first frame is the rest state, the
// last usually the end state); a list, so references to its entries stay valid. A state that is
// not finite has none.
class CenterlineCache {
 public:
  explicit CenterlineCache(const KnitModel& m) : m_(m) {}
  const std::vector<CurveSamples>& of(const std::vector<Vec3>& state) {
    if (!std::all_of(state.begin(), state.end(), is_finite)) return none_;
    for (const auto& c : computed_)
      if (std::equal(c.first.begin(), c.first.end(), state.begin(), state.end(),
                     [](Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }))
        return c.second;
    computed_.emplace_back(state, course_centerlines(m_, state));
    return computed_.back().second;
  }

 private:
  const KnitModel& m_;
  std::list<std::pair<std::vector<Vec3>, std::vector<CurveSamples>>> computed_;
  const std::vector<CurveSamples> none_;
};

void write_points_csv(const fs::path& path, const KnitModel& m, const std::vector<Vec3>& pos) {
  std::string csv = "id,wale,level,x,y,z,x0,y0,z0\n";
  for (size_t k = 0; k < pos.size(); ++k) {
    const KnitPoint& q = m.points[k];
    append_row(csv, {static_cast<long long>(k), q.wale, q.level},
               {pos[k].x, pos[k].y, pos[k].z, q.rest.x, q.rest.y, q.rest.z});
  }
  write_file_atomic(path, csv);
}

void write_typevalue_csv(const fs::path& path, const KnitModel& m, const std::vector<Vec3>& pos) {
  std::string csv = "course,loop,k,x,y,z\n";
  const std::vector<LoopTypeValues> tv = type_value_points(m, pos);
  for (size_t l = 0; l < tv.size(); ++l)
    for (size_t k = 0; k < tv[l].k.size(); ++k) {
      const Vec3& p = tv[l].t[k];
      append_row(csv, {m.loops[l].course, m.loops[l].wale, tv[l].k[k]}, {p.x, p.y, p.z});
    }
  write_file_atomic(path, csv);
}

void write_centerlines_csv(const fs::path& path, const std::vector<CurveSamples>& lines) {
  std::string csv = "course,u,x,y,z\n";
  for (size_t j = 0; j < lines.size(); ++j)
    for (size_t k = 0; k < lines[j].points.size(); ++k) {
      const Vec3& p = lines[j].points[k];
      append_row(csv, {static_cast<long long>(j)}, {lines[j].u[k], p.x, p.y, p.z});
    }
  write_file_atomic(path, csv);
}

// frames/: each captured frame's centrelines (VTK) and front view; returns summary.json's list.
nlohmann::json write_frames(const fs::path& dir, const KnitScene& scene, const KnitResult& r,
                            CenterlineCache& centerlines, bool pictures) {
  const KnitModel& m = r.model;
  remove_stale_output(dir / "frames");  // an earlier run's may have had more frames
  fs::create_directories(dir / "frames");
  for (size_t f = 0; f < r.frames.size(); ++f) {
    const FrameRecorder::Frame& frame = r.frames[f];
    char stem[32];
    std::snprintf(stem, sizeof stem, "%03zu", f);
    const std::vector<Vec3> fp = knit_positions(m, frame.t, frame.x);
    const std::vector<CurveSamples>& fl = centerlines.of(fp);
    const std::string label = scene.name + ": frame " + stem + ", check " +
                              std::to_string(frame.check) + ", t = " + format_number(frame.t, 4) +
                              " s, residual " + format_number(frame.residual, 3);
    write_file_atomic(dir / "frames" / (std::string("centerlines_") + stem + ".vtk"),
                      centerlines_vtk("knitsim knit " + label, fl));
    if (pictures)
      render_front(dir / "frames" / (std::string("frame_") + stem + ".png"), m, fp, fl, label);
  }
  return knit_frames_json(r);
}

}  // namespace

nlohmann::json knit_frames_json(const KnitResult& r) {
  nlohmann::json list = nlohmann::json::array();
  for (size_t f = 0; f < r.frames.size(); ++f) {
    const FrameRecorder::Frame& frame = r.frames[f];
    list.push_back({{"index", f},
                    {"check", frame.check},
                    {"t", frame.t},
                    {"residual", frame.residual},
                    {"max_displacement_over_r",
                     max_displacement_over_r(r.model, knit_positions(r.model, frame.t, frame.x))}});
  }
  return list;
}

nlohmann::json knit_summary(const KnitScene& scene, const KnitResult& r,
                            const nlohmann::json& frames, const TextileMeasures* textile) {
  const KnitModel& m = r.model;
  const RunStats& stats = r.stats;
  nlohmann::json fabric = nullptr;
  if (textile)
    fabric = fabric_json(textile->fabric);
  else if (std::all_of(r.positions.begin(), r.positions.end(), is_finite))
    fabric = fabric_json(textile_measures(m, r.positions).fabric);
  nlohmann::json springs;
  for (KnitSpringKind kind :
       {KnitSpringKind::Wale, KnitSpringKind::Course, KnitSpringKind::Tuck, KnitSpringKind::Float,
        KnitSpringKind::Shear, KnitSpringKind::Bending})
    springs[to_string(kind)] = m.count(kind);
  nlohmann::json summary = {{"chart", scene.name},
          {"chart_file", scene.chart_file},
          {"status", to_string(stats.status)},
          {"message", stats.message},
          {"integrator", stats.integrator},
          {"t_start", r.t_start},
          {"t_final", stats.t_final},
          {"residual", stats.residual},
          {"wall_seconds", stats.wall_seconds},
          {"stats", to_json(stats)},
          {"wales", m.chart.wales},
          {"courses", m.chart.courses},
          {"points", m.points.size()},
          {"loops", m.loops.size()},
          {"springs", m.network.spec().springs.size()},
          {"springs_by_kind", springs},
          {"dof", m.network.dof()},
          {"max_displacement_over_r", max_displacement_over_r(m, r.positions)},
          {"yarn", measures_json(r.measures)},
          {"fabric", fabric},
          {"contact", contact_json(m, stats.t_final, r.x)},
          {"frames", frames},
          {"params", params_json(m.params)},
          {"options", to_json(scene.options)},
          {"units", knit_units(params_json(m.params), to_json(scene.options))}};
  if (!m.clamps.empty()) summary["clamps"] = clamps_json(m, stats.t_final, r.x);
  if (!r.load_steps.empty()) {  // a run under load: the balance counts the applied loads
    summary["loads"] = knit_loads_json(r);
    if (!m.clamps.empty()) {
      summary["clamps"]["applied_N"] = summary["loads"]["applied_N"];
      summary["clamps"]["balance_N"] = summary["loads"]["balance_N"];
    }
  }
  if (r.yarn) add_yarn_knit_summary(*r.yarn, r.x.size(), summary);  // knit.model = yarn
  return summary;
}

void write_knit_outputs(const fs::path& dir, const KnitScene& scene, const KnitResult& r,
                        const nlohmann::json& model_keys, bool pictures) {
  const KnitModel& m = r.model;
  const RunStats& stats = r.stats;
  write_points_csv(dir / "points.csv", m, r.positions);
  write_typevalue_csv(dir / "typevalue.csv", m, r.positions);
  if (!r.load_steps.empty())
    write_file_atomic(dir / "loads.csv", knit_loads_csv(r));
  else
    remove_stale_output(dir / "loads.csv");
  CenterlineCache centerlines(m);
  // knit.model = yarn: the yarn's own polylines and measures, not curves through the points.
  const std::vector<CurveSamples>& lines =
      r.yarn && !r.yarn->centerlines.empty() ? r.yarn->centerlines : centerlines.of(r.positions);
  write_centerlines_csv(dir / "centerlines.csv", lines);
  std::optional<TextileMeasures> textile;
  if (std::all_of(r.positions.begin(), r.positions.end(), is_finite)) {
    textile = r.yarn ? r.yarn->textile : textile_measures(m, r.positions);
    write_file_atomic(dir / "stitches.csv", stitches_csv(*textile));
  } else {
    remove_stale_output(dir / "stitches.csv");
  }

  // The equilibrium solver's flow leaves t where it started: its steps say how far it went.
  const std::string when = stats.t_final > r.t_start
                               ? " at t = " + format_number(stats.t_final, 4) + " s"
                               : " after " + std::to_string(stats.steps) + " steps";
  const std::string state =
      std::string(to_string(stats.status)) + when + " (" + stats.integrator + ")";
  write_file_atomic(dir / "centerlines.vtk",
                    centerlines_vtk("knitsim knit " + scene.name + ": " + state, lines));
  if (pictures) {
    const std::vector<Vec3> rest = m.rest_positions();
    render_front(dir / "before.png", m, rest, centerlines.of(rest), scene.name + ": at rest");
    render_front(dir / "after.png", m, r.positions, lines, scene.name + ": " + state);
  } else {
    remove_stale_output(dir / "before.png");
    remove_stale_output(dir / "after.png");
  }
  const nlohmann::json frames = write_frames(dir, scene, r, centerlines, pictures);
  write_json_atomic(dir / "summary.json",
                    knit_summary(scene, r, frames, textile ? &*textile : nullptr));
  // state.json before manifest.json, the last file of the set (src/base/files.hpp).
  write_run_state(dir, {"knit", {stats.t_final, r.x, r.v}, stats.integrator, stats.dt, model_keys});
  finish_output_folder(dir, manifest({{"chart", scene.chart_file},
                                      {"integrator", stats.integrator},
                                      {"frames", scene.frames},
                                      {"params", params_json(m.params)},
                                      {"options", to_json(scene.options)}}));
}

}  // namespace knitsim
