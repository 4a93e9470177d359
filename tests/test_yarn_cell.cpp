// YarnCell (models/yarn_cell.hpp): forces = -grad E and the Jacobian against finite differences
// with the cell's width and height as unknowns, images and the periodic same-yarn exclusion
// (a cell of two repeats holds twice the energy of one), a straight yarn's tension against its
// closed form, infeasible states as +inf energy, and the relaxed plain-jersey cell.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <ctime>
#include <memory>
#include <random>
#include <vector>

#include "models/yarn_cell.hpp"
#include "solvers/integrator.hpp"
#include "src/core/jacobian_check.hpp"
#include "src/scene/yarn_cell_run.hpp"
#include "tests/corrupted_stiffness.hpp"

using namespace knitsim;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kJacobianTol = 1e-5;

// Two wavy courses along x, n vertices each over a cell of width n * 0.5 d: course 1 0.9 d above
// course 0 (in y) and course 0's image H = 1.8 d above course 1, so each course touches the one
// above and below; each course weaves in z. `repeats` copies of the period make one cell of
// that many wales (the same fabric). Vertices jittered by `jitter` d (the same jitter in every
// repeat).
YarnCellSpec wavy_cell(const YarnParams& p, int n, int repeats, double jitter, unsigned seed,
                       CellSize size = CellSize::Free) {
  const double d = p.diameter(), l = 0.5 * d;
  YarnCellSpec s;
  s.yarn = p;
  s.width = repeats * n * l;
  s.height = 1.8 * d;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter * d, jitter * d);
  for (int c = 0; c < 2; ++c) {
    std::vector<Vec3> jit(n);
    for (Vec3& j : jit) j = {u(rng), u(rng), u(rng)};
    std::vector<Vec3> v;
    for (int r = 0; r < repeats; ++r)
      for (int k = 0; k < n; ++k) {
        const double a = 2.0 * kPi * k / n;
        v.push_back(Vec3{(r * n + k) * l, 0.9 * d * c + 0.1 * d * std::sin(a),
                         (c == 0 ? 0.3 : -0.3) * d * std::cos(a)} +
                    jit[k]);
      }
    s.initial.push_back(v);
    s.rest.push_back(std::vector<double>(v.size(), 1.05 * l));
  }
  s.size = size;
  return s;
}

std::vector<double> start_of(const MechanicalSystem& sys) {
  std::vector<double> x(sys.dof()), v(sys.dof());
  sys.initial_state(x.data(), v.data());
  return x;
}

// max_i |f_i + dE/dx_i| / max_i |f_i| by central differences of step h.
double gradient_error(const YarnCell& sys, const std::vector<double>& x, double h) {
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

}  // namespace

TEST_CASE(
    "yarn cell: forces are -dE/d(x, W, H) and the Jacobian matches finite differences, in "
    "contact with the images") {
  for (CellSize size : {CellSize::Free, CellSize::HeightHeld, CellSize::WidthHeld}) {
    for (double modulus : {2.0, 1e-6}) {
      YarnParams p;
      p.tensile_modulus = modulus;
      for (unsigned seed : {1u, 2u}) {
        YarnCell sys(wavy_cell(p, 12, 1, 0.04, seed, size));
        const std::vector<double> x = start_of(sys);
        const double ec = sys.contact_energy(x.data());
        INFO("size " << static_cast<int>(size) << " modulus " << modulus << " seed " << seed
                     << " contact energy " << ec);
        REQUIRE(ec > 0.0);
        REQUIRE(std::isfinite(ec));
        const double ge = gradient_error(sys, x, 1e-10);
        CHECK(ge < 1e-5);
        const JacobianCheck c = check_stiffness_jacobian(sys, 0.0, x.data(), 1e-8);
        INFO("worst (" << c.worst_row << "," << c.worst_col << ") analytic " << c.worst_analytic
                       << " fd " << c.worst_fd);
        CHECK(c.max_relative_error < kJacobianTol);
        WARN("size mode " << static_cast<int>(size) << ", modulus " << modulus << ", seed " << seed
                          << ": force vs -dE/dx " << ge << ", Jacobian " << c.max_relative_error);
      }
    }
  }
}

TEST_CASE("yarn cell: a 1 % error in the W or H rows of the Jacobian is caught") {
  YarnParams p;
  p.tensile_modulus = 1e-6;
  YarnCell sys(wavy_cell(p, 12, 1, 0.04, 1u));
  const std::vector<double> x = start_of(sys);
  const int n = sys.dof();
  for (int row : {n - 2, n - 1}) {  // W, H
    std::vector<int> entries;
    for (int c = 0; c < n; ++c) entries.push_back(sys.stiffness_pattern().find(row, c));
    test::CorruptedStiffness bad(sys, entries);
    CHECK(check_stiffness_jacobian(bad, 0.0, x.data(), 1e-8).max_relative_error >
          10 * kJacobianTol);
  }
}

