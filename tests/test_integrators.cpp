// Integrators and the equilibrium driver (docs/equilibrium.md, docs/numerics.md): closed-form
// equilibria for every integrator in the catalog, observed orders of the fixed-step methods,
// Verlet's energy behaviour, cross-integrator agreement on the drape equilibrium, the
// elongation limit on both paths, and the driver's statuses.
#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "models/drape_grid.hpp"
#include "solvers/integrator.hpp"
#include "solvers/sundials_common.hpp"
#include "src/core/first_order.hpp"
#include "tests/test_systems.hpp"

using namespace knitsim;
using namespace knitsim::test;

namespace {

// Hanging mass / chain of the closed-form tests: m 0.1 kg, k 100 N/m, L0 0.1 m, damping ratio
// 0.5 on a single spring (c = sqrt(k m), gamma = omega = 31.6 /s). Starts unstretched.
ChainParams hanging(int particles) {
  ChainParams p;
  p.particles = particles;
  p.damping = std::sqrt(p.stiffness * p.mass);
  return p;
}

// Runs `integrator` to equilibrium from the model's initial state; returns the final x.
std::vector<double> equilibrium(const MechanicalSystem& sys, const std::string& integrator,
                                const IntegratorOptions& opt, RunStats& stats) {
  std::vector<double> x, v;
  stats = run_to_equilibrium(sys, integrator, opt, x, v);
  return x;
}

IntegratorOptions with_dt(double dt) {
  IntegratorOptions opt;
  opt.dt = dt;
  return opt;
}

// Classical RK4 on the first-order form with `steps` equal steps to T: the reference
// solution of the order test (its error ~ (h omega)^4 is far below the methods' errors).
std::vector<double> rk4_positions(const MechanicalSystem& sys, double T, long steps) {
  const FirstOrderSystem f(sys);
  const int n = f.size();
  std::vector<double> y(n), k1(n), k2(n), k3(n), k4(n), tmp(n);
  sys.initial_state(y.data(), y.data() + n / 2);
  const double h = T / steps;
  auto stage = [&](const std::vector<double>& k, double scale) {
    for (int i = 0; i < n; ++i) tmp[i] = y[i] + scale * h * k[i];
  };
  for (long s = 0; s < steps; ++s) {
    const double t = s * h;
    f.rhs(t, y.data(), k1.data());
    stage(k1, 0.5);
    f.rhs(t + 0.5 * h, tmp.data(), k2.data());
    stage(k2, 0.5);
    f.rhs(t + 0.5 * h, tmp.data(), k3.data());
    stage(k3, 1.0);
    f.rhs(t + h, tmp.data(), k4.data());
    for (int i = 0; i < n; ++i) y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
  }
  y.resize(n / 2);
  return y;
}

// Positions at T by `integrator` with fixed step dt through the Integrator interface.
std::vector<double> positions_at(const MechanicalSystem& sys, const std::string& integrator,
                                 double dt, double T) {
  auto integ = make_integrator(integrator);
  std::vector<double> x(sys.dof()), v(sys.dof());
  sys.initial_state(x.data(), v.data());
  integ->start(sys, 0.0, x.data(), v.data(), with_dt(dt));
  const std::string failure = advance_to(*integ, T);
  INFO(integrator << " dt " << dt << ": " << failure);
  REQUIRE(failure.empty());
  REQUIRE(integ->time() == T);
  return std::vector<double>(integ->positions(), integ->positions() + sys.dof());
}

// Least-squares slope of log(err) against log(dt).
double fitted_order(const std::vector<double>& dt, const std::vector<double>& err) {
  double mx = 0.0, my = 0.0;
  for (size_t i = 0; i < dt.size(); ++i) {
    mx += std::log(dt[i]) / dt.size();
    my += std::log(err[i]) / dt.size();
  }
  double sxy = 0.0, sxx = 0.0;
  for (size_t i = 0; i < dt.size(); ++i) {
    sxy += (std::log(dt[i]) - mx) * (std::log(err[i]) - my);
    sxx += (std::log(dt[i]) - mx) * (std::log(dt[i]) - mx);
  }
  return sxy / sxx;
}

}  // namespace

