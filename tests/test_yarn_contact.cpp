// Yarn contact (models/yarn_contact.hpp; knit.contact): the contact points at rest, forces and
// Jacobian against finite differences, the barrier's core, the step filter and the solvers that
// use it, and the keys' refusals.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include "models/knit_loops.hpp"
#include "models/yarn_contact.hpp"
#include "solvers/integrator.hpp"
#include "src/core/jacobian_check.hpp"
#include "src/measure/yarn_measures.hpp"
#include "src/scene/knit_run.hpp"
#include "tests/test_files.hpp"

using namespace knitsim;
using knitsim::test::chart_file;

namespace {

KnitParams with_contact(double c = 1.0) {
  KnitParams p;
  p.contact_ratio = c;
  return p;
}

KnitModel chart_model(const std::string& name, KnitParams p) {
  return build_knit(parse_knit_chart(chart_file(name)), p);
}

// single_tuck relaxed with contact by implicit-euler (h = 1 s): a state where pairs are in
// contact. (cvode-bdf crawls there: docs/knit.md, "Yarn contact".)
std::vector<double> tuck_in_contact(const KnitModel& m) {
  std::vector<double> x, v;
  IntegratorOptions opt;
  opt.max_wall_seconds = 30.0;  // a guard: it takes ~10 steps
  const RunStats s = run_to_equilibrium(*m.contact, "implicit-euler", opt, x, v);
  REQUIRE(s.status == RunStatus::Equilibrium);
  return x;
}

// Two particles 2 apart on x joined by a spring of rest 2, and a contact point on each, of
// different yarns (touching distance 1, core 0.9, kappa 10).
SpringNetworkSpec two_particles() {
  SpringNetworkSpec spec;
  spec.positions = {{0.0, 0.0, 0.0}, {2.0, 0.0, 0.0}};
  spec.masses = {1.0, 1.0};
  spec.springs = {{0, 1, 2.0, 1.0}};
  spec.gravity = {0.0, 0.0, 0.0};
  spec.residual_force_scale = 1.0;
  return spec;
}
YarnContactSpec two_points() {
  YarnContactSpec c;
  ContactPoint p0;
  p0.particles[0] = 0;
  p0.weights[0] = {1.0, 0.0, 0.0, 1.0};
  ContactPoint p1 = p0;
  p1.particles[0] = 1;
  p1.yarn = 1;
  c.points = {p0, p1};
  c.touching = 1.0;
  c.core = 0.9;
  c.stiffness = 10.0;
  return c;
}

}  // namespace

TEST_CASE("yarn contact: the points are the rest polylines' vertices, affine in the points",
          "[contact]") {
  for (const char* chart : {"plain_jersey.chart", "single_tuck.chart", "several_misses.chart"}) {
    INFO(chart);
    const KnitModel m = chart_model(chart, with_contact());
    REQUIRE(m.contact != nullptr);
    const std::vector<Vec3> rest = m.rest_positions();
    const YarnPolylines lines = yarn_polylines(m, rest, kContactSamplesPerInterval);
    const std::vector<ContactPoint>& pts = m.contact->points();
    std::size_t k = 0;
    double worst = 0.0, weight_error = 0.0;
    for (std::size_t j = 0; j < lines.vertices.size(); ++j)
      for (std::size_t v = 0; v < lines.vertices[j].size(); ++v, ++k) {
        REQUIRE(k < pts.size());
        const ContactPoint& p = pts[k];
        CHECK(p.yarn == static_cast<int>(j));
        const Vec3 s = position_of(p, rest);
        std::array<double, 6> sum{};
        for (int i = 0; i < kContactParticles && p.particles[i] >= 0; ++i)
          for (int e = 0; e < 6; ++e) sum[e] += p.weights[i][e];
        // translations in the plane carried: the weights sum to [I; 0]
        weight_error =
            std::max({weight_error, std::abs(sum[0] - 1.0), std::abs(sum[1]), std::abs(sum[2]),
                      std::abs(sum[3] - 1.0), std::abs(sum[4]), std::abs(sum[5])});
        worst = std::max(worst, norm(s - lines.vertices[j][v]));
      }
    CHECK(k == pts.size());
    CHECK(worst <= 1e-12 * m.params.loop_radius);
    CHECK(weight_error <= 1e-12);
  }
}

