// knitsim knit (SPEC 2.9, 2.10): a stitch chart's interlacing-point network (paper 2) run to
// its steady state, with the loops' type-value points and NURBS centrelines.
//
// Order of work: parse the flags, read and parse the chart, apply --set, check the parameters,
// the run options and the integrator name, build the model, create and probe --out; only then
// run and write. Bad input (a bad chart: one line naming row and column) therefore writes
// nothing and exits 2; a run that ends in any status but equilibrium still writes everything
// and exits 3 -- or 128 + the signal (130, 143) when Ctrl-C or SIGTERM stopped it (status
// interrupted, src/cli/interrupt.hpp). --continue DIR starts from the state.json of an earlier
// run of the same chart and --set (read and checked with the other input, before --out is made).
//
// Outputs in --out (lengths in m):
//   points.csv       id,wale,level,x,y,z,x0,y0,z0  every interlacing point at the end and at rest
//   typevalue.csv    course,loop,k,x,y,z  T0..T8 of every loop at the end (loop = its wale;
//                    a tuck has no T1, T7)
//   centerlines.csv  course,u,x,y,z  each course's NURBS centreline sampled in arc length, 8
//                    samples per interval between yarn points
//   centerlines.vtk  the same as legacy VTK POLYDATA LINES, one line per course (cell data
//                    `course`)
//   frames/centerlines_NNN.vtk, frames/frame_NNN.png   the captured frames (below)
//   before.png, after.png   front views at rest and at the end (yarns as z-buffered tubes,
//                    render_strokes_png; interlacing points as dots); --no-pictures skips every PNG
//   summary.json, manifest.json   summary.json's "yarn" block: the clearance between yarn
//                    centrelines (src/measure/yarn_measures.hpp) at rest, at the end and its
//                    minimum over the run (where and when), in r, and how many of the designed
//                    crossings changed over/under order at the end; stdout shows the same, and a
//                    run whose clearance fell below kClearanceWarning r or whose crossings
//                    changed prints one `warning:` line
//   state.json       x, v at t_final and what was integrated, for --continue (write_run_state;
//                    omitted if not finite)
//   steps.csv        with --step-history: step,t,h,order,residual (src/io/step_log.hpp)
// Numbers in the CSV and VTK files are the shortest decimal text that reads back as the same
// double (std::to_chars). The centrelines of each distinct state are computed once (the first
// frame is the rest state, the last usually the end state); most of the writing's cost is the
// pictures (--no-pictures skips them).
// Frames: the start and states at the residual checks of the run, --frames of them evenly
// spaced in log time (first = the start, then from the first check to the last; the equilibrium
// solver, whose flow leaves t where it started, in log of the check's count). The recorder
// keeps a check's state when log t has advanced by `spacing` since the last kept one; past
// 2 x frames states it drops every other one and doubles `spacing`, so memory is bounded
// whatever the number of checks. summary.json lists each frame's check, t, residual and
// largest displacement.
//
// Network: the stabilised default or, by knit.network = paper (or knit.stabiliser = 0), paper 2's
// bare network, which prints one warning line (a mechanism: its steady state depends on the
// path). models/knit_loops.hpp, docs/knit.md.
//
// Velocity tolerance. With the stabiliser on (the default network), an adaptive integrator and
// no --velocity-atol, the run uses velocity_atol = kStabilisedVelocityAtol (1e-3 m/s, ~ atol
// 1e-9 m x 1e6 rad/s, above the network's fastest modes, omega ~ 2e5 rad/s): the stabilised
// steady state is unique, so the ringing of the stiff modes need not be followed
// (IntegratorOptions::velocity_atol). Paper 2's network (knit.network = paper) is a mechanism
// whose end state depends on the path, so it keeps atol on the velocities too. Steps and shape
// against velocity_atol: experiments/benchmark/README.md, "Knit case".
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <iostream>
#include <list>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <utility>

#include "models/knit_loops.hpp"
#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/commands.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/io/progress.hpp"
#include "src/io/run_state.hpp"
#include "src/io/step_log.hpp"
#include "src/measure/yarn_measures.hpp"
#include "src/render/render.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

namespace fs = std::filesystem;

