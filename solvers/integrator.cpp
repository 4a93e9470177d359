#include "solvers/integrator.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "solvers/equilibrium_check.hpp"
#include "solvers/factories.hpp"
#include "src/core/invalid_field.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim {

namespace {

// The round-off floor may stand in for equilibrium_tol up to this factor above it: a tolerance
// is never loosened by more (equilibrium_tol = 1e-300 still means "run to t_max"). It also
// bounds when the floor (one pass over the springs) is worth evaluating.
constexpr double kFloorCheckFactor = 1e3;
// The stop in positions is tested (one factorisation of K) once the static residual is below
// max(kProbeStart, equilibrium_tol), then each time it has fallen kProbeDrop-fold since the last
// test, or after kProbeEvery checks, or once t has doubled since (an adaptive integrator's slow
// tail takes few, long steps), and at t_max: a few factorisations per run.
constexpr double kProbeStart = 1e-4;
constexpr double kProbeDrop = 10.0;
constexpr long kProbeEvery = 50;
// Above kProbeStart the stop is still tested where the residual stands on its round-off floor
// (within kFloorProbe of it): a very light fabric's spring forces round off to a large part of
// a particle's weight, its residual cannot fall to kProbeStart, and without this only t_max
// ended its run (fabric.areal_density = 1e-6: time_limit). The floor is evaluated only where
// the residual is below 1, every kFloorEvery checks.
constexpr double kFloorProbe = 2.0;
constexpr long kFloorEvery = 16;
// The energy check's allowance for round-off, relative to the energies compared.
constexpr double kEnergyRoundoff = 1e-9;
// Fewer steps than this across the pins' motion: the energy check is inconclusive (below).
constexpr long kMotionSteps = 10;

struct Entry {
  IntegratorInfo info;
  std::function<std::unique_ptr<Integrator>()> make;
};

const std::vector<Entry>& registry() {
  static const std::vector<Entry> entries = [] {
    std::vector<Entry> e;
    auto add = [&e](std::function<std::unique_ptr<Integrator>()> make) {
      auto probe = make();
      e.push_back({probe->info(), std::move(make)});
    };
    add(detail::make_euler);
    add(detail::make_verlet);
    add(detail::make_implicit_euler);
    add(detail::make_cvode_bdf);
    add(detail::make_cvode_bdf_dense);
    add(detail::make_cvode_bdf_gmres);
    add(detail::make_cvode_adams);
    add(detail::make_arkode_erk);
    add(detail::make_arkode_dirk);
    add(detail::make_arkode_imex);
    add(detail::make_static);
    add(detail::make_equilibrium);
    return e;
  }();
  return entries;
}

}  // namespace