TEST_CASE(
    "yarn contact: the points are the vertices to first order (their weights are the "
    "vertices' derivatives)",
    "[contact]") {
  // Each point is the first-order Taylor map of its vertex at rest, so at a small in-plane
  // displacement of size delta its error is O(delta^2): wrong weights would leave O(delta).
  for (const char* chart : {"single_tuck.chart", "several_misses.chart", "several_tucks.chart"}) {
    INFO(chart);
    const KnitModel m = chart_model(chart, with_contact());
    const double r = m.params.loop_radius;
    auto worst_error = [&](double delta) {
      std::mt19937 shake(5);
      std::uniform_real_distribution<double> u(-delta * r, delta * r);
      std::vector<Vec3> pos = m.rest_positions();
      for (Vec3& p : pos) p.x += u(shake), p.y += u(shake);
      const YarnPolylines lines = yarn_polylines(m, pos, kContactSamplesPerInterval);
      double worst = 0.0;
      std::size_t k = 0;
      for (const std::vector<Vec3>& course : lines.vertices)
        for (const Vec3& vertex : course)
          worst = std::max(worst, norm(position_of(m.contact->points()[k++], pos) - vertex));
      return worst / r;
    };
    const double coarse = worst_error(1e-3), fine = worst_error(5e-4);
    CHECK(coarse <= 1e-4);         // delta = 1e-3: O(delta) errors would be ~1e-3
    CHECK(fine <= 0.35 * coarse);  // halving delta divides a second-order error by ~4
  }
}

TEST_CASE("yarn contact: refresh re-linearises the points about the state where they stray",
          "[contact]") {
  const KnitModel m = chart_model("several_tucks.chart", with_contact());
  ContactNetwork& net = *m.contact;
  const double r = m.params.loop_radius;
  std::vector<double> x(net.dof()), v(net.dof());
  net.initial_state(x.data(), v.data());
  auto worst_stray = [&]() {
    std::vector<Vec3> pos;
    net.network().all_positions(0.0, x.data(), pos);
    const YarnPolylines lines = yarn_polylines(m, pos, kContactSamplesPerInterval);
    double worst = 0.0;
    std::size_t k = 0;
    for (const std::vector<Vec3>& course : lines.vertices)
      for (const Vec3& vertex : course)
        worst = std::max(worst, norm(position_of(net.points()[k++], pos) - vertex));
    return worst / r;
  };
  // The rest state turned by 0.3 rad and moved: the co-rotated points follow the vertices
  // exactly (an affine map would stray: it does not turn its offsets), so nothing is renewed.
  const double cs = std::cos(0.3), sn = std::sin(0.3);
  for (int i = 0; i < net.dof(); i += 3) {
    const double X = x[i], Y = x[i + 1];
    x[i] = cs * X - sn * Y + 3.0 * r;
    x[i + 1] = sn * X + cs * Y - 5.0 * r;
  }
  CHECK(worst_stray() <= 1e-9);
  CHECK_FALSE(net.update(0.0, x.data()));
  // Then stretched by 1.2 along x (the vertices move off their first-order maps): the points
  // stray.
  for (int i = 0; i < net.dof(); i += 3) x[i] *= 1.2;
  REQUIRE(net.min_distance(0.0, x.data()) > net.contact().core);
  const double before = worst_stray();
  CHECK(before > 2.0 * kContactRefreshTol);
  CHECK(net.update(0.0, x.data()));
  CHECK(net.cut_renewals() == 0);
  CHECK(worst_stray() <= 1e-9);  // linearised here: the points are the vertices
  CHECK(net.refreshes() == m.chart.courses);
  CHECK_FALSE(net.update(0.0, x.data()));  // nothing strays now
  // The renewed points' forces are still -grad E of one smooth energy (central differences).
  std::vector<double> a(net.dof());
  std::vector<double> xp = x, xm = x;
  const double eps = 1e-7 * r;
  net.conservative_acceleration(0.0, x.data(), a.data());
  double slope = 0.0;
  std::mt19937 shake(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < net.dof(); i += 3)
    for (int c = 0; c < 2; ++c) {
      const double d = u(shake);
      xp[i + c] += eps * d, xm[i + c] -= eps * d;
      slope += net.mass()[i + c] * a[i + c] * d;
    }
  const double fd =
      -(net.potential_energy(0.0, xp.data()) - net.potential_energy(0.0, xm.data())) / (2.0 * eps);
  CHECK(std::abs(fd - slope) <= 1e-5 * std::abs(slope));
}

