// The stop in positions, the certificate and the equilibrium solver (solvers/equilibrium_check.hpp,
// solvers/equilibrium_solver.cpp): a state the dynamics cannot reach is refused, a saddle is
// neither certified nor kept, the stop works on a refined mesh, and the solver agrees with the
// dynamics where both settle, moving pins included.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "models/spring_network.hpp"
#include "solvers/equilibrium_check.hpp"
#include "solvers/integrator.hpp"
#include "src/core/jacobian_check.hpp"
#include "src/scene/scene.hpp"

using namespace knitsim;

namespace {

// A double well, E = k/4 (x^2 - 1)^2 + k/2 y^2 (J), one particle of mass m with two dof: a
// saddle at the origin (d2E/dx2 = -k there), minima at x = +-1 m.
class DoubleWell final : public MechanicalSystem {
 public:
  DoubleWell() : pattern_(make_csc_pattern(2, 2, {{0, 0}, {1, 1}}, true)) {}
  int dof() const override { return 2; }
  void initial_state(double* x, double* v) const override { x[0] = x[1] = v[0] = v[1] = 0.0; }
  void conservative_acceleration(double, const double* x, double* a) const override {
    a[0] = -k_ * x[0] * (x[0] * x[0] - 1.0) / m_;
    a[1] = -k_ * x[1] / m_;
  }
  const std::vector<double>& damping_rate() const override { return gamma_; }
  const std::vector<double>& mass() const override { return mass_; }
  const CscPattern& stiffness_pattern() const override { return pattern_; }
  void stiffness_values(double, const double* x, double* v) const override {
    v[0] = -k_ * (3.0 * x[0] * x[0] - 1.0) / m_;
    v[1] = -k_ / m_;
  }
  double static_residual(double, const double* x) const override {
    return std::max(std::abs(k_ * x[0] * (x[0] * x[0] - 1.0)), std::abs(k_ * x[1])) / k_;
  }
  double potential_energy(double, const double* x) const override {
    return 0.25 * k_ * (x[0] * x[0] - 1.0) * (x[0] * x[0] - 1.0) + 0.5 * k_ * x[1] * x[1];
  }
  std::string describe() const override { return "double well"; }

 private:
  double k_ = 2.0, m_ = 1.0;
  std::vector<double> gamma_{1.0, 1.0}, mass_{1.0, 1.0};
  CscPattern pattern_;
};

double max_distance(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double d = 0.0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, norm(a[i] - b[i]));
  return d;
}

// Two states that each passed the stop lie within their Newton corrections' bounds of the same
// minimum: |x1 - x2| <= tol1 + tol2 to first order; x2 for the second-order rest.
double agreement_bound(const RunStats& a, const RunStats& b, double position_tol) {
  return 2.0 * (std::max(position_tol, a.newton_floor) + std::max(position_tol, b.newton_floor));
}

}  // namespace

TEST_CASE("a large implicit step that lands where the dynamics cannot is not an equilibrium") {
  // implicit-euler at dt = 1e4 s crumples two_corner into a state of +5.3 J, against 0 J at the
  // start: K is positive definite there, so only the energy check tells.
  Scene scene = load_scene("two_corner");
  scene.options.dt = 1e4;
  const DrapeResult r = run_drape(scene, "implicit-euler");
  INFO(r.stats.message);
  CHECK(r.stats.status == RunStatus::SpuriousEquilibrium);
  CHECK(r.stats.energy > r.stats.energy_reference + 1.0);
  CHECK(r.stats.certificate.empty());
  // The default solver on the same scene: a certified minimum below the start's energy.
  const DrapeResult d = run_drape(load_scene("two_corner"), default_integrator());
  CHECK(d.stats.status == RunStatus::Equilibrium);
  CHECK(d.stats.certificate == "stable_minimum");
  CHECK(d.stats.energy < d.stats.energy_reference);
}

