// SpringNetwork and DrapeGrid: analytic Jacobian vs finite differences, closed forms, energy.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>

#include "models/drape_grid.hpp"
#include "models/spring_network.hpp"
#include "solvers/integrator.hpp"
#include "src/core/jacobian_check.hpp"
#include "tests/corrupted_stiffness.hpp"
#include "src/core/sparse.hpp"

using namespace knitsim;

namespace {

// A random non-equilibrium state: rest positions + uniform noise of `amp` metres.
std::vector<double> perturbed_state(const MechanicalSystem& sys, double amp, unsigned seed) {
  std::vector<double> x(sys.dof()), v(sys.dof());
  sys.initial_state(x.data(), v.data());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amp, amp);
  for (double& xi : x) xi += u(rng);
  return x;
}

// At perturbed states (seeds 1, 2) at time t: the Jacobian by central differences, and the net
// forces as minus the energy's gradient (central differences of step h).
void check_derivatives(const SpringNetwork& net, double t, double h) {
  const int n = net.dof();
  std::vector<double> f(n);
  for (unsigned seed : {1u, 2u}) {
    const std::vector<double> x = perturbed_state(net, 0.01, seed);
    CHECK(check_stiffness_jacobian(net, t, x.data()).max_relative_error < 1e-6);
    net.net_force(t, x.data(), f.data());
    for (int i = 0; i < n; ++i) {
      std::vector<double> xp = x, xm = x;
      xp[i] += h;
      xm[i] -= h;
      const double grad =
          (net.potential_energy(t, xp.data()) - net.potential_energy(t, xm.data())) / (2 * h);
      CHECK(f[i] == Approx(-grad).margin(1e-7));
    }
  }
}


}  // namespace

TEST_CASE("analytic Jacobian matches central differences for topologies a, b, c") {
  for (char topo : {'a', 'b', 'c'}) {
    DrapeParams p;
    p.natural_length = 0.1;  // 6 x 6 grid: small enough for a dense check
    p.width = 0.5;
    p.topology = topo;
    p.elongation_limit = 0.0;
    DrapeGrid g = build_drape_grid(p);
    for (unsigned seed : {1u, 2u, 3u}) {
      auto x = perturbed_state(g.network, 0.02, seed);
      JacobianCheck c = check_stiffness_jacobian(g.network, 0.0, x.data());
      INFO("topology " << topo << " seed " << seed << " worst (" << c.worst_row << ","
                       << c.worst_col << ") analytic " << c.worst_analytic << " fd " << c.worst_fd);
      CHECK(c.max_relative_error < 1e-6);
    }
  }
}

TEST_CASE("Jacobian check catches a deliberately wrong Jacobian") {
  DrapeParams p;
  p.natural_length = 0.1;
  DrapeGrid g = build_drape_grid(p);
  const int mid = g.network.dof() / 2;  // a 1 % error in one entry
  const test::CorruptedStiffness wrong(g.network, {g.network.stiffness_pattern().find(mid, mid)});
  auto x = perturbed_state(g.network, 0.02, 7);
  CHECK(check_stiffness_jacobian(g.network, 0.0, x.data()).max_relative_error < 1e-6);
  CHECK(check_stiffness_jacobian(wrong, 0.0, x.data()).max_relative_error > 1e-3);
}

TEST_CASE("Jacobian includes the elongation-limit spring when it is active") {
  DrapeParams p;
  p.natural_length = 0.1;
  p.elongation_limit = 1.0;  // 1 %: the 2 cm perturbation activates it on many springs
  DrapeGrid g = build_drape_grid(p);
  auto x = perturbed_state(g.network, 0.02, 11);
  REQUIRE(g.network.max_strain(0.0, x.data()) > 0.01);
  // Finite differences straddle the kink of the limiting spring for a few springs; a small
  // step keeps that rare.
  CHECK(check_stiffness_jacobian(g.network, 0.0, x.data(), 1e-8).max_relative_error < 1e-4);
}