TEST_CASE("yarn contact: co-rotated points follow rigid motions exactly; forces and Jacobian exact",
          "[contact]") {
  // Two yarns of two particles each, one co-rotated point on each with a general map (weights
  // summing to [I; 0], a depth row, an offset), a wide barrier (core 0.5 of d = 1) so that the
  // maps' curvature terms weigh against J^T H J in the Jacobian.
  SpringNetworkSpec spec;
  spec.positions = {{0.0, 0.0, 0.0}, {1.0, 0.2, 0.0}, {0.4, 1.0, 0.0}, {1.3, 1.4, 0.0}};
  spec.masses.assign(4, 1.0);
  spec.springs = {{0, 1, norm(spec.positions[1] - spec.positions[0]), 1e-3},
                  {2, 3, norm(spec.positions[3] - spec.positions[2]), 1e-3}};
  spec.gravity = {0.0, 0.0, 0.0};
  spec.residual_force_scale = 1.0;
  YarnContactSpec c;
  auto point = [&](int i, int j, std::array<double, 6> w, Vec3 offset, int yarn) {
    ContactPoint p;
    p.particles[0] = i;
    p.particles[1] = j;
    p.weights[0] = w;
    p.weights[1] = {1.0 - w[0], -w[1], -w[2], 1.0 - w[3], -w[4], -w[5]};
    p.offset = offset;
    p.yarn = yarn;
    const Vec3 v = spec.positions[j] - spec.positions[i];
    p.turn = {0, 1};
    p.axis = {v.x / std::hypot(v.x, v.y), v.y / std::hypot(v.x, v.y)};
    return p;
  };
  c.points = {point(0, 1, {0.6, 0.1, -0.05, 0.5, 0.2, 0.1}, {0.1, 0.2, 0.1}, 0),
              point(2, 3, {0.3, -0.2, 0.15, 0.7, -0.1, 0.25}, {-0.1, -0.3, -0.1}, 1)};
  c.touching = 1.0;
  c.core = 0.5;
  c.stiffness = 10.0;
  ContactNetwork net(SpringNetwork(spec), c);
  // A state away from the maps' own: each pair of particles turned and stretched differently,
  // then yarn 1 moved in the plane until the points are 0.75 apart (g = 0.5).
  std::vector<double> x(net.dof()), v(net.dof());
  net.initial_state(x.data(), v.data());
  x[3] = 0.9, x[4] = 0.6;   // particle 1
  x[9] = 1.0, x[10] = 1.9;  // particle 3
  std::vector<Vec3> pos;
  net.network().all_positions(0.0, x.data(), pos);
  const Vec3 d = position_of(c.points[0], pos) - position_of(c.points[1], pos);
  REQUIRE(std::abs(d.z) < 0.7);
  const double planar = std::sqrt(0.75 * 0.75 - d.z * d.z), have = std::hypot(d.x, d.y);
  for (int i : {6, 9}) {
    x[i] += d.x * (1.0 - planar / have);
    x[i + 1] += d.y * (1.0 - planar / have);
  }
  int touching = 0;
  REQUIRE(net.min_distance(0.0, x.data(), &touching) == Approx(0.75).epsilon(1e-12));
  REQUIRE(touching == 1);
  const JacobianCheck jc = check_stiffness_jacobian(net, 0.0, x.data(), 1e-7);
  INFO("worst (" << jc.worst_row << ", " << jc.worst_col << "): " << jc.worst_analytic << " vs "
                 << jc.worst_fd);
  CHECK(jc.max_relative_error < 1e-6);
  // Forces are -grad E (central differences, every coordinate).
  std::vector<double> a(net.dof());
  net.conservative_acceleration(0.0, x.data(), a.data());
  for (int i = 0; i < net.dof(); ++i) {
    std::vector<double> xp = x, xm = x;
    xp[i] += 1e-7, xm[i] -= 1e-7;
    const double fd =
        -(net.potential_energy(0.0, xp.data()) - net.potential_energy(0.0, xm.data())) / 2e-7;
    CHECK(a[i] * net.mass()[i] == Approx(fd).margin(1e-7));
  }
  // A rigid motion in the plane moves each point rigidly (depth kept) and keeps the energy.
  const double E = net.contact_energy(0.0, x.data());
  CHECK(E > 0.0);
  const double cs = std::cos(2.0), sn = std::sin(2.0);
  std::vector<double> y = x;
  for (int i = 0; i < net.dof(); i += 3) {
    y[i] = cs * x[i] - sn * x[i + 1] + 5.0;
    y[i + 1] = sn * x[i] + cs * x[i + 1] - 2.0;
  }
  std::vector<Vec3> moved;
  net.network().all_positions(0.0, x.data(), pos);
  net.network().all_positions(0.0, y.data(), moved);
  for (const ContactPoint& p : c.points) {
    const Vec3 q = position_of(p, pos), after = position_of(p, moved);
    CHECK(after.x == Approx(cs * q.x - sn * q.y + 5.0).margin(1e-12));
    CHECK(after.y == Approx(sn * q.x + cs * q.y - 2.0).margin(1e-12));
    CHECK(after.z == Approx(q.z).margin(1e-12));
  }
  CHECK(net.contact_energy(0.0, y.data()) == Approx(E).epsilon(1e-10));
  // A point's turning pair must be two of its particles.
  YarnContactSpec bad = c;
  bad.points[0].turn = {0, 0};
  CHECK_THROWS_WITH(ContactNetwork(SpringNetwork(spec), bad), Catch::Contains("turning pair"));
}