TEST_CASE("a run that steps over the pins' motion is not certified by the energy check") {
  // two_corner_slack's pins move for 100 s. implicit-euler at dt = 1e4 s crosses that in one
  // step: its energy when the pins stop (~1.7e6 J) is no bound on where the dynamics go, and its
  // end state (0.56 m from the dynamics') would pass a check against it.
  Scene scene = load_scene("two_corner_slack");
  scene.options.dt = 1e4;
  const DrapeResult r = run_drape(scene, "implicit-euler");
  INFO(r.stats.message);
  CHECK(r.stats.certificate == "inconclusive");
  CHECK(r.stats.message.find("energy check inconclusive") != std::string::npos);
  // At dt = 10 s (10 steps over the motion) the check applies, and certifies.
  scene.options.dt = 10.0;
  const DrapeResult fine = run_drape(scene, "implicit-euler");
  INFO(fine.stats.message);
  CHECK(fine.stats.certificate == "stable_minimum");
}

TEST_CASE("a saddle is neither certified nor kept") {
  const DoubleWell well;
  IntegratorOptions opt;
  opt.t_max = 200.0;
  SECTION("the dynamics sit on it and never pass the stop") {
    std::vector<double> x, v;
    const RunStats s = run_to_equilibrium(well, "cvode-bdf", opt, x, v);
    CHECK(s.status == RunStatus::TimeLimit);
    CHECK(x[0] == 0.0);
  }
  SECTION("the equilibrium solver leaves it along its negative mode, with the documented sign") {
    std::vector<double> x, v;
    const RunStats s = run_to_equilibrium(well, "equilibrium", opt, x, v);
    INFO(s.message);
    CHECK(s.status == RunStatus::Equilibrium);
    CHECK(s.saddle_escapes == 1);
    CHECK(s.certificate == "stable_minimum");
    CHECK(std::abs(x[0] - 1.0) <= 2.0 * opt.position_tol);  // +1: the mode's largest component > 0
    CHECK(std::abs(x[1]) <= 2.0 * opt.position_tol);
    // K = diag(2k, k) at (1, 0): the eigenvalue nearest 0 is k = 2, by 8 inverse iterations
    // converged to (2 / 4)^16 ~ 1.5e-5.
    CHECK(s.min_eigenvalue == Approx(2.0).epsilon(1e-4));
  }
  SECTION("the probe sees the saddle's negative pivot") {
    detail::StiffnessProbe probe(well, IntegratorOptions::Factorization::Automatic);
    const double at[2] = {0.0, 0.0};
    const detail::StiffnessProbe::Result r = probe.probe(0.0, at);
    CHECK(r.factored);
    CHECK(r.negative_pivots == 1);
    CHECK(r.newton_step == 0.0);
  }
}

TEST_CASE("a sheet held flat in compression, gravity off, is left for a certified minimum") {
  // Every boundary particle pinned 10 % inward: the flat sheet is an equilibrium (each interior
  // particle between symmetric neighbours) with every spring compressed, so its out-of-plane
  // stiffness f / L < 0 (a saddle).
  DrapeParams p;
  p.natural_length = 0.05;  // n = 4
  p.topology = 'b';         // no bending springs: those of the particles next to the pinned
                            // boundary would reach over it, unbalanced
  SpringNetworkSpec spec = build_drape_grid(p).network.spec();
  const int side = static_cast<int>(std::lround(std::sqrt(spec.positions.size())));
  Vec3 centre{0.0, 0.0, 0.0};
  for (const Vec3& q : spec.positions) centre = centre + (1.0 / spec.positions.size()) * q;
  for (Vec3& q : spec.positions) q = centre + 0.9 * (q - centre);
  spec.pinned.clear();
  spec.pin_paths.clear();
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j)
      if (i == 0 || j == 0 || i == side - 1 || j == side - 1) {
        spec.pinned.push_back(i * side + j);
        spec.pin_paths.push_back({spec.positions[i * side + j], spec.positions[i * side + j], 0.0});
      }
  spec.gravity = {0.0, 0.0, 0.0};
  spec.residual_force_scale = 1.0;
  const SpringNetwork sheet(spec);
  std::vector<double> x0(sheet.dof()), v0(sheet.dof());
  sheet.initial_state(x0.data(), v0.data());
  detail::StiffnessProbe probe(sheet, IntegratorOptions::Factorization::Automatic);
  const detail::StiffnessProbe::Result flat = probe.probe(0.0, x0.data());
  CHECK(sheet.static_residual(0.0, x0.data()) < 1e-12);
  CHECK(flat.negative_pivots > 0);
  IntegratorOptions opt;
  std::vector<double> x = x0, v = v0;
  const RunStats s = run_to_equilibrium(sheet, "equilibrium", opt, x, v);
  INFO(s.message);
  CHECK(s.status == RunStatus::Equilibrium);
  CHECK(s.saddle_escapes >= 1);
  CHECK(s.certificate == "stable_minimum");
  CHECK(s.energy < sheet.potential_energy(0.0, x0.data()));
}

