// YarnRods (models/yarn_rods.hpp): derivatives against finite differences, a yarn in tension and
// the cantilevered elastica against closed forms, two yarns pushed together that never cross,
// yarn length kept. The elastica reference values come from tests/elastica_reference.py (scipy).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <ctime>
#include <iomanip>
#include <random>
#include <vector>

#include "models/yarn_rods.hpp"
#include "solvers/integrator.hpp"
#include "src/core/jacobian_check.hpp"
#include "tests/corrupted_stiffness.hpp"

using namespace knitsim;

namespace {

constexpr double kPi = 3.14159265358979323846;
// Largest relative Jacobian error accepted (check_stiffness_jacobian, central differences of
// 1e-8 m); a wrong term must show at least ten times that.
constexpr double kJacobianTol = 1e-5;

// n + 1 vertices from `from`, spaced `step` along the unit vector `dir`.
std::vector<Vec3> straight(Vec3 from, Vec3 dir, double step, int n) {
  std::vector<Vec3> v;
  for (int i = 0; i <= n; ++i) v.push_back(from + (i * step) * dir);
  return v;
}

// A hairpin of one yarn: two legs along x, `sep` apart in y, joined by a half circle.
std::vector<Vec3> hairpin(double leg, double sep, double step, Vec3 at) {
  std::vector<Vec3> v;
  const int nl = static_cast<int>(std::round(leg / step));
  for (int i = 0; i <= nl; ++i) v.push_back(at + Vec3{i * step, 0.0, 0.0});
  const double r = 0.5 * sep;
  const int nc = std::max(4, static_cast<int>(std::round(kPi * r / step)));
  for (int i = 1; i < nc; ++i) {
    const double a = -0.5 * kPi + kPi * i / nc;
    v.push_back(at + Vec3{nl * step + r * std::cos(a), r + r * std::sin(a), 0.0});
  }
  for (int i = nl; i >= 0; --i) v.push_back(at + Vec3{i * step, sep, 0.0});
  return v;
}

// Three yarns in contact: a hairpin whose legs are 0.85 d apart (same-yarn contact), a yarn
// crossing it 0.85 d above, and a yarn curved at rest; each vertex jittered by `jitter` d.
YarnRodsSpec contact_scene(const YarnParams& p, double jitter, unsigned seed) {
  const double d = p.diameter(), l = 0.5 * d;
  YarnRodsSpec s;
  s.yarn = p;
  s.rest.push_back(hairpin(8 * l, 0.85 * d, l, {0.0, 0.0, 0.0}));
  s.rest.push_back(straight({4 * l, -4 * l, 0.85 * d}, {0.0, 1.0, 0.0}, l, 10));
  s.rest.push_back(straight({-2 * l, -3 * d, 0.0}, {1.0, 0.0, 0.0}, l, 6));
  s.initial = s.rest;
  // The third yarn starts on an arc (turning 0.3 rad per vertex) and is curved at rest (0.2 at
  // each vertex), so its bending energy's kappa0 terms are checked too.
  s.rest_curvature = {std::vector<double>(s.rest[0].size(), 0.0),
                      std::vector<double>(s.rest[1].size(), 0.0), std::vector<double>(7, 0.2)};
  for (int i = 1; i <= 6; ++i) {
    const double turn = 0.3 * i;
    s.initial[2][i] = s.initial[2][i - 1] + Vec3{l * std::cos(turn), 0.0, l * std::sin(turn)};
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter * d, jitter * d);
  for (auto& yarn : s.initial)
    for (Vec3& v : yarn) v = v + Vec3{u(rng), u(rng), u(rng)};
  s.pins = {{0, 0}, {1, 0}, {2, 0}};
  s.loads = {{{2, 6}, {1e-4, 2e-4, -3e-4}}};
  return s;
}

std::vector<double> start_of(const MechanicalSystem& sys) {
  std::vector<double> x(sys.dof()), v(sys.dof());
  sys.initial_state(x.data(), v.data());
  return x;
}

// The Jacobian 1 % off in the 3 x 3 block (row vertex r, column vertex c): the check must catch it.
test::CorruptedStiffness corrupt_block(const YarnRods& s, int r, int c) {
  return test::CorruptedStiffness(
      s, test::block_entries(s.stiffness_pattern(), s.free_index(r), s.free_index(c)));
}

// max_i |f_i + dE/dx_i| / max_i |f_i| by central differences of step h (m).
double gradient_error(const YarnRods& sys, const std::vector<double>& x, double h) {
  std::vector<double> f(sys.dof());
  sys.net_force(x.data(), f.data());
  double worst = 0.0, scale = 0.0;
  for (int i = 0; i < sys.dof(); ++i) {
    std::vector<double> xp = x, xm = x;
    xp[i] += h;
    xm[i] -= h;
    const double grad =
        (sys.potential_energy(0.0, xp.data()) - sys.potential_energy(0.0, xm.data())) / (2 * h);
    worst = std::max(worst, std::abs(f[i] + grad));
    scale = std::max(scale, std::abs(f[i]));
  }
  return worst / scale;
}

// Records the smallest clearance over every state the run checks (every step of the implicit
// methods).
struct ClearanceWatch final : RunObserver {
  const YarnRods& sys;
  double smallest = std::numeric_limits<double>::infinity();
  long checks = 0;
  explicit ClearanceWatch(const YarnRods& s) : sys(s) {}
  void on_check(double, const double* x, const double*, double) override {
    smallest = std::min(smallest, sys.min_clearance(x));
    ++checks;
  }
};

// A cantilever of length L clamped at x = 0: n + 1 edges of length h = L / (n + 1/2), vertices 0
// (at -h/2) and 1 (at h/2) pinned, so the clamped edge's midpoint is at the origin -- a discrete
// rod's clamp is its edge (the vertex 1 as the clamp point gives a rod h/2 longer: a first-order
// error 3h/(2L) in the deflection, measured), a dead load P at the tip along -z.
// Returns the tip's (x, -z) / L at equilibrium.
std::pair<double, double> cantilever_tip(int n, double L, double alpha, double* length_change) {
  YarnRodsSpec s;
  const double h = L / (n + 0.5);
  s.rest.push_back(straight({-0.5 * h, 0.0, 0.0}, {1.0, 0.0, 0.0}, h, n + 1));
  s.pins = {{0, 0}, {0, 1}};
  const double P = alpha * s.yarn.bending_rigidity / (L * L);
  s.loads = {{{0, n + 1}, {0.0, 0.0, -P}}};
  s.residual_force_scale = P;
  s.contact = false;
  YarnRods sys(s);
  std::vector<double> x, v;
  const RunStats st = run_to_equilibrium(sys, "equilibrium", IntegratorOptions{}, x, v);
  REQUIRE(st.status == RunStatus::Equilibrium);
  std::vector<Vec3> pos;
  sys.all_positions(x.data(), pos);
  if (length_change) *length_change = sys.yarn_length(0, x.data()) / sys.rest_length(0) - 1.0;
  return {pos.back().x / L, -pos.back().z / L};
}

}  // namespace