TEST_CASE(
    "make_csc_pattern: sorted unique rows per column and where each pair lies, against a set") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const int rows = 1 + static_cast<int>(rng() % 9), cols = 1 + static_cast<int>(rng() % 9);
    const bool diagonal = rows == cols && trial % 2 == 0;
    std::vector<std::pair<int, int>> entries;
    const int count = static_cast<int>(rng() % 40);  // includes none, and many duplicates
    for (int k = 0; k < count; ++k)
      entries.emplace_back(static_cast<int>(rng() % rows), static_cast<int>(rng() % cols));
    std::set<std::pair<int, int>> expected;  // (col, row): the CSC order
    for (const auto& [r, c] : entries) expected.insert({c, r});
    if (diagonal)
      for (int i = 0; i < rows; ++i) expected.insert({i, i});

    std::vector<int> position;
    const CscPattern p = make_csc_pattern(rows, cols, entries, diagonal, &position);
    REQUIRE(p.rows == rows);
    REQUIRE(p.cols == cols);
    REQUIRE(p.colptr.size() == static_cast<size_t>(cols + 1));
    std::vector<std::pair<int, int>> got;
    for (int j = 0; j < cols; ++j)
      for (int k = p.colptr[j]; k < p.colptr[j + 1]; ++k) got.emplace_back(j, p.rowind[k]);
    CHECK(got == std::vector<std::pair<int, int>>(expected.begin(), expected.end()));
    for (const auto& [c, r] : expected) CHECK(p.find(r, c) >= 0);
    REQUIRE(position.size() == entries.size());  // one per pair given, not the diagonal added
    for (size_t k = 0; k < entries.size(); ++k)
      CHECK(position[k] == p.find(entries[k].first, entries[k].second));
  }
  CHECK_THROWS_AS(make_csc_pattern(2, 2, {{2, 0}}, false), std::logic_error);
  CHECK_THROWS_AS(make_csc_pattern(2, 3, {}, true), std::logic_error);
}

TEST_CASE("expand_node_pattern: the 3x3 blocks of a node pattern, and where each entry lies") {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const int nodes = 1 + static_cast<int>(rng() % 7);
    std::vector<std::pair<int, int>> pairs, dofs;
    const int count = static_cast<int>(rng() % 20);
    for (int k = 0; k < count; ++k)
      pairs.emplace_back(static_cast<int>(rng() % nodes), static_cast<int>(rng() % nodes));
    for (const auto& [r, c] : pairs)
      for (int p = 0; p < 3; ++p)
        for (int q = 0; q < 3; ++q) dofs.emplace_back(3 * r + p, 3 * c + q);
    for (int i = 0; i < nodes; ++i)
      for (int p = 0; p < 3; ++p)
        for (int q = 0; q < 3; ++q) dofs.emplace_back(3 * i + p, 3 * i + q);
    const CscPattern np = make_csc_pattern(nodes, nodes, pairs, true);
    const CscPattern got = expand_node_pattern(np);
    const CscPattern expected = make_csc_pattern(3 * nodes, 3 * nodes, dofs, false);
    CHECK(got.rows == expected.rows);
    CHECK(got.cols == expected.cols);
    CHECK(got.colptr == expected.colptr);
    CHECK(got.rowind == expected.rowind);
    for (int c = 0; c < nodes; ++c)
      for (int e = np.colptr[c]; e < np.colptr[c + 1]; ++e)
        for (int p = 0; p < 3; ++p)
          for (int q = 0; q < 3; ++q)
            CHECK(node_block_entry(np, e, c, p, q) == got.find(3 * np.rowind[e] + p, 3 * c + q));
  }
}

TEST_CASE("the stiffness layout memo: shared by networks with the same ends, never by others") {
  // Four particles, 0 pinned, four springs: a path 0-1-2-3 closed by 3-1, and the same counts
  // with the springs between other particles (1-3 instead of 1-2), so only the ends differ.
  const auto network = [](std::vector<std::pair<int, int>> ends, double k) {
    SpringNetworkSpec spec;
    spec.positions = {{0, 0, 0}, {0.1, 0, 0}, {0.2, 0.01, 0}, {0.1, 0.1, 0.02}};
    spec.masses = {0.01, 0.01, 0.01, 0.01};
    for (const auto& [a, b] : ends)
      spec.springs.push_back({a, b, norm(spec.positions[b] - spec.positions[a]), k});
    spec.pinned = {0};
    spec.pin_paths = {{spec.positions[0], spec.positions[0], 0.0}};
    return SpringNetwork(spec);
  };
  const SpringNetwork first = network({{0, 1}, {1, 2}, {2, 3}, {3, 1}}, 600.0);
  const SpringNetwork other = network({{0, 1}, {1, 3}, {2, 3}, {3, 0}}, 600.0);
  const SpringNetwork stiffer = network({{0, 1}, {1, 2}, {2, 3}, {3, 1}}, 900.0);
  // A hit is the same layout object; a network with other ends gets its own.
  CHECK(&first.stiffness_pattern() == &stiffer.stiffness_pattern());
  CHECK(&first.stiffness_pattern() != &other.stiffness_pattern());
  CHECK(first.stiffness_pattern().find(0, 3) >= 0);  // particles 1 and 2 (free 0, 1) joined
  CHECK(other.stiffness_pattern().find(0, 3) < 0);   // not in the other network
  for (const SpringNetwork* net : {&first, &other, &stiffer}) {
    auto x = perturbed_state(*net, 0.01, 5);
    CHECK(check_stiffness_jacobian(*net, 0.0, x.data()).max_relative_error < 1e-6);
  }
}