TEST_CASE("yarn cell: two repeats in one cell hold twice the energy of one (images, exclusion)") {
  YarnParams p;
  YarnCell one(wavy_cell(p, 12, 1, 0.04, 7u));
  YarnCell two(wavy_cell(p, 12, 2, 0.04, 7u));
  const std::vector<double> x1 = start_of(one), x2 = start_of(two);
  const double e1 = one.contact_energy(x1.data()), e2 = two.contact_energy(x2.data());
  REQUIRE(e1 > 0.0);
  CHECK(e2 == Approx(2.0 * e1).epsilon(1e-12));
  CHECK(two.potential_energy(0, x2.data()) ==
        Approx(2.0 * one.potential_energy(0, x1.data())).epsilon(1e-12));
  // Per cell, dE/dH doubles and dE/dW is the same per repeat (dE/dW = 2 x dE/d(2W) ... by
  // dW' = 2 dW, dE'/dW' = (2 dE) / (2 dW)).
  const auto g1 = one.size_gradient(x1.data()), g2 = two.size_gradient(x2.data());
  CHECK(g2[0] == Approx(g1[0]).epsilon(1e-9));
  CHECK(g2[1] == Approx(2.0 * g1[1]).epsilon(1e-9));
  CHECK(two.min_clearance(x2.data()) == Approx(one.min_clearance(x1.data())).epsilon(1e-12));
}

TEST_CASE("yarn cell: a straight periodic yarn carries EA (W / L - 1) and relaxes to its length") {
  YarnParams p;
  const double d = p.diameter(), L = 20 * d;
  for (CellSize size : {CellSize::Held, CellSize::Free}) {
    YarnCellSpec s;
    s.yarn = p;
    s.contact = false;
    s.width = 1.01 * L;
    s.height = 5 * d;
    std::vector<Vec3> v;
    for (int k = 0; k < 16; ++k) v.push_back({s.width * k / 16, 0.0, 0.0});
    s.initial = {v};
    s.rest = {std::vector<double>(16, L / 16)};
    s.size = size;
    YarnCell sys(s);
    std::vector<double> x = start_of(sys), vel(sys.dof(), 0.0);
    if (size == CellSize::Held) {
      // The tension across the cell's face: dE/dW = EA (W / L - 1).
      CHECK(sys.size_gradient(x.data())[0] ==
            Approx(p.stretch_stiffness() * (s.width / L - 1.0)).epsilon(1e-9));
      CHECK(sys.size_gradient(x.data())[1] == 0.0);
      continue;
    }
    const RunStats st = run_to_equilibrium(sys, "equilibrium", IntegratorOptions{}, x, vel);
    REQUIRE(st.status == RunStatus::Equilibrium);
    CHECK(sys.width(x.data()) == Approx(L).epsilon(1e-9));
    CHECK(sys.course_length(0, x.data()) == Approx(L).epsilon(1e-9));
  }
}

TEST_CASE("yarn cell: infeasible states give +inf energy and NaN forces, never a crash") {
  YarnParams p;
  YarnCellSpec s = wavy_cell(p, 12, 1, 0.0, 1u);
  YarnCell sys(s);
  std::vector<double> x = start_of(sys);
  // H so small that course 1 sits inside course 0's image.
  std::vector<double> y = x;
  y[sys.dof() - 1] = 1.0 * p.diameter();
  CHECK(sys.potential_energy(0, y.data()) == std::numeric_limits<double>::infinity());
  std::vector<double> f(sys.dof());
  sys.net_force(y.data(), f.data());
  CHECK(std::isnan(f[0]));
  y[sys.dof() - 1] = -1.0;  // H < 0
  CHECK(sys.potential_energy(0, y.data()) == std::numeric_limits<double>::infinity());
  // A step that would take H there is cut: the admitted fraction keeps the clearance above the
  // core.
  std::vector<double> dx(sys.dof(), 0.0);
  dx[sys.dof() - 1] = -0.9 * p.diameter();
  const double admit = sys.admissible_step(0, x.data(), dx.data());
  REQUIRE(admit > 0.0);
  REQUIRE(admit < 1.0);
  y = x;
  y[sys.dof() - 1] += admit * dx[sys.dof() - 1];
  CHECK(std::isfinite(sys.potential_energy(0, y.data())));
  CHECK(sys.min_clearance(y.data()) > p.core_fraction * p.diameter());
  CHECK_THROWS_WITH(YarnCell([] {
                      YarnCellSpec b;
                      b.width = 1e-3;
                      b.height = 0.0;
                      b.initial = {{{0, 0, 0}, {1e-4, 0, 0}, {2e-4, 0, 0}}};
                      b.rest = {{1e-4, 1e-4, 1e-4}};
                      return b;
                    }()),
                    Catch::Contains("width and height"));
}

