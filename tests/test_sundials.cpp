// The SUNDIALS integrators (cvode.cpp, arkode.cpp, static_newton.cpp): cross-integrator
// agreement on the drape equilibria against a tight cvode-bdf reference, the static
// accelerator landing on the dynamics' state, the stiffness penalty of the non-stiff
// methods, and SUNDIALS failures reported as statuses.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/drape_grid.hpp"
#include "solvers/integrator.hpp"
#include "solvers/sundials_common.hpp"
#include "tests/test_systems.hpp"

using namespace knitsim;
using knitsim::test::max_abs_difference;
using knitsim::test::settled_distance_bound;

namespace {

struct Drape {
  RunStats stats;
  std::vector<double> x, v;
};

Drape drape(const MechanicalSystem& sys, const std::string& integrator,
            const IntegratorOptions& opt) {
  Drape d;
  d.stats = run_to_equilibrium(sys, integrator, opt, d.x, d.v);
  return d;
}

IntegratorOptions reference_options() {
  IntegratorOptions opt;
  opt.rtol = 1e-8;
  opt.atol = 1e-10;
  return opt;
}

// The paper-default four_corner drape and its cvode-bdf reference (rtol 1e-8, atol 1e-10).
const DrapeGrid& four_corner() {
  static const DrapeGrid grid = build_drape_grid(DrapeParams{});
  return grid;
}
const Drape& four_corner_reference() {
  static const Drape ref = drape(four_corner().network, "cvode-bdf", reference_options());
  return ref;
}

// 6 x 6 grid (natural length 0.1 m) with damping c (N s/m).
DrapeGrid coarse_grid(double damping) {
  DrapeParams p;
  p.natural_length = 0.1;
  p.damping = damping;
  return build_drape_grid(p);
}

// How far apart two runs that both stopped at equilibrium can be (m): each is within
// equilibrium_distance_bound(its stop threshold: equilibrium_tol, or the round-off floor where
// that is larger) of the exact equilibrium (tests/test_systems.hpp). Measured 2026-11-27
// (Release): four_corner 1.8e-11 to 3.9e-11 m against a bound of 6.4e-10 m; two_corner up to
// 1.9e-8 m (GMRES) against 3.4e-7 m (a soft hanging sheet: small lambda_min); the 6 x 6 grid
// 5e-12 to 9e-12 m against 4.8e-10 m.
double agreement_bound(const SpringNetwork& net, const Drape& a, const Drape& b) {
  return settled_distance_bound(net, a.stats.t_final, a.x, b.stats.t_final, b.x);
}

void require_agreement(const SpringNetwork& net, const Drape& d, const Drape& ref) {
  INFO(d.stats.integrator << ": " << to_string(d.stats.status) << " (" << d.stats.message
                          << "), residual " << d.stats.residual << ", steps " << d.stats.steps);
  REQUIRE(d.stats.status == RunStatus::Equilibrium);
  CHECK(d.stats.certificate == "stable_minimum");
  const double diff = max_abs_difference(d.x, ref.x), bound = agreement_bound(net, d, ref);
  INFO("max |x - x_ref| " << diff << " m, bound " << bound << " m");
  CHECK(diff <= bound);
}

const std::vector<std::string> kSundials = {"cvode-bdf",   "cvode-bdf-dense", "cvode-bdf-gmres",
                                            "cvode-adams", "arkode-erk",      "arkode-dirk",
                                            "arkode-imex", "static"};

}  // namespace

TEST_CASE("every SUNDIALS integrator is registered in order after implicit-euler") {
  std::vector<std::string> names;
  for (const auto& info : integrator_catalog()) names.push_back(info.name);
  auto it = std::find(names.begin(), names.end(), "implicit-euler");
  REQUIRE(it != names.end());
  REQUIRE(std::distance(it, names.end()) >= static_cast<long>(kSundials.size()) + 1);
  CHECK(std::vector<std::string>(it + 1, it + 1 + kSundials.size()) == kSundials);
}

