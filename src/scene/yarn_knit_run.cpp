#include "src/scene/yarn_knit_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>

#include "models/yarn_rods.hpp"
#include "src/geometry/segment_distance.hpp"

namespace knitsim {

namespace {

// Steps of one round (above): short enough that the pattern follows the contacts. An explicit
// method uses no Jacobian, so its run is one round (its checks come every 1000 steps: rounds of
// 50 would never reach one, nor so the wall cap or the stop).
constexpr long kYarnRoundSteps = 50;
// A ramp stage's carried start must keep every pair the contact sees this far apart (in d; the
// barrier's core is at YarnParams::core_fraction = 0.7 d), or half its gap to the core where the
// yarn is closer already; else the stage is halved, at most kYarnCarrySplits times, and then run
// whole without the carry.
constexpr double kYarnCarryClearance = 0.75;
constexpr int kYarnCarrySplits = 4;

double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// Measures the clearance at every residual check, then passes the check on.
class ClearanceWatch final : public RunObserver {
 public:
  ClearanceWatch(const YarnRods& rods, RunObserver* next) : rods_(rods), next_(next) {}
  void on_run_start() override {
    if (next_) next_->on_run_start();
  }
  void on_step(double t, double h, int order) override {
    if (next_) next_->on_step(t, h, order);
  }
  void on_check(double t, const double* x, const double* v, double residual) override {
    const double c = rods_.min_clearance(x);
    if (c < min_) min_ = c;
    ++checks_;
    if (next_) next_->on_check(t, x, v, residual);
  }
  double minimum() const { return min_; }
  int checks() const { return checks_; }