TEST_CASE("yarn contact: a renewal that would bring a pair near its core is taken part way",
          "[contact]") {
  const SpringNetworkSpec spec = two_particles();
  YarnContactSpec c = two_points();  // touching 1, core 0.9
  const ContactPoint p0 = c.points[0], p1 = c.points[1];
  c.refresh_tol = 0.01;
  double shift = 0.0;  // the exact positions: yarn 1's point `shift` to the left of its particle
  c.exact = [&](const std::vector<Vec3>& pos, std::vector<Vec3>& out) {
    out = {pos[0], pos[1] - Vec3{shift, 0.0, 0.0}};
  };
  c.linearise = [&](const std::vector<Vec3>& pos, int y) {
    ContactPoint p = y == 0 ? p0 : p1;
    p.offset = y == 0 ? Vec3{} : Vec3{-shift, 0.0, 0.0};
    (void)pos;
    return std::vector<ContactPoint>{p};
  };
  ContactNetwork net(SpringNetwork(spec), c);
  REQUIRE(net.contact().renew_keep == 0.5);
  std::vector<double> x = {0.0, 0.0, 0.0, 1.05, 0.0, 0.0};
  shift = 0.08;  // renewed, the points are 0.97 apart: above the floor 0.9 + 0.5 (1 - 0.9)
  CHECK(net.update(0.0, x.data()));
  CHECK(net.cut_renewals() == 0);
  CHECK(net.min_distance(0.0, x.data()) == Approx(0.97));
  // Exact positions 0.85 apart, inside the core: the points move only to 0.9 + 0.5 (0.97 - 0.9).
  shift = 0.2;
  CHECK(net.update(0.0, x.data()));
  CHECK(net.cut_renewals() == 1);
  CHECK(net.refreshes() == 2);
  CHECK(net.min_distance(0.0, x.data()) == Approx(0.935));
  // Renewed again at the same state, they close half the remaining gap each time, never the core.
  double last = net.min_distance(0.0, x.data());
  for (int k = 0; k < 30; ++k) {
    net.update(0.0, x.data());
    const double now = net.min_distance(0.0, x.data());
    CHECK(now < last);
    CHECK(now > 0.9);
    last = now;
  }
  CHECK(std::isfinite(net.potential_energy(0.0, x.data())));
}

TEST_CASE("yarn contact: a renewal refused at its check leaves the maps as they were, bit for bit",
          "[contact]") {
  // The run holds one set of maps: a renewal writes the fresh ones in place and, refused, makes
  // the old ones again from their recipe (the positions they were linearised about, and the
  // offsets of a renewal cut short). Yarn 1's exact point lies z0 to the left of its particle,
  // z0 the z of particle 0 (which the points do not see otherwise): linearise is a function of
  // the positions alone, as it must be.
  const SpringNetworkSpec spec = two_particles();
  YarnContactSpec c = two_points();  // touching 1, core 0.9
  const ContactPoint p0 = c.points[0], p1 = c.points[1];
  c.refresh_tol = 0.01;
  c.exact = [](const std::vector<Vec3>& pos, std::vector<Vec3>& out) {
    out = {pos[0], pos[1] - Vec3{pos[0].z, 0.0, 0.0}};
  };
  c.linearise = [p0, p1](const std::vector<Vec3>& pos, int y) {
    ContactPoint p = y == 0 ? p0 : p1;
    p.offset = y == 0 ? Vec3{} : Vec3{-pos[0].z, 0.0, 0.0};
    return std::vector<ContactPoint>{p};
  };
  ContactNetwork net(SpringNetwork(spec), c);
  std::vector<double> x = {0.0, 0.0, 0.08, 1.05, 0.0, 0.0};
  REQUIRE(net.update(0.0, x.data()));  // yarn 1 renewed whole: 0.97 apart
  x[2] = 0.2;                          // exact 0.85 apart, inside the core: cut short
  REQUIRE(net.update(0.0, x.data()));
  REQUIRE(net.cut_renewals() == 1);
  const std::vector<ContactPoint> kept = net.points();
  const double apart = net.min_distance(0.0, x.data());
  // Renewed whole at z0 = 0.3 the points would be 0.75 apart, inside the core: refused.
  x[2] = 0.3;
  CHECK_FALSE(net.renew(0.0, x.data()));
  REQUIRE(net.points().size() == kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const ContactPoint &p = kept[k], &q = net.points()[k];
    CHECK(p.particles == q.particles);
    CHECK(p.weights == q.weights);
    CHECK((p.offset.x == q.offset.x && p.offset.y == q.offset.y && p.offset.z == q.offset.z));
    CHECK((p.yarn == q.yarn && p.arc == q.arc && p.turn == q.turn && p.axis == q.axis));
  }
  CHECK(net.points()[1].offset.x != -0.2);  // the cut offset, not the linearised one
  x[2] = 0.2;
  CHECK(net.min_distance(0.0, x.data()) == apart);
}