TEST_CASE("matrix-based SUNDIALS integrators reach the four_corner equilibrium of cvode-bdf") {
  const Drape& ref = four_corner_reference();
  REQUIRE(ref.stats.status == RunStatus::Equilibrium);
  // The sheet sags under gravity; the reference BDF used orders above 1.
  double z_min = 0.0;
  for (std::size_t i = 2; i < ref.x.size(); i += 3) z_min = std::min(z_min, ref.x[i]);
  CHECK(z_min < -0.01);
  CHECK(ref.stats.max_order_used >= 3);
  for (const char* name : {"cvode-bdf", "arkode-dirk", "arkode-imex", "static"}) {
    SECTION(name) {
      const Drape d = drape(four_corner().network, name, IntegratorOptions{});
      require_agreement(four_corner().network, d, ref);
      CHECK(d.stats.jac_evals > 0);
      CHECK(d.stats.lin_setups >= d.stats.jac_evals);
      CHECK(d.stats.nonlin_iters >= d.stats.steps);
    }
  }
}

TEST_CASE("static polishes with Newton: exact rest state, same four_corner equilibrium") {
  const Drape d = drape(four_corner().network, "static", IntegratorOptions{});
  REQUIRE(d.stats.status == RunStatus::Equilibrium);
  // An accepted polish leaves v = 0 exactly; the damped dynamics alone never do.
  CHECK(max_abs_difference(d.v, std::vector<double>(d.v.size(), 0.0)) == 0.0);
  const Drape relaxed = drape(four_corner().network, "cvode-bdf", IntegratorOptions{});
  CHECK(max_abs_difference(relaxed.v, std::vector<double>(relaxed.v.size(), 0.0)) > 0.0);
  CHECK(d.stats.steps < relaxed.stats.steps);  // the polish ends the run early
}

TEST_CASE("static and cvode-bdf stop in positions where the residual cannot reach equilibrium_tol") {
  // At k = 1e5 N/m the residual at rest is ~2.5e-8, above the default tolerance 1e-8, whatever
  // the integrator: the stop in positions (solvers/equilibrium_check.hpp) ends both runs, static
  // by an accepted polish.
  DrapeParams p;
  p.stiffness = 1e5;
  const DrapeGrid grid = build_drape_grid(p);
  const IntegratorOptions opt;
  const Drape bdf = drape(grid.network, "cvode-bdf", opt);
  const Drape st = drape(grid.network, "static", opt);
  for (const Drape* d : {&bdf, &st}) {
    INFO(d->stats.integrator << ": " << d->stats.message);
    REQUIRE(d->stats.status == RunStatus::Equilibrium);
    CHECK(d->stats.certificate == "stable_minimum");
    CHECK(d->stats.newton_step <= std::max(opt.position_tol, d->stats.newton_floor));
  }
  CHECK(max_abs_difference(st.v, std::vector<double>(st.v.size(), 0.0)) == 0.0);
  // (measured 6.6e-11 m against a bound of 4.7e-9 m)
  CHECK(max_abs_difference(st.x, bdf.x) <= agreement_bound(grid.network, st, bdf));
  // The floor never loosens a tolerance by more than 1e3: 1e-14 stays below it.
  CHECK(equilibrium_threshold(grid.network, bdf.stats.t_final, bdf.x.data(), 1e-14) == 1e-11);
}

TEST_CASE("static lands on the two_corner equilibrium of the dynamics") {
  DrapeParams p;
  p.layout = PinLayout::TwoCorner;
  const DrapeGrid grid = build_drape_grid(p);
  const Drape ref = drape(grid.network, "cvode-bdf", reference_options());
  REQUIRE(ref.stats.status == RunStatus::Equilibrium);
  double z_min = 0.0;
  for (std::size_t i = 2; i < ref.x.size(); i += 3) z_min = std::min(z_min, ref.x[i]);
  CHECK(z_min < -0.45);  // the sheet has swung down and hangs from its two corners
  const Drape d = drape(grid.network, "static", IntegratorOptions{});
  require_agreement(grid.network, d, ref);
}