constexpr double kStabilisedVelocityAtol = 1e-3;  // m/s, see the file comment
// A run whose yarns came closer than this (in r) warns: the clearance the knit model aims at
// (docs/knit.md, "Yarn measures").
constexpr double kClearanceWarning = 0.9;
// The clearance over the run is measured when an interlacing point has moved by 0.05 r since
// the last measured state (src/measure/yarn_measures.hpp, ClearanceOverRun: a dip shallower than
// 2 A 0.05 r can be missed, A the measured amplification, reported; figures per chart in
// docs/knit.md, "Yarn measures").
constexpr double kClearanceResample = 0.05;

struct KnitArgs {
  std::string chart;
  std::vector<std::string> sets;
  std::string integrator;            // empty: default_knit_integrator()
  IntegratorOptions options;         // only the fields add_run_options binds are taken from here
  bool velocity_atol_given = false;  // --velocity-atol on the command line
  int frames = 4;
  std::string out;
  bool step_history = false;
  bool quiet = false;
  bool no_pictures = false;
  std::string continue_from;  // --continue DIR
};

// The --set keys, each bound to one field.
struct SetKey {
  const char* name;
  double* field;
};

std::vector<SetKey> set_keys(KnitParams& p, IntegratorOptions& o) {
  return {{"knit.loop_radius", &p.loop_radius},
          {"knit.wale_stiffness", &p.wale_stiffness},
          {"knit.course_stiffness", &p.course_stiffness},
          {"knit.damping", &p.damping},
          {"knit.areal_density", &p.areal_density},
          {"knit.stabiliser", &p.stabiliser_ratio},
          {"knit.bending", &p.bending_ratio},
          {"knit.contact", &p.contact_ratio},
          {"run.t_max", &o.t_max},
          {"run.equilibrium_tol", &o.equilibrium_tol},
          {"run.position_tol", &o.position_tol}};
}

// The one --set key whose value is a name: knit.network = stabilised | paper.
constexpr const char* kNetworkKey = "knit.network";

// Applies "key=value" overrides; throws std::invalid_argument naming the bad --set.
// knit.network = paper with an explicit knit.stabiliser, knit.bending or knit.contact > 0 is
// refused (the paper's network has none of them).
void apply_sets(const std::vector<std::string>& sets, KnitParams& p, IntegratorOptions& o) {
  const std::vector<SetKey> keys = set_keys(p, o);
  bool stabiliser_given = false;
  for (const std::string& s : sets) {
    const size_t eq = s.find('=');
    const std::string key = s.substr(0, eq);
    if (key == kNetworkKey) {
      p.network = parse_knit_network(eq == std::string::npos ? "" : s.substr(eq + 1));
      continue;
    }
    stabiliser_given = stabiliser_given || key == "knit.stabiliser" || key == "knit.bending" ||
                       key == "knit.contact";
    const SetKey* found = nullptr;
    for (const SetKey& k : keys)
      if (key == k.name) found = &k;
    if (found == nullptr) {
      std::vector<std::string> names;
      for (const SetKey& k : keys) names.push_back(k.name);
      names.push_back(kNetworkKey);
      throw std::invalid_argument(unknown_key_message(key, names));
    }
    const std::string value = eq == std::string::npos ? "" : s.substr(eq + 1);
    size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (value.empty() || used != value.size())
      throw std::invalid_argument("--set " + s + ": expected " + key + "=<number>");
    *found->field = v;
  }
  if (p.network == KnitNetwork::Paper && stabiliser_given &&
      (p.stabiliser_ratio > 0.0 || p.bending_ratio > 0.0 || p.contact_ratio > 0.0))
    throw std::invalid_argument(
        "--set knit.stabiliser, knit.bending or knit.contact with knit.network = paper: paper 2's "
        "network has no stabiliser, bending or contact (drop one of them)");
}