TEST_CASE("the stop in positions settles the built-in mesh and a hand-refined one") {
  // At L0 = 1.25 cm (17 x 17 particles) the residual in weights is a round-off lottery for
  // cvode-bdf (it used to end at t_max); the Newton correction is not.
  for (const std::string l0 : {"0.02", "0.0125"})
    for (const std::string& integ : {std::string("cvode-bdf"), default_integrator()}) {
      const Scene scene = load_scene("four_corner", {"model.natural_length=" + l0});
      const DrapeResult r = run_drape(scene, integ);
      INFO(l0 << " " << integ << ": " << r.stats.message);
      CHECK(r.stats.status == RunStatus::Equilibrium);
      CHECK(r.stats.certificate == "stable_minimum");
      CHECK(r.stats.newton_step <= std::max(scene.options.position_tol, r.stats.newton_floor));
    }
}

TEST_CASE("with pins in motion: the Jacobian is right, and the solver ends where the dynamics do") {
  const Scene scene = load_scene("two_corner_slack");
  const DrapeResult bdf = run_drape(scene, "cvode-bdf");
  const DrapeResult eq = run_drape(scene, "equilibrium");
  INFO(bdf.stats.message << " | " << eq.stats.message);
  REQUIRE(bdf.stats.status == RunStatus::Equilibrium);
  REQUIRE(eq.stats.status == RunStatus::Equilibrium);
  CHECK(eq.stats.certificate == "stable_minimum");
  const double move = scene.params.pin_move_time;
  CHECK(eq.stats.t_final == move);  // the solver's t stops where the pins stop
  CHECK(max_distance(bdf.positions, eq.positions) <=
        agreement_bound(bdf.stats, eq.stats, scene.options.position_tol));
  // Mid-move (the dynamics' state at t = 50 s) the pins enter a_c through t only; the Jacobian
  // in x must still match central differences, as at rest (test_spring_network).
  Scene half_way = scene;
  half_way.options.t_max = 0.5 * move;
  const DrapeResult mid = run_drape(half_way, "cvode-bdf");
  REQUIRE(mid.stats.status == RunStatus::TimeLimit);
  const JacobianCheck j =
      check_stiffness_jacobian(mid.grid.network, mid.stats.t_final, mid.state_x.data());
  CHECK(j.max_relative_error < 1e-6);
}

TEST_CASE("equilibrium agrees with cvode-bdf on the built-in scenes") {
  for (const std::string name : {"four_corner", "two_corner"}) {
    const Scene scene = load_scene(name, {"model.symmetry=none"});
    const DrapeResult bdf = run_drape(scene, "cvode-bdf");
    const DrapeResult eq = run_drape(scene, "equilibrium");
    INFO(name << ": " << bdf.stats.message << " | " << eq.stats.message);
    REQUIRE(bdf.stats.status == RunStatus::Equilibrium);
    REQUIRE(eq.stats.status == RunStatus::Equilibrium);
    CHECK(max_distance(bdf.positions, eq.positions) <=
          agreement_bound(bdf.stats, eq.stats, scene.options.position_tol));
    CHECK(eq.stats.steps < bdf.stats.steps);
  }
}