TEST_CASE("stencils: forces and Jacobian are the energy's derivatives, zero on rigid motions") {
  // A flat 3 x 2 lattice (x along i, y along j): a wale-like second difference, a twist quad,
  // and a spring; particle 0 pinned and moving, so stencils meet pinned ends in every role.
  SpringNetworkSpec spec;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 3; ++i) spec.positions.push_back({0.1 * i, 0.07 * j, 0.0});
  spec.masses.assign(6, 0.01);
  spec.springs.push_back({1, 4, 0.07, 50.0});
  spec.stencils.push_back({{0, 1, 2, -1}, {1.0, -2.0, 1.0, 0.0}, 3.0});
  spec.stencils.push_back({{0, 1, 3, 4}, {1.0, -1.0, -1.0, 1.0}, 2.0});
  spec.stencils.push_back({{1, 2, 4, 5}, {1.0, -1.0, -1.0, 1.0}, 2.0});
  spec.pinned = {0};
  spec.pin_paths = {{spec.positions[0], spec.positions[0] + Vec3{0.0, 0.0, 0.03}, 2.0}};
  spec.gravity = {0.0, 0.0, 0.0};
  spec.residual_force_scale = 1.0;
  const SpringNetwork net(spec);
  const int n = net.dof();

  // At rest the stencils hold no energy and exert no force.
  std::vector<double> x(n), v(n), f(n);
  net.initial_state(x.data(), v.data());
  CHECK(net.potential_energy(0.0, x.data()) == 0.0);
  CHECK(net.static_residual(0.0, x.data()) == 0.0);

  // Away from rest, the pin half-way through its move: the Jacobian by central differences,
  // the forces as minus the energy's gradient.
  check_derivatives(net, 1.0, 1e-6);

  // A rigid motion of the rest lattice (pin included: at t = 0 it is at rest) is free: the
  // stencils' energy stays zero, whatever the rotation.
  SpringNetworkSpec moved = spec;
  const double c = std::cos(0.7), s = std::sin(0.7);
  for (Vec3& p : moved.positions)
    p = Vec3{c * p.x - s * p.z, p.y, s * p.x + c * p.z} + Vec3{1, 2, 3};
  moved.pin_paths = {{moved.positions[0], moved.positions[0], 0.0}};
  moved.springs.clear();
  const SpringNetwork turned(moved);
  turned.initial_state(x.data(), v.data());
  CHECK(turned.potential_energy(0.0, x.data()) == Approx(0.0).margin(1e-28));
  CHECK(turned.static_residual(0.0, x.data()) == Approx(0.0).margin(1e-13));

  // The layout depends on the stencils: the same springs without them give another pattern.
  SpringNetworkSpec bare = spec;
  bare.stencils.clear();
  const SpringNetwork without(bare);
  CHECK(&without.stiffness_pattern() != &net.stiffness_pattern());
  CHECK(net.stiffness_pattern().find(0, 3 * 4) >= 0);     // particles 1 and 5 (free 0 and 4)
  CHECK(without.stiffness_pattern().find(0, 3 * 4) < 0);  // share only a twist quad

  // Bad stencils are refused at construction.
  SpringNetworkSpec bad = spec;
  bad.stencils[0].particles = {0, 1, 1, -1};
  CHECK_THROWS_WITH(SpringNetwork(bad), Catch::Contains("names a particle twice"));
  bad = spec;
  bad.stencils[0].particles = {0, 9, 2, -1};
  CHECK_THROWS_WITH(SpringNetwork(bad), Catch::Contains("stencil particle out of range"));
  bad = spec;
  bad.stencils[0].particles = {0, -1, 2, -1};
  CHECK_THROWS_WITH(SpringNetwork(bad), Catch::Contains("stencil particle out of range"));
  bad = spec;
  bad.stencils[0].stiffness = 0.0;
  CHECK_THROWS_WITH(SpringNetwork(bad), Catch::Contains("stencil stiffness must be > 0"));
}