TEST_CASE("yarn contact: plain jersey stays exactly at rest, no pair in contact", "[contact]") {
  const KnitModel m = chart_model("plain_jersey.chart", with_contact());
  std::vector<double> x0(m.system().dof()), v0(m.system().dof());
  m.system().initial_state(x0.data(), v0.data());
  int touching = -1;
  CHECK(m.contact->min_distance(0.0, x0.data(), &touching) > m.params.loop_radius);
  CHECK(touching == 0);
  CHECK(m.contact->contact_energy(0.0, x0.data()) == 0.0);
  for (const char* integrator : {"cvode-bdf", "equilibrium", "verlet"}) {
    INFO(integrator);
    std::vector<double> x, v;
    const RunStats s = run_to_equilibrium(*m.contact, integrator, IntegratorOptions{}, x, v);
    CHECK(s.status == RunStatus::Equilibrium);
    CHECK(x == x0);
  }
}

TEST_CASE("yarn contact: forces are -grad E and the Jacobian is exact, pairs in contact",
          "[contact]") {
  const KnitModel m = chart_model("single_tuck.chart", with_contact());
  std::vector<double> x = tuck_in_contact(m);
  const double r = m.params.loop_radius;
  // Off the equilibrium (F != 0), still outside every core.
  std::mt19937 shake(3);
  std::uniform_real_distribution<double> jitter(-0.01 * r, 0.01 * r);
  for (double& xi : x) xi += jitter(shake);
  int touching = 0;
  const double dmin = m.contact->min_distance(0.0, x.data(), &touching);
  REQUIRE(touching > 0);  // the barrier acts here
  CHECK(dmin > 0.9 * r);  // outside its core
  const JacobianCheck jc = check_stiffness_jacobian(m.system(), 0.0, x.data(), 1e-9);
  INFO("worst (" << jc.worst_row << ", " << jc.worst_col << "): " << jc.worst_analytic << " vs "
                 << jc.worst_fd);
  CHECK(jc.max_relative_error < 1e-5);
  CHECK_FALSE(jc.outside_pattern);
  // F = -dE/dx along random directions (central differences of the total energy).
  const MechanicalSystem& sys = m.system();
  const int n = sys.dof();
  std::vector<double> a(n), dir(n), xp(x), xm(x);
  sys.conservative_acceleration(0.0, x.data(), a.data());
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss;
  for (int trial = 0; trial < 4; ++trial) {
    for (double& d : dir) d = gauss(rng);
    const double eps = 1e-6 * r;
    double slope = 0.0;  // F . dir
    for (int i = 0; i < n; ++i) {
      xp[i] = x[i] + eps * dir[i];
      xm[i] = x[i] - eps * dir[i];
      slope += sys.mass()[i] * a[i] * dir[i];
    }
    const double fd =
        -(sys.potential_energy(0.0, xp.data()) - sys.potential_energy(0.0, xm.data())) /
        (2.0 * eps);
    INFO("F.dir " << slope << ", -dE/ds " << fd);
    CHECK(std::abs(slope) > 0.0);
    CHECK(std::abs(fd - slope) <= 1e-5 * std::abs(slope));
  }
}

