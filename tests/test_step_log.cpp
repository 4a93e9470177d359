// StepLog (src/io/step_log.hpp) and the driver's on_step calls: the logged steps add up to the
// run, carry the orders the integrators report, the residuals the driver checked, and stay
// bounded and evenly thinned on long runs.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "models/drape_grid.hpp"
#include "solvers/integrator.hpp"
#include "src/io/step_log.hpp"

using namespace knitsim;

namespace {

// 6 x 6 grid (natural length 0.1 m): fast for every integrator.
const DrapeGrid& coarse() {
  static const DrapeGrid grid = [] {
    DrapeParams p;
    p.natural_length = 0.1;
    return build_drape_grid(p);
  }();
  return grid;
}

struct Logged {
  RunStats stats;
  std::vector<StepLog::Row> rows;
};

Logged run_logged(const std::string& integrator, const IntegratorOptions& opt = {}) {
  StepLog log;
  std::vector<double> x, v;
  Logged out;
  out.stats = run_to_equilibrium(coarse().network, integrator, opt, x, v, &log);
  out.rows = log.rows();
  return out;
}

}  // namespace

TEST_CASE(
    "cvode-bdf: one row per step, sizes add up to t_final, orders and residuals as reported") {
  const Logged l = run_logged("cvode-bdf");
  REQUIRE(l.stats.status == RunStatus::Equilibrium);
  REQUIRE(static_cast<long>(l.rows.size()) == l.stats.steps);
  double sum = 0.0;
  int max_order = 0;
  for (std::size_t i = 0; i < l.rows.size(); ++i) {
    const StepLog::Row& r = l.rows[i];
    CHECK(r.step == static_cast<long>(i) + 1);
    CHECK(r.h > 0.0);
    CHECK(r.order >= 1);
    CHECK(r.order <= 5);
    CHECK(std::isfinite(r.residual));  // adaptive: the driver checks every step
    sum += r.h;
    max_order = std::max(max_order, r.order);
  }
  CHECK(sum == Approx(l.stats.t_final).epsilon(1e-12));
  CHECK(l.rows.back().t == l.stats.t_final);
  CHECK(l.rows.back().residual == l.stats.residual);
  CHECK(max_order == l.stats.max_order_used);
  CHECK(l.rows.front().order == 1);  // BDF starts at order 1
}

TEST_CASE("verlet: fixed step and order 2; residuals only at the driver's checks") {
  IntegratorOptions opt;
  opt.t_max = 0.5;
  opt.check_every = 7;
  const Logged l = run_logged("verlet", opt);
  REQUIRE(static_cast<long>(l.rows.size()) == l.stats.steps);
  for (const StepLog::Row& r : l.rows) {
    CHECK(r.order == 2);
    if (r.t < opt.t_max) CHECK(r.h == Approx(l.stats.dt).epsilon(1e-9));
    CHECK(std::isfinite(r.residual) == (r.step % 7 == 0 || r.t >= opt.t_max));
  }
}

TEST_CASE("static: polish attempts are steps that do not advance time") {
  const Logged l = run_logged("static");
  REQUIRE(l.stats.status == RunStatus::Equilibrium);
  long zero = 0;
  for (const StepLog::Row& r : l.rows) zero += r.h == 0.0 ? 1 : 0;
  CHECK(zero >= 1);
}

TEST_CASE("StepLog keeps between max_rows and 2 max_rows rows, evenly spaced, and the last step") {
  StepLog log(nullptr, 10);
  const long n = 1000;
  for (long k = 1; k <= n; ++k) {
    log.on_step(0.1 * k, 0.1, 1);
    if (k % 3 == 0) log.on_check(0.1 * k, nullptr, nullptr, 1.0 / k);
  }
  const std::vector<StepLog::Row> rows = log.rows();
  REQUIRE(rows.size() >= 10);
  REQUIRE(rows.size() <= 21);  // 2 max_rows kept, plus the last step
  const long stride = rows[1].step - rows[0].step;
  CHECK(stride == 64);  // 1000 steps thinned to < 20: stride doubled six times
  for (std::size_t i = 0; i + 1 < rows.size(); ++i) {
    if (i + 2 < rows.size()) CHECK(rows[i + 1].step - rows[i].step == stride);
    CHECK(rows[i].t == Approx(0.1 * rows[i].step));
    CHECK(std::isfinite(rows[i].residual) == (rows[i].step % 3 == 0));
  }
  CHECK(rows.back().step == n);
  CHECK(std::isnan(rows.back().residual));  // 1000 is not a multiple of 3
  CHECK_THROWS_WITH(StepLog(nullptr, 0), "StepLog max_rows = 0: must be >= 1");
}

TEST_CASE("StepLog forwards steps and checks to the next observer") {
  struct Count final : RunObserver {
    int steps = 0, checks = 0;
    void on_step(double, double, int) override { ++steps; }
    void on_check(double, const double*, const double*, double) override { ++checks; }
  } count;
  StepLog log(&count);
  log.on_step(1.0, 1.0, 1);
  log.on_check(1.0, nullptr, nullptr, 0.5);
  log.on_step(2.0, 1.0, 2);
  CHECK(count.steps == 2);
  CHECK(count.checks == 1);
  const std::string csv = log.csv();
  CHECK(csv == "step,t,h,order,residual\n1,1,1,1,0.5\n2,2,1,2,\n");
}