TEST_CASE(
    "yarn diameter from tex, fibre density and packing fraction; the handbook's 4.44e-3 "
    "hides a packing fraction of 0.646") {
  YarnParams p;  // 25 tex cotton, 1520 kg/m^3, 0.6
  CHECK(p.diameter() == Approx(std::sqrt(4 * 25e-6 / (kPi * 1520 * 0.6))).epsilon(1e-12));
  CHECK(p.diameter() == Approx(1.868e-4).epsilon(1e-3));  // m
  // d (cm) = 4.44e-3 sqrt(tex / rho (g/cm^3)) equals ours at phi = (sqrt(4e-5 / pi) / 4.44e-3)^2.
  p.packing_fraction = 4e-5 / kPi / (4.44e-3 * 4.44e-3);
  CHECK(p.packing_fraction == Approx(0.6458).epsilon(1e-3));
  CHECK(p.diameter() * 100 == Approx(4.44e-3 * std::sqrt(25.0 / 1.52)).epsilon(1e-12));
  CHECK(p.stretch_stiffness() == Approx(67.5));  // N: 2.7 N/tex x 25 tex
}

TEST_CASE("yarn parameters out of range are refused naming the field") {
  YarnParams p;
  p.packing_fraction = 1.2;
  CHECK_THROWS_WITH(p.validate(),
                    Catch::Contains("yarn.packing_fraction") && Catch::Contains("(0.1, 0.9]"));
  p = YarnParams{};
  p.core_fraction = 1.0;
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("yarn.core_fraction"));
  p = YarnParams{};
  p.bending_rigidity = 0.0;
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("yarn.bending_rigidity"));
  YarnRodsSpec s;
  s.rest = {{{0, 0, 0}}};
  CHECK_THROWS_WITH(YarnRods(s), Catch::Contains("fewer than 2 vertices"));
}