TEST_CASE("cvode-bdf-dense agrees with cvode-bdf on a small mesh") {
  const DrapeGrid grid = coarse_grid(DrapeParams{}.damping);
  const Drape ref = drape(grid.network, "cvode-bdf", reference_options());
  REQUIRE(ref.stats.status == RunStatus::Equilibrium);
  const Drape d = drape(grid.network, "cvode-bdf-dense", reference_options());
  require_agreement(grid.network, d, ref);
  CHECK(d.stats.jac_evals > 0);
}

TEST_CASE("cvode-bdf-dense refuses a large system, naming its size") {
  DrapeParams p;
  p.natural_length = 0.0165;  // 31 x 31 cells: 2n = 6 x 1020 free particles
  const DrapeGrid grid = build_drape_grid(p);
  const int two_n = 2 * grid.network.dof();
  REQUIRE(two_n > 3000);
  std::vector<double> x, v;
  REQUIRE_THROWS_WITH(
      run_to_equilibrium(grid.network, "cvode-bdf-dense", IntegratorOptions{}, x, v),
      Catch::Contains(std::to_string(two_n)));
}

TEST_CASE("cvode-bdf-gmres reaches the four_corner equilibrium; its floor is set by eps_lin") {
  // GMRES stops at eps_lin x the Newton tolerance, and with the block-Jacobi preconditioner
  // the static residual it leaves is proportional to eps_lin: at SUNDIALS' 0.05 the run ends
  // at t_max on a floor of ~3e-5; at the default (5e-7) every preconditioner settles below
  // equilibrium_tol 1e-8 like the direct solvers.
  const Drape d = drape(four_corner().network, "cvode-bdf-gmres", IntegratorOptions{});
  INFO(d.stats.message);
  REQUIRE(d.stats.status == RunStatus::Equilibrium);
  CHECK(d.stats.residual < 1e-8);
  CHECK(d.stats.lin_iters > 0);
  require_agreement(four_corner().network, d, four_corner_reference());

  IntegratorOptions loose;  // block-Jacobi: its preconditioned residual is a poor error measure
  loose.gmres_preconditioner = IntegratorOptions::GmresPreconditioner::BlockJacobi;
  loose.krylov_eps_lin = 0.05;
  const Drape l = drape(four_corner().network, "cvode-bdf-gmres", loose);
  INFO(l.stats.message);
  CHECK(l.stats.status == RunStatus::TimeLimit);
  CHECK(l.stats.residual > 1e-6);
}

TEST_CASE(
    "every GMRES preconditioner settles four_corner; the lagged Schur LDL^T needs fewest "
    "iterations") {
  using GP = IntegratorOptions::GmresPreconditioner;
  long iters[3] = {0, 0, 0};
  const GP all[3] = {GP::BlockJacobi, GP::SchurIc, GP::SchurLdl};
  for (int i = 0; i < 3; ++i) {
    IntegratorOptions opt;
    opt.gmres_preconditioner = all[i];
    const Drape d = drape(four_corner().network, "cvode-bdf-gmres", opt);
    INFO(to_string(all[i]) << ": " << d.stats.message);
    require_agreement(four_corner().network, d, four_corner_reference());
    iters[i] = d.stats.lin_iters;
  }
  // Measured 4091 / 3249 / 1371.
  CHECK(iters[2] * 2 < iters[0]);
  CHECK(iters[2] * 2 < iters[1]);
}