namespace {

// One wale x one course of plain jersey at the given stitch length (m) and edges per loop,
// relaxed from paper 2's structure with the cell free (the ramp in 4 stages).
YarnCellRun relaxed_jersey(double stitch_length, int vertices) {
  KnitChart repeat;
  repeat.wales = repeat.courses = 1;
  repeat.stitches = {Stitch::Knit};
  YarnKnitParams yp;
  yp.model = KnitModelKind::Yarn;
  yp.vertices_per_loop = vertices;
  yp.stitch_length = stitch_length;
  auto start =
      std::make_shared<const YarnCellStart>(build_yarn_cell_start(repeat, KnitParams{}, yp));
  return run_yarn_cell(start, "equilibrium", IntegratorOptions{});
}

}  // namespace

TEST_CASE(
    "yarn cell: plain jersey relaxes from paper 2's structure to a free cell: yarn length kept, "
    "no crossing, zero stress") {
  const double l = 3.4e-3;  // the default yarn at tightness factor 1.47
  const YarnCellRun run = relaxed_jersey(l, 16);
  const YarnCellStart& st = *run.start;
  REQUIRE(run.stats.status == RunStatus::Equilibrium);
  REQUIRE(run.stages.size() == 4);
  for (const YarnCellRun::Stage& s : run.stages) CHECK(s.status == RunStatus::Equilibrium);
  // The start is clear of every image at d; no sample pair ever reaches the barrier's core.
  CHECK(run.clearance_start_over_d >= kYarnStartClearance);
  CHECK(run.clearance_min_over_d > st.params.yarn.core_fraction);
  CHECK(run.stitch_length == Approx(l).epsilon(1e-12));
  CHECK(std::abs(run.course_end[0] / run.course_knitted[0] - 1.0) < 1e-3);
  // The ramp took 40 % of the yarn out: the free cell shrank, no jam.
  CHECK(run.end.width < 0.8 * st.width);
  CHECK(run.end.height < 0.8 * st.height);
  // Zero stress across the cell's faces: |dE/dW|, |dE/dH| far below the yarn's bending force
  // scale B / l^2 (1.9e-4 N here).
  const double f = st.params.yarn.bending_rigidity / (l * l);
  CHECK(std::abs(run.size_gradient[0]) < 1e-5 * f);
  CHECK(std::abs(run.size_gradient[1]) < 1e-5 * f);
  WARN("relaxed plain jersey, l = 3.4 mm: "
       << run.courses_per_cm << " courses/cm, " << run.wales_per_cm << " wales/cm, K_c " << run.k_c
       << ", K_w " << run.k_w << ", K_s " << run.k_s << ", R " << run.r << "; " << run.stats.steps
       << " steps, " << run.stats.cpu_seconds << " s CPU");
}

TEST_CASE(
    "yarn cell: halving the edge length from 32 to 64 per loop moves the relaxed courses and "
    "wales per cm by less than 1 %; the step filter lets edges shorter than the core ramp") {
  // At 32 edges per loop of 3.4 mm an edge is 0.57 d at the end of the ramp: the segment
  // distance of two edges of one yarn two apart is below the core while none of their samples
  // pair (a step filter bounding such a pair by that distance stalled the ramp at 24 % stretch).
  const YarnCellRun a = relaxed_jersey(3.4e-3, 32), b = relaxed_jersey(3.4e-3, 64);
  REQUIRE(a.stats.status == RunStatus::Equilibrium);
  REQUIRE(b.stats.status == RunStatus::Equilibrium);
  CHECK(std::abs(a.course_end[0] / a.course_knitted[0] - 1.0) < 1e-3);
  CHECK(std::abs(b.courses_per_cm / a.courses_per_cm - 1.0) < 0.01);
  CHECK(std::abs(b.wales_per_cm / a.wales_per_cm - 1.0) < 0.01);
  WARN("32 -> 64 edges per loop: courses/cm " << a.courses_per_cm << " -> " << b.courses_per_cm
                                              << ", wales/cm " << a.wales_per_cm << " -> "
                                              << b.wales_per_cm);
}

TEST_CASE(
    "yarn cell: a repeat with a tuck or a miss on its edge wale and top course starts (the "
    "tiling knits its own edges; the swatch's chart rules do not apply to a repeat)") {
  YarnKnitParams yp;
  yp.model = KnitModelKind::Yarn;
  yp.vertices_per_loop = 16;
  yp.stitch_length = 3.4e-3;
  for (const char* text : {"KT\nKK\n", "KM\nKK\n"}) {
    const KnitChart repeat = parse_knit_chart(text, true);
    REQUIRE(repeat.at(1, 1) != Stitch::Knit);
    const YarnCellStart st = build_yarn_cell_start(repeat, KnitParams{}, yp);
    CHECK(st.repeat.at(1, 1) == repeat.at(1, 1));
    REQUIRE(st.start.size() == 2);
    CHECK(st.start[0].size() == 32);
    CHECK(st.start_clearance >= kYarnStartClearance * st.d);
    // The tuck or float cell (course 1, wale 2) takes less yarn than the knit beside it.
    CHECK(st.cell_target[1][1] < st.cell_target[1][0]);
  }
}