TEST_CASE(
    "yarn rods: forces are -dE/dx and the Jacobian matches finite differences, bent, in "
    "contact (between yarns and within one)") {
  // Soft stretching (1e-6 N/tex) lets bending and contact dominate the columns, so their
  // Hessians are checked as sharply as the stretching's (2 N/tex, near the default 2.7).
  for (double modulus : {2.0, 1e-6}) {
    YarnParams p;
    p.tensile_modulus = modulus;
    for (unsigned seed : {1u, 2u, 3u}) {
      YarnRods sys(contact_scene(p, 0.04, seed));
      const std::vector<double> x = start_of(sys);
      const double ec = sys.contact_energy(x.data());
      INFO("modulus " << modulus << " seed " << seed << " contact energy " << ec);
      REQUIRE(ec > 0.0);
      REQUIRE(std::isfinite(ec));
      REQUIRE(sys.bend_energy(x.data()) > 0.0);
      const double ge = gradient_error(sys, x, 1e-10);
      CHECK(ge < 1e-5);
      const JacobianCheck c = check_stiffness_jacobian(sys, 0.0, x.data(), 1e-8);
      INFO("worst (" << c.worst_row << "," << c.worst_col << ") analytic " << c.worst_analytic
                     << " fd " << c.worst_fd);
      CHECK(c.max_relative_error < kJacobianTol);
      WARN("modulus " << modulus << " N/tex, seed " << seed << ": force vs -dE/dx " << ge
                      << ", Jacobian " << c.max_relative_error << " (relative)");
      CHECK(sys.pattern_misses() == 0);
    }
  }
}

TEST_CASE(
    "a yarn curved at rest and clamped at one end relaxes to its rest shape, a regular "
    "polygon on a circle") {
  // kappa0 = 2 tan(theta / 2) at every vertex, theta = 2 pi / 24: the unloaded equilibrium is
  // half of a regular 24-gon of edge l, circumradius l / (2 sin(theta / 2)), in the plane it
  // starts bent in. It starts bent more (1.5 theta per vertex): below kappa0 the energy of a
  // scalar rest curvature is not convex (models/yarn_rods.hpp, "Rest curvature").
  const double l = 1e-3, theta = 2 * kPi / 24;
  YarnRodsSpec s;
  s.rest.push_back(straight({0, 0, 0}, {1.0, 0.0, 0.0}, l, 12));
  s.rest_curvature = {std::vector<double>(13, 2 * std::tan(theta / 2))};
  s.initial = s.rest;
  for (int i = 2; i <= 12; ++i) {
    const double a = 1.5 * theta * (i - 1);
    s.initial[0][i] = s.initial[0][i - 1] + Vec3{l * std::cos(a), 0.0, l * std::sin(a)};
  }
  s.pins = {{0, 0}, {0, 1}};
  s.residual_force_scale = s.yarn.bending_rigidity / (l * l);
  s.contact = false;
  YarnRods sys(s);
  std::vector<double> x, v;
  IntegratorOptions opt;
  opt.max_wall_seconds = 30.0;  // a guard (it takes ~170 flow steps)
  const RunStats st = run_to_equilibrium(sys, "equilibrium", opt, x, v);
  INFO(st.message);
  REQUIRE(st.status == RunStatus::Equilibrium);
  std::vector<Vec3> pos;
  sys.all_positions(x.data(), pos);
  const double R = l / (2 * std::sin(theta / 2));
  const Vec3 centre{0.5 * l, 0.0, std::sqrt(R * R - 0.25 * l * l)};
  double worst = 0.0;
  for (const Vec3& p : pos) worst = std::max(worst, std::abs(norm(p - centre) - R));
  WARN("largest distance from the 24-gon's circle: " << worst / R << " R");
  CHECK(worst < 1e-5 * R);  // kappa = 2 sin(phi / 2) in place of 2 tan: a circle ~1 % larger
}