TEST_CASE("yarn contact: inside the core the energy is infinite and forces are not finite",
          "[contact]") {
  // Two points of different yarns on single particles, pushed together along x.
  const SpringNetworkSpec spec = two_particles();
  YarnContactSpec c = two_points();
  ContactNetwork net(SpringNetwork(spec), c);
  std::vector<double> x = {0.0, 0.0, 0.0, 0.95, 0.0, 0.0};
  CHECK(std::isfinite(net.potential_energy(0.0, x.data())));
  std::vector<double> a(6);
  net.conservative_acceleration(0.0, x.data(), a.data());
  CHECK(a[0] < 0.0);  // pushed apart: particle 0 to -x, particle 1 to +x
  CHECK(a[3] > 0.0);
  CHECK(a[1] == 0.0);
  CHECK(a[2] == 0.0);  // no z force: the contact sees x and y only
  x[3] = 0.9;
  CHECK(net.potential_energy(0.0, x.data()) == std::numeric_limits<double>::infinity());
  net.conservative_acceleration(0.0, x.data(), a.data());
  CHECK_FALSE(std::isfinite(a[0]));
  // The step filter: from 1.5 apart, a step to -0.5 (through the other point) is cut where the
  // distance reaches core + keep (min(D0, d) - core) = 0.92; a step away is whole.
  x[3] = 1.5;
  std::vector<double> dx = {0.0, 0.0, 0.0, -2.0, 0.0, 0.0};
  const double f = net.admissible_step(0.0, x.data(), dx.data());
  CHECK(f == Approx((1.5 - 0.92) / 2.0).epsilon(1e-12));
  dx[3] = 2.0;
  CHECK(net.admissible_step(0.0, x.data(), dx.data()) == 1.0);
  // Points of one yarn closer along it than same_yarn_gap never pair.
  c.points[1].yarn = 0;
  c.points[1].arc = 0.5;
  c.same_yarn_gap = 1.0;
  const ContactNetwork one_yarn(SpringNetwork(spec), c);
  x[3] = 0.5;
  CHECK(one_yarn.contact_energy(0.0, x.data()) == 0.0);
}

TEST_CASE("yarn contact: a state's points are kept for the next call and renewed maps are seen",
          "[contact]") {
  const KnitModel m = chart_model("single_tuck.chart", with_contact());
  ContactNetwork& net = *m.contact;
  const double r = m.params.loop_radius;
  const std::vector<double> x = tuck_in_contact(m);  // pairs in contact
  std::vector<double> y = x;
  y[0] += 0.1 * r;
  const double before = net.min_distance(0.0, x.data());
  REQUIRE(before > net.contact().core);
  REQUIRE(before < net.contact().touching);
  // The step filter evaluates other states; x's points are put back, not recomputed.
  std::vector<double> dx(net.dof(), 0.0), a0(net.dof()), a1(net.dof());
  for (int i = 0; i < net.dof(); i += 3) dx[i + 1] = 0.3 * r * std::sin(0.7 * i);
  net.conservative_acceleration(0.0, x.data(), a0.data());
  net.admissible_step(0.0, x.data(), dx.data());
  net.conservative_acceleration(0.0, x.data(), a1.data());
  CHECK(a1 == a0);
  // Renewed maps at the same state: the next call sees them, as a call after another state does.
  REQUIRE(net.renew(0.0, x.data()));
  const double renewed = net.min_distance(0.0, x.data());
  CHECK(renewed != before);
  net.min_distance(0.0, y.data());
  CHECK(net.min_distance(0.0, x.data()) == renewed);
}

TEST_CASE("yarn contact: the step filter keeps every pair outside the core", "[contact]") {
  const KnitModel m = chart_model("single_tuck.chart", with_contact());
  const std::vector<double> x = tuck_in_contact(m);
  const double core = m.contact->contact().core;
  const int n = m.system().dof();
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss;
  int cut = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> dx(n), y(n);
    for (double& d : dx) d = 3.0 * m.params.loop_radius * gauss(rng);
    const double f = m.system().admissible_step(0.0, x.data(), dx.data());
    REQUIRE(f >= 0.0);
    REQUIRE(f <= 1.0);
    cut += f < 1.0;
    // Along the admitted part of the step no pair reaches the core (sampled finely).
    for (int s = 1; s <= 16; ++s) {
      for (int i = 0; i < n; ++i) y[i] = x[i] + f * s / 16.0 * dx[i];
      CHECK(m.contact->min_distance(0.0, y.data()) > core);
    }
  }
  CHECK(cut > 0);  // random steps of 3 r do hit the barrier
}