TEST_CASE("restart: the same state and time, counters kept, a fresh small first step") {
  // Run each implicit SUNDIALS method until its step has grown to ~1 s, restart, and step
  // once more: the new step starts from the method's initial-step estimate (CVODE: at order
  // 1), not from the step-size history.
  const DrapeGrid grid = coarse_grid(DrapeParams{}.damping);
  const MechanicalSystem& sys = grid.network;
  const int n = sys.dof();
  std::vector<double> x0(n), v0(n);
  sys.initial_state(x0.data(), v0.data());
  const IntegratorOptions opt;
  for (const char* name : {"cvode-bdf", "cvode-bdf-gmres", "arkode-dirk", "arkode-imex"}) {
    INFO(name);
    auto integ = make_integrator(name);
    integ->start(sys, 0.0, x0.data(), v0.data(), opt);
    double h_before = 0.0;
    for (int i = 0; i < 2000 && integ->time() < 10.0; ++i) {  // h grows to ~1 s by t = 10 s
      const double t = integ->time();
      REQUIRE(integ->step(opt.t_max).ok);
      h_before = integ->time() - t;
    }
    RunStats before, kept, after;
    integ->fill_stats(before);
    const double t = integ->time();
    const std::vector<double> x(integ->positions(), integ->positions() + n);
    REQUIRE(integ->restart());
    integ->fill_stats(kept);
    CHECK(integ->time() == t);
    CHECK(max_abs_difference(std::vector<double>(integ->positions(), integ->positions() + n), x) ==
          0.0);
    CHECK(kept.steps == before.steps);
    CHECK(kept.rhs_evals == before.rhs_evals);
    CHECK(kept.lin_setups == before.lin_setups);
    CHECK(kept.nonlin_iters == before.nonlin_iters);
    REQUIRE(integ->step(opt.t_max).ok);
    integ->fill_stats(after);
    CHECK(after.steps == before.steps + 1);
    CHECK(after.rhs_evals > before.rhs_evals);
    CHECK(integ->time() - t < 1e-2 * h_before);
    if (std::string(name).rfind("cvode", 0) == 0) CHECK(integ->last_order() == 1);
  }
}

namespace {

// A SUNDIALS integrator whose `fail_at`-th step call fails once, recoverably, without stepping
// (the state stays the last accepted one, as after CVODE's CV_ERR_FAILURE); restart() is the
// real method's. Records the order of the step before the failure and of the step after it.
class FailOnce final : public Integrator {
 public:
  FailOnce(const std::string& name, long fail_at)
      : inner_(make_integrator(name)), fail_at_(fail_at) {}
  const IntegratorInfo& info() const override { return inner_->info(); }
  void start(const MechanicalSystem& sys, double t0, const double* x0, const double* v0,
             const IntegratorOptions& opt) override {
    inner_->start(sys, t0, x0, v0, opt);
  }
  Step step(double t_stop) override {
    ++calls_;
    if (calls_ == fail_at_) {
      order_before_ = inner_->last_order();
      return {false, "injected error-test failure", true};
    }
    const Step st = inner_->step(t_stop);
    if (calls_ == fail_at_ + 1) order_after_ = inner_->last_order();
    return st;
  }
  bool restart() override { return inner_->restart(); }
  int last_order() const override { return inner_->last_order(); }
  double time() const override { return inner_->time(); }
  const double* positions() const override { return inner_->positions(); }
  const double* velocities() const override { return inner_->velocities(); }
  void fill_stats(RunStats& st) const override { inner_->fill_stats(st); }
  int order_before() const { return order_before_; }
  int order_after() const { return order_after_; }

 private:
  std::unique_ptr<Integrator> inner_;
  long fail_at_, calls_ = 0;
  int order_before_ = 0, order_after_ = 0;
};

}  // namespace