TEST_CASE("one yarn's parts touch each other only beyond same_yarn_gap along it") {
  YarnParams p;
  const double d = p.diameter();
  YarnRodsSpec s;
  s.yarn = p;
  s.rest.push_back(hairpin(4 * d, 0.85 * d, 0.5 * d, {0.0, 0.0, 0.0}));  // legs 0.85 d apart
  s.pins = {{0, 0}};
  const YarnRods near(s);
  const std::vector<double> x = start_of(near);
  CHECK(near.contact_energy(x.data()) > 0.0);
  CHECK(near.min_clearance(x.data()) == Approx(0.85 * d).epsilon(1e-9));
  s.yarn.same_yarn_gap = 20.0;  // longer than the whole yarn: no pair left
  const YarnRods far(s);
  CHECK(far.contact_energy(x.data()) == 0.0);
  CHECK(std::isinf(far.min_clearance(x.data())));
}

TEST_CASE(
    "yarn rods: the Jacobian check catches a 1 % error in a bending-only and in a "
    "contact-only block") {
  YarnParams p;
  p.tensile_modulus = 1e-6;
  YarnRods sys(contact_scene(p, 0.04, 1));
  const std::vector<double> x = start_of(sys);
  REQUIRE(check_stiffness_jacobian(sys, 0.0, x.data(), 1e-8).max_relative_error < kJacobianTol);
  // Vertices 3 and 5 of the hairpin meet only through bending (x_{i-1}, x_{i+1} of vertex 4).
  const test::CorruptedStiffness bending =
      corrupt_block(sys, sys.vertex_index(0, 3), sys.vertex_index(0, 5));
  CHECK(check_stiffness_jacobian(bending, 0.0, x.data(), 1e-8).max_relative_error >
        10 * kJacobianTol);
  // The crossing yarn's vertex 5 and the hairpin's vertex 4 meet only through contact.
  const test::CorruptedStiffness contact =
      corrupt_block(sys, sys.vertex_index(1, 5), sys.vertex_index(0, 4));
  CHECK(check_stiffness_jacobian(contact, 0.0, x.data(), 1e-8).max_relative_error >
        10 * kJacobianTol);
}

TEST_CASE(
    "a straight yarn held at one end and pulled by F at the other stretches by F L / EA, "
    "and keeps its length within 1 % under 0.1 N") {
  YarnRodsSpec s;
  const double L = 0.01;  // m
  const int n = 20;
  s.rest.push_back(straight({0, 0, 0}, {1.0, 0.0, 0.0}, L / n, n));
  s.pins = {{0, 0}};
  const double F = 0.1;  // N: a few times a knitting machine's yarn input tension
  s.loads = {{{0, n}, {F, 0.0, 0.0}}};
  s.residual_force_scale = F;
  YarnRods sys(s);
  for (const char* method : {"equilibrium", "cvode-bdf"}) {
    std::vector<double> x, v;
    IntegratorOptions opt;
    opt.position_tol = 1e-14;  // m: the elongation is 2e-5 m
    const RunStats st = run_to_equilibrium(sys, method, opt, x, v);
    REQUIRE(st.status == RunStatus::Equilibrium);
    const double stretch = x[3 * (n - 1)] - L;  // the tip is free vertex n - 1
    const double exact = F * L / s.yarn.stretch_stiffness();
    INFO(method << ": elongation " << std::setprecision(12) << stretch << " m, closed form "
                << exact << " m");
    CHECK(stretch == Approx(exact).epsilon(1e-6));
    WARN(method << ": elongation relative error " << std::abs(stretch / exact - 1.0) << ", "
                << st.steps << " steps");
    CHECK(std::abs(sys.yarn_length(0, x.data()) / L - 1.0) < 0.01);
  }
}

TEST_CASE(
    "cantilevered elastica: small deflection P L^3 / (3 B) and large deflection (P L^2 / "
    "B = 2) against the elastica, converging with the segment count") {
  const double L = 0.01;
  // Small: alpha = 3e-3, so the geometric nonlinearity (relative ~ alpha^2) is below 1e-5.
  std::vector<double> small_err, large_err;
  for (int n : {8, 16, 32, 64}) {
    const auto [xs, ys] = cantilever_tip(n, L, 3e-3, nullptr);
    small_err.push_back(std::abs(ys / (3e-3 / 3.0) - 1.0));
    double dl = 0.0;
    const auto [xl, yl] = cantilever_tip(n, L, 2.0, &dl);
    // Reference: tests/elastica_reference.py (collocation and shooting agree to 8 digits).
    large_err.push_back(std::hypot(xl - 0.83935828, yl - 0.49345748));
    CHECK(std::abs(dl) < 0.01);  // length kept under the large deflection
    WARN("n = " << n << ": small deflection relative error " << small_err.back()
                << ", large deflection tip error / L " << large_err.back() << ", length change "
                << dl);
  }
  CHECK(small_err.back() < 1e-3);
  CHECK(large_err.back() < 1e-3);
  // Observed order from the last halving: at least first order in the edge length.
  const double small_order = std::log2(small_err[2] / small_err[3]);
  const double large_order = std::log2(large_err[2] / large_err[3]);
  WARN("observed orders: small " << small_order << ", large " << large_order);
  CHECK(small_order > 0.9);
  CHECK(large_order > 0.9);
}