TEST_CASE("yarn contact: small steps are swept on the near-pair list, to the same fraction",
          "[contact]") {
  // Steps whose points stay within half the skin of where the list was made are swept on the
  // list; a network whose skin is too thin for that sweeps the same steps by their boxes.
  const KnitModel m = chart_model("single_tuck.chart", with_contact());
  const std::vector<double> x = tuck_in_contact(m);
  YarnContactSpec thin = m.contact->contact();
  thin.points = m.contact->points();  // the run's, renewed
  thin.remake_at_start = false;
  thin.skin = 1e-9 * thin.touching;
  const ContactNetwork boxes(m.network, thin);
  const ContactNetwork& listed = *m.contact;
  const double r = m.params.loop_radius;
  const int n = listed.dof();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int cut = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> dx(n);
    for (double& d : dx) d = 0.01 * r * u(rng);
    const long before = listed.list_sweeps();
    const double f = listed.admissible_step(0.0, x.data(), dx.data());
    CHECK(listed.list_sweeps() > before);
    CHECK(boxes.admissible_step(0.0, x.data(), dx.data()) == f);  // bit for bit
    cut += f < 1.0;
  }
  CHECK(boxes.list_sweeps() == 0);
  CHECK(cut > 0);  // pairs near their floor: some of these steps are cut
}

TEST_CASE("yarn contact: the equilibrium solver and implicit-euler stay outside the core",
          "[contact]") {
  const KnitModel m = chart_model("single_tuck.chart", with_contact(10.0));
  for (const char* integrator : {"equilibrium", "implicit-euler"}) {
    INFO(integrator);
    IntegratorOptions opt;
    // Both end at the steady state in ~15 steps (the equilibrium solver without falling back to
    // the dynamics: the planar network's z block and the co-rotated points leave its flow no
    // spurious negative curvature). Capped by steps, not wall time, so that a loaded or
    // sanitized run checks the same.
    opt.max_steps = 300;
    std::vector<double> x, v;
    const RunStats s = run_to_equilibrium(*m.contact, integrator, opt, x, v);
    INFO(s.message);
    CHECK(s.status == RunStatus::Equilibrium);
    CHECK(s.fallbacks == 0);
    CHECK(s.steps < 60);
    CHECK(m.contact->min_distance(0.0, x.data()) > m.contact->contact().core);
    // The free planar chart is certified on its deformations: its 3 in-plane rigid motions are
    // held (MechanicalSystem::planar), the rest of K is positive definite (it was singular: the
    // stop fell back to the static residual, certificate inconclusive).
    CHECK(s.certificate == "stable_minimum");
    CHECK(s.negative_pivots == 0);
    CHECK(s.min_eigenvalue > s.eigenvalue_threshold);
  }
}

TEST_CASE("yarn contact: refused with the paper's network's absence and with bending",
          "[contact]") {
  KnitParams p = with_contact();
  p.bending_ratio = 1.0;
  CHECK_THROWS_WITH(p.validate(),
                    Catch::Contains("knit.bending") && Catch::Contains("knit.contact"));
  p = with_contact(101.0);
  CHECK_THROWS_WITH(p.validate(), Catch::Contains("knit.contact") && Catch::Contains("[0, 100]"));
  p = with_contact();
  p.network = KnitNetwork::Paper;  // paper 2's network has no contact
  CHECK_FALSE(p.yarn_contact());
  CHECK(chart_model("single_tuck.chart", p).contact == nullptr);
  CHECK(chart_model("single_tuck.chart", KnitParams{}).contact != nullptr);  // on by default
  p = KnitParams{};
  p.contact_ratio = 0.0;
  CHECK(chart_model("single_tuck.chart", p).contact == nullptr);
}

TEST_CASE("yarn contact: single_tuck relaxed with contact keeps its yarns apart", "[contact]") {
  // implicit-euler (h = 1 s, its default) reaches the steady state in ~10 steps; without contact
  // the same chart's yarns come to 0.53 r (tests/test_yarn_measures.cpp has the bare network).
  const KnitModel m = chart_model("single_tuck.chart", with_contact(10.0));
  std::vector<double> x, v;
  const RunStats s = run_to_equilibrium(*m.contact, "implicit-euler", IntegratorOptions{}, x, v);
  INFO(s.message);
  REQUIRE(s.status == RunStatus::Equilibrium);
  std::vector<Vec3> pos;
  m.network.all_positions(0.0, x.data(), pos);
  const YarnPolylines lines = yarn_polylines(m, pos);
  const double r = m.params.loop_radius;
  const YarnClearance c = yarn_clearance(m, lines);
  CHECK(c.over_r >= 0.9);  // measured 0.947
  const YarnPolylines rest = yarn_polylines(m, m.rest_positions());
  CHECK(check_crossings(designed_crossings(m, rest), lines).changed == 0);
  // The contact points follow the centreline: renewed where they strayed more than
  // kContactRefreshTol (measured 0.0069 r at the end; 0.24 r without renewal).
  const YarnPolylines fine = yarn_polylines(m, pos, kContactSamplesPerInterval);
  double worst = 0.0;
  std::size_t idx = 0;
  for (const std::vector<Vec3>& course : fine.vertices)
    for (const Vec3& vertex : course)
      worst = std::max(worst, norm(position_of(m.contact->points()[idx++], pos) - vertex));
  CHECK(worst <= 2.0 * kContactRefreshTol * r);
  CHECK(m.contact->min_distance(0.0, x.data()) > m.contact->contact().core);
}