void IntegratorOptions::validate() const {
  if (!(rtol > 0.0 && rtol < 1.0)) bad_field("rtol", rtol, "must be in (0, 1)");
  if (!(atol > 0.0) || !std::isfinite(atol)) bad_field("atol", atol, "must be > 0");
  if (!(velocity_atol >= 0.0) || !std::isfinite(velocity_atol))
    bad_field("velocity_atol", velocity_atol, "must be >= 0 m/s and finite (0 = same as atol)");
  if (!(dt >= 0.0) || !std::isfinite(dt)) bad_field("dt", dt, "must be >= 0 s (0 = automatic)");
  if (!(dt_safety > 0.0 && dt_safety <= 1.0))
    bad_field("dt_safety", dt_safety, "must be in (0, 1]");
  if (max_order < 0 || max_order > 12)
    bad_field("max_order", max_order, "must be in 0..12 (0 = method default)");
  if (max_steps <= 0) bad_field("max_steps", static_cast<double>(max_steps), "must be > 0");
  // Bounded where the adaptive integrators still work: CVODE and ARKODE take t_max as their
  // output and stop time, and their first-step heuristic fails beyond ~1e21 s (CV_ERR_FAILURE
  // at t = 0) or at 1e-300 s ("tstop is behind current t").
  if (!(t_max >= 1e-9 && t_max <= 1e15)) bad_field("t_max", t_max, "must be in [1e-9, 1e15] s");
  if (!(equilibrium_tol > 0.0) || !std::isfinite(equilibrium_tol))
    bad_field("equilibrium_tol", equilibrium_tol, "must be > 0");
  if (!(position_tol > 0.0 && position_tol <= 1e-2))
    bad_field("position_tol", position_tol, "must be in (0, 1e-2] m");
  if (!(max_wall_seconds >= 0.0) || !std::isfinite(max_wall_seconds))
    bad_field("max_wall_seconds", max_wall_seconds, "must be >= 0 s and finite (0 = no cap)");
  if (check_every < 0)
    bad_field("check_every", static_cast<double>(check_every), "must be >= 0 (0 = automatic)");
  if (!(runaway_position > 0.0) || !std::isfinite(runaway_position))
    bad_field("runaway_position", runaway_position, "must be > 0 m and finite");
  if (max_restarts < 0 || max_restarts > 1000)
    bad_field("max_restarts", max_restarts, "must be in 0..1000 (0 = never restart)");
  if (stall_checks < 0 || stall_checks > 1'000'000'000)
    bad_field("stall_checks", static_cast<double>(stall_checks),
              "must be in 0..1000000000 (0 = never)");
  if (krylov_dim < 0 || krylov_dim > 500)
    bad_field("krylov_dim", krylov_dim, "must be in 0..500 (0 = default)");
  if (!(krylov_eps_lin > 0.0 && krylov_eps_lin <= 1.0))
    bad_field("krylov_eps_lin", krylov_eps_lin, "must be in (0, 1]");
}

const char* to_string(IntegratorOptions::NewtonSolver s) {
  switch (s) {
    case IntegratorOptions::NewtonSolver::Klu:
      return "klu";
    case IntegratorOptions::NewtonSolver::SchurLdl:
      return "ldl";
    case IntegratorOptions::NewtonSolver::SchurCgLdl:
      return "cg-ldl";
  }
  return "?";
}

const char* to_string(IntegratorOptions::Factorization f) {
  switch (f) {
    case IntegratorOptions::Factorization::Automatic:
      return "auto";
    case IntegratorOptions::Factorization::Simplicial:
      return "simplicial";
    case IntegratorOptions::Factorization::Block:
      return "block";
    case IntegratorOptions::Factorization::Supernodal:
      return "supernodal";
  }
  return "?";
}

const char* to_string(IntegratorOptions::GmresPreconditioner p) {
  switch (p) {
    case IntegratorOptions::GmresPreconditioner::None:
      return "none";
    case IntegratorOptions::GmresPreconditioner::BlockJacobi:
      return "block-jacobi";
    case IntegratorOptions::GmresPreconditioner::SchurIc:
      return "schur-ic";
    case IntegratorOptions::GmresPreconditioner::SchurLdl:
      return "schur-ldl";
  }
  return "?";
}

const char* to_string(RunStatus s) {
  switch (s) {
    case RunStatus::Equilibrium:
      return "equilibrium";
    case RunStatus::SpuriousEquilibrium:
      return "spurious_equilibrium";
    case RunStatus::OutsideModelLimits:
      return "outside_model_limits";
    case RunStatus::TimeLimit:
      return "time_limit";
    case RunStatus::StepLimit:
      return "step_limit";
    case RunStatus::WallLimit:
      return "wall_limit";
    case RunStatus::Interrupted:
      return "interrupted";
    case RunStatus::Stalled:
      return "stalled";
    case RunStatus::SolverFailure:
      return "solver_failure";
    case RunStatus::Diverged:
      return "diverged";
  }
  return "unknown";
}

void add_counters(RunStats& total, const RunStats& part) {
  total.steps += part.steps;
  total.rhs_evals += part.rhs_evals;
  total.jac_evals += part.jac_evals;
  total.lin_setups += part.lin_setups;
  total.factorisations += part.factorisations;
  total.lin_iters += part.lin_iters;
  total.nonlin_iters += part.nonlin_iters;
  total.nonlin_fails += part.nonlin_fails;
  total.err_test_fails += part.err_test_fails;
  total.ldl_fallbacks += part.ldl_fallbacks;
  if (total.factorization.empty()) {
    total.factorization = part.factorization;
    total.factor_nonzeros = part.factor_nonzeros;
    total.factor_flops = part.factor_flops;
  }
  total.max_order_used = std::max(total.max_order_used, part.max_order_used);
}

const std::vector<IntegratorInfo>& integrator_catalog() {
  static const std::vector<IntegratorInfo> infos = [] {
    std::vector<IntegratorInfo> v;
    for (const auto& e : registry()) v.push_back(e.info);
    return v;
  }();
  return infos;
}

std::unique_ptr<Integrator> make_integrator(const std::string& name) {
  for (const auto& e : registry())
    if (e.info.name == name) return e.make();
  std::string names;
  for (const auto& e : registry()) names += (names.empty() ? "" : ", ") + e.info.name;
  throw std::invalid_argument("integrator = " + name + ": must be one of " + names);
}

namespace {

// One run to equilibrium (run_to_equilibrium): the loop in run(), its steps and predicates named
// beside it. `sys` is what the integrator evaluates; `updatable` the same object where the run
// may update its state between steps (MechanicalSystem::update), else null.
class EquilibriumRun {
 public:
  EquilibriumRun(const MechanicalSystem& sys, MechanicalSystem* updatable, Integrator& integ,
                 const IntegratorOptions& opt, std::vector<double>& x, std::vector<double>& v,
                 RunObserver* observer, double t0)
      : sys_(sys),
        updatable_(updatable),
        integ_(integ),
        opt_(opt),
        x_(x),
        v_(v),
        observer_(observer),
        t0_(t0),
        n_(sys.dof()),
        t_start_eq_(sys.equilibrium_start_time()) {}

  RunStats run() {
    start();
    // A stop asked before the run (a driver of many runs, each concluded at its start, would
    // otherwise never see it: a tensile test's steps certified by their warm start).
    if (observer_) observer_->on_run_start();
    if (interrupted()) return finish(RunStatus::Interrupted, "interrupted before equilibrium");
    // The initial state may already be at rest (e.g. a plain knit chart).
    if (t_start_eq_ <= t0_) {
      const double r0 = sys_.static_residual(t0_, x_.data());
      const std::string why = stop_test(t0_, x_.data(), r0, true);
      if (!why.empty()) return conclude("initial state is already at equilibrium: " + why);
    }
    double t_prev = integ_.time();
    while (true) {
      const Integrator::Step st = integ_.step(opt_.t_max);
      // After every step, not only at the residual checks: one check can be minutes away (a
      // large grid's factorisations). A step cut short by the request (the SUNDIALS callbacks
      // and the block factorisation read it too) fails: the state is the last accepted one.
      if (interrupted()) return finish(RunStatus::Interrupted, "interrupted before equilibrium");
      if (!st.ok) {  // a failed step is not counted: the cap is on steps taken
        const bool diverged = !state_ok();
        if (!diverged && restart_after_failure(st)) continue;
        return end_after_failure(st, diverged);
      }
      ++steps_;
      if (t_prev < t_start_eq_) ++motion_steps_;
      const double t = integ_.time();
      if (observer_) observer_->on_step(t, t - t_prev, integ_.last_order());
      t_prev = t;
      if (check_due(t)) {
        std::optional<RunStats> end = check(t);
        if (end) return *end;
      }
      if (t >= opt_.t_max) return finish(RunStatus::TimeLimit, "t_max reached before equilibrium");
      if (steps_ >= opt_.max_steps)
        return finish(RunStatus::StepLimit, "step cap reached before equilibrium");
    }
  }

 private:
  using clock = std::chrono::steady_clock;

  // Validates, fills an empty state with the model's initial one, starts the integrator.
  void start() {
    opt_.validate();
    if (!(t0_ >= 0.0) || !(t0_ < opt_.t_max))
      throw std::invalid_argument("run_to_equilibrium: t0 = " + std::to_string(t0_) +
                                  " s: must be >= 0 and < t_max");
    if (x_.empty() || v_.empty()) {
      x_.assign(n_, 0.0);
      v_.assign(n_, 0.0);
      sys_.initial_state(x_.data(), v_.data());
    }
    if (static_cast<int>(x_.size()) != n_ || static_cast<int>(v_.size()) != n_)
      throw std::invalid_argument("run_to_equilibrium: state size does not match the model");
    wall_start_ = clock::now();
    cpu_start_ = std::clock();
    stats_.integrator = integ_.info().name;
    integ_.start(sys_, t0_, x_.data(), v_.data(), opt_);
    const bool cheap_steps = integ_.info().explicit_method && !integ_.info().adaptive;
    check_every_ = opt_.check_every > 0 ? opt_.check_every : (cheap_steps ? 1000 : 1);
    note_reference(t0_, x_.data(), v_.data());
  }

  double wall() const { return std::chrono::duration<double>(clock::now() - wall_start_).count(); }

  // The caller's flag, or the process-wide request (src/core/stop_request.hpp) that the loops
  // inside a step read: a step they cut short must end the run, not count as a failure.
  bool interrupted() const {
    return (opt_.interrupt && opt_.interrupt->load(std::memory_order_relaxed)) || stop_requested();
  }

  // The state is finite and within runaway_position.
  bool state_ok() const {
    const double* xs = integ_.positions();
    const double* vs = integ_.velocities();
    for (int i = 0; i < n_; ++i)
      if (!(std::abs(xs[i]) <= opt_.runaway_position) || !std::isfinite(vs[i])) return false;
    return true;
  }

  // A failed step from a sound state that the integrator may cure by a restart: true if it
  // restarted.
  bool restart_after_failure(const Integrator::Step& st) {
    if (st.recoverable && restarts_ < opt_.max_restarts && integ_.restart()) {
      ++restarts_;
      return true;
    }
    return false;
  }

  RunStats end_after_failure(const Integrator::Step& st, bool diverged) {
    std::string why = st.message;
    if (restarts_ > 0) why += " (after " + std::to_string(restarts_) + " restarts)";
    return finish(diverged ? RunStatus::Diverged : RunStatus::SolverFailure, why);
  }

  bool check_due(double t) const { return steps_ % check_every_ == 0 || t >= opt_.t_max; }

  // The check every check_every steps: the state's sanity, the model's update, the stop, the
  // caps. A RunStats where the run ends there.
  std::optional<RunStats> check(double t) {
    if (!state_ok()) {
      std::ostringstream os;
      os << "non-finite or runaway state at t = " << t << " s";
      integ_.fill_stats(stats_);
      if (stats_.dt_predicted > 0.0)
        os << " (dt = " << stats_.dt << " s, predicted stability limit " << stats_.dt_predicted
           << " s)";
      return finish(RunStatus::Diverged, os.str());
    }
    if (updatable_ && updatable_->update(t, integ_.positions())) integ_.model_changed();
    const double r = sys_.static_residual(t, integ_.positions());
    if (observer_) observer_->on_check(t, integ_.positions(), integ_.velocities(), r);
    note_reference(t, integ_.positions(), integ_.velocities());
    if (t >= t_start_eq_) {
      const std::string why = stop_test(t, integ_.positions(), r, t >= opt_.t_max);
      if (!why.empty()) return conclude(why);
    }
    if (stalled(t, r)) return finish(RunStatus::Stalled, stall_message(t));
    if (opt_.max_wall_seconds > 0.0 && wall() > opt_.max_wall_seconds)
      return finish(RunStatus::WallLimit, "wall-clock cap reached");
    return std::nullopt;
  }

  // The stall rule (docs/equilibrium.md, "The stall rule"), at a check past the pins' motion
  // that did not stop the run: progress is t advancing or the static residual r falling below
  // its lowest value since t last advanced; stall_checks checks in a row without it end the
  // run. t advances at every step of the dynamics, so only a run whose t stands still (the
  // equilibrium solver's flow, a continuation in h) can stall; there the residual must come
  // down, and a flow whose residual climbs for ever (a knit chart whose yarns crawl while its
  // energy falls by 1e-5 of itself a step) is ended, not run for its 5000 flow steps and then
  // the dynamics' failing error test.
  bool stalled(double t, double r) {
    if (opt_.stall_checks <= 0 || t < t_start_eq_) return false;
    if (t != t_still_ || r < lowest_residual_) {
      t_still_ = t;
      lowest_residual_ = r;
      checks_without_progress_ = 0;
      return false;
    }
    return ++checks_without_progress_ >= stall_window();
  }
  // The checks without progress that end a run: stall_checks for a model of up to 2500
  // unknowns, growing as sqrt(n / 2500) above it (default 1000: 20 sqrt(n)), since a converging
  // flow's longest stretch without a new minimum grows with the grid (about 4 sqrt(n) measured on
  // two_corner's refinements: docs/equilibrium.md, "The stall rule").
  long stall_window() const {
    const double grow = std::max(1.0, std::sqrt(static_cast<double>(n_) / 2500.0));
    return static_cast<long>(std::ceil(static_cast<double>(opt_.stall_checks) * grow));
  }

  std::string stall_message(double t) const {
    std::ostringstream os;
    os << "stalled: the static residual stayed above its lowest value " << lowest_residual_
       << " for " << checks_without_progress_ << " checks in a row (--stall-checks) while t "
       << "stood at " << t << " s; the run made no progress toward an equilibrium";
    return os.str();
  }

  // The energy check's reference: the total energy once the pins have stopped. From then on
  // damping can only lower it, so no state the dynamics reach lies above it.
  void note_reference(double t, const double* xs, const double* vs) {
    if (std::isnan(energy_reference_) && t >= t_start_eq_)
      energy_reference_ = sys_.potential_energy(t, xs) + sys_.kinetic_energy(vs);
  }

  // Whether (t, xs) at residual r is due a probe of K (a factorisation): below
  // max(kProbeStart, equilibrium_tol) or within kFloorProbe of its round-off floor, and forced,
  // or fallen kProbeDrop-fold since the last probe, or kProbeEvery checks since, or t doubled
  // since.
  bool probe_due(double t, const double* xs, double r, bool force) {
    ++checks_since_probe_;
    if (!(r <= std::max(kProbeStart, opt_.equilibrium_tol))) {
      if (!(r <= 1.0)) return false;
      if (++floor_age_ >= kFloorEvery) floor_seen_ = sys_.residual_roundoff(t, xs), floor_age_ = 0;
      if (!(r <= kFloorProbe * floor_seen_)) return false;
    }
    return force || r <= next_probe_ || checks_since_probe_ >= kProbeEvery ||
           (t > 0.0 && t >= 2.0 * t_probe_);
  }

  // The stop (a probe of K where the residual is small, equilibrium_check.hpp): the status
  // message if (t, xs) passes it, with the certificate in stats_; else "".
  std::string stop_test(double t, const double* xs, double r, bool force) {
    if (!probe_due(t, xs, r, force)) return "";
    next_probe_ = r / kProbeDrop;
    checks_since_probe_ = 0;
    t_probe_ = t;
    if (!probe_) probe_ = std::make_unique<detail::StiffnessProbe>(sys_, opt_.factorization);
    const detail::StiffnessProbe::Result p = probe_->probe(t, xs);
    std::ostringstream os;
    if (p.singular) {  // rigid-body or mechanism modes: the residual decides
      const double threshold = equilibrium_threshold(sys_, t, xs, opt_.equilibrium_tol);
      if (!(r <= threshold)) return "";
      os << "static residual " << r << " below " << threshold
         << " (the stop in positions does not apply: the stiffness is singular)";
      stats_.certificate = "inconclusive";
      stats_.residual_decided = true;
    } else {
      if (p.negative_pivots > 0) return "";  // a saddle: not yet
      const double tol = std::max(opt_.position_tol, p.newton_floor);
      if (!(p.newton_step <= tol)) return "";
      os << "Newton correction " << p.newton_step << " m below ";
      if (p.newton_floor > opt_.position_tol)
        os << "its round-off floor " << tol << " m, the correction the forces' rounding alone "
           << "makes, above position_tol " << opt_.position_tol << " m";
      else
        os << "position_tol " << tol << " m";
      stats_.certificate = "stable_minimum";
      stats_.residual_decided = false;
    }
    stats_.negative_pivots = p.negative_pivots;
    stats_.min_eigenvalue = p.min_eigenvalue;
    stats_.eigenvalue_threshold = p.threshold;
    stats_.newton_step = p.newton_step;
    stats_.newton_floor = p.newton_floor;
    return os.str();
  }

  // An end state that passed the stop: Equilibrium, unless it fails the energy check. A run
  // that crossed the pins' motion in fewer than kMotionSteps steps did not follow the pins'
  // path, so its reference is not the dynamics' energy (docs/equilibrium.md, "The certificate
  // and the energy check", has an example) and the energy check cannot certify its end state.
  RunStats conclude(std::string message) {
    const double t = integ_.time();
    const double e =
        sys_.potential_energy(t, integ_.positions()) + sys_.kinetic_energy(integ_.velocities());
    stats_.energy = e;
    stats_.energy_reference = energy_reference_;
    if (t_start_eq_ > t0_ && motion_steps_ < kMotionSteps) {
      std::ostringstream os;
      os << message << "; energy check inconclusive: the pins' motion was crossed in "
         << motion_steps_ << " step(s), fewer than " << kMotionSteps
         << ", so the run's energy when the pins stopped is not the dynamics'";
      message = os.str();
      stats_.certificate = "inconclusive";
    }
    const double allowance = kEnergyRoundoff * (std::abs(e) + std::abs(energy_reference_));
    if (e > energy_reference_ + allowance) {
      std::ostringstream os;
      os << "energy " << e << " J above the " << energy_reference_
         << " J the run had once the pins stopped: the damped dynamics cannot reach this state ("
         << message << ")";
      stats_.certificate = "";
      return finish(RunStatus::SpuriousEquilibrium, os.str());
    }
    return finish(RunStatus::Equilibrium, message);
  }

  // The end: the final state into x, v and the run's figures into the result.
  RunStats finish(RunStatus status, std::string message) {
    const double t = integ_.time();
    std::copy_n(integ_.positions(), n_, x_.begin());
    std::copy_n(integ_.velocities(), n_, v_.begin());
    integ_.fill_stats(stats_);
    if (probe_) stats_.stop_factorisations = probe_->factorisations();
    stats_.restarts = restarts_;
    stats_.status = status;
    stats_.message = std::move(message) + integ_.run_note();
    stats_.t_final = t;
    stats_.residual = sys_.static_residual(t, x_.data());
    stats_.residual_floor = sys_.residual_roundoff(t, x_.data());
    stats_.wall_seconds = wall();
    stats_.cpu_seconds = static_cast<double>(std::clock() - cpu_start_) / CLOCKS_PER_SEC;
    return stats_;
  }

  const MechanicalSystem& sys_;
  MechanicalSystem* const updatable_;
  Integrator& integ_;
  const IntegratorOptions& opt_;
  std::vector<double>& x_;
  std::vector<double>& v_;
  RunObserver* const observer_;
  const double t0_;
  const int n_;
  const double t_start_eq_;

  RunStats stats_;
  clock::time_point wall_start_;
  std::clock_t cpu_start_ = 0;
  long check_every_ = 1;
  long steps_ = 0;
  long restarts_ = 0;
  long motion_steps_ = 0;  // steps taken while the pins moved (conclude)
  double energy_reference_ = std::numeric_limits<double>::quiet_NaN();
  // The stop's probes of K (equilibrium_check.hpp), made at the first.
  std::unique_ptr<detail::StiffnessProbe> probe_;
  double next_probe_ = std::max(kProbeStart, opt_.equilibrium_tol);
  long checks_since_probe_ = 0;
  double t_probe_ = std::numeric_limits<double>::infinity();  // t of the latest probe
  double floor_seen_ = 0.0;  // the residual's round-off floor at a recent check
  long floor_age_ = kFloorEvery;
  // The stall rule (stalled()): t at the latest check, the lowest residual since t last
  // advanced, and the checks since the last progress.
  double t_still_ = std::numeric_limits<double>::quiet_NaN();
  double lowest_residual_ = std::numeric_limits<double>::infinity();
  long checks_without_progress_ = 0;
};

}  // namespace

RunStats run_to_equilibrium(MechanicalSystem& sys, Integrator& integ, const IntegratorOptions& opt,
                            std::vector<double>& x, std::vector<double>& v, RunObserver* observer,
                            double t0) {
  return EquilibriumRun(sys, &sys, integ, opt, x, v, observer, t0).run();
}

RunStats run_to_equilibrium(const MechanicalSystem& sys, Integrator& integ,
                            const IntegratorOptions& opt, std::vector<double>& x,
                            std::vector<double>& v, RunObserver* observer, double t0) {
  if (sys.has_run_state())
    throw std::logic_error("run_to_equilibrium: " + sys.describe() +
                           " has run state: pass it non-const, so it can be updated");
  return EquilibriumRun(sys, nullptr, integ, opt, x, v, observer, t0).run();
}

RunStats run_to_equilibrium(MechanicalSystem& sys, const std::string& integrator,
                            const IntegratorOptions& opt, std::vector<double>& x,
                            std::vector<double>& v, RunObserver* observer, double t0) {
  auto integ = make_integrator(integrator);
  return run_to_equilibrium(sys, *integ, opt, x, v, observer, t0);
}

RunStats run_to_equilibrium(const MechanicalSystem& sys, const std::string& integrator,
                            const IntegratorOptions& opt, std::vector<double>& x,
                            std::vector<double>& v, RunObserver* observer, double t0) {
  auto integ = make_integrator(integrator);
  return run_to_equilibrium(sys, *integ, opt, x, v, observer, t0);
}

double equilibrium_threshold(const MechanicalSystem& sys, double t, const double* x,
                             double equilibrium_tol) {
  return std::max(equilibrium_tol,
                  std::min(sys.residual_roundoff(t, x), kFloorCheckFactor * equilibrium_tol));
}

// ---- stability prediction -----------------------------------------------------------------

namespace {

double euler_limit(double w2, double g) {
  if (w2 <= 0.0) return g > 0.0 ? 2.0 / g : std::numeric_limits<double>::infinity();
  const double disc = 0.25 * g * g - w2;
  if (disc >= 0.0) return 2.0 / (0.5 * g + std::sqrt(disc));  // overdamped: real eigenvalues
  return g / w2;                                              // underdamped
}

double verlet_limit(double w2, double g) {
  if (w2 <= 0.0) return std::numeric_limits<double>::infinity();
  // f(h) = h phi w2 - 2 (1 + e^2)/(1 + e) is increasing in h; bisect for its root.
  auto f = [&](double h) {
    const double e = std::exp(-0.5 * g * h);
    const double phi = g > 0.0 ? -std::expm1(-0.5 * g * h) / g : 0.5 * h;
    return h * phi * w2 - 2.0 * (1.0 + e * e) / (1.0 + e);
  };
  double lo = 0.0, hi = 2.0 / std::sqrt(w2);
  while (f(hi) < 0.0) hi *= 2.0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < 0.0 ? lo : hi) = mid;
  }
  return lo;
}