// What a knit run integrates, as SavedRun::model (--continue): the chart, one string of stitch
// letters per course from the bottom, and the knit.* parameters under their --set names.
nlohmann::json knit_model_keys(const KnitChart& chart, KnitParams params) {
  nlohmann::json keys = nlohmann::json::object();
  std::vector<std::string> courses;
  for (int c = 0; c < chart.courses; ++c) {
    std::string row;
    for (int w = 0; w < chart.wales; ++w) row += static_cast<char>(chart.at(w, c));
    courses.push_back(row);
  }
  keys["chart"] = courses;
  keys[kNetworkKey] = to_string(params.network);
  IntegratorOptions unused;
  for (const SetKey& k : set_keys(params, unused))
    if (std::string(k.name).rfind("knit.", 0) == 0) keys[k.name] = *k.field;
  return keys;
}

KnitChart read_chart(const std::string& path) {
  // 4 million points (KnitParams::max_points) are ~4 MB of letters: a larger file is refused.
  constexpr std::size_t kMaxChartFileBytes = std::size_t{16} << 20;
  std::string text, why;
  if (!read_input_file(path, kMaxChartFileBytes, text, why))
    throw std::invalid_argument("--chart " + path + ": cannot read the file: " + why);
  try {
    return parse_knit_chart(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

// Captures states at residual checks (see the file comment) and forwards to the progress line.
class FrameRecorder final : public RunObserver {
 public:
  struct Frame {
    double t = 0.0;
    double residual = 0.0;
    std::vector<double> x;  // free dofs
    long check = 0;         // 0: the start; k: the k-th residual check
    double clock = 0.0;     // t, or the check where t stands still (the equilibrium solver)
  };

  FrameRecorder(int frames, RunObserver* next) : frames_(frames), next_(next) {}

  // Checks are kept log-spaced in t; the equilibrium solver's flow does not advance t, and its
  // checks are log-spaced in their count.
  void record(double t, const double* x, int n, double residual) {
    const long check = kept_.empty() ? 0 : last_.check + 1;
    const double clock = kept_.empty() || t != kept_.front().t ? t : static_cast<double>(check);
    last_ = {t, residual, std::vector<double>(x, x + n), check, clock};
    if (kept_.size() < 2 || std::log(clock / kept_.back().clock) >= spacing_)
      kept_.push_back(last_);
    if (static_cast<int>(kept_.size()) > 2 * frames_ + 1) {
      std::vector<Frame> half{std::move(kept_[0])};  // the start, then every other check
      for (size_t k = 1; k < kept_.size(); k += 2) half.push_back(std::move(kept_[k]));
      kept_ = std::move(half);
      spacing_ *= 2.0;
    }
  }
  void set_dof(int n) { n_ = n; }
  void on_check(double t, const double* x, const double* v, double residual) override {
    record(t, x, n_, residual);
    if (next_) next_->on_check(t, x, v, residual);
  }

  // `frames` states evenly spaced over the recorded checks, the last check included.
  std::vector<Frame> frames() const {
    std::vector<Frame> all = kept_;
    if (all.back().check != last_.check) all.push_back(last_);
    if (static_cast<int>(all.size()) <= frames_) return all;
    std::vector<Frame> out;
    for (int k = 0; k < frames_; ++k) {
      const double at = frames_ == 1 ? all.size() - 1.0 : k * (all.size() - 1.0) / (frames_ - 1);
      out.push_back(all[static_cast<size_t>(std::lround(at))]);
    }
    return out;
  }

 private:
  int frames_;
  RunObserver* next_;
  int n_ = 0;
  double spacing_ = 1e-3;  // in log t
  std::vector<Frame> kept_;
  Frame last_;
};

std::vector<Vec3> all_points(const KnitModel& m, double t, const std::vector<double>& x) {
  std::vector<Vec3> pos;
  m.network.all_positions(t, x.data(), pos);
  return pos;
}

// One line of fields separated by `sep`: the integers, then the numbers (shortest exact text).
void append_row(std::string& out, std::initializer_list<long long> ints,
                std::initializer_list<double> numbers, char sep = ',') {
  bool first = true;
  for (long long v : ints) {
    if (!first) out += sep;
    append_integer(out, v);
    first = false;
  }
  for (double v : numbers) {
    if (!first) out += sep;
    append_number(out, v);
    first = false;
  }
  out += '\n';
}

// Legacy VTK POLYDATA with one LINES cell per course centreline, cell data `course`.
std::string centerlines_vtk(const std::string& title, const std::vector<CurveSamples>& lines) {
  size_t points = 0;
  for (const CurveSamples& c : lines) points += c.points.size();
  std::string os = "# vtk DataFile Version 3.0\n" + title + "\nASCII\nDATASET POLYDATA\n";
  os.reserve(80 * points);
  os += "POINTS " + std::to_string(points) + " double\n";
  for (const CurveSamples& c : lines)
    for (const Vec3& p : c.points) append_row(os, {}, {p.x, p.y, p.z}, ' ');
  os +=
      "LINES " + std::to_string(lines.size()) + " " + std::to_string(points + lines.size()) + "\n";
  long long next = 0;
  for (const CurveSamples& c : lines) {
    append_integer(os, static_cast<long long>(c.points.size()));
    for (size_t k = 0; k < c.points.size(); ++k) {
      os += ' ';
      append_integer(os, next++);
    }
    os += '\n';
  }
  os += "CELL_DATA " + std::to_string(lines.size()) +
        "\nSCALARS course int 1\nLOOKUP_TABLE default\n";
  for (size_t j = 0; j < lines.size(); ++j) os += std::to_string(j) + "\n";
  return os;
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

// Front view of the centrelines, courses in alternating colours, interlacing points as dots.
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

double max_displacement_over_r(const KnitModel& m, const std::vector<Vec3>& pos) {
  double d = 0.0;
  for (size_t k = 0; k < pos.size(); ++k) d = std::max(d, norm(pos[k] - m.points[k].rest));
  return d / m.params.loop_radius;
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

// The yarn measures of a run (src/measure/yarn_measures.hpp), in units of r.
struct KnitMeasures {
  double rest_clearance = 0.0;  // at rest (t = 0 of the chart, whatever --continue gave)
  double end_clearance = 0.0;
  YarnClearance min_clearance;  // over the measured states of the run, start and end included
  double t_min_clearance = 0.0;
  long check_min_clearance = 0;  // the residual check of the minimum (0: the start)
  int measured_states = 0;
  double measure_cpu_seconds = 0.0;  // the clearance over the run, inside stats.cpu_seconds
  double min_resolution = 0.0;  // 2 A tau: a deeper dip between measured states would be seen
  CrossingCheck crossings;      // at the end against the rest state
};

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

void write_outputs(const fs::path& dir, const KnitArgs& args, const KnitModel& m,
                   const IntegratorOptions& opt, const RunStats& stats,
                   const std::vector<double>& x, const std::vector<FrameRecorder::Frame>& frames,
                   double t_start, const KnitMeasures& measures) {
  const std::string name = fs::path(args.chart).stem().string();
  const std::vector<Vec3> pos = all_points(m, stats.t_final, x);
  const std::vector<Vec3> rest = m.rest_positions();

  std::string csv = "id,wale,level,x,y,z,x0,y0,z0\n";
  for (size_t k = 0; k < pos.size(); ++k) {
    const KnitPoint& q = m.points[k];
    append_row(csv, {static_cast<long long>(k), q.wale, q.level},
               {pos[k].x, pos[k].y, pos[k].z, q.rest.x, q.rest.y, q.rest.z});
  }
  write_file_atomic(dir / "points.csv", csv);

  csv = "course,loop,k,x,y,z\n";
  const std::vector<LoopTypeValues> tv = type_value_points(m, pos);
  for (size_t l = 0; l < tv.size(); ++l)
    for (size_t k = 0; k < tv[l].k.size(); ++k) {
      const Vec3& p = tv[l].t[k];
      append_row(csv, {m.loops[l].course, m.loops[l].wale, tv[l].k[k]}, {p.x, p.y, p.z});
    }
  write_file_atomic(dir / "typevalue.csv", csv);

  // The centrelines of each distinct state, computed once (the first frame is the rest state,
  // the last usually the end state); a list, so references to its entries stay valid. A state
  // that is not finite (a diverged run) has none: its points are still written, as they are.
  std::list<std::pair<std::vector<Vec3>, std::vector<CurveSamples>>> computed;
  const std::vector<CurveSamples> no_lines;
  auto centerlines_of = [&](const std::vector<Vec3>& state) -> const std::vector<CurveSamples>& {
    if (!std::all_of(state.begin(), state.end(), is_finite)) return no_lines;
    for (const auto& c : computed)
      if (std::equal(c.first.begin(), c.first.end(), state.begin(), state.end(),
                     [](Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }))
        return c.second;
    computed.emplace_back(state, course_centerlines(m, state));
    return computed.back().second;
  };
  const std::vector<CurveSamples>& lines = centerlines_of(pos);
  csv = "course,u,x,y,z\n";
  for (size_t j = 0; j < lines.size(); ++j)
    for (size_t k = 0; k < lines[j].points.size(); ++k) {
      const Vec3& p = lines[j].points[k];
      append_row(csv, {static_cast<long long>(j)}, {lines[j].u[k], p.x, p.y, p.z});
    }
  write_file_atomic(dir / "centerlines.csv", csv);

  // The equilibrium solver's flow leaves t where it started: its steps say how far it went.
  const std::string when = stats.t_final > t_start
                               ? " at t = " + format_number(stats.t_final, 4) + " s"
                               : " after " + std::to_string(stats.steps) + " steps";
  const std::string state =
      std::string(to_string(stats.status)) + when + " (" + stats.integrator + ")";
  write_file_atomic(dir / "centerlines.vtk",
                    centerlines_vtk("knitsim knit " + name + ": " + state, lines));
  if (!args.no_pictures) {
    render_front(dir / "before.png", m, rest, centerlines_of(rest), name + ": at rest");
    render_front(dir / "after.png", m, pos, lines, name + ": " + state);
  } else {
    remove_stale_output(dir / "before.png");
    remove_stale_output(dir / "after.png");
  }

  remove_stale_output(dir / "frames");  // an earlier run's may have had more frames
  fs::create_directories(dir / "frames");
  nlohmann::json frame_list = nlohmann::json::array();
  for (size_t f = 0; f < frames.size(); ++f) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "%03zu", f);
    const std::vector<Vec3> fp = all_points(m, frames[f].t, frames[f].x);
    const std::vector<CurveSamples>& fl = centerlines_of(fp);
    const std::string label = name + ": frame " + stem + ", check " +
                              std::to_string(frames[f].check) +
                              ", t = " + format_number(frames[f].t, 4) + " s, residual " +
                              format_number(frames[f].residual, 3);
    write_file_atomic(dir / "frames" / (std::string("centerlines_") + stem + ".vtk"),
                      centerlines_vtk("knitsim knit " + label, fl));
    if (!args.no_pictures)
      render_front(dir / "frames" / (std::string("frame_") + stem + ".png"), m, fp, fl, label);
    frame_list.push_back({{"index", f},
                          {"check", frames[f].check},
                          {"t", frames[f].t},
                          {"residual", frames[f].residual},
                          {"max_displacement_over_r", max_displacement_over_r(m, fp)}});
  }

  nlohmann::json springs;
  for (KnitSpringKind kind :
       {KnitSpringKind::Wale, KnitSpringKind::Course, KnitSpringKind::Tuck, KnitSpringKind::Float,
        KnitSpringKind::Shear, KnitSpringKind::Bending})
    springs[to_string(kind)] = m.count(kind);
  nlohmann::json options = to_json(opt);
  const nlohmann::json summary = {
      {"chart", name},
      {"chart_file", args.chart},
      {"status", to_string(stats.status)},
      {"message", stats.message},
      {"integrator", stats.integrator},
      {"t_start", t_start},
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
      {"max_displacement_over_r", max_displacement_over_r(m, pos)},
      {"yarn", measures_json(measures)},
      {"contact", contact_json(m, stats.t_final, x)},
      {"frames", frame_list},
      {"params", params_json(m.params)},
      {"options", options},
      {"units",
       summary_units({{"residual, residual_floor",
                       "1: the static residual (docs/equilibrium.md), max "
                       "over free points of |net force| / (k_w r), "
                       "a wale spring stretched by one loop radius "
                       "(with gravity: or the mean point weight, "
                       "the smaller)"},
                      {"max_displacement_over_r", "1: largest displacement / loop radius"},
                      {"yarn",
                       "clearance_*_over_r 1: smallest segment-to-segment distance "
                       "between yarn centreline pieces of different courses (or one "
                       "course, >= pi r apart along it) / loop radius, 2 = at least 2; "
                       "clearance_min_t s; clearance_min_check: its residual check (0: the "
                       "start); clearance_min_where m; "
                       "clearance_min_resolution_over_r 1: a dip between measured "
                       "states shallower than this can be missed; "
                       "clearance_cpu_seconds s: the measuring inside the run, part of "
                       "stats.cpu_seconds; crossings: designed "
                       "front-view crossings at rest and how many changed over/under "
                       "order at the end"},
                      {"contact",
                       "null without yarn contact; min_point_distance_over_r 1: the "
                       "closest two contact points at the end / loop radius (null: no "
                       "pair within reach); pairs_in_contact: pairs closer than the touching "
                       "distance r; renewed_yarns, renewals_cut, pattern_misses, "
                       "list_rebuilds, list_sweeps: counts over the run (docs/knit.md, Yarn "
                       "contact)"},
                      {"params",
                       "loop_radius m; wale_stiffness, "
                       "course_stiffness N/m; damping N s/m; "
                       "areal_density g/m^2; stabiliser_ratio 1"}})}};
  write_json_atomic(dir / "summary.json", summary);
  write_json_atomic(dir / "manifest.json", manifest({{"chart", args.chart},
                                                     {"integrator", stats.integrator},
                                                     {"frames", args.frames},
                                                     {"params", params_json(m.params)},
                                                     {"options", options}}));
}

void run(const KnitArgs& args) {
  const KnitChart chart = read_chart(args.chart);
  KnitParams params;
  IntegratorOptions opt;
  apply_sets(args.sets, params, opt);
  copy_run_flags(args.options, opt);
  const std::string integrator =
      args.integrator.empty() ? default_knit_integrator(params.yarn_contact()) : args.integrator;
  std::unique_ptr<Integrator> integ;
  try {
    integ = make_integrator(integrator);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--") + e.what());  // "--integrator = X: ..."
  }
  // The stabilised default is an error-control setting: the fixed-step methods have none, so
  // their summaries keep the (unused) value given, not 1e-3.
  const bool stabilised_default =
      !args.velocity_atol_given && !params.mechanism() && integ->info().adaptive;
  if (stabilised_default) opt.velocity_atol = kStabilisedVelocityAtol;
  try {
    opt.validate();
  } catch (const std::invalid_argument& e) {
    rethrow_with_flag_names(e, run_option_names());  // run.t_max, --rtol, ...
  }
  if (args.frames < 1)
    throw std::invalid_argument("--frames = " + std::to_string(args.frames) + ": must be >= 1");
  KnitModel model = build_knit(chart, params);  // validates params (non-const: its contact run)
  std::vector<double> x(model.network.dof()), v(model.network.dof());
  model.network.initial_state(x.data(), v.data());
  double t0 = 0.0;
  if (!args.continue_from.empty()) {
    const RunState from = continue_state(args.continue_from, "knit", knit_model_keys(chart, params),
                                         "--chart and --set", integrator, opt);
    if (from.x.size() != x.size())  // same chart and parameters: only a corrupt file gets here
      throw std::invalid_argument("--continue " + args.continue_from + ": the state has " +
                                  std::to_string(from.x.size()) + " unknowns; this chart has " +
                                  std::to_string(x.size()));
    t0 = from.t, x = from.x, v = from.v;
    // The contact points were made at rest: linearised afresh about the saved state, they stand
    // for the yarn there (the run goes on from the same state, not with the same points).
    if (model.contact && !model.contact->renew(t0, x.data()))
      throw std::invalid_argument("--continue " + args.continue_from +
                                  ": the saved state's yarns lie inside the contact's core "
                                  "(closer than " +
                                  format_number(kContactCore, 3) + " r); it cannot go on");
  }

  const std::string name = fs::path(args.chart).stem().string();
  // The handlers first: a signal once the folder is locked ends the run with its outputs.
  const InterruptScope interrupt;
  opt.interrupt = interrupt.flag();
  bool created = false;
  const fs::path dir = make_output_dir(args.out, "knit-" + name, &created);
  warn_about_run("knit.damping", params.damping, integ->info(), args.options, opt.t_max);
  if (model.contact && integ->info().explicit_method)  // docs/knit.md, "What is not met, and why"
    warn("yarn contact with " + integrator +
         ": the chart's first impacts (~10 us in) carry more energy than the barrier holds above "
         "its core in double precision, so it fails there whatever its step (docs/knit.md, \"What "
         "is not met, and why\"); equilibrium (the default) and implicit-euler keep every pair "
         "off its core");
  if (params.mechanism())
    warn(std::string(params.network == KnitNetwork::Paper ? "knit.network = paper"
                                                          : "knit.stabiliser = 0") +
         ": paper 2's bare network is a mechanism (blocks of fabric shear and swing at no "
         "energy); its steady state depends on the path (integrator, step, tolerances)");
  RunStats stats;
  std::vector<FrameRecorder::Frame> frames;
  KnitMeasures measures;
  const YarnPolylines rest_lines = yarn_polylines(model, model.rest_positions());
  const std::vector<YarnCrossing> crossings = designed_crossings(model, rest_lines);
  measures.rest_clearance = yarn_clearance(model, rest_lines).over_r;
  {
    ProgressLine progress(name + " " + integrator, opt.equilibrium_tol, !args.quiet);
    FrameRecorder recorder(args.frames, &progress);
    recorder.set_dof(model.network.dof());
    recorder.record(t0, x.data(), model.network.dof(),
                    model.system().static_residual(t0, x.data()));
    StepLog steps(&recorder);
    ClearanceOverRun clearance(model,
                               args.step_history ? static_cast<RunObserver*>(&steps) : &recorder,
                               kClearanceResample);
    clearance.observe(t0, x.data(), true);
    const double measure_cpu_before = clearance.cpu_seconds();
    try {
      stats = run_to_equilibrium(model.system(), *integ, opt, x, v, &clearance, t0);
    } catch (const std::invalid_argument& e) {  // an option the model refuses at the start
      refuse_at_run_start(e, dir, created);
    }
    measures.measure_cpu_seconds = clearance.cpu_seconds() - measure_cpu_before;
    clearance.observe(stats.t_final, x.data(), true);
    measures.min_clearance = clearance.minimum();
    measures.t_min_clearance = clearance.t_of_minimum();
    measures.check_min_clearance = clearance.check_of_minimum();
    measures.measured_states = clearance.measured_states();
    measures.min_resolution = clearance.resolution_over_r();
    const std::vector<Vec3> end = all_points(model, stats.t_final, x);
    if (std::all_of(end.begin(), end.end(), is_finite)) {
      const YarnPolylines end_lines = yarn_polylines(model, end);
      measures.end_clearance = yarn_clearance(model, end_lines).over_r;
      measures.crossings = check_crossings(crossings, end_lines);
    } else {
      measures.end_clearance = std::nan("");
      measures.crossings.designed = static_cast<int>(crossings.size());
      measures.crossings.changed = -1;  // unknown: the end state is not finite
    }
    frames = recorder.frames();
    if (args.step_history)
      write_file_atomic(dir / "steps.csv", steps.csv());
    else
      remove_stale_output(dir / "steps.csv");
  }
  write_outputs(dir, args, model, opt, stats, x, frames, t0, measures);
  if (measures.crossings.changed > 0 || measures.min_clearance.over_r < kClearanceWarning)
    warn("yarns overlap: clearance down to " + format_number(measures.min_clearance.over_r, 3) +
         " r (courses " + std::to_string(measures.min_clearance.a.course) + " and " +
         std::to_string(measures.min_clearance.b.course) + ", at check " +
         std::to_string(measures.check_min_clearance) +
         ", t = " + format_number(measures.t_min_clearance, 3) + " s), " +
         std::to_string(measures.crossings.changed) + " of " +
         std::to_string(measures.crossings.designed) +
         " designed crossings changed over/under order");
  write_run_state(
      dir,
      {"knit", {stats.t_final, x, v}, stats.integrator, stats.dt, knit_model_keys(chart, params)});
  if (!args.quiet) {
    Table t;
    t.columns = {"knit", name + " (" + args.chart + ")"};
    t.rows = {{"chart", std::to_string(chart.wales) + " wales x " + std::to_string(chart.courses) +
                            " courses, " + std::to_string(model.points.size()) + " points, " +
                            std::to_string(model.network.spec().springs.size()) + " springs"},
              {"integrator", stats.integrator},
              {"status", std::string(to_string(stats.status)) + " (" + stats.message + ")"},
              {"certificate", certificate_summary(stats)},
              {"t_final",
               format_number(stats.t_final, 6) + " s" +
                   (stats.t_final > t0 || stats.steps == 0 ? "" : " (its steps do not advance t)")},
              {"steps", steps_summary(stats)}};
    if (const std::string la = linear_algebra_summary(stats); !la.empty())
      t.rows.push_back({"linear algebra", la});
    t.rows.insert(
        t.rows.end(),
        {{"residual", residual_summary(stats, opt.position_tol)},
         {"max displacement",
          format_number(max_displacement_over_r(model, all_points(model, stats.t_final, x)), 4) +
              " r"},
         {"clearance", "min " + format_number(measures.min_clearance.over_r, 3) +
                           " r over the run (" + std::to_string(measures.measured_states) +
                           " states, to " + format_number(measures.min_resolution, 2) +
                           " r), end " + format_number(measures.end_clearance, 3) + " r, rest " +
                           format_number(measures.rest_clearance, 3) + " r"},
         {"crossings", std::to_string(measures.crossings.designed) + " designed, " +
                           std::to_string(measures.crossings.changed) + " changed over/under"},
         {"wall", format_number(1e3 * stats.wall_seconds, 4) + " ms"},
         {"outputs", dir.string() + "/"}});
    std::cout << t.text() << std::flush;
  }
  exit_with_run_status("knit", stats, interrupt, dir.string());
}

}  // namespace

void register_knit_command(CLI::App& app) {
  auto args = std::make_shared<KnitArgs>();
  CLI::App* cmd = app.add_subcommand(
      "knit",
      "Run a stitch chart's interlacing-point network (paper 2) to its steady state; writes "
      "points.csv, typevalue.csv, centerlines.csv/.vtk, before/after.png, frames/, summary.json, "
      "state.json and manifest.json into --out");
  cmd->add_option("--chart", args->chart, "Stitch chart file (K knit, T tuck, M miss)")->required();
  cmd->add_option("--set", args->sets,
                  "Override a parameter, e.g. knit.network=paper (repeatable); keys "
                  "knit.network (stabilised | paper), knit.loop_radius, knit.wale_stiffness, "
                  "knit.course_stiffness, knit.damping, knit.areal_density, knit.stabiliser, "
                  "knit.bending, knit.contact, run.t_max, run.equilibrium_tol, run.position_tol")
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--integrator", args->integrator,
                  "Integrator (knitsim list integrators); default equilibrium with yarn contact "
                  "(knit.contact > 0, the default), else cvode-bdf");
  CLI::Option* velocity_atol = add_run_options(cmd, args->options);
  velocity_atol->description(velocity_atol->get_description() +
                             "; not given: 0.001 (stabilised network), or 0 (paper network)");
  cmd->add_option("--frames", args->frames,
                  "Captured frames (the start to the last residual check), >= 1")
      ->capture_default_str();
  cmd->add_option("--out", args->out,
                  "Output folder (default: a fresh out/knit-<chart>-<YYYYmmdd-HHMMSS>)");
  cmd->add_flag("--no-pictures", args->no_pictures,
                "Skip before.png, after.png and the frames' PNGs (the CSV and VTK files stay)");
  add_history_and_continue_options(cmd, args->step_history, args->continue_from,
                                   "--chart and --set");
  cmd->add_flag("--quiet", args->quiet, "No progress line and no summary on stdout");
  cmd->callback([args, velocity_atol] {
    args->velocity_atol_given = velocity_atol->count() > 0;
    run(*args);
  });
}

}  // namespace knitsim