TEST_CASE("every integrator reaches the closed-form equilibrium of a hanging mass and chain") {
  for (const IntegratorInfo& info : integrator_catalog())
    for (int particles : {1, 4}) {
      const ChainParams p = hanging(particles);
      const SpringNetwork net(build_chain(p));
      const double g = -net.spec().gravity.z;
      IntegratorOptions opt;    // explicit methods: automatic dt
      opt.max_steps = 100'000;  // bounds the cost of a method that fails to settle
      RunStats s;
      const auto x = equilibrium(net, info.name, opt, s);
      INFO(info.name << ", " << particles << " particle(s): " << to_string(s.status) << " ("
                     << s.message << ") t " << s.t_final << " steps " << s.steps);
      CHECK(s.status == RunStatus::Equilibrium);
      if (s.status != RunStatus::Equilibrium) continue;
      CHECK(s.integrator == info.name);
      CHECK(s.steps > 0);
      CHECK((s.t_final > 0.0) == info.follows_time);  // equilibrium's t stays where pins stop
      CHECK(s.certificate == "stable_minimum");
      // Spring j (1 = at the pin) carries the weight of the N - j + 1 particles below it. The
      // run ends with a force of at most r m g on each particle (r: the residual it stopped at,
      // or the residual stop's threshold if larger, plus the residual's round-off floor), so
      // spring j's tension is within (N - j + 1) r m g of that weight: |stretch - exact| <=
      // r exact, plus the rounding of the z differences (4 eps |z|). A theorem, not a margin.
      const double r = std::max(equilibrium_threshold(net, s.t_final, x.data(), opt.equilibrium_tol),
                                s.residual) +
                       net.residual_roundoff(s.t_final, x.data());
      double z_above = 0.0;
      for (int j = 1; j <= particles; ++j) {
        const double z = x[3 * (j - 1) + 2];
        const double stretch = (z_above - z) - p.rest;
        const double exact = (particles - j + 1) * p.mass * g / p.stiffness;
        INFO("spring " << j << " stretch " << stretch << " exact " << exact);
        const double eps = std::numeric_limits<double>::epsilon();
        CHECK(std::abs(stretch - exact) <= r * exact + 4 * eps * std::abs(z));
        CHECK(std::abs(x[3 * (j - 1)]) < 1e-12);  // no force ever acts across the line
        CHECK(std::abs(x[3 * (j - 1) + 1]) < 1e-12);
        z_above = z;
      }
    }
}