TEST_CASE("a recoverable failure mid-run: the driver restarts CVODE, which settles as before") {
  // Whether a real run needs a restart is a knife edge (two_corner, cvode-bdf-gmres: CVODE's
  // seventh error-test failure in a row, or not, depending on round-off; docs/numerics.md,
  // "Restarts"), so the mechanism is tested with a failure injected half-way through a
  // four_corner run, at high order and large steps: the driver must restart the real CVODE
  // (fresh order 1), and the run must still settle on the same equilibrium within the stop
  // criterion's bound.
  const SpringNetwork& net = four_corner().network;
  const Drape clean = drape(net, "cvode-bdf-gmres", IntegratorOptions{});
  REQUIRE(clean.stats.status == RunStatus::Equilibrium);
  FailOnce failing("cvode-bdf-gmres", clean.stats.steps / 2);
  Drape d;
  d.stats = run_to_equilibrium(net, failing, IntegratorOptions{}, d.x, d.v);
  INFO(d.stats.message << "; order before the failure " << failing.order_before() << ", after "
                       << failing.order_after());
  CHECK(d.stats.restarts >= 1);
  CHECK(failing.order_before() >= 2);  // the history that a restart throws away
  CHECK(failing.order_after() == 1);
  require_agreement(net, d, four_corner_reference());
  // Without restarts the same failure ends the run, saying what failed.
  IntegratorOptions none;
  none.max_restarts = 0;
  FailOnce again("cvode-bdf-gmres", clean.stats.steps / 2);
  std::vector<double> x, v;
  const RunStats s = run_to_equilibrium(net, again, none, x, v);
  CHECK(s.status == RunStatus::SolverFailure);
  CHECK(s.message == "injected error-test failure");
}

TEST_CASE("with restarts allowed, cvode-bdf-gmres settles two_corner at eps_lin 5e-3 to 5e-6") {
  // Without restarts, schur-ldl GMRES failed CVODE's error test seven times in a row (order 4,
  // h 130 s -> 2e-3 s) at these eps_lin; a restart from the last accepted state settled each.
  // Whether a run needs the restart at all is a round-off knife edge, so only the outcome is
  // asserted: every run settles on the reference equilibrium (the mechanism: the test above).
  DrapeParams p;
  p.layout = PinLayout::TwoCorner;
  const DrapeGrid grid = build_drape_grid(p);
  const Drape ref = drape(grid.network, "cvode-bdf", IntegratorOptions{});
  REQUIRE(ref.stats.status == RunStatus::Equilibrium);
  for (const double eps_lin : {5e-3, 5e-5, 5e-6}) {
    IntegratorOptions opt;
    opt.krylov_eps_lin = eps_lin;
    const Drape d = drape(grid.network, "cvode-bdf-gmres", opt);
    INFO("eps_lin " << eps_lin << ": " << d.stats.message << ", " << d.stats.restarts
                    << " restarts");
    require_agreement(grid.network, d, ref);
  }
}

TEST_CASE("the block-Jacobi preconditioner cuts GMRES iterations") {
  const DrapeGrid grid = coarse_grid(DrapeParams{}.damping);
  IntegratorOptions opt;
  opt.krylov_dim = 20;
  opt.t_max = 10.0;
  long iters[2] = {0, 0};
  for (bool pre : {false, true}) {
    opt.gmres_preconditioner = pre ? IntegratorOptions::GmresPreconditioner::BlockJacobi
                                   : IntegratorOptions::GmresPreconditioner::None;
    const Drape d = drape(grid.network, "cvode-bdf-gmres", opt);
    INFO(d.stats.message);
    REQUIRE(d.stats.status == RunStatus::TimeLimit);
    iters[pre] = d.stats.lin_iters;
  }
  CHECK(iters[1] * 3 < iters[0]);
}

TEST_CASE("non-stiff methods agree with cvode-bdf on a lightly damped coarse drape") {
  // c = 0.05 N s/m makes the drape non-stiff (gamma = c/m ~ 1e2 /s instead of ~3e4 /s).
  const DrapeGrid grid = coarse_grid(0.05);
  const Drape ref = drape(grid.network, "cvode-bdf", reference_options());
  REQUIRE(ref.stats.status == RunStatus::Equilibrium);
  for (const char* name : {"cvode-adams", "arkode-erk"}) {
    SECTION(name) {
      const Drape d = drape(grid.network, name, reference_options());
      require_agreement(grid.network, d, ref);
      CHECK(d.stats.jac_evals == 0);
      CHECK(d.stats.lin_setups == 0);
    }
  }
}