TEST_CASE("a free-floating body: its rigid-body modes are factored out of the certificate") {
  // A cube of 8 particles joined by all 28 springs, no pins, no gravity: K has exactly the 6
  // rigid-body modes in its null space. Started stretched 10 % and sheared, it relaxes to the
  // cube, which the certificate must call a stable minimum (not "inconclusive").
  SpringNetworkSpec spec;
  for (int i = 0; i < 8; ++i)
    spec.positions.push_back({0.1 * (i & 1), 0.1 * ((i >> 1) & 1), 0.1 * ((i >> 2) & 1)});
  for (int a = 0; a < 8; ++a)
    for (int b = a + 1; b < 8; ++b)
      spec.springs.push_back({a, b, norm(spec.positions[a] - spec.positions[b]), 50.0});
  for (Vec3& q : spec.positions) q = Vec3{1.1 * q.x + 0.02 * q.z, 1.1 * q.y, 1.1 * q.z};
  spec.masses.assign(8, 0.01);
  spec.damping = 0.05;
  spec.gravity = {0.0, 0.0, 0.0};
  spec.residual_force_scale = 1.0;
  spec.free_floating = true;
  const SpringNetwork cube(spec);
  REQUIRE(cube.free_floating());
  for (const std::string integrator : {"equilibrium", "cvode-bdf"}) {
    DYNAMIC_SECTION(integrator) {
      IntegratorOptions opt;
      std::vector<double> x, v;
      const RunStats s = run_to_equilibrium(cube, integrator, opt, x, v);
      INFO(s.message);
      CHECK(s.status == RunStatus::Equilibrium);
      CHECK(s.certificate == "stable_minimum");
      CHECK(s.negative_pivots == 0);
      CHECK(s.min_eigenvalue > s.eigenvalue_threshold);
      std::vector<Vec3> p;
      cube.all_positions(0.0, x.data(), p);
      for (const Spring& sp : spec.springs)
        CHECK(std::abs(norm(p[sp.a] - p[sp.b]) - sp.rest) <= 10.0 * opt.position_tol);
    }
  }
  SECTION("undeclared, the same body's certificate is inconclusive (K singular)") {
    SpringNetworkSpec undeclared = spec;
    undeclared.free_floating = false;
    const SpringNetwork same(undeclared);
    IntegratorOptions opt;
    std::vector<double> x, v;
    const RunStats s = run_to_equilibrium(same, "equilibrium", opt, x, v);
    CHECK(s.status == RunStatus::Equilibrium);
    CHECK(s.certificate == "inconclusive");
  }
  SECTION("the probe holds 6 gauge dofs; the modes are outside its spectrum") {
    std::vector<double> x(cube.dof()), v(cube.dof());
    cube.initial_state(x.data(), v.data());
    detail::StiffnessProbe probe(cube, IntegratorOptions::Factorization::Automatic);
    const detail::StiffnessProbe::Result r = probe.probe(0.0, x.data());
    CHECK(probe.gauge().size() == 6);
    CHECK_FALSE(r.singular);
  }
}

TEST_CASE("a free planar body is certified with its 3 in-plane rigid motions held") {
  // A braced square of 4 particles in z = 0, the plane holding z (SpringNetwork's planar mode):
  // its stiffness has exactly the 3 in-plane rigid modes in its null space. The probe holds 3
  // gauge dofs (not space's 6), the rest is positive definite, and the equilibrium solver
  // certifies a stretched start's end as a stable minimum.
  SpringNetworkSpec spec;
  spec.positions = {{0.0, 0.0, 0.0}, {0.1, 0.0, 0.0}, {0.1, 0.1, 0.0}, {0.0, 0.1, 0.0}};
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      spec.springs.push_back({a, b, norm(spec.positions[a] - spec.positions[b]), 50.0});
  for (Vec3& q : spec.positions) q = Vec3{1.1 * q.x + 0.02 * q.y, 1.05 * q.y, 0.0};
  spec.masses.assign(4, 0.01);
  spec.damping = 0.05;
  spec.gravity = {0.0, 0.0, 0.0};
  spec.residual_force_scale = 1.0;
  spec.free_floating = true;
  spec.plane_stiffness = 50.0;
  const SpringNetwork square(spec);
  REQUIRE(square.free_floating());
  REQUIRE(square.planar());
  std::vector<double> x(square.dof()), v(square.dof());
  square.initial_state(x.data(), v.data());
  detail::StiffnessProbe probe(square, IntegratorOptions::Factorization::Automatic);
  const detail::StiffnessProbe::Result r = probe.probe(0.0, x.data());
  CHECK(probe.gauge().size() == 3);
  for (int g : probe.gauge()) CHECK(g % 3 != 2);  // x and y dofs: z is not a rigid mode here
  CHECK_FALSE(r.singular);
  IntegratorOptions opt;
  const RunStats s = run_to_equilibrium(square, "equilibrium", opt, x, v);
  INFO(s.message);
  CHECK(s.status == RunStatus::Equilibrium);
  CHECK(s.certificate == "stable_minimum");
}