TEST_CASE("planar: springs measure in the plane, the plane holds z, the z block is k_p I") {
  // A flat square with a diagonal, every spring compressed (rest 1.2 x its length): without the
  // plane a compressed spring's z stiffness f/L is negative.
  SpringNetworkSpec spec;
  spec.positions = {{0, 0, 0}, {0.1, 0, 0}, {0.1, 0.1, 0}, {0, 0.1, 0}};
  spec.masses.assign(4, 0.01);
  for (auto [a, b] : {std::pair{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 2}})
    spec.springs.push_back({a, b, 1.2 * norm(spec.positions[b] - spec.positions[a]), 50.0});
  spec.gravity = {0.0, 0.0, 0.0};
  spec.residual_force_scale = 1.0;
  spec.plane_stiffness = 7.0;
  const SpringNetwork net(spec);
  const int n = net.dof();
  std::vector<double> x(n), v(n), f(n), values(net.stiffness_pattern().nnz());
  net.initial_state(x.data(), v.data());
  // Flat: no z force; the z block is exactly -k_p / m on the diagonal, nothing else.
  net.net_force(0.0, x.data(), f.data());
  net.stiffness_values(0.0, x.data(), values.data());
  const CscPattern& pat = net.stiffness_pattern();
  for (int col = 0; col < n; ++col)
    for (int k = pat.colptr[col]; k < pat.colptr[col + 1]; ++k) {
      const int row = pat.rowind[k];
      if (row % 3 != 2 && col % 3 != 2) continue;
      CHECK(values[k] == (row == col ? -7.0 / 0.01 : 0.0));
    }
  for (int i = 2; i < n; i += 3) CHECK(f[i] == 0.0);
  // Off the plane: forces are -grad E and the Jacobian is exact; the springs' lengths ignore z.
  check_derivatives(net, 0.0, 1e-7);
  x = perturbed_state(net, 0.01, 1);
  net.net_force(0.0, x.data(), f.data());
  for (int i = 2; i < n; i += 3) CHECK(f[i] == Approx(-7.0 * x[i]).epsilon(1e-12));
  // A planar network must start flat, and the plane takes no stencils or z gravity.
  SpringNetworkSpec bad = spec;
  bad.positions[2].z = 1e-3;
  CHECK_THROWS_WITH(SpringNetwork(bad), Catch::Contains("planar network"));
  bad = spec;
  bad.gravity = {0.0, 0.0, -9.81};
  CHECK_THROWS_WITH(SpringNetwork(bad), Catch::Contains("planar network"));
  bad = spec;
  bad.plane_stiffness = -1.0;
  CHECK_THROWS_WITH(SpringNetwork(bad), Catch::Contains("plane_stiffness must be >= 0"));
}

TEST_CASE("every diagonal entry is in the stiffness pattern") {
  DrapeParams p;
  p.topology = 'c';
  DrapeGrid g = build_drape_grid(p);
  const CscPattern& pat = g.network.stiffness_pattern();
  for (int j = 0; j < pat.cols; ++j) CHECK(pat.find(j, j) >= 0);
}

TEST_CASE("drape grid: particle count, masses, springs per topology") {
  DrapeParams p;  // W 0.5 m, L0 4.9 cm -> n = 10
  DrapeGrid a = build_drape_grid(p);
  REQUIRE(a.n == 10);
  CHECK(a.network.particle_count() == 121);
  CHECK(a.network.dof() == 3 * (121 - 4));
  double total = 0.0;
  for (double m : a.network.spec().masses) total += m;
  CHECK(total == Approx(41.65e-3 * 0.49 * 0.49).epsilon(1e-12));
  CHECK(a.network.spec().masses[a.index(0, 0)] == Approx(total / 400.0));
  CHECK(a.network.spec().masses[a.index(5, 5)] == Approx(total / 100.0));
  // structural 2 n (n+1), shear 2 n^2, bending 2 (n+1)(n-1)
  const size_t structural = 2 * 10 * 11, shear = 2 * 100, bending = 2 * 11 * 9;
  CHECK(a.network.spec().springs.size() == structural + shear + bending);
  p.topology = 'b';
  CHECK(build_drape_grid(p).network.spec().springs.size() == structural + shear);
  p.topology = 'c';
  CHECK(build_drape_grid(p).network.spec().springs.size() == structural + bending);
}