TEST_CASE("non-stiff methods pay the stiffness penalty on the paper's damping") {
  const DrapeGrid grid = coarse_grid(DrapeParams{}.damping);
  const Drape bdf = drape(grid.network, "cvode-bdf", reference_options());
  REQUIRE(bdf.stats.status == RunStatus::Equilibrium);
  IntegratorOptions opt = reference_options();
  opt.max_steps = 20 * bdf.stats.steps;
  for (const char* name : {"cvode-adams", "arkode-erk"}) {
    const Drape d = drape(grid.network, name, opt);
    INFO(name << ": " << d.stats.message);
    CHECK(d.stats.status == RunStatus::StepLimit);
    CHECK(d.stats.residual > 1e-3);  // nowhere near rest after 20x cvode-bdf's steps
  }
}

TEST_CASE("SUNDIALS limits and failures are statuses, not exceptions") {
  const DrapeGrid grid = coarse_grid(DrapeParams{}.damping);
  test::NanAccelerationSystem nan_system(grid.network);
  for (const std::string& name : kSundials) {
    SECTION(name) {
      std::vector<double> x, v;
      IntegratorOptions opt;
      opt.max_steps = 1;
      RunStats s = run_to_equilibrium(grid.network, name, opt, x, v);
      CHECK(s.status == RunStatus::StepLimit);
      CHECK(s.steps >= 1);

      opt = IntegratorOptions{};
      opt.t_max = 1e-6;
      x.clear();
      s = run_to_equilibrium(grid.network, name, opt, x, v);
      CHECK(s.status == RunStatus::TimeLimit);
      CHECK(s.t_final == Approx(1e-6).epsilon(1e-12));  // the stop time is never passed

      x.clear();
      s = run_to_equilibrium(nan_system, name, IntegratorOptions{}, x, v);
      INFO(s.message);
      CHECK((s.status == RunStatus::SolverFailure || s.status == RunStatus::Diverged));
      // The message names the SUNDIALS call and its flag.
      CHECK_THAT(s.message, Catch::Matches(".*(CVode|ARKStepEvolve|ERKStepEvolve): "
                                           "[A-Z_]*_(ERR|FAIL)[A-Z_]* at t = .*"));
    }
  }
}

TEST_CASE("SUNDIALS integrators reject orders their methods do not have") {
  const DrapeGrid grid = coarse_grid(DrapeParams{}.damping);
  std::vector<double> x, v;
  IntegratorOptions opt;
  opt.max_order = 6;
  REQUIRE_THROWS_WITH(run_to_equilibrium(grid.network, "cvode-bdf", opt, x, v),
                      Catch::Contains("max_order = 6"));
  REQUIRE_THROWS_WITH(run_to_equilibrium(grid.network, "arkode-dirk", opt, x, v),
                      Catch::Contains("max_order = 6"));
  opt.max_order = 2;
  opt.max_steps = 50;
  const RunStats s = run_to_equilibrium(grid.network, "cvode-bdf", opt, x, v);
  CHECK(s.max_order_used == 2);
}