TEST_CASE(
    "two crossing yarns pushed together never pass through each other and settle about "
    "one diameter apart (equilibrium and cvode-bdf); without contact they cross") {
  // Held at both ends, a yarn pushed sideways stiffens as a string (its stretch grows as the
  // square of the deflection), so it is long (20 mm, 214 edges of d/2) to be pushed through.
  YarnParams p;
  const double d = p.diameter(), L = 0.02, F = 1e-3;  // m, m, N
  const int n = static_cast<int>(std::round(L / (0.5 * d)));
  auto scene = [&](bool contact) {
    YarnRodsSpec s;
    s.yarn = p;
    s.rest.push_back(straight({-L / 2, 0.0, 0.75 * d}, {1.0, 0.0, 0.0}, L / n, n));
    s.rest.push_back(straight({0.0, -L / 2, -0.75 * d}, {0.0, 1.0, 0.0}, L / n, n));
    s.pins = {{0, 0}, {0, n}, {1, 0}, {1, n}};
    s.loads = {{{0, n / 2}, {0.0, 0.0, -F}}, {{1, n / 2}, {0.0, 0.0, F}}};
    s.residual_force_scale = F;
    s.contact = contact;
    return s;
  };
  {  // Without contact the loads carry the yarns through each other.
    YarnRods free(scene(false));
    std::vector<double> x, v;
    REQUIRE(run_to_equilibrium(free, "equilibrium", IntegratorOptions{}, x, v).status ==
            RunStatus::Equilibrium);
    std::vector<Vec3> pos;
    free.all_positions(x.data(), pos);
    REQUIRE(pos[n / 2].z < pos[free.vertex_index(1, n / 2)].z);
  }
  YarnRods sys(scene(true));
  for (const char* method : {"equilibrium", "cvode-bdf"}) {
    std::vector<double> x, v;
    ClearanceWatch watch(sys);
    IntegratorOptions opt;
    opt.max_wall_seconds = 60.0;  // a guard
    const RunStats st = run_to_equilibrium(sys, method, opt, x, v, &watch);
    INFO(method << ": " << st.message << ", steps " << st.steps);
    REQUIRE(st.status == RunStatus::Equilibrium);
    const double gap = sys.min_clearance(x.data());
    WARN(method << ": " << st.steps << " steps, " << watch.checks << " states checked, smallest "
                << "clearance " << watch.smallest / d << " d, final " << gap / d << " d");
    CHECK(watch.checks >= 5);
    CHECK(watch.smallest > 0.25 * d);  // the bound d0 - d/4 of the sampling
    CHECK(gap / d > 0.9);
    CHECK(gap / d < 1.0);
    for (int y = 0; y < 2; ++y)
      CHECK(std::abs(sys.yarn_length(y, x.data()) / sys.rest_length(y) - 1.0) < 0.01);
  }
}