TEST_CASE("fixed-step integrators show their classical order on a swinging chain") {
  // Three particles (m 0.01 kg, k 10 N/m, L0 0.1 m, c 1e-3 N s/m: gamma = 0.1 /s, lightly
  // damped) start horizontal and swing down under gravity: smooth, nonlinear, no elongation
  // limit. Error in positions at T = 0.5 s against RK4 with 2.5e5 steps; dt halved three times
  // from 1e-4 s (h omega_max <= 7e-3: the asymptotic regime, errors >> the reference error).
  ChainParams p;
  p.particles = 3;
  p.mass = 0.01;
  p.stiffness = 10.0;
  p.damping = 1e-3;
  p.direction = {1, 0, 0};
  const SpringNetwork net(build_chain(p));
  const double T = 0.5;
  const auto reference = rk4_positions(net, T, 250'000);

  std::map<std::string, int> expected{{"euler", 1}, {"verlet", 2}, {"implicit-euler", 1}};
  int fixed_step_methods = 0;
  for (const IntegratorInfo& info : integrator_catalog()) {
    if (info.adaptive || info.order <= 0) continue;
    ++fixed_step_methods;
    if (expected.count(info.name)) CHECK(info.order == expected[info.name]);
    std::vector<double> dts, errs;
    for (double dt = 1e-4; dt > 1e-5; dt /= 2) {
      dts.push_back(dt);
      errs.push_back(max_abs_difference(positions_at(net, info.name, dt, T), reference));
    }
    const double order = fitted_order(dts, errs);
    WARN(info.name << ": position errors " << errs[0] << " " << errs[1] << " " << errs[2] << " "
                   << errs[3] << " m, observed order " << order << " (classical " << info.order
                   << ")");
    CHECK(std::abs(order - info.order) <= 0.15);
  }
  CHECK(fixed_step_methods >= 3);
}

TEST_CASE("undamped Verlet keeps the energy bounded; explicit Euler gains energy") {
  // A taut string: 8 particles (m 0.01 kg) between two pins, k 100 N/m, 10 % pre-stretch,
  // plucked 2 cm out of line, no gravity, no damping. omega_max ~ 2 sqrt(k/m) = 200 rad/s;
  // dt = 5e-4 s (h omega_max ~ 0.1), 1e5 steps (50 s, ~80 periods of the plucked mode).
  // Energy relative to the oscillation energy E0 - E_line (E_line: the straight string).
  ChainParams p;
  p.particles = 8;
  p.mass = 0.01;
  p.stiffness = 100.0;
  p.direction = {1, 0, 0};
  p.stretch = 0.1;
  p.far_pin = true;
  p.gravity = false;
  const SpringNetwork line(build_chain(p));
  p.pluck = 0.02;
  const SpringNetwork net(build_chain(p));
  const int n = net.dof();
  std::vector<double> x(n), v(n);
  line.initial_state(x.data(), v.data());
  const double e_line = total_energy(line, 0.0, x.data(), v.data());
  net.initial_state(x.data(), v.data());
  const double e0 = total_energy(net, 0.0, x.data(), v.data());
  REQUIRE(e0 - e_line > 0.0);
  const double dt = 5e-4;

  // Relative energy error (E - E0) / (E0 - E_line) after each of `steps` steps.
  auto energy_errors = [&](const std::string& name, long steps) {
    auto integ = make_integrator(name);
    integ->start(net, 0.0, x.data(), v.data(), with_dt(dt));
    std::vector<double> err;
    const std::string failure = advance_to(*integ, steps * dt, [&] {
      err.push_back(
          (total_energy(net, integ->time(), integ->positions(), integ->velocities()) - e0) /
          (e0 - e_line));
    });
    INFO(name << ": " << failure);
    REQUIRE(failure.empty());
    return err;
  };
  // Max |error| over the first and the last tenth of the run.
  auto tenths = [](const std::vector<double>& err) {
    const size_t w = err.size() / 10;
    double first = 0.0, last = 0.0;
    for (size_t i = 0; i < w; ++i) {
      first = std::max(first, std::abs(err[i]));
      last = std::max(last, std::abs(err[err.size() - 1 - i]));
    }
    return std::make_pair(first, last);
  };

  const auto verlet = energy_errors("verlet", 100'000);
  REQUIRE(verlet.size() >= 100'000);
  const auto [v_first, v_last] = tenths(verlet);
  WARN("verlet, 1e5 steps: max relative energy error " << v_first << " (first tenth), " << v_last
                                                       << " (last tenth)");
  CHECK(std::max(v_first, v_last) < 1e-4);
  CHECK(v_last < 1.5 * v_first);  // bounded oscillation, no secular growth

  // Explicit Euler: every undamped mode grows by sqrt(1 + (h omega)^2) per step.
  const auto euler = energy_errors("euler", 5'000);
  const auto [e_first, e_last] = tenths(euler);
  WARN("euler, 5e3 steps: relative energy gain " << euler.back() << "; max over first tenth "
                                                 << e_first << ", last tenth " << e_last);
  CHECK(euler.back() > 0.1);
  CHECK(e_last > 2.0 * e_first);
}

TEST_CASE("euler and verlet reach the implicit-euler drape equilibrium") {
  // four_corner, DrapeParams{} but c = 0.05 N s/m so that the explicit paths settle in a few
  // seconds of physical time (at c = 12 the overdamped sheet needs ~1e3 s). Euler on the
  // paper's 11 x 11 grid takes 1.8e6 steps (~10 s), so it runs on the 6 x 6 grid only.
  struct Case {
    double natural_length;
    std::vector<std::string> methods;
  };
  for (const Case& c : {Case{0.1, {"euler", "verlet"}}, Case{0.049, {"verlet"}}}) {
    DrapeParams params;
    params.damping = 0.05;
    params.natural_length = c.natural_length;
    const DrapeGrid g = build_drape_grid(params);
    RunStats ref_stats;
    const auto ref = equilibrium(g.network, "implicit-euler", with_dt(10.0), ref_stats);
    REQUIRE(ref_stats.status == RunStatus::Equilibrium);
    for (const std::string& name : c.methods) {
      RunStats s;
      const auto x = equilibrium(g.network, name, IntegratorOptions{}, s);
      const double diff = max_abs_difference(x, ref);
      // The stop criterion's bound (test_systems.hpp). Measured 2026-11-27: 2.2e-11 to 2.7e-11 m
      // against 4.8e-10 m (6 x 6) and 6.4e-10 m (11 x 11).
      const double bound = settled_distance_bound(g.network, s.t_final, x, ref_stats.t_final, ref);
      WARN(name << " on the " << g.n + 1 << "x" << g.n + 1 << " grid: " << to_string(s.status)
                << " at t " << s.t_final << " s, " << s.steps << " steps, dt " << s.dt
                << " s, wall " << s.wall_seconds << " s; max |x - x_implicit| " << diff
                << " m (bound " << bound << " m)");
      CHECK(s.status == RunStatus::Equilibrium);
      CHECK(diff <= bound);
    }
  }
}

TEST_CASE("elongation limit: Provot on the reference path, a stiff penalty on the implicit") {
  // A soft fabric where the limit binds: 6 x 6 grid, four corners, k = 2 N/m, eps_max = 5 %.
  // (At k = 5 N/m the free sheet's largest strain is 4.6 %: the limit would be inactive.)
  DrapeParams params;
  params.natural_length = 0.1;
  params.stiffness = 2.0;
  params.elongation_limit = 5.0;
  const double eps_max = 0.05;
  const DrapeGrid g = build_drape_grid(params);
  const SpringNetwork& limited = g.network;

  // Without the limit the sheet stretches beyond 5 %.
  SpringNetworkSpec free_spec = limited.spec();
  free_spec.elongation_limit = 0.0;
  const SpringNetwork unlimited(free_spec);
  RunStats s;
  const auto x_free = equilibrium(unlimited, "verlet", IntegratorOptions{}, s);
  REQUIRE(s.status == RunStatus::Equilibrium);
  const double eps_free = unlimited.max_strain(0.0, x_free.data());
  CHECK(eps_free > eps_max);

  // Reference path: the Provot correction holds every spring at <= eps_max. Its fixed point
  // keeps a velocity v = F/c pushing into the constraints, and the static residual does not
  // see the constraint forces, so the run ends at t_max rather than at Equilibrium; the state
  // itself is stationary, which we check by running on.
  IntegratorOptions opt;
  opt.t_max = 2000.0;
  std::vector<double> x_provot, v_provot;
  s = run_to_equilibrium(limited, "verlet", opt, x_provot, v_provot);
  WARN("verlet with the Provot limit: " << to_string(s.status) << " at t " << s.t_final
                                        << " s, residual " << s.residual << ", max strain "
                                        << limited.max_strain(0.0, x_provot.data()));
  REQUIRE((s.status == RunStatus::Equilibrium || s.status == RunStatus::TimeLimit));
  CHECK(limited.max_strain(0.0, x_provot.data()) <= eps_max + 1e-9);
  const auto x_stationary = x_provot;
  run_to_equilibrium(limited, "verlet", opt, x_provot, v_provot);
  CHECK(max_abs_difference(x_provot, x_stationary) < 1e-12);

  // Implicit path: a limiting spring k_lim = factor x k above L_max. A spring at the limit
  // carries tension T = k L0 (eps_max + d) + k_lim L0 d, so the overshoot is
  // d = (T / (k L0) - eps_max) k / (k + k_lim) ~ (k / k_lim)(T / (k L0) - eps_max): first order
  // in k / k_lim, and the penalty equilibrium tends to the constrained one at the same rate.
  // T exceeds the unlimited sheet's tension (the limited sheet sags less), so d is about twice
  // (k / k_lim)(eps_free - eps_max) here; we assert three times.
  double previous_overshoot = 0.0, previous_difference = 0.0;
  for (double factor : {100.0, 1000.0}) {
    SpringNetworkSpec spec = limited.spec();
    spec.limit_stiffness_factor = factor;
    const SpringNetwork penalty(spec);
    const auto x = equilibrium(penalty, "implicit-euler", IntegratorOptions{}, s);
    REQUIRE(s.status == RunStatus::Equilibrium);
    const double overshoot = penalty.max_strain(0.0, x.data()) - eps_max;
    const double difference = max_abs_difference(x, x_provot);
    WARN("implicit-euler, k_lim = " << factor << " k: max strain overshoot " << overshoot
                                    << " (bound " << 3.0 * (eps_free - eps_max) / factor
                                    << "); max |x - x_provot| " << difference << " m");
    CHECK(overshoot > 0.0);
    CHECK(overshoot <= 3.0 * (eps_free - eps_max) / factor);
    if (previous_overshoot > 0.0) {
      CHECK(previous_overshoot / overshoot == Approx(10.0).epsilon(0.2));
      CHECK(previous_difference / difference == Approx(10.0).epsilon(0.2));
    }
    previous_overshoot = overshoot;
    previous_difference = difference;
  }
}

TEST_CASE("driver statuses: time, step and wall limits, interrupts, divergence, bad options") {
  const SpringNetwork net(build_chain(hanging(1)));
  std::vector<double> x, v;

  SECTION("t_max reached first: TimeLimit at exactly t_max") {
    for (const char* name : {"euler", "implicit-euler"}) {
      IntegratorOptions opt;
      opt.t_max = 1e-3;
      x.clear();
      const RunStats s = run_to_equilibrium(net, name, opt, x, v);
      INFO(name << ": " << s.message);
      CHECK(s.status == RunStatus::TimeLimit);
      CHECK(s.t_final == Approx(1e-3).epsilon(1e-12));
    }
  }
  SECTION("step cap reached first: StepLimit after exactly max_steps") {
    for (const char* name : {"euler", "implicit-euler"}) {
      IntegratorOptions opt = with_dt(1e-3);  // implicit-euler at 1 s would settle in 5 steps
      opt.max_steps = 7;
      x.clear();
      const RunStats s = run_to_equilibrium(net, name, opt, x, v);
      INFO(name << ": " << s.message);
      CHECK(s.status == RunStatus::StepLimit);
      CHECK(s.steps == 7);
    }
  }
  SECTION("wall-clock cap reached first: WallLimit") {
    IntegratorOptions opt = with_dt(1e-7);
    opt.max_wall_seconds = 1e-9;
    const RunStats s = run_to_equilibrium(net, "implicit-euler", opt, x, v);
    CHECK(s.status == RunStatus::WallLimit);
  }
  SECTION("t0: a run continued from (t0, x, v) starts there; t0 outside [0, t_max) is refused") {
    IntegratorOptions opt = with_dt(1e-4);
    opt.max_steps = 10;
    x.clear();
    const RunStats first = run_to_equilibrium(net, "euler", opt, x, v);
    REQUIRE(first.status == RunStatus::StepLimit);
    const RunStats second = run_to_equilibrium(net, "euler", opt, x, v, nullptr, first.t_final);
    CHECK(second.steps == 10);
    CHECK(second.t_final == Approx(first.t_final + 10 * 1e-4).epsilon(1e-12));
    opt.t_max = 1.0;
    CHECK_THROWS_AS(run_to_equilibrium(net, "euler", opt, x, v, nullptr, 1.0),
                    std::invalid_argument);
    CHECK_THROWS_AS(run_to_equilibrium(net, "euler", opt, x, v, nullptr, -1.0),
                    std::invalid_argument);
  }
  SECTION("interrupt request: Interrupted after the current step, with the state reached") {
    std::atomic<bool> stop{false};
    IntegratorOptions opt;
    opt.interrupt = &stop;
    x.clear();
    const RunStats settled = run_to_equilibrium(net, "cvode-bdf", opt, x, v);
    CHECK(settled.status == RunStatus::Equilibrium);  // an unset request changes nothing
    // The request comes during the first step (as a signal would): the run ends after it.
    struct StopOnStep final : RunObserver {
      std::atomic<bool>* stop;
      explicit StopOnStep(std::atomic<bool>* s) : stop(s) {}
      void on_step(double, double, int) override { *stop = true; }
      void on_check(double, const double*, const double*, double) override {}
    } request(&stop);
    for (const char* name : {"cvode-bdf", "euler"}) {
      stop = false;
      opt.dt = std::string(name) == "euler" ? 1e-7 : 0.0;  // 1000 steps do not settle
      x.clear();
      const RunStats s = run_to_equilibrium(net, name, opt, x, v, &request);
      INFO(name << ": " << s.message);
      CHECK(s.status == RunStatus::Interrupted);
      CHECK(std::string(to_string(s.status)) == "interrupted");
      // stopped within a step of the request, not at the first residual check (euler: 1000
      // steps)
      CHECK(s.steps >= 1);
      CHECK(s.steps <= 2);
      CHECK(s.t_final > 0.0);
      CHECK(static_cast<int>(x.size()) == net.dof());
      CHECK(s.residual > opt.equilibrium_tol);
      // A request standing before the run ends it at its start, no step taken (a driver of
      // runs that conclude at their start, the tensile test's, would otherwise never see it).
      stop = true;
      x.clear();
      const RunStats before = run_to_equilibrium(net, name, opt, x, v);
      CHECK(before.status == RunStatus::Interrupted);
      CHECK(before.steps == 0);
      CHECK(static_cast<int>(x.size()) == net.dof());
    }
  }
  SECTION("NaN acceleration is a status for every integrator, never an exception") {
    const NanAccelerationSystem nan_system(net);
    for (const IntegratorInfo& info : integrator_catalog()) {
      RunStats s;
      x.clear();
      CHECK_NOTHROW(s = run_to_equilibrium(nan_system, info.name, IntegratorOptions{}, x, v));
      INFO(info.name << ": " << to_string(s.status) << " (" << s.message << ")");
      if (info.explicit_method && !info.adaptive)
        CHECK(s.status == RunStatus::Diverged);
      else
        CHECK((s.status == RunStatus::Diverged || s.status == RunStatus::SolverFailure));
      if (!info.explicit_method)  // no stability limit to blame
        CHECK_THAT(s.message, !Catch::Contains("predicted stability limit"));
    }
  }
  SECTION("euler at 10x the predicted limit diverges and says why") {
    std::vector<double> x0(net.dof()), v0(net.dof());
    net.initial_state(x0.data(), v0.data());
    const double limit = predict_stable_dt("euler", net, 0.0, x0.data());
    const RunStats s = run_to_equilibrium(net, "euler", with_dt(10.0 * limit), x, v);
    INFO(s.message);
    CHECK(s.status == RunStatus::Diverged);
    CHECK_THAT(s.message, Catch::Contains("predicted stability limit"));
    CHECK(s.dt_predicted == Approx(limit));
  }
  SECTION("undamped euler with automatic dt is a set-up error naming dt") {
    ChainParams p = hanging(1);
    p.damping = 0.0;
    const SpringNetwork undamped(build_chain(p));
    CHECK_THROWS_AS(run_to_equilibrium(undamped, "euler", IntegratorOptions{}, x, v),
                    std::invalid_argument);
    x.clear();
    CHECK_THROWS_WITH(run_to_equilibrium(undamped, "euler", IntegratorOptions{}, x, v),
                      Catch::Contains("dt = 0"));
  }
  SECTION("bad options and unknown names throw, naming the field") {
    IntegratorOptions opt;
    opt.rtol = 2.0;
    CHECK_THROWS_WITH(run_to_equilibrium(net, "implicit-euler", opt, x, v),
                      Catch::StartsWith("rtol = 2"));
    opt.rtol = 1e-6;
    opt.velocity_atol = -1e-3;
    CHECK_THROWS_WITH(opt.validate(), Catch::StartsWith("velocity_atol = -0.001: must be >= 0"));
    opt.velocity_atol = std::nan("");
    CHECK_THROWS_WITH(opt.validate(), Catch::StartsWith("velocity_atol = nan: must be >= 0"));
    opt.velocity_atol = HUGE_VAL;
    CHECK_THROWS_WITH(opt.validate(), Catch::StartsWith("velocity_atol = inf: must be >= 0"));
    CHECK_THROWS_WITH(
        make_integrator("no-such-method"),
        Catch::Contains("integrator = no-such-method") && Catch::Contains("implicit-euler"));
  }
}

namespace {

// implicit-euler with injected step failures: the calls listed in `fail_at` (1-based) fail
// without stepping, `recoverable` as given; restart() succeeds unless `can_restart` is false.
class FlakyIntegrator final : public Integrator {
 public:
  FlakyIntegrator(std::vector<long> fail_at, bool recoverable, bool can_restart = true)
      : inner_(make_integrator("implicit-euler")),
        fail_at_(std::move(fail_at)),
        recoverable_(recoverable),
        can_restart_(can_restart) {}
  const IntegratorInfo& info() const override { return inner_->info(); }
  void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
             const IntegratorOptions& opt) override {
    inner_->start(sys, t0, x0, v0, opt);
  }
  Step step(double t_stop) override {
    ++calls_;
    if (std::find(fail_at_.begin(), fail_at_.end(), calls_) != fail_at_.end())
      return {false, "injected failure", recoverable_};
    return inner_->step(t_stop);
  }
  bool restart() override {
    ++restarts_;
    return can_restart_;
  }
  double time() const override { return inner_->time(); }
  const double* positions() const override { return inner_->positions(); }
  const double* velocities() const override { return inner_->velocities(); }
  void fill_stats(RunStats& st) const override { inner_->fill_stats(st); }
  long restarts() const { return restarts_; }

 private:
  std::unique_ptr<Integrator> inner_;
  std::vector<long> fail_at_;
  bool recoverable_, can_restart_;
  long calls_ = 0, restarts_ = 0;
};

}  // namespace

TEST_CASE("driver restarts after recoverable step failures, up to max_restarts") {
  const SpringNetwork net(build_chain(hanging(2)));
  std::vector<double> x, v;
  RunStats clean_stats;
  const auto clean = equilibrium(net, "implicit-euler", IntegratorOptions{}, clean_stats);
  REQUIRE(clean_stats.status == RunStatus::Equilibrium);

  SECTION("recoverable failures within the cap: the run goes on to the same equilibrium") {
    FlakyIntegrator flaky({2, 3, 5}, true);
    const RunStats s = run_to_equilibrium(net, flaky, IntegratorOptions{}, x, v);
    INFO(s.message);
    CHECK(s.status == RunStatus::Equilibrium);
    CHECK(s.restarts == 3);
    CHECK(flaky.restarts() == 3);
    CHECK(max_abs_difference(x, clean) == 0.0);
  }
  SECTION("more failures in a row than max_restarts: solver_failure, saying how many") {
    IntegratorOptions opt;
    opt.max_restarts = 2;
    FlakyIntegrator flaky({2, 3, 4}, true);
    const RunStats s = run_to_equilibrium(net, flaky, opt, x, v);
    CHECK(s.status == RunStatus::SolverFailure);
    CHECK(s.restarts == 2);
    CHECK_THAT(s.message, Catch::Equals("injected failure (after 2 restarts)"));
  }
  SECTION("max_restarts 0, an unrecoverable failure or a method that cannot restart: no restart") {
    IntegratorOptions off;
    off.max_restarts = 0;
    FlakyIntegrator a({2}, true), b({2}, false), c({2}, true, false);
    for (auto [integ, opt] : {std::pair<FlakyIntegrator*, IntegratorOptions>{&a, off},
                              {&b, IntegratorOptions{}},
                              {&c, IntegratorOptions{}}}) {
      x.clear();
      const RunStats s = run_to_equilibrium(net, *integ, opt, x, v);
      CHECK(s.status == RunStatus::SolverFailure);
      CHECK(s.restarts == 0);
      CHECK(s.message == "injected failure");
    }
    CHECK(a.restarts() == 0);
    CHECK(b.restarts() == 0);
    CHECK(c.restarts() == 1);  // asked, refused
  }
  SECTION("max_restarts out of range names the field") {
    IntegratorOptions opt;
    opt.max_restarts = -1;
    CHECK_THROWS_WITH(opt.validate(), Catch::StartsWith("max_restarts = -1: must be in 0..1000"));
  }
}

TEST_CASE("every implicit integrator lands on the implicit-euler drape equilibrium") {
  // four_corner with the built-in defaults (sample 1: k 852 N/m, c 12 N s/m) but on the 6 x 6
  // grid (L0 10 cm): on the paper's 11 x 11 grid cvode-bdf-dense and arkode-dirk alone cost
  // ~10 s of CPU. A step cap bounds the cost of a method unfit for this stiffness.
  DrapeParams params;
  params.natural_length = 0.1;
  const DrapeGrid g = build_drape_grid(params);
  RunStats ref_stats;
  const auto ref = equilibrium(g.network, "implicit-euler", with_dt(10.0), ref_stats);
  REQUIRE(ref_stats.status == RunStatus::Equilibrium);
  for (const IntegratorInfo& info : integrator_catalog()) {
    if (info.explicit_method) continue;
    IntegratorOptions opt;
    opt.max_steps = 20'000;
    RunStats s;
    const auto x = equilibrium(g.network, info.name, opt, s);
    const double diff = max_abs_difference(x, ref);
    // The stop criterion's bound (test_systems.hpp). Measured 2026-11-27: 4.4e-12 to 2.4e-11 m
    // against 4.8e-10 m.
    const double bound = settled_distance_bound(g.network, s.t_final, x, ref_stats.t_final, ref);
    WARN(info.name << ": " << to_string(s.status) << " at t " << s.t_final << " s, " << s.steps
                   << " steps, residual " << s.residual << ", wall " << s.wall_seconds
                   << " s; max |x - x_ref| " << diff << " m (bound " << bound << " m)");
    CHECK(s.status == RunStatus::Equilibrium);
    CHECK(diff <= bound);
  }
}

TEST_CASE("velocity_atol: the per-component tolerance vector [atol; velocity_atol]") {
  SECTION("velocity_atol = atol takes exactly the steps of the scalar tolerance (0)") {
    // velocity_atol 0 sets CVODE/ARKODE's scalar pair (rtol, atol); any other value the vector
    // [atol (x); velocity_atol (v)]. With the two equal the error weights are the same numbers,
    // so every adaptive method must take the same steps to the same state.
    const SpringNetwork net(build_chain(hanging(4)));
    for (const IntegratorInfo& info : integrator_catalog()) {
      if (!info.adaptive) continue;
      IntegratorOptions scalar;
      scalar.max_steps = 100'000;
      IntegratorOptions vector = scalar;
      vector.velocity_atol = scalar.atol;
      RunStats s0, s1;
      const auto x0 = equilibrium(net, info.name, scalar, s0);
      const auto x1 = equilibrium(net, info.name, vector, s1);
      INFO(info.name << ": " << s0.steps << " vs " << s1.steps << " steps");
      CHECK(s0.status == RunStatus::Equilibrium);
      CHECK(s1.steps == s0.steps);
      CHECK(s1.rhs_evals == s0.rhs_evals);
      CHECK(max_abs_difference(x0, x1) == 0.0);
    }
  }
  SECTION("the vector: atol on the n positions, velocity_atol on the n velocities") {
    const sun::ContextPtr ctx = sun::make_context();
    IntegratorOptions opt;
    opt.atol = 1e-9;
    opt.velocity_atol = 1e-3;
    const sun::VectorPtr tol = sun::absolute_tolerances(opt, 3, ctx.get());
    REQUIRE(tol != nullptr);
    REQUIRE(N_VGetLength(tol.get()) == 6);
    const double* t = sun::vec_data(tol.get());
    CHECK(std::vector<double>(t, t + 6) ==
          std::vector<double>{1e-9, 1e-9, 1e-9, 1e-3, 1e-3, 1e-3});  // y = [x; v]
    opt.velocity_atol = 0.0;
    CHECK(sun::absolute_tolerances(opt, 3, ctx.get()) == nullptr);  // scalar (rtol, atol)
  }
}
