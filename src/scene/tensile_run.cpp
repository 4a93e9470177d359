#include "src/scene/tensile_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <functional>
#include <memory>
#include <set>
#include <stdexcept>
#include <utility>

#include "solvers/equilibrium_check.hpp"
#include "src/base/text.hpp"
#include "src/core/held_points.hpp"
#include "src/core/invalid_field.hpp"
#include "src/scene/knit_run.hpp"

namespace knitsim {

namespace {

double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// The status of one step's solve (TensileStep::status).
std::string step_status(const RunStats& s) {
  if (s.status != RunStatus::Equilibrium) return to_string(s.status);
  if (s.saddle_escapes > 0) return "equilibrium_after_saddle";
  if (s.certificate == "inconclusive") return "equilibrium_inconclusive";
  return "equilibrium";
}

// The load fraction of each step after rest: up in `steps` equal steps, then down if unloading.
std::vector<double> load_fractions(const TensileOptions& o) {
  std::vector<double> f;
  for (int k = 1; k <= o.steps; ++k) f.push_back(static_cast<double>(k) / o.steps);
  if (o.unload)
    for (int k = o.steps - 1; k >= 0; --k) f.push_back(static_cast<double>(k) / o.steps);
  return f;
}

// The steps whose whole state is kept: `count` spread over 1..total, the last included.
std::set<int> kept_steps(int total, int count) {
  std::set<int> kept;
  for (int k = 1; k <= count; ++k)
    kept.insert(std::max(1, static_cast<int>(std::lround(static_cast<double>(total) * k / count))));
  return kept;
}

}  // namespace

void TensileOptions::validate() const {
  if (direction != "wale" && direction != "course")
    bad_field("--direction", direction, "must be wale or course");
  if (steps < 1 || steps > 100000) bad_field("--steps", steps, "must be an integer in [1, 100000]");
  if (!(strain > 0.0 && strain <= 1.0)) bad_field("--strain", strain, "must be in (0, 1]");
  if (!(gauge_ratio > 0.0 && gauge_ratio <= 100.0))
    bad_field("--gauge-ratio", gauge_ratio, "must be in (0, 100]");
  if (outputs < 0 || outputs > 1000) bad_field("--outputs", outputs, "must be in [0, 1000]");
}

KnitChart tensile_specimen(const KnitChart& chart, const TensileOptions& o, const KnitParams& p) {
  KnitChart s = chart;
  const double w = p.wale_spacing(), h = p.course_spacing();
  if (o.direction == "wale") {  // gauge: the chart's courses; width: wales
    const double gauge = chart.courses * h;
    s.wales = std::max(3L, std::lround(gauge / (o.gauge_ratio * w)));
  } else {  // gauge: wale 0 to the last; width: courses
    const double gauge = (chart.wales - 1) * w;
    s.courses = std::max(2L, std::lround(gauge / (o.gauge_ratio * h)));
  }
  s.stitches.resize(static_cast<size_t>(s.wales) * s.courses);
  for (int j = 0; j < s.courses; ++j)
    for (int i = 0; i < s.wales; ++i)
      s.stitches[static_cast<size_t>(j) * s.wales + i] = chart.at(i % chart.wales, j % chart.courses);
  try {
    s.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--gauge-ratio " + format_number(o.gauge_ratio, 6) +
                                ": the specimen (" + std::to_string(s.wales) + " wales x " +
                                std::to_string(s.courses) + " courses, the chart " +
                                (o.direction == "wale" ? "columns" : "rows") +
                                " repeated) breaks the chart rules: " + e.what());
  }
  return s;
}

double tensile_work(const std::vector<TensileStep>& steps, std::size_t from, std::size_t to) {
  double work = 0.0;
  for (std::size_t k = from; k < to; ++k)
    work += 0.5 * (steps[k].force + steps[k + 1].force) *
            (steps[k + 1].displacement - steps[k].displacement);
  return work;
}