TEST_CASE(
    "yarn rods: the step filter admits the whole of a step that keeps away and cuts one "
    "that would cross") {
  YarnParams p;
  const double d = p.diameter();
  YarnRodsSpec s;
  s.yarn = p;
  s.rest.push_back(straight({-4 * d, 0.0, 0.6 * d}, {1.0, 0.0, 0.0}, 0.5 * d, 16));
  s.rest.push_back(straight({0.0, -4 * d, -0.6 * d}, {0.0, 1.0, 0.0}, 0.5 * d, 16));
  s.pins = {{1, 0}, {1, 16}};
  YarnRods sys(s);
  std::vector<double> x = start_of(sys), dx(sys.dof(), 0.0);
  for (int i = 0; i < 17; ++i) dx[3 * i + 2] = 0.1 * d;  // yarn 0 up, away
  CHECK(sys.admissible_step(0.0, x.data(), dx.data()) == 1.0);
  for (int i = 0; i < 17; ++i) dx[3 * i + 2] = -1.2 * d;  // yarn 0 down onto yarn 1
  const double admit = sys.admissible_step(0.0, x.data(), dx.data());
  CHECK(admit > 0.0);
  CHECK(admit < 1.0);
  std::vector<double> y = x;
  for (size_t i = 0; i < y.size(); ++i) y[i] += admit * dx[i];
  CHECK(std::isfinite(sys.potential_energy(0.0, y.data())));
  CHECK(sys.min_clearance(y.data()) > 0.25 * d);
  for (size_t i = 0; i < y.size(); ++i) y[i] = x[i] + dx[i];
  CHECK(std::isinf(sys.potential_energy(0.0, y.data())));  // the whole step: inside the core
  CHECK(sys.min_clearance(y.data()) < 1e-3 * d);
  // A step 40 d long through the other yarn is cut where the 1.2 d one is: the pair that binds
  // is found by its own edges' moves (the boxes grow by each edge's move, capped, not by the
  // largest), and the cut point is the same.
  for (int i = 0; i < 17; ++i) dx[3 * i + 2] = -40.0 * d;
  const double admit_far = sys.admissible_step(0.0, x.data(), dx.data());
  CHECK(std::abs(admit_far * 40.0 - admit * 1.2) < 1e-9 * admit);
  // Two short yarns (no same-yarn pairs) 10 d apart: a step 40 d long taking one away from the
  // other is cut to move no vertex more than 2 (1 - step_keep) d = 1.6 d, the filter's reach.
  YarnRodsSpec s2;
  s2.yarn = p;
  s2.rest.push_back(straight({0.0, 0.0, 5.0 * d}, {1.0, 0.0, 0.0}, 0.5 * d, 3));
  s2.rest.push_back(straight({0.0, 0.0, -5.0 * d}, {1.0, 0.0, 0.0}, 0.5 * d, 3));
  YarnRods two(s2);
  std::vector<double> x2 = start_of(two), dx2(two.dof(), 0.0);
  for (int i = 0; i < 4; ++i) dx2[3 * i + 2] = 40.0 * d;
  CHECK(std::abs(two.admissible_step(0.0, x2.data(), dx2.data()) * 40.0 - 1.6) < 1e-12);
  for (int i = 0; i < 4; ++i) dx2[3 * i + 2] = 1.0 * d;  // within the reach: whole
  CHECK(two.admissible_step(0.0, x2.data(), dx2.data()) == 1.0);
}

TEST_CASE("yarn rods: cost per evaluation", "[.][cost]") {
  // Not run by default: prints the cost of forces, stiffness and energy on one long yarn coiled
  // in a helix of pitch 0.9 d (neighbouring turns in contact).
  YarnParams p;
  const double d = p.diameter();
  for (int n : {1000, 10000})
    for (bool contact : {false, true}) {
      YarnRodsSpec s;
      s.contact = contact;
      s.yarn = p;
      std::vector<Vec3> v;
      const double R = 1e-3, step = 0.5 * d;
      const double per_turn = 2 * kPi * R / step;
      for (int i = 0; i <= n; ++i) {
        const double a = 2 * kPi * i / per_turn;
        v.push_back({R * std::cos(a), R * std::sin(a), 0.9 * d * i / per_turn});
      }
      s.rest.push_back(v);
      s.pins = {{0, 0}};
      YarnRods sys(s);
      std::vector<double> x = start_of(sys), f(sys.dof()), vals(sys.stiffness_pattern().nnz());
      auto time = [&](auto&& fn) {  // process CPU time (the machine is shared), mean of 20
        const std::clock_t c0 = std::clock();
        for (int r = 0; r < 20; ++r) fn();
        return static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC / 20;
      };
      const double tf = time([&] { sys.conservative_acceleration(0.0, x.data(), f.data()); });
      const double tk = time([&] { sys.stiffness_values(0.0, x.data(), vals.data()); });
      const double te = time([&] { sys.potential_energy(0.0, x.data()); });
      WARN(n << " edges, " << (contact ? "contact" : "no contact") << ", "
             << sys.stiffness_pattern().nnz() / sys.dof()
             << " pattern entries per dof, contact energy " << sys.contact_energy(x.data())
             << " J: forces " << tf * 1e6 << " us, stiffness " << tk * 1e6 << " us, energy "
             << te * 1e6 << " us per evaluation (" << tf / n * 1e9 << " ns per vertex for forces)");
    }
}