 private:
  const YarnRods& rods_;
  RunObserver* next_;
  double min_ = std::numeric_limits<double>::infinity();
  int checks_ = 0;
};

// The structure's free dofs at the given points (the structure has no pins).
std::vector<double> structure_state(const KnitModel& m, const std::vector<Vec3>& points) {
  std::vector<double> x(m.network.dof(), 0.0);
  for (std::size_t p = 0; p < points.size(); ++p) {
    const int f = m.network.free_index(static_cast<int>(p));
    if (f < 0) continue;
    x[3 * f] = points[p].x, x[3 * f + 1] = points[p].y, x[3 * f + 2] = points[p].z;
  }
  return x;
}

YarnKnitRun::Verlet verlet_estimate(const YarnRods& rods, double t, const std::vector<double>& x) {
  YarnKnitRun::Verlet out;
  const YarnParams& p = rods.spec().yarn;
  const double c = std::sqrt(p.stretch_stiffness() / p.linear_density());
  double l_min = std::numeric_limits<double>::infinity();
  for (const std::vector<Vec3>& rest : rods.spec().rest)
    for (std::size_t k = 1; k < rest.size(); ++k)
      l_min = std::min(l_min, norm(rest[k] - rest[k - 1]));
  out.dt_axial = l_min / c;
  out.dt_estimated = estimate_stable_dt("verlet", rods, t, x.data());
  out.dt_predicted = predict_stable_dt("verlet", rods, t, x.data());
  std::vector<double> a(x.size());
  constexpr int kRepeats = 5;
  const double c0 = cpu_now();
  for (int k = 0; k < kRepeats; ++k) rods.conservative_acceleration(t, x.data(), a.data());
  out.force_cpu_seconds = (cpu_now() - c0) / kRepeats;
  out.steps_to_steady = t > 0.0 ? t / out.dt_estimated : std::nan("");
  return out;
}

}  // namespace

KnitYarns yarn_knit_yarns(const YarnKnit& y, const std::vector<Vec3>& all) {
  KnitYarns out;
  out.chart = y.structure.chart;
  out.lines.samples_per_interval = 1;
  out.lines.vertices = y.course_polylines(all);
  for (const std::vector<Vec3>& v : out.lines.vertices) {
    std::vector<double> arc(v.size(), 0.0);
    for (std::size_t k = 1; k < v.size(); ++k) arc[k] = arc[k - 1] + norm(v[k] - v[k - 1]);
    out.lines.arc.push_back(std::move(arc));
  }
  const int wales = out.chart.wales;
  out.marks.resize(y.marks.size());
  for (std::size_t c = 0; c < y.marks.size(); ++c) {
    const std::vector<double>& arc = out.lines.arc[c / wales];
    auto at = [&arc](double q) {
      if (!std::isfinite(q)) return kNoMark;
      const int last = static_cast<int>(arc.size()) - 1;
      const int k = std::clamp(static_cast<int>(std::floor(q)), 0, last - 1);
      const double s = std::clamp(q - k, 0.0, 1.0);
      return (1.0 - s) * arc[k] + s * arc[k + 1];
    };
    const YarnCellMarks& m = y.marks[c];
    const bool miss = out.chart.stitches[c] == Stitch::Miss;
    out.marks[c] = {at(m.begin), at(m.end), miss ? kNoMark : at(m.loop_begin),
                    miss ? kNoMark : at(m.loop_end)};
  }
  return out;
}

namespace {

// The yarn's course polylines as the crossing check reads them: a crossing is looked for up to
// 2 samples_per_interval edges from where it was designed, here one chart cell.
YarnPolylines crossing_lines(const YarnKnit& y, const std::vector<Vec3>& all) {
  YarnPolylines lines = yarn_knit_yarns(y, all).lines;
  lines.samples_per_interval = std::max(1, static_cast<int>(y.params.vertices_per_loop) / 2);
  return lines;
}

}  // namespace

std::vector<YarnCrossing> yarn_designed_crossings(const YarnKnit& y) {
  return designed_crossings(y.structure, crossing_lines(y, y.start));
}

YarnStructure check_yarn_structure(const YarnKnit& y, const std::vector<YarnCrossing>& designed,
                                   const std::vector<Vec3>& all) {
  YarnStructure out;
  if (!std::all_of(all.begin(), all.end(), is_finite)) {
    out.crossings.designed = static_cast<int>(designed.size());
    out.crossings.changed = -1;
    return out;
  }
  out.crossings = check_crossings(designed, crossing_lines(y, all));
  const KnitModel& m = y.structure;
  // A stretch of course j's vertices from material index q0 to q1, widened by a quarter cell
  // each side (the yarn slides through the loops).
  const double widen = 0.25 * y.params.vertices_per_loop;
  auto stretch = [&](int j, double q0, double q1) {
    const std::vector<int>& idx = y.course_vertices[j];
    const int last = static_cast<int>(idx.size()) - 1;
    const int k0 = std::clamp(static_cast<int>(std::floor(std::min(q0, q1) - widen)), 0, last);
    const int k1 = std::clamp(static_cast<int>(std::ceil(std::max(q0, q1) + widen)), 0, last);
    std::vector<int> out_v;
    for (int k = k0; k <= k1; ++k) out_v.push_back(idx[k]);
    return out_v;
  };
  // Per interlacing point: the head arcs of the loops whose upper point it is, and the whole
  // loops (loop begin to loop end) whose lower point it is; each pair's closest vertices.
  std::vector<std::vector<int>> heads(m.points.size()), held(m.points.size());
  for (std::size_t l = 0; l < m.loops.size(); ++l) {
    const KnitLoop& loop = m.loops[l];
    const std::array<double, 4>& q = y.loop_points[l];
    if (loop.upper >= 0 && std::isfinite(q[2]) && std::isfinite(q[3]))
      heads[loop.upper] = stretch(loop.course, q[2], q[3]);
    const YarnCellMarks& mk = y.marks[loop.course * m.chart.wales + loop.wale];
    if (loop.lower >= 0 && std::isfinite(mk.loop_begin) && std::isfinite(mk.loop_end))
      held[loop.lower] = stretch(loop.course, mk.loop_begin, mk.loop_end);
  }
  for (std::size_t p = 0; p < m.points.size(); ++p) {
    if (heads[p].empty() || held[p].empty()) continue;
    double gap = std::numeric_limits<double>::infinity();
    for (std::size_t a = 1; a < heads[p].size(); ++a)
      for (std::size_t b = 1; b < held[p].size(); ++b)
        gap = std::min(gap, closest_points(all[heads[p][a - 1]], all[heads[p][a]],
                                           all[held[p][b - 1]], all[held[p][b]])
                                .distance);
    gap /= y.d;
    ++out.interlocks;
    out.interlock_gap_max_over_d = std::max(out.interlock_gap_max_over_d, gap);
    if (gap > kYarnWithdrawn) ++out.withdrawn;
  }
  return out;
}

std::string yarn_structure_message(const YarnStructure& s) {
  if (!s.lost()) return "";
  std::string text = "the yarn lost its knitted structure:";
  if (s.crossings.changed < 0)
    text += " its end state is not finite";
  else
    text += " " + std::to_string(s.crossings.changed) + " of " +
            std::to_string(s.crossings.designed) + " designed crossings changed over/under, " +
            std::to_string(s.withdrawn) + " of " + std::to_string(s.interlocks) +
            " loops withdrawn from the head they pass through";
  return text;
}

void report_yarn_structure(const YarnStructure& s, RunStats& stats) {
  if (!s.lost()) return;
  const std::string lost = yarn_structure_message(s);
  // Withdrawn loops end the run outside the model's limits; changed crossings alone are said
  // (the barrier keeps every pair apart, so a crossing changes by a loop turning over, which
  // the front-view order also counts: docs/yarn_model.md, "The structure check").
  if (stats.status == RunStatus::Equilibrium && (s.withdrawn > 0 || s.crossings.changed < 0)) {
    stats.status = RunStatus::OutsideModelLimits;
    stats.message = lost;
  } else {
    stats.message += (stats.message.empty() ? "" : "; ") + lost;
  }
}

KnitStart start_yarn_knit(const KnitScene& scene) {
  auto yarn = std::make_shared<YarnKnit>(build_yarn_knit(scene.chart, scene.params, scene.yarn));
  KnitStart s{yarn->structure, 0.0, {}, {}, yarn};
  const YarnRods rods(yarn->spec(0, 1));
  s.x.resize(rods.dof());
  s.v.resize(rods.dof());
  rods.initial_state(s.x.data(), s.v.data());
  return s;
}

KnitResult run_yarn_knit(KnitStart start, const KnitScene& scene, const std::string& integrator,
                         RunObserver* observer) {
  // An unknown name is refused before anything runs.
  const bool explicit_method = make_integrator(integrator)->info().explicit_method;
  const std::shared_ptr<const YarnKnit> yk = start.yarn;
  const double d = yk->d;
  const auto wall0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_now();
  KnitResult r{std::move(start.model), {}, 0.0, {}, {}, {}, {}, {}, nullptr, {}};
  auto run = std::make_shared<YarnKnitRun>();
  run->knit = yk;
  run->clearance_start_over_d = yk->start_clearance / d;
  double min_clearance = yk->start_clearance;
  int checks = 0;

  // No ramp where the knitted lengths are the start's (knit.stitch_length = 0 on every type).
  bool ramp = false;
  for (std::size_t e = 0; e < yk->start_length.size(); ++e)
    ramp = ramp || yk->target_length[e] != yk->start_length[e];
  const int stages = ramp ? yk->ramp_stages() : 1;
  std::vector<Vec3> pos = yk->start;
  // Each stage in rounds of at most kYarnRoundSteps steps: between rounds the rods are made
  // afresh at the state reached, so the contact's Jacobian pattern (fixed per YarnRods, the pairs
  // near at its start) follows the yarn; a round ending at the stop ends the stage.
  double t = 0.0;
  long steps_left = scene.options.max_steps;
  std::unique_ptr<YarnRods> rods;
  std::vector<double> x, v;
  bool done = false;
  double f_done = 0.0;  // the ramp's fraction reached (relaxed)
  // The frames over the whole ramp, the start first.
  FrameRecorder recorder(scene.frames, 3 * static_cast<int>(pos.size() - yk->pins.size()),
                         observer);
  for (int s = 1; s <= stages && !done;) {
    // The stage's state: the yarn carried to the stage's scale (the held groups with it). A
    // carry that would put a pair near the barrier's core is halved (a stage inserted) up to
    // kYarnCarrySplits times; past that the stage starts where the last one ended.
    const double f_stage = static_cast<double>(s) / stages;
    double f = f_stage;
    std::vector<Vec3> moved = pos;
    if (ramp) {
      // The floor: kYarnCarryClearance d, or half the way from the stage's clearance to the
      // core where the yarn already sits closer.
      double floor = kYarnCarryClearance * d;
      {
        const YarnRods here(yk->spec_at(f_done, pos));
        std::vector<double> hx(here.dof()), hv(here.dof());
        here.initial_state(hx.data(), hv.data());
        const double core = here.spec().yarn.core_fraction * d;
        floor = std::min(floor, core + 0.5 * (here.min_clearance(hx.data()) - core));
      }
      for (int split = 0;; ++split) {
        moved = yk->carried(pos, yk->ramp_scale(f_done), yk->ramp_scale(f));
        const YarnRods probe(yk->spec_at(f, moved));
        std::vector<double> px(probe.dof()), pv(probe.dof());
        probe.initial_state(px.data(), pv.data());
        const bool clear = std::isfinite(probe.potential_energy(0.0, px.data())) &&
                           probe.min_clearance(px.data()) >= floor;
        if (clear) break;
        if (split == kYarnCarrySplits) {  // the whole stage, uncarried
          f = f_stage;
          moved = pos;
          ++run->carries_refused;
          break;
        }
        f = 0.5 * (f_done + f);
      }
    }
    const bool last = f >= 1.0;
    const double c0 = cpu_now();
    const auto w0 = std::chrono::steady_clock::now();
    YarnKnitRun::Stage stage;
    stage.fraction = f;
    for (int round = 0;; ++round) {
      rods.reset();  // one set of rods alive at a time (memory)
      rods = std::make_unique<YarnRods>(yk->spec_at(f, round == 0 ? moved : pos));
      x.assign(rods->dof(), 0.0), v.assign(rods->dof(), 0.0);
      rods->initial_state(x.data(), v.data());
      if (round == 0 && run->stages.empty()) {  // the start (before any carry)
        const YarnRods at_start(yk->spec_at(0.0));
        std::vector<double> x0(at_start.dof()), v0(at_start.dof());
        at_start.initial_state(x0.data(), v0.data());
        recorder.record(t, x0.data(), at_start.static_residual(t, x0.data()));
      }
      ClearanceWatch watch(*rods, &recorder);
      IntegratorOptions options = scene.options;
      options.max_steps = explicit_method ? steps_left : std::min(steps_left, kYarnRoundSteps);
      if (scene.options.max_wall_seconds > 0.0) {
        const double used =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
        options.max_wall_seconds = std::max(1e-3, scene.options.max_wall_seconds - used);
      }
      std::unique_ptr<Integrator> integ = make_integrator(integrator);
      RunStats st = run_to_equilibrium(*rods, *integ, options, x, v, &watch, t);
      steps_left -= st.steps;
      stage.steps += st.steps;
      run->pattern_misses += rods->pattern_misses();
      min_clearance = std::min(min_clearance, watch.minimum());
      checks += watch.checks();
      rods->all_positions(x.data(), pos);
      if (st.t_final > t) t = st.t_final;
      r.stats = st;
      r.stats.steps = stage.steps;
      const bool more = st.status == RunStatus::StepLimit && steps_left > 0;
      if (!more) {
        if (st.status == RunStatus::StepLimit) r.stats.status = RunStatus::StepLimit;
        break;
      }
    }
    stage.status = r.stats.status;
    stage.residual = r.stats.residual;
    stage.cpu_seconds = cpu_now() - c0;
    stage.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    run->stages.push_back(stage);
    r.x = x, r.v = v;
    f_done = f;
    if (f >= f_stage) ++s;
    if (last || r.stats.status != RunStatus::Equilibrium) {
      const double end_clearance = rods->min_clearance(x.data());
      min_clearance = std::min(min_clearance, end_clearance);
      run->clearance_end_over_d = end_clearance / d;
      run->vertices = rods->vertex_count();
      run->verlet = verlet_estimate(*rods, t, x);
      run->free_vertices = rods->dof() / 3;
      // The frames as states of the structure (its interlacing points read off the yarn).
      for (FrameRecorder::Frame fr : recorder.frames()) {
        std::vector<Vec3> all;
        rods->all_positions(fr.x.data(), all);
        fr.x = structure_state(r.model, yk->interlacing_points(all));
        r.frames.push_back(std::move(fr));
      }
      done = true;
    }
  }
  // The structure: the start's designed crossings and interlocks, checked at the end; a run
  // that lost them ends outside the model's limits, whatever its stop said.
  const std::vector<YarnCrossing> designed = yarn_designed_crossings(*yk);
  run->structure_start = check_yarn_structure(*yk, designed, yk->start);
  run->structure_end = check_yarn_structure(*yk, designed, pos);
  r.measures.crossings = run->structure_end.crossings;
  report_yarn_structure(run->structure_end, r.stats);
  run->clearance_min_over_d = min_clearance / d;
  run->clearance_checks = checks;
  run->end = pos;
  for (int j = 0; j < r.model.chart.courses; ++j) {
    double knitted = 0.0;
    const std::vector<int>& idx = yk->course_vertices[j];
    for (std::size_t k = 1; k < idx.size(); ++k)
      knitted += yk->target_length[std::min(idx[k], idx[k - 1])];
    run->course_knitted.push_back(knitted);
    run->course_start.push_back(yk->course_length(j, yk->start));
    run->course_end.push_back(yk->course_length(j, pos));
  }
  r.positions = yk->interlacing_points(pos);
  if (std::all_of(pos.begin(), pos.end(), is_finite)) {
    run->textile = textile_measures(yarn_knit_yarns(*yk, pos), yarn_knit_yarns(*yk, yk->start));
    for (const std::vector<Vec3>& line : yk->course_polylines(pos)) {
      CurveSamples c;
      c.points = line;
      double a = 0.0;
      for (std::size_t k = 0; k < line.size(); ++k) {
        if (k > 0) a += norm(line[k] - line[k - 1]);
        c.u.push_back(a);
      }
      run->centerlines.push_back(std::move(c));
    }
  }
  // The network's yarn measures, in r, from the yarn's own (designed crossings not checked).
  const double r_over_d = yk->r / d;
  r.measures.rest_clearance = run->clearance_start_over_d / r_over_d;
  r.measures.end_clearance = run->clearance_end_over_d / r_over_d;
  r.measures.min_clearance.over_r = run->clearance_min_over_d / r_over_d;
  r.measures.measured_states = checks;
  r.stats.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  r.stats.cpu_seconds = cpu_now() - cpu0;
  r.yarn = std::move(run);
  return r;
}

}  // namespace knitsim
