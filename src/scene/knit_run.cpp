#include "src/scene/knit_run.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "src/base/text.hpp"
#include "src/scene/knit_load_steps.hpp"
#include "src/scene/yarn_knit_run.hpp"

namespace knitsim {

namespace {

// The clearance over the run is measured when an interlacing point has moved by 0.05 r since
// the last measured state (src/measure/yarn_measures.hpp, ClearanceOverRun: a dip shallower than
// 2 A 0.05 r can be missed, A the measured amplification, reported; figures per chart in
// docs/knit.md, "Yarn measures").
constexpr double kClearanceResample = 0.05;

// The clearance and crossings at the end of the run, against the rest state's `crossings`.
void measure_end(const KnitModel& model, const std::vector<Vec3>& end,
                 const std::vector<YarnCrossing>& crossings, KnitMeasures& measures) {
  if (std::all_of(end.begin(), end.end(), is_finite)) {
    const YarnPolylines end_lines = yarn_polylines(model, end);
    measures.end_clearance = yarn_clearance(model, end_lines).over_r;
    measures.crossings = check_crossings(crossings, end_lines);
  } else {
    measures.end_clearance = std::nan("");
    measures.crossings.designed = static_cast<int>(crossings.size());
    measures.crossings.changed = -1;  // unknown: the end state is not finite
  }
}

// With yarn contact, a chart whose yarns lie inside the contact's core already at rest (tucks
// stacked 8 high or more in one wale, a block of tucks) cannot start: its first force is
// infinite. Refused before anything is made, naming the row (top course first) and column.
void refuse_overlap_at_rest(const KnitModel& m) {
  if (!m.contact) return;
  const YarnClearance c = yarn_clearance(m, yarn_polylines(m, m.rest_positions()));
  if (!(c.over_r < kContactCore)) return;
  const double w =
      m.chart.wales > 1 ? m.points[m.point(1, 0)].rest.x - m.points[m.point(0, 0)].rest.x : 1.0;
  const long wale = std::clamp(std::lround(c.where.x / w), 0L, long{m.chart.wales - 1});
  std::ostringstream os;
  os << "chart row " << m.chart.courses - c.b.course << ", column " << wale + 1
     << (c.a.course == c.b.course
             ? ": two stretches of the yarn of course " + std::to_string(c.a.course + 1)
             : ": the yarns of courses " + std::to_string(c.a.course + 1) + " and " +
                   std::to_string(c.b.course + 1))
     << " (from the bottom) lie " << format_number(c.over_r, 3)
     << " r apart at rest, inside the yarn contact's core (" << kContactCore
     << " r): the model cannot hold this stitch arrangement (tucks stacked 8 or more high in "
        "one wale); knit.contact = 0 runs it without contact";
  throw std::invalid_argument(os.str());
}

}  // namespace

std::string default_knit_integrator(bool yarn_contact) {
  return yarn_contact ? "equilibrium" : "cvode-bdf";
}

void set_default_knit_velocity_atol(IntegratorOptions& options, const KnitParams& params,
                                    const IntegratorInfo& integrator) {
  if (!params.mechanism() && integrator.adaptive) options.velocity_atol = kStabilisedVelocityAtol;
}

std::vector<std::string> knit_run_warnings(const KnitParams& params, const std::string& integrator,
                                           const IntegratorInfo& info) {
  std::vector<std::string> w;
  if (params.yarn_contact() && info.explicit_method)
    w.push_back("yarn contact with " + integrator +
                ": the chart's first impacts (~10 us in) carry more energy than the barrier holds "
                "above its core in double precision, so it fails there whatever its step "
                "(docs/knit.md, \"What is not met, and why\"); equilibrium (the default) and "
                "implicit-euler keep every pair off its core");
  if (params.mechanism())
    w.push_back(std::string(params.network == KnitNetwork::Paper ? "knit.network = paper"
                                                                 : "knit.stabiliser = 0") +
                ": paper 2's bare network is a mechanism (blocks of fabric shear and swing at no "
                "energy); its steady state depends on the path (integrator, step, tolerances)");
  return w;
}

std::string knit_overlap_warning(const KnitMeasures& m) {
  if (m.crossings.changed <= 0 && !(m.min_clearance.over_r < kClearanceWarning)) return "";
  return "yarns overlap: clearance down to " + format_number(m.min_clearance.over_r, 3) +
         " r (courses " + std::to_string(m.min_clearance.a.course) + " and " +
         std::to_string(m.min_clearance.b.course) + ", at check " +
         std::to_string(m.check_min_clearance) + ", t = " + format_number(m.t_min_clearance, 3) +
         " s), " + std::to_string(m.crossings.changed) + " of " +
         std::to_string(m.crossings.designed) + " designed crossings changed over/under order";
}

KnitStart start_knit(const KnitScene& scene) {
  if (scene.yarn.model == KnitModelKind::Yarn) {
    if (scene.params.pins != KnitPins::None || !scene.params.clamps.empty() || scene.params.gravity)
      throw std::invalid_argument(
          "knit.model = yarn holds its first and last courses itself: knit.pins, knit.clamps and "
          "knit.gravity apply to knit.model = network only (docs/yarn_model.md)");
    if (knit_load_stepped(scene.params))
      throw std::invalid_argument(
          "knit.forces and knit.load_steps apply to knit.model = network only (docs/knit.md, "
          "\"Under load\")");
    return start_yarn_knit(scene);
  }
  KnitStart s{build_knit(scene.chart, scene.params), 0.0, {}, {}, nullptr};  // validates params
  refuse_overlap_at_rest(s.model);
  validate_knit_loads(s.model);
  s.x.resize(s.model.network.dof());
  s.v.resize(s.model.network.dof());
  s.model.network.initial_state(s.x.data(), s.v.data());
  // Moving clamps stand at their path's end (load fraction 1): a knit run is one load step
  // (knitsim tensile steps through them; so does a run under load, from rest).
  const bool moves = !knit_load_stepped(scene.params) &&
                     std::any_of(s.model.clamps.begin(), s.model.clamps.end(),
                                 [](const Clamp& c) { return !c.path.fixed(); });
  if (moves) {
    HeldPoints& held = *s.model.system().held_points();
    std::vector<Vec3> rest(held.held_count());
    for (int k = 0; k < held.held_count(); ++k) rest[k] = s.model.points[held.held_particle(k)].rest;
    move_clamps(held, s.model.clamps, rest, 1.0);
  }
  return s;
}

void continue_knit(KnitStart& start, const RunState& from) {
  if (start.yarn)
    throw std::invalid_argument("knit.model = yarn cannot go on from a saved state yet");
  if (knit_load_stepped(start.model.params))
    throw std::invalid_argument(
        "a run under load (knit.forces, a clamp's force, knit.load_steps) steps from rest; it "
        "cannot go on from a saved state");
  if (from.x.size() != start.x.size())  // same chart and parameters: only a corrupt file gets here
    throw std::invalid_argument("the state has " + std::to_string(from.x.size()) +
                                " unknowns; this chart has " + std::to_string(start.x.size()));
  start.t = from.t, start.x = from.x, start.v = from.v;
  // The contact points were made at rest: linearised afresh about the saved state, they stand
  // for the yarn there (the run goes on from the same state, not with the same points).
  if (start.model.contact && !start.model.contact->renew(start.t, start.x.data()))
    throw std::invalid_argument(
        "the saved state's yarns lie inside the contact's core (closer than " +
        format_number(kContactCore, 3) + " r); it cannot go on");
}

KnitResult run_knit(KnitStart start, const KnitScene& scene, const std::string& integrator,
                    RunObserver* observer) {
  if (start.yarn) return run_yarn_knit(std::move(start), scene, integrator, observer);
  std::unique_ptr<Integrator> integ = make_integrator(integrator);
  KnitResult r{std::move(start.model), {}, start.t, std::move(start.x), std::move(start.v),
               {}, {}, {}, nullptr, {}};
  const KnitModel& model = r.model;
  const int dof = model.network.dof();
  const YarnPolylines rest_lines = yarn_polylines(model, model.rest_positions());
  const std::vector<YarnCrossing> crossings = designed_crossings(model, rest_lines);
  KnitMeasures& measures = r.measures;
  measures.rest_clearance = yarn_clearance(model, rest_lines).over_r;

  FrameRecorder recorder(scene.frames, dof, observer);
  recorder.record(r.t_start, r.x.data(), model.system().static_residual(r.t_start, r.x.data()));
  ClearanceOverRun clearance(model, &recorder, kClearanceResample);
  clearance.observe(r.t_start, r.x.data(), true);
  const double measure_cpu_before = clearance.cpu_seconds();
  r.stats = knit_load_stepped(scene.params)
                ? run_knit_load_steps(r.model, *integ, scene.options, r.x, r.v, &clearance,
                                      r.load_steps)
                : run_to_equilibrium(r.model.system(), *integ, scene.options, r.x, r.v,
                                     &clearance, r.t_start);
  measures.measure_cpu_seconds = clearance.cpu_seconds() - measure_cpu_before;
  clearance.observe(r.stats.t_final, r.x.data(), true);
  measures.min_clearance = clearance.minimum();
  measures.t_min_clearance = clearance.t_of_minimum();
  measures.check_min_clearance = clearance.check_of_minimum();
  measures.measured_states = clearance.measured_states();
  measures.min_resolution = clearance.resolution_over_r();
  r.positions = knit_positions(model, r.stats.t_final, r.x);
  measure_end(model, r.positions, crossings, measures);
  r.frames = recorder.frames();
  return r;
}

KnitResult run_knit(const KnitScene& scene, const std::string& integrator, RunObserver* observer,
                    const RunState* from) {
  KnitStart start = start_knit(scene);
  if (from) continue_knit(start, *from);
  return run_knit(std::move(start), scene, integrator, observer);
}

std::vector<ClampReaction> knit_clamp_reactions(const KnitModel& m, double t,
                                                const std::vector<double>& x) {
  const HeldPoints& held = *m.system().held_points();
  const std::vector<Vec3> each = clamp_reactions(held, m.clamps, t, x.data());
  const std::vector<Vec3> at = held.held_positions(t);
  std::vector<ClampReaction> out;
  for (std::size_t c = 0; c < m.clamps.size(); ++c) {
    const Clamp& clamp = m.clamps[c];
    const int first = clamp.held.front();
    out.push_back({clamp.name, static_cast<int>(clamp.held.size()),
                   at[first] - m.points[held.held_particle(first)].rest, each[c]});
  }
  return out;
}

Vec3 knit_weight(const KnitModel& m) {
  const SpringNetworkSpec& spec = m.network.spec();
  double mass = 0.0;
  for (double q : spec.masses) mass += q;
  return mass * spec.gravity;
}

std::vector<Vec3> knit_positions(const KnitModel& m, double t, const std::vector<double>& x) {
  std::vector<Vec3> pos;
  m.all_positions(t, x.data(), pos);
  return pos;
}

double max_displacement_over_r(const KnitModel& m, const std::vector<Vec3>& pos) {
  double d = 0.0;
  for (size_t k = 0; k < pos.size(); ++k) d = std::max(d, norm(pos[k] - m.points[k].rest));
  return d / m.params.loop_radius;
}

}  // namespace knitsim