TEST_CASE("the compiled N_Vector operations give SUNDIALS' own results bit for bit") {
  // make_vector installs knitsim's loops for SUNDIALS' -O0 ones (sundials_common.cpp); every
  // case of N_VLinearSum and N_VScale, in place or not, must round exactly as the library does.
  using namespace knitsim::sun;
  const ContextPtr ctx = make_context();
  const long n = 37;  // odd: the vectorised loops' remainders too
  std::vector<double> xs(n), ys(n);
  for (long i = 0; i < n; ++i) {
    xs[i] = std::sin(1.3 * i + 0.2) * std::pow(10.0, (i % 7) - 3);
    ys[i] = std::cos(0.7 * i - 0.4) * std::pow(10.0, 2 - (i % 5));
  }
  ys[3] = 0.0;
  auto vec = [&](const std::vector<double>& v) {
    VectorPtr p = make_vector(n, ctx.get());
    std::copy(v.begin(), v.end(), N_VGetArrayPointer(p.get()));
    return p;
  };
  auto values = [&](N_Vector v) {
    const double* d = N_VGetArrayPointer(v);
    return std::vector<double>(d, d + n);
  };
  auto bits_equal = [](const std::vector<double>& a, const std::vector<double>& b) {
    return std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
  };
  const double coefficients[] = {1.0, -1.0, 0.0, 2.5, -2.5, 1.0 / 3.0, -0.1};
  int cases = 0;
  for (double a : coefficients)
    for (double b : coefficients)
      for (int alias = 0; alias < 3; ++alias) {  // z separate, z = x, z = y
        INFO("a = " << a << ", b = " << b << ", alias " << alias);
        VectorPtr x1 = vec(xs), y1 = vec(ys), z1 = vec(ys), x2 = vec(xs), y2 = vec(ys),
                  z2 = vec(ys);
        N_Vector za = alias == 1 ? x1.get() : alias == 2 ? y1.get() : z1.get();
        N_Vector zb = alias == 1 ? x2.get() : alias == 2 ? y2.get() : z2.get();
        N_VLinearSum(a, x1.get(), b, y1.get(), za);         // knitsim's
        N_VLinearSum_Serial(a, x2.get(), b, y2.get(), zb);  // SUNDIALS'
        CHECK(bits_equal(values(za), values(zb)));
        if (b == coefficients[0]) {
          N_VScale(a, x1.get(), alias == 0 ? z1.get() : x1.get());
          N_VScale_Serial(a, x2.get(), alias == 0 ? z2.get() : x2.get());
          CHECK(bits_equal(values(alias == 0 ? z1.get() : x1.get()),
                           values(alias == 0 ? z2.get() : x2.get())));
        }
        ++cases;
      }
  CHECK(cases == 147);
  VectorPtr x = vec(xs), y = vec(ys), z1 = vec(ys), z2 = vec(ys);
  auto same = [&](auto ours, auto theirs) {
    ours(z1.get());
    theirs(z2.get());
    return bits_equal(values(z1.get()), values(z2.get()));
  };
  CHECK(same([&](N_Vector z) { N_VProd(x.get(), y.get(), z); },
             [&](N_Vector z) { N_VProd_Serial(x.get(), y.get(), z); }));
  CHECK(same([&](N_Vector z) { N_VDiv(y.get(), x.get(), z); },
             [&](N_Vector z) { N_VDiv_Serial(y.get(), x.get(), z); }));
  CHECK(same([&](N_Vector z) { N_VAbs(x.get(), z); },
             [&](N_Vector z) { N_VAbs_Serial(x.get(), z); }));
  CHECK(same([&](N_Vector z) { N_VInv(x.get(), z); },
             [&](N_Vector z) { N_VInv_Serial(x.get(), z); }));
  CHECK(same([&](N_Vector z) { N_VAddConst(x.get(), 0.3, z); },
             [&](N_Vector z) { N_VAddConst_Serial(x.get(), 0.3, z); }));
  CHECK(same([&](N_Vector z) { N_VCompare(0.05, x.get(), z); },
             [&](N_Vector z) { N_VCompare_Serial(0.05, x.get(), z); }));
  CHECK(same([&](N_Vector z) { N_VConst(-4.25, z); },
             [&](N_Vector z) { N_VConst_Serial(-4.25, z); }));
  CHECK(N_VMaxNorm(y.get()) == N_VMaxNorm_Serial(y.get()));
  CHECK(N_VDotProd(x.get(), y.get()) == N_VDotProd_Serial(x.get(), y.get()));
  // ...and they are knitsim's, not SUNDIALS' (else the comparisons above prove nothing).
  CHECK(x->ops->nvlinearsum != N_VLinearSum_Serial);
  CHECK(x->ops->nvscale != N_VScale_Serial);
}