TensileResult run_tensile(const KnitScene& scene, const TensileOptions& o, RunObserver* observer,
                          const TensileKeptCallback& on_kept) {
  o.validate();
  if (scene.yarn.model == KnitModelKind::Yarn)
    throw std::invalid_argument(
        "knit.model = yarn: knitsim tensile runs the network model only (the yarn model has no "
        "clamps yet: docs/yarn_model.md)");
  if (scene.params.pins != KnitPins::None || !scene.params.clamps.empty())
    throw std::invalid_argument(
        std::string(scene.params.pins != KnitPins::None ? "knit.pins" : "knit.clamps") +
        ": tensile clamps the specimen itself (--direction); leave knit.pins and knit.clamps "
        "unset");
  if (!scene.params.point_forces.empty() || scene.params.load_steps > 0)
    throw std::invalid_argument(
        std::string(scene.params.load_steps > 0 ? "knit.load_steps" : "knit.forces") +
        ": tensile steps its own clamp (--steps) and applies no force; leave it unset");
  const bool wale = o.direction == "wale";
  KnitScene spec_scene = scene;
  spec_scene.chart = tensile_specimen(scene.chart, o, scene.params);
  const KnitParams& p = scene.params;
  const double w = p.wale_spacing(), h = p.course_spacing();
  const int W = spec_scene.chart.wales, C = spec_scene.chart.courses;
  const double gauge = wale ? C * h : (W - 1) * w;
  const Vec3 pull = wale ? Vec3{0.0, 1.0, 0.0} : Vec3{1.0, 0.0, 0.0};
  const double u_max = o.strain * gauge;
  KnitClampSpec fixed, moving;
  fixed.where = wale ? KnitClampSpec::Where::Bottom : KnitClampSpec::Where::Left;
  fixed.text = wale ? "bottom" : "left";
  moving.where = wale ? KnitClampSpec::Where::Top : KnitClampSpec::Where::Right;
  moving.text = std::string(wale ? "top" : "right") + " move " +
                (wale ? "0," + format_number(u_max, 17) : format_number(u_max, 17) + ",0");
  moving.path.s = {1.0};
  moving.path.u = {u_max * pull};
  spec_scene.params.clamps = {fixed, moving};

  KnitStart start = start_knit(spec_scene);
  TensileResult r{std::move(start.model), spec_scene.chart, gauge, wale ? W * w : C * h, pull,
                  {}, {}, false, 0.0, 0.0};
  KnitModel& m = r.model;
  MechanicalSystem& sys = m.system();
  HeldPoints& held = *sys.held_points();
  // start_knit stood the moving clamp at its path's end: the test starts from rest.
  std::vector<Vec3> held_rest(held.held_count());
  for (int k = 0; k < held.held_count(); ++k) held_rest[k] = m.points[held.held_particle(k)].rest;
  move_clamps(held, m.clamps, held_rest, 0.0);
  std::vector<double> x = std::move(start.x), v = std::move(start.v);
  const int n = sys.dof();
  // Along-pull rest coordinate of every dof's particle, for the affine predictor: xi in [0, 1].
  std::vector<double> x0(n), v0(n), xi(n, 0.0);
  sys.initial_state(x0.data(), v0.data());
  for (int i = 0; i < n; i += 3)  // the fixed clamp at coordinate 0 (level 0, wale 0)
    xi[i] = xi[i + 1] = xi[i + 2] = (wale ? x0[i + 1] : x0[i]) / gauge;
  // Lateral strain's points: the edge wales on the middle level, or the middle wale's ends.
  const int a = wale ? m.point(0, C / 2) : m.point(W / 2, 0);
  const int b = wale ? m.point(W - 1, C / 2) : m.point(W / 2, C);
  const double lateral0 = wale ? (W - 1) * w : C * h;
  auto measure = [&](int step, double load, const RunStats& stats) {
    TensileStep s;
    s.step = step;
    s.displacement = load * u_max;
    s.strain = s.displacement / gauge;
    s.reactions = clamp_reactions(held, m.clamps, 0.0, x.data());
    s.force = dot(s.reactions[1], pull);
    s.force_per_width = s.force / r.width;
    std::vector<Vec3> pos;
    m.all_positions(0.0, x.data(), pos);
    const double across = wale ? pos[b].x - pos[a].x : pos[b].y - pos[a].y;
    s.lateral_strain = (across - lateral0) / lateral0;
    s.energy = sys.potential_energy(0.0, x.data());
    s.status = step_status(stats);
    s.stats = stats;
    return s;
  };
  const std::vector<double> loads = load_fractions(o);
  const std::set<int> kept = kept_steps(static_cast<int>(loads.size()), o.outputs);
  std::unique_ptr<Integrator> integ = make_integrator("equilibrium");
  const auto wall0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_now();
  auto finish = [&] {
    r.cpu_seconds = cpu_now() - cpu0;
    r.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  };
  // One step's equilibrium. The energy check compares the end with the energy at the step's
  // start; a renewal of the contact's maps during the flow changes E(x) itself (by a little, up
  // or down), so an end "above" the start after renewals is not the dynamics' failing: the
  // solve is repeated from there, with the renewed maps' energy as its reference (at most
  // kEnergyRestarts times; the counters add up, the status and certificate are the last's).
  constexpr int kEnergyRestarts = 3;
  auto solve = [&](std::vector<double>& xs, std::vector<double>& vs) {
    RunStats total = run_to_equilibrium(sys, *integ, scene.options, xs, vs, observer, 0.0);
    for (int again = 0; again < kEnergyRestarts && sys.has_run_state() &&
                        total.status == RunStatus::SpuriousEquilibrium;
         ++again) {
      std::fill(vs.begin(), vs.end(), 0.0);
      RunStats part = run_to_equilibrium(sys, *integ, scene.options, xs, vs, observer, 0.0);
      add_counters(part, total);
      part.cpu_seconds += total.cpu_seconds, part.wall_seconds += total.wall_seconds;
      part.saddle_escapes += total.saddle_escapes;
      part.message += " (the energy check restarted after the contact's renewal)";
      total = part;
    }
    return total;
  };
  // Step 0: the chart settled between its clamps at rest (the rest lattice is not an
  // equilibrium: the clamps may hold a force there already).
  {
    const RunStats stats = solve(x, v);
    r.steps.push_back(measure(0, 0.0, stats));
    if (stats.status != RunStatus::Equilibrium) {
      finish();
      return r;
    }
  }
  // The last equilibria (at most 3, the latest last) and their load fractions: the predictor's
  // nodes.
  std::vector<std::pair<double, std::vector<double>>> solved{{0.0, x}};
  std::vector<double> trial(n);
  double load = 0.0;
  r.complete = true;
  auto admissible = [&](const std::vector<double>& y) {
    return std::isfinite(sys.potential_energy(0.0, y.data()));
  };
  // trial = the polynomial through the last `nodes` equilibria (2: the secant, 3: a quadratic)
  // in the load fraction, at `target`.
  auto extrapolate = [&](int nodes, double target) {
    const std::size_t first = solved.size() - nodes;
    std::fill(trial.begin(), trial.end(), 0.0);
    for (std::size_t node = first; node < solved.size(); ++node) {
      double weight = 1.0;  // Lagrange's basis polynomial of `node` at target
      for (std::size_t q = first; q < solved.size(); ++q)
        if (q != node)
          weight *= (target - solved[q].first) / (solved[node].first - solved[q].first);
      for (int i = 0; i < n; ++i) trial[i] += weight * solved[node].second[i];
    }
  };
  // One Newton step from the predictor y, taken where K is positive definite there, the step
  // admitted whole by the model and the energy falls along it (else y stays): true if taken.
  detail::StiffnessProbe newton_probe(sys, scene.options.factorization);
  std::vector<double> correction;
  auto newton_step = [&](std::vector<double>& y) {
    if (!newton_probe.newton_correction(0.0, y.data(), correction)) return false;
    if (!(sys.admissible_step(0.0, y.data(), correction.data()) >= 1.0)) return false;
    // E at y first, while the model's caches hold y (the factorisation's state); then at the
    // step's end, which the solver's first evaluation then finds cached.
    const double e_start = sys.potential_energy(0.0, y.data());
    for (int i = 0; i < n; ++i) trial[i] = y[i] + correction[i];
    if (!(sys.potential_energy(0.0, trial.data()) <= e_start)) return false;
    y = trial;
    return true;
  };
  // The clamps moved from `load` to `target` and the state solved there. Warm start: the
  // quadratic through the last three equilibria, else the secant through the last two, else the
  // affine stretch from the last equilibrium, else that equilibrium as it is (see the header);
  // where none is admissible (the moved clamp's yarn lands inside another's contact core) the
  // move is halved and each half solved in turn, up to kMaxHalvings deep.
  constexpr int kMaxHalvings = 6;
  std::function<RunStats(double, int)> advance = [&](double target, int depth) -> RunStats {
    const double change = target - load;
    move_clamps(held, m.clamps, held_rest, target);
    bool predicted = false;
    for (int nodes = std::min<int>(3, static_cast<int>(solved.size())); nodes >= 2 && !predicted;
         --nodes) {
      extrapolate(nodes, target);
      predicted = admissible(trial);
    }
    if (!predicted) {
      for (int i = 0; i < n; ++i)
        trial[i] = x[i] + change * u_max * xi[i] * (i % 3 == (wale ? 1 : 0) ? 1.0 : 0.0);
      predicted = admissible(trial);
    }
    if (!predicted && !admissible(x) && depth < kMaxHalvings) {
      move_clamps(held, m.clamps, held_rest, load);
      RunStats first = advance(load + 0.5 * change, depth + 1);
      if (first.status != RunStatus::Equilibrium) return first;
      RunStats second = advance(target, depth + 1);
      add_counters(second, first);
      second.cpu_seconds += first.cpu_seconds, second.wall_seconds += first.wall_seconds;
      second.saddle_escapes += first.saddle_escapes;
      return second;
    }
    if (predicted) x = trial;
    // The contact's maps renewed at the predicted state (as the solver's check after its first
    // step would), so that the Newton step is the renewed energy's; then one Newton step, which
    // the solver's stop certifies at once where it converged (its counters count it).
    const double cpu_newton = cpu_now();
    const auto wall_newton = std::chrono::steady_clock::now();
    sys.update(0.0, x.data());
    const bool newton = newton_step(x);
    const double newton_cpu = cpu_now() - cpu_newton;
    const double newton_wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_newton).count();
    std::fill(v.begin(), v.end(), 0.0);
    RunStats stats = solve(x, v);
    stats.steps += newton ? 1 : 0;
    stats.factorisations += 1;
    stats.cpu_seconds += newton_cpu, stats.wall_seconds += newton_wall;
    load = target;
    if (solved.size() == 3) solved.erase(solved.begin());
    solved.emplace_back(load, x);
    return stats;
  };
  for (std::size_t k = 0; k < loads.size(); ++k) {
    const RunStats stats = advance(loads[k], 0);
    r.steps.push_back(measure(static_cast<int>(k) + 1, load, stats));
    const bool ok = stats.status == RunStatus::Equilibrium;
    if (ok && kept.count(static_cast<int>(k) + 1)) {
      TensileResult::Kept keep{static_cast<int>(k) + 1, x, {}, stats};
      m.all_positions(0.0, x.data(), keep.positions);
      r.kept.push_back(std::move(keep));
      if (on_kept) on_kept(r, static_cast<int>(k) + 1, v);
    }
    if (!ok) {
      r.complete = false;
      break;
    }
  }
  finish();
  return r;
}

}  // namespace knitsim