// Largest eigenvalue of D^-1/2 S D^-1/2, S = -(K + K^T)/2, K = M Ax (Ax in the pattern `p`),
// D = diag(d) > 0: `steps` Lanczos steps with full reorthogonalisation from a fixed start; returns
// the top Ritz value plus its residual norm |beta_k s_k|, or +inf if d has a non-positive entry.
double lanczos_largest(const CscPattern& p, const std::vector<double>& ax,
                       const std::vector<double>& m, const std::vector<double>& d, int steps) {
  const int n = p.cols;
  if (n == 0) return 0.0;  // no mode at all
  std::vector<double> scale(n);
  for (int i = 0; i < n; ++i) {
    if (!(d[i] > 0.0)) return std::numeric_limits<double>::infinity();
    scale[i] = 1.0 / std::sqrt(d[i]);
  }
  std::vector<double> half(p.nnz());  // entry k of -K/2, scaled by D^-1/2 on both sides
  for (int j = 0; j < n; ++j)
    for (int k = p.colptr[j]; k < p.colptr[j + 1]; ++k) {
      const int i = p.rowind[k];
      half[k] = -0.5 * m[i] * ax[k] * scale[i] * scale[j];
    }
  auto apply = [&](const double* in, double* out) {
    std::fill_n(out, n, 0.0);
    for (int j = 0; j < n; ++j) {
      double out_j = 0.0;  // in a register: out[j] += ... would be a store per entry
      for (int k = p.colptr[j]; k < p.colptr[j + 1]; ++k) {
        const int i = p.rowind[k];
        out[i] += half[k] * in[j];
        out_j += half[k] * in[i];
      }
      out[j] += out_j;
    }
  };
  const int k_max = std::max(1, std::min(steps, n));
  std::vector<std::vector<double>> q;
  std::vector<double> alpha, beta, w(n), v(n);
  for (int i = 0; i < n; ++i) v[i] = 1.0 + 0.5 * std::sin(1.0 + 7.0 * i);  // fixed, generic start
  double norm = 0.0;
  for (double vi : v) norm += vi * vi;
  for (double& vi : v) vi /= std::sqrt(norm);
  for (int k = 0; k < k_max; ++k) {
    q.push_back(v);
    apply(v.data(), w.data());
    double a = 0.0;
    for (int i = 0; i < n; ++i) a += w[i] * v[i];
    alpha.push_back(a);
    for (const auto& qj : q) {  // full reorthogonalisation (k_max is small)
      double c = 0.0;
      for (int i = 0; i < n; ++i) c += w[i] * qj[i];
      for (int i = 0; i < n; ++i) w[i] -= c * qj[i];
    }
    double b = 0.0;
    for (double wi : w) b += wi * wi;
    b = std::sqrt(b);
    beta.push_back(b);
    if (!(b > 1e-12 * std::abs(a))) break;  // invariant subspace: the Ritz values are exact
    for (int i = 0; i < n; ++i) v[i] = w[i] / b;
  }
  const int k = static_cast<int>(alpha.size());
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(k, k);
  for (int i = 0; i < k; ++i) {
    T(i, i) = alpha[i];
    if (i + 1 < k) T(i, i + 1) = T(i + 1, i) = beta[i];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(T);
  return eig.eigenvalues()(k - 1) + std::abs(beta[k - 1] * eig.eigenvectors()(k - 1, k - 1));
}

constexpr int kLanczosSteps = 40;

// predict_stable_dt (sharp = false) and estimate_stable_dt (sharp = true).
double stable_dt(const std::string& method, const MechanicalSystem& sys, double t, const double* x,
                 bool sharp) {
  if (method != "euler" && method != "verlet")
    throw std::invalid_argument(std::string(sharp ? "estimate" : "predict") +
                                "_stable_dt: method = " + method + ": must be euler or verlet");
  const CscPattern& p = sys.stiffness_pattern();
  std::vector<double> values(p.nnz());
  sys.stiffness_values(t, x, values.data());
  const int n = sys.dof();
  std::vector<double> w2(n, 0.0);  // Gershgorin: omega_i^2 <= sum_j |Ax_ij|
  for (int k = 0; k < p.nnz(); ++k) w2[p.rowind[k]] += std::abs(values[k]);
  const auto& gamma = sys.damping_rate();
  auto limit = [&](double w2i, double g) {
    return method == "euler" ? euler_limit(w2i, g) : verlet_limit(w2i, g);
  };
  double best = std::numeric_limits<double>::infinity();
  if (!sharp) {  // dof by dof: dt_predicted, the automatic dt, is exactly this bound
    for (int i = 0; i < n; ++i) best = std::min(best, limit(w2[i], gamma[i]));
    return best;
  }
  const auto& m = sys.mass();
  std::vector<double> c(n);
  for (int i = 0; i < n; ++i) c[i] = gamma[i] * m[i];
  const double omega2_max = lanczos_largest(p, values, m, m, kLanczosSteps);
  const double rate_max = lanczos_largest(p, values, m, c, kLanczosSteps);
  // For one damping rate g, both limits are unimodal in omega^2 (euler: rising while
  // overdamped, then g / omega^2; verlet: falling), so the least over the dofs sharing g is
  // at their smallest or largest omega^2: two evaluations per distinct g instead of one
  // bisection per dof (most dofs share a handful of rates).
  std::map<double, std::pair<double, double>> range;  // g -> (min, max) capped omega^2
  for (int i = 0; i < n; ++i) {
    double w = std::min(w2[i], omega2_max);
    if (std::isfinite(rate_max)) w = std::min(w, gamma[i] * rate_max);  // all c_i > 0
    auto [it, fresh] = range.emplace(gamma[i], std::make_pair(w, w));
    if (!fresh) {
      it->second.first = std::min(it->second.first, w);
      it->second.second = std::max(it->second.second, w);
    }
  }
  for (const auto& [g, w] : range) best = std::min({best, limit(w.first, g), limit(w.second, g)});
  return best;
}

}  // namespace

double predict_stable_dt(const std::string& method, const MechanicalSystem& sys, double t,
                         const double* x) {
  return stable_dt(method, sys, t, x, false);
}

double estimate_stable_dt(const std::string& method, const MechanicalSystem& sys, double t,
                          const double* x) {
  return stable_dt(method, sys, t, x, true);
}

}  // namespace knitsim