TEST_CASE("yarn contact: the committed tuck and miss charts keep 0.9 r over the whole run",
          "[contact]") {
  // The knit default with contact (the equilibrium solver); the minimum is over every residual
  // check of the run (ClearanceOverRun), not only the end. several_misses' renewals are taken
  // part way where the exact centreline is already inside a core (it came to 0.26 r when such
  // renewals were refused).
  for (const char* chart : {"single_tuck.chart", "several_tucks.chart", "several_misses.chart"}) {
    INFO(chart);
    const KnitModel m = chart_model(chart, with_contact(10.0));
    ClearanceOverRun over(m, nullptr);
    std::vector<double> x(m.network.dof()), v(m.network.dof());
    m.network.initial_state(x.data(), v.data());
    over.observe(0.0, x.data(), true);
    IntegratorOptions opt;
    opt.max_steps = 300;  // a guard: each takes 15-40 flow steps, a few seconds
    const RunStats s =
        run_to_equilibrium(*m.contact, default_knit_integrator(true), opt, x, v, &over);
    INFO(s.message);
    REQUIRE(s.status == RunStatus::Equilibrium);
    CHECK(s.fallbacks == 0);
    over.observe(s.t_final, x.data(), true);
    CHECK(over.minimum().over_r >= 0.9);  // measured 0.947, 0.941, 0.936
    CHECK(m.contact->min_distance(s.t_final, x.data()) > m.contact->contact().core);
  }
}

TEST_CASE("yarn contact: one model runs on two threads at once, each to the single run's bytes",
          "[contact][threads]") {
  // The model is const and shared; each run (ContactNetwork) owns its renewed points. single_tuck
  // renews its yarns during the run, so the runs' states do change.
  const KnitModel m = chart_model("single_tuck.chart", with_contact(10.0));
  const std::shared_ptr<const ContactModel> model = m.contact->shared_model();
  struct Result {
    std::vector<double> x, v;
    RunStats stats;
    long renewed = 0;
  };
  IntegratorOptions opt;
  opt.max_steps = 300;         // a guard: ~20 flow steps
  auto run = [&](Result& r) {  // no Catch macros here: they are not thread-safe
    ContactNetwork sys(model);
    r.stats = run_to_equilibrium(sys, default_knit_integrator(true), opt, r.x, r.v);
    r.renewed = sys.refreshes();
  };
  Result single, a, b;
  run(single);
  std::thread ta([&] { run(a); }), tb([&] { run(b); });
  ta.join();
  tb.join();
  REQUIRE(single.stats.status == RunStatus::Equilibrium);
  CHECK(single.renewed > 0);
  for (const Result* r : {&a, &b}) {
    CHECK(r->stats.status == single.stats.status);
    CHECK(r->stats.steps == single.stats.steps);
    CHECK(r->stats.rhs_evals == single.stats.rhs_evals);
    CHECK(r->renewed == single.renewed);
    CHECK(r->x == single.x);  // bit for bit
    CHECK(r->v == single.v);
    CHECK(r->stats.residual == single.stats.residual);
  }
  // The knit model's own run and the model's points are untouched by the runs.
  CHECK(m.contact->refreshes() == 0);
  CHECK(model->spec().points.empty());  // remade by each run (remake_at_start)
}

TEST_CASE("yarn contact: a run's points remade at rest are the set-up points, bit for bit",
          "[contact]") {
  // The knit's model keeps no maps (remake_at_start): each run linearises every course about
  // the rest state, given the set-up points' particles; that must be the set-up points exactly.
  const KnitModel m = chart_model("several_misses.chart", with_contact());
  const std::vector<ContactPoint> setup = knit_contact_points(m);
  const ContactNetwork run(m.contact->shared_model());
  const std::vector<ContactPoint>& remade = run.points();
  REQUIRE(remade.size() == setup.size());
  long differ = 0;
  for (std::size_t k = 0; k < setup.size(); ++k) {
    const ContactPoint &p = setup[k], &q = remade[k];
    differ += p.particles != q.particles || p.weights != q.weights || p.offset.x != q.offset.x ||
              p.offset.y != q.offset.y || p.offset.z != q.offset.z || p.yarn != q.yarn ||
              p.arc != q.arc || p.turn != q.turn || p.axis != q.axis;
  }
  CHECK(differ == 0);
}