TEST_CASE("bad drape parameters name the field and the range") {
  DrapeParams p;
  p.stiffness = -5;
  CHECK_THROWS_WITH(p.validate(), "model.stiffness = -5: must be > 0 N/m");
  p = DrapeParams{};
  p.stiffness = std::nan("");
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("model.stiffness"));
  p = DrapeParams{};
  p.natural_length = 0.0;
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("model.natural_length"));
  p = DrapeParams{};
  p.topology = 'd';
  CHECK_THROWS_WITH(p.validate(), "model.topology = d: must be one of a, b, c");
  p = DrapeParams{};
  p.natural_length = 1e-5;  // 50 000^2 particles
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("over the cap"));
}

TEST_CASE("Provot projection shortens over-stretched springs to exactly the limit") {
  DrapeParams p;
  p.natural_length = 0.1;
  p.elongation_limit = 5.0;
  DrapeGrid g = build_drape_grid(p);
  auto x = perturbed_state(g.network, 0.03, 5);
  std::vector<double> v(x.size(), 0.0);
  REQUIRE(g.network.max_strain(0.0, x.data()) > 0.05);
  for (int pass = 0; pass < 200 && g.network.max_strain(0.0, x.data()) > 0.05 + 1e-12; ++pass)
    g.network.project(0.0, x.data(), v.data());
  CHECK(g.network.max_strain(0.0, x.data()) <= 0.05 + 1e-12);
}

TEST_CASE("residual round-off floor: closed form for one spring, proportional to stiffness") {
  SpringNetworkSpec spec;
  spec.positions = {{0.0, 0.0, 1.0}, {0.0, 0.3, 0.4}};  // |x_a| = 1, |x_b| = 0.5 m
  spec.masses = {1.0, 2e-3};
  spec.springs = {{0, 1, 0.1, 1e5}};
  spec.pinned = {0};
  spec.pin_paths = {PinPath{spec.positions[0], spec.positions[0], 0.0}};
  const SpringNetwork net(spec);
  std::vector<double> x(3), v(3);
  net.initial_state(x.data(), v.data());
  const double eps = std::numeric_limits<double>::epsilon();
  CHECK(net.residual_roundoff(0.0, x.data()) ==
        Approx(1e5 * eps * 1.5 / (2e-3 * 9.81)).epsilon(1e-12));
  spec.springs[0].stiffness = 3e5;
  CHECK(SpringNetwork(spec).residual_roundoff(0.0, x.data()) ==
        Approx(3.0 * net.residual_roundoff(0.0, x.data())).epsilon(1e-12));
}

TEST_CASE("a drape too stiff for equilibrium_tol stops in positions, not at t_max") {
  // k = 3e5 N/m: measured residual at rest ~9e-8 for every integrator (static included),
  // above the default equilibrium_tol 1e-8, and below the floor bound: the stop in positions
  // (solvers/equilibrium_check.hpp) ends the run.
  DrapeParams p;
  p.stiffness = 3e5;
  p.natural_length = 0.1;  // n = 5: a small, fast grid
  const DrapeGrid g = build_drape_grid(p);
  IntegratorOptions opt;
  opt.t_max = 1e6;
  std::vector<double> x, v;
  const RunStats s = run_to_equilibrium(g.network, "cvode-bdf", opt, x, v);
  INFO(s.message << " residual " << s.residual << " floor " << s.residual_floor);
  CHECK(s.status == RunStatus::Equilibrium);
  CHECK(s.residual > opt.equilibrium_tol);
  CHECK(s.residual <= s.residual_floor);
  CHECK(s.certificate == "stable_minimum");
  CHECK(s.newton_step <= std::max(opt.position_tol, s.newton_floor));
  // At the paper's stiffness the floor is far below the tolerance and changes nothing.
  p.stiffness = 1000.0;
  const DrapeGrid soft = build_drape_grid(p);
  x.clear();
  v.clear();
  const RunStats s1 = run_to_equilibrium(soft.network, "cvode-bdf", opt, x, v);
  CHECK(s1.status == RunStatus::Equilibrium);
  CHECK(s1.newton_step <= std::max(opt.position_tol, s1.newton_floor));
  CHECK(s1.residual_floor < opt.equilibrium_tol);
}
