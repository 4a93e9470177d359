// Drape measurement (docs/fitting.md, "1. Measure"): normalisation rules on hand-computed points, the QR polynomial
// fit (exact recovery, least-squares optimality, an ill-conditioned case against an SVD solve),
// the Eq. 5 objective, edges of analytic sheets, and the target CSV (lab data, round trip,
// every malformed-file error).
#include <unistd.h>

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <tuple>

#include "models/drape_grid.hpp"
#include "src/measure/measurement.hpp"
#include "src/fit/targets.hpp"

using namespace knitsim;
using Catch::Matchers::Contains;

namespace {

const double kPi = std::acos(-1.0);

double poly(const std::vector<double>& c, double s) {
  double v = 0.0;
  for (size_t k = c.size(); k-- > 0;) v = v * s + c[k];
  return v;
}

std::vector<double> as_vector(const EdgeCoefficients& c) { return {c.begin(), c.end()}; }

void check_coefficients(const EdgeCoefficients& got, const std::vector<double>& want, double tol) {
  REQUIRE(want.size() == got.size());
  for (size_t i = 0; i < got.size(); ++i) {
    INFO("p" << i << " got " << got[i] << " want " << want[i]);
    CHECK(std::abs(got[i] - want[i]) <= tol);
  }
}

// A scratch directory for this test process, removed at exit.
struct ScratchDir {
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("knitsim_test_measurement_" + std::to_string(getpid()));
  ScratchDir() { std::filesystem::create_directories(path); }
  ~ScratchDir() { std::filesystem::remove_all(path); }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string file = (path / name).string();
    std::ofstream(file) << text;
    return file;
  }
};

DrapeParams grid_params(PinLayout layout) {
  DrapeParams p;  // W = 0.5 m, L0 = 4.9 cm -> n = 10, model width 0.49 m
  p.layout = layout;
  return p;
}

// Positions of the grid at rest with z replaced by height(x, y) and y by y + bulge(x, y).
template <class Height, class Bulge>
std::vector<Vec3> sheet(const DrapeGrid& g, Height height, Bulge bulge) {
  std::vector<Vec3> pos(g.network.particle_count());
  for (int i = 0; i <= g.n; ++i)
    for (int j = 0; j <= g.n; ++j) {
      const double x = j * g.params.natural_length, y = i * g.params.natural_length;
      pos[g.index(i, j)] = {x, y + bulge(x, y), height(x, y)};
    }
  return pos;
}

}  // namespace

TEST_CASE("span-edge normalisation on hand-computed points") {
  // A = 0, B = (4, 0, 3): |AB| = 5, e = (0.8, 0, 0.6). Point (2, 1, 0): s = 1.6/5 = 0.32,
  // z_line = 0.32 * 3 = 0.96, d = -(0 - 0.96)/5 = 0.192 (below the chord: positive).
  const EdgePoints p = normalise_span_edge({{2, 1, 0}, {0, 0, 0}, {4, 0, 3}}, {0, 0, 0}, {4, 0, 3});
  CHECK(p.s[0] == Approx(0.32).epsilon(1e-15));
  CHECK(p.d[0] == Approx(0.192).epsilon(1e-15));
  CHECK(p.s[1] == 0.0);
  CHECK(p.d[1] == 0.0);
  CHECK(p.s[2] == Approx(1.0).epsilon(1e-15));
  CHECK(std::abs(p.d[2]) < 1e-15);
  CHECK_THROWS_AS(normalise_span_edge({{0, 0, 0}}, {1, 1, 1}, {1, 1, 1}), std::invalid_argument);
  CHECK_THROWS_AS(normalise_span_edge({{NAN, 0, 0}}, {0, 0, 0}, {1, 0, 0}), std::invalid_argument);
}

TEST_CASE("hanging-edge normalisation on hand-computed points, pins at unequal heights") {
  // pin1 (0,_,0), pin2 (3,_,4): S = 5, sigma = +1, z_ref = 2. Point (1, 7, -3) (y ignored):
  //   top/bottom: s = 1/5 = 0.2,         d = (2 + 3)/5 = 1
  //   left:       s = (0 + 3)/5 = 0.6,   d = 1/5 = 0.2
  //   right:      s = (4 + 3)/5 = 1.4,   d = -(1 - 3)/5 = 0.4
  const Vec3 pin1{0, 0, 0}, pin2{3, 0, 4}, x{1, 7, -3};
  struct Case {
    EdgeSide side;
    double s, d;
  };
  for (Case c : {Case{EdgeSide::Top, 0.2, 1.0}, Case{EdgeSide::Bottom, 0.2, 1.0},
                 Case{EdgeSide::Left, 0.6, 0.2}, Case{EdgeSide::Right, 1.4, 0.4}}) {
    INFO(to_string(c.side));
    const EdgePoints p = normalise_hanging_edge(c.side, {x}, pin1, pin2);
    CHECK(p.s[0] == Approx(c.s).epsilon(1e-15));
    CHECK(p.d[0] == Approx(c.d).epsilon(1e-15));
  }
  // Listing the pins the other way round (a photo from the back, sigma = -1) swaps the roles:
  // top s is measured from pin1 = (3,_,4) toward pin2: (3 - 1)/5 = 0.4; left now hangs from
  // (3,_,4) and gets what right had.
  const EdgePoints top = normalise_hanging_edge(EdgeSide::Top, {x}, pin2, pin1);
  CHECK(top.s[0] == Approx(0.4).epsilon(1e-15));
  CHECK(top.d[0] == Approx(1.0).epsilon(1e-15));
  const EdgePoints left = normalise_hanging_edge(EdgeSide::Left, {x}, pin2, pin1);
  CHECK(left.s[0] == Approx(1.4).epsilon(1e-15));
  CHECK(left.d[0] == Approx(0.4).epsilon(1e-15));
  CHECK_THROWS_AS(normalise_hanging_edge(EdgeSide::Top, {x}, {1, 0, 0}, {1, 0, 5}),
                  std::invalid_argument);
}

TEST_CASE("fit_polynomial recovers a quartic exactly and is a least-squares solution") {
  const std::vector<double> p{0.3, -1.2, 2.5, -0.7, 0.45};
  std::vector<double> s, d;
  for (int k = 0; k <= 10; ++k) {
    s.push_back(k / 10.0);
    d.push_back(poly(p, s.back()));
  }
  const std::vector<double> c = fit_polynomial(s, d, 4);
  for (int i = 0; i < 5; ++i) CHECK(std::abs(c[i] - p[i]) < 1e-12);

  // Noisy data on a side-edge range s in [0, 1.7]: the residual is orthogonal to every
  // column s^i of the Vandermonde matrix (the normal equations hold at the solution).
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  s.clear();
  d.clear();
  for (int k = 0; k < 40; ++k) {
    s.push_back(1.7 * k / 39.0);
    d.push_back(poly(p, s.back()) + noise(rng));
  }
  const std::vector<double> cn = fit_polynomial(s, d, 4);
  for (int i = 0; i < 5; ++i) {
    double dot_ri = 0.0, scale = 0.0;
    for (size_t k = 0; k < s.size(); ++k) {
      dot_ri += (d[k] - poly(cn, s[k])) * std::pow(s[k], i);
      scale += std::abs(d[k] * std::pow(s[k], i));
    }
    CHECK(std::abs(dot_ri) < 1e-13 * scale);
  }
  // Perturbing the solution increases the residual (a minimum, not just a stationary point).
  auto sse = [&](const std::vector<double>& coef) {
    double r = 0.0;
    for (size_t k = 0; k < s.size(); ++k) r += std::pow(d[k] - poly(coef, s[k]), 2);
    return r;
  };
  for (int i = 0; i < 5; ++i) {
    std::vector<double> q = cn;
    q[i] += 1e-4;
    CHECK(sse(q) > sse(cn));
  }
}

TEST_CASE("QR fit stays accurate on an ill-conditioned abscissa set") {
  // 20 points crowded in [0.95, 1]: the Vandermonde matrix has condition number ~1e8, so the
  // normal equations (condition ~1e16) lose every digit while QR keeps about eight.
  std::vector<double> s, d;
  const std::vector<double> p{0.1, 0.2, -0.3, 0.4, -0.5};
  for (int k = 0; k < 20; ++k) {
    s.push_back(0.95 + 0.05 * k / 19.0);
    d.push_back(poly(p, s.back()));
  }
  Eigen::MatrixXd V(20, 5);
  Eigen::VectorXd rhs(20);
  for (int k = 0; k < 20; ++k) {
    for (int i = 0; i < 5; ++i) V(k, i) = std::pow(s[k], i);
    rhs(k) = d[k];
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(V, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const double cond = svd.singularValues()(0) / svd.singularValues()(4);
  INFO("condition number " << cond);
  REQUIRE(cond > 1e7);

  const std::vector<double> c = fit_polynomial(s, d, 4);
  const Eigen::VectorXd normal = (V.transpose() * V).ldlt().solve(V.transpose() * rhs);
  double qr_err = 0.0, normal_err = 0.0;
  for (int i = 0; i < 5; ++i) {
    qr_err = std::max(qr_err, std::abs(c[i] - p[i]));
    normal_err = std::max(normal_err, std::abs(normal(i) - p[i]));
  }
  INFO("QR error " << qr_err << ", normal-equations error " << normal_err);
  CHECK(qr_err < 1e-6);
  CHECK(normal_err > 100 * qr_err);  // the set really is hard: QR is what makes it accurate

  // Noisy data: QR agrees with the SVD least-squares solution (an independent method).
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1e-3);
  for (int k = 0; k < 20; ++k) {
    d[k] += noise(rng);
    rhs(k) = d[k];
  }
  const std::vector<double> cq = fit_polynomial(s, d, 4);
  const Eigen::VectorXd cs = svd.solve(rhs);
  for (int i = 0; i < 5; ++i) CHECK(std::abs(cq[i] - cs(i)) < 1e-7 * cs.cwiseAbs().maxCoeff());
}

TEST_CASE("fit_polynomial rejects bad input") {
  const std::vector<double> four{0, 0.25, 0.5, 0.75}, five{0, 0.25, 0.5, 0.75, 1};
  CHECK_THROWS_WITH(fit_polynomial(four, four, 4), Contains("4 points") && Contains("at least 5"));
  CHECK_THROWS_WITH(fit_polynomial({0, 0.5, 0.5, 0.75, 1}, five, 4), Contains("distinct"));
  CHECK_THROWS_AS(fit_polynomial(five, four, 4), std::invalid_argument);
  CHECK_THROWS_AS(fit_polynomial(five, {0, 1, NAN, 2, 3}, 4), std::invalid_argument);
  CHECK_THROWS_AS(fit_polynomial(five, five, -1), std::invalid_argument);
  CHECK_THROWS_AS(fit_edge("top", {four, four}), std::invalid_argument);
}

TEST_CASE("objective is Eq. 5 over all edges and coefficients") {
  std::vector<EdgeFit> measured;
  const char* names[] = {"top", "bottom", "left", "right"};
  for (int e = 0; e < 4; ++e)
    measured.push_back({names[e], {}, {0.01 * e, 0.2, -0.3 + e, 0.04, 0.5}});
  std::vector<EdgeFit> simulated(measured.rbegin(), measured.rend());  // matched by name
  simulated.push_back({"extra", {}, {9, 9, 9, 9, 9}});                 // ignored
  CHECK(objective(measured, simulated) == 0.0);
  simulated[1].coefficients[3] += 0.01;  // one of 20 coefficients off by 0.01
  CHECK(objective(measured, simulated) == Approx(100.0 * std::sqrt(1e-4 / 20.0)).epsilon(1e-12));
  for (EdgeFit& e : simulated)
    for (double& c : e.coefficients) c -= 0.02;
  // Now 19 differences of 0.02 and one of 0.01: E = 100 sqrt((19 * 4e-4 + 1e-4) / 20).
  CHECK(objective(measured, simulated) ==
        Approx(100.0 * std::sqrt((19 * 4e-4 + 1e-4) / 20.0)).epsilon(1e-12));
  // Paper Eq. 5 for one edge: sqrt(sum_5 (Pe - Ps)^2 / 5) x 100.
  CHECK(objective({measured[0]}, {{"top", {}, {0.01, 0.2, -0.3, 0.04, 0.53}}}) ==
        Approx(100.0 * std::sqrt((1e-4 + 0.0009) / 5.0)).epsilon(1e-12));

  CHECK_THROWS_WITH(objective(measured, {measured[0]}), Contains("bottom"));
  CHECK_THROWS_AS(objective({}, simulated), std::invalid_argument);
  CHECK_THROWS_WITH(objective({measured[0], measured[0]}, simulated), Contains("twice"));
}

TEST_CASE("four_corner: a sheet with straight edges has d = 0 on every edge") {
  // z = -a sin(pi x / W) sin(pi y / W) vanishes on all four boundary lines: however deep the
  // middle sags, each edge is the straight chord between its corners.
  const DrapeGrid g = build_drape_grid(grid_params(PinLayout::FourCorner));
  const double W = g.n * g.params.natural_length, a = 0.12;
  const std::vector<Vec3> pos = sheet(
      g, [&](double x, double y) { return -a * std::sin(kPi * x / W) * std::sin(kPi * y / W); },
      [](double, double) { return 0.0; });
  const std::vector<EdgeFit> fits = measure_edges(g, pos);
  REQUIRE(fits.size() == 4);
  for (const EdgeFit& f : fits) {
    INFO(f.name);
    REQUIRE(f.points.s.size() == static_cast<size_t>(g.n + 1));
    for (int k = 0; k <= g.n; ++k) {
      CHECK(f.points.s[k] == Approx(double(k) / g.n).margin(1e-15));
      CHECK(std::abs(f.points.d[k]) < 1e-15);
    }
    check_coefficients(f.coefficients, {0, 0, 0, 0, 0}, 1e-14);
  }
  // Tilting the sheet (corners at different heights, z += 0.1 x - 0.05 y) keeps every edge a
  // straight chord: still d = 0, and s is still the fraction along the edge.
  const std::vector<Vec3> tilted = sheet(
      g,
      [&](double x, double y) {
        return -a * std::sin(kPi * x / W) * std::sin(kPi * y / W) + 0.1 * x - 0.05 * y;
      },
      [](double, double) { return 0.0; });
  for (const EdgeFit& f : measure_edges(g, tilted))
    for (int k = 0; k <= g.n; ++k) {
      CHECK(f.points.s[k] == Approx(double(k) / g.n).margin(1e-15));
      CHECK(std::abs(f.points.d[k]) < 1e-15);
    }
}

TEST_CASE("four_corner: a mirror-symmetric sagging sheet gives four identical edge fits") {
  // z = -a (sin(pi x/W) + sin(pi y/W)): corners at z = 0, every edge sags as a sin(pi s), so
  // d_k = (a/W) sin(pi k/n) on every edge. The top and bottom edges also bow in the horizontal
  // plane (y += 0.01 sin(pi x/W)), which a camera facing the edge cannot see: s uses only the
  // projection on A->B.
  const DrapeGrid g = build_drape_grid(grid_params(PinLayout::FourCorner));
  const double W = g.n * g.params.natural_length, a = 0.05;
  const std::vector<Vec3> pos = sheet(
      g, [&](double x, double y) { return -a * (std::sin(kPi * x / W) + std::sin(kPi * y / W)); },
      [&](double x, double) { return 0.01 * std::sin(kPi * x / W); });
  const std::vector<EdgeFit> fits = measure_edges(g, pos);
  for (const EdgeFit& f : fits) {
    INFO(f.name);
    for (int k = 0; k <= g.n; ++k) {
      CHECK(f.points.s[k] == Approx(double(k) / g.n).margin(1e-15));
      CHECK(f.points.d[k] == Approx(a / W * std::sin(kPi * k / g.n)).margin(1e-15));
    }
    for (int i = 0; i < 5; ++i)
      CHECK(std::abs(f.coefficients[i] - fits[0].coefficients[i]) < 1e-14);
    // The fit inherits the mirror symmetry d(s) = d(1 - s) and follows (a/W) sin(pi s) to
    // within the quartic's approximation error (well under 1 % of the sag).
    const std::vector<double> c = as_vector(f.coefficients);
    for (double s : {0.0, 0.1, 0.23, 0.4}) {
      CHECK(std::abs(poly(c, s) - poly(c, 1.0 - s)) < 1e-13);
      CHECK(std::abs(poly(c, s) - a / W * std::sin(kPi * s)) < 1e-2 * a / W);
    }
  }
}

TEST_CASE("two_corner conventions on a hand-built hanging sheet") {
  // Pins at x1 = 0.1, x2 = 0.4 (S = 0.3, as after a span move), height z0 = 0.2. With t = j/n,
  // u = i/n, W = n L0, c = (x1 + x2)/2, h = 0.03, w(u) = 1 - 0.2 u^2:
  //   x = c + (x1 + t S - c) w(u),   z = z0 - u W - 4 h t (1 - t)
  // Expected fits (hand-derived):
  //   top    (u = 0): s = t, d = (4h/S) t(1-t)                -> (0, 4h/S, -4h/S, 0, 0)
  //   bottom (u = 1): s = 0.1 + 0.8 t, d = W/S + (4h/S) t(1-t) = W/S + (6.25h/S)(-s^2+s-0.09)
  //   left/right:     s = u W/S (up to W/S = 1.63), d = 0.1 u^2 = 0.1 (S/W)^2 s^2 (inward > 0)
  DrapeParams p = grid_params(PinLayout::TwoCorner);
  p.pin_span = 0.6;
  const DrapeGrid g = build_drape_grid(p);
  const double W = g.n * p.natural_length, x1 = 0.1, S = 0.3, c = x1 + S / 2, z0 = 0.2, h = 0.03;
  std::vector<Vec3> pos(g.network.particle_count());
  for (int i = 0; i <= g.n; ++i)
    for (int j = 0; j <= g.n; ++j) {
      const double t = double(j) / g.n, u = double(i) / g.n;
      pos[g.index(i, j)] = {c + (x1 + t * S - c) * (1 - 0.2 * u * u), 0.37 * u,
                            z0 - u * W - 4 * h * t * (1 - t)};
    }
  const std::vector<EdgeFit> fits = measure_edges(g, pos);
  REQUIRE(fits.size() == 4);
  const double q = h / S;
  for (const EdgeFit& f : fits) {
    INFO(f.name);
    if (f.name == "top") check_coefficients(f.coefficients, {0, 4 * q, -4 * q, 0, 0}, 1e-12);
    if (f.name == "bottom")
      check_coefficients(f.coefficients, {W / S - 0.5625 * q, 6.25 * q, -6.25 * q, 0, 0}, 1e-12);
    if (f.name == "left" || f.name == "right") {
      check_coefficients(f.coefficients, {0, 0, 0.1 * (S / W) * (S / W), 0, 0}, 1e-12);
      CHECK(f.points.s.front() == 0.0);
      CHECK(f.points.s.back() == Approx(W / S));
      CHECK(f.points.d.back() == Approx(0.1));  // inward: positive on both sides
    }
  }
  CHECK_THROWS_AS(measure_edges(g, std::vector<Vec3>(3)), std::invalid_argument);
  pos[g.index(3, 3)].z = NAN;  // a diverged run
  CHECK_THROWS_AS(measure_edges(g, pos), std::invalid_argument);
}

TEST_CASE("lab targets in mm are normalised exactly like the simulation") {
  // The two_corner sheet of the previous test, "photographed" in mm from the front, and a
  // four_corner sheet photographed edge by edge, give the simulation's fits.
  ScratchDir dir;
  DrapeParams p2 = grid_params(PinLayout::TwoCorner);
  const DrapeGrid g2 = build_drape_grid(p2);
  const double W = g2.n * p2.natural_length;
  std::vector<Vec3> hang(g2.network.particle_count());
  for (int i = 0; i <= g2.n; ++i)
    for (int j = 0; j <= g2.n; ++j) {
      const double t = double(j) / g2.n, u = double(i) / g2.n;
      hang[g2.index(i, j)] = {W * t + 0.02 * u * std::sin(3 * t), 0.1, -W * u - 0.04 * t * t};
    }
  hang[g2.index(0, g2.n)].z = 0.0;  // the pins are level
  const std::vector<Vec3>& hanging = hang;
  TargetScene two{"two_corner", {}, {}};
  for (int pin : {g2.index(0, 0), g2.index(0, g2.n)})
    two.pins.push_back({1000 * hang[pin].x, 1000 * hang[pin].z});
  for (const GridEdge& e : g2.edges) {
    TargetEdge te;
    te.name = e.name;
    te.kind = TargetKind::LabPoints;
    for (int q : e.particles) te.lab_points.push_back({1000 * hang[q].x, 1000 * hang[q].z});
    two.edges.push_back(te);
  }

  const DrapeGrid g4 = build_drape_grid(grid_params(PinLayout::FourCorner));
  const std::vector<Vec3> drape = sheet(
      g4, [&](double x, double y) { return -0.04 * std::sin(kPi * x / W) * (1 + y) - 0.03 * y; },
      [](double, double) { return 0.0; });
  TargetScene four{"four_corner", {}, {}};
  for (const GridEdge& e : g4.edges) {
    TargetEdge te;
    te.name = e.name;
    te.kind = TargetKind::LabPoints;
    // Each edge's photo: horizontal camera axis along the edge (x for top/bottom, y for the
    // sides), z up; the corners A (first particle) and B (last) are the pin rows.
    const bool along_x = e.name == "top" || e.name == "bottom";
    auto cam = [&](int q) {
      return CameraPoint{1000 * (along_x ? drape[q].x : drape[q].y), 1000 * drape[q].z};
    };
    te.pins = {cam(e.particles.front()), cam(e.particles.back())};
    for (int q : e.particles) te.lab_points.push_back(cam(q));
    four.edges.push_back(te);
  }
  const Target target{{four, two}};
  const std::string file = (dir.path / "lab.csv").string();
  write_target_csv(target, file, {"hand-made lab target"});
  const Target read = read_target_csv(file);

  for (auto [scene, grid, pos] :
       {std::tuple{"four_corner", &g4, &drape}, std::tuple{"two_corner", &g2, &hanging}}) {
    const std::vector<EdgeFit> sim = measure_edges(*grid, *pos);
    const std::vector<EdgeFit> lab = fit_target_scene(read.scene(scene));
    REQUIRE(lab.size() == sim.size());
    for (size_t e = 0; e < sim.size(); ++e) {
      INFO(scene << " " << sim[e].name);
      CHECK(lab[e].name == sim[e].name);
      check_coefficients(lab[e].coefficients, as_vector(sim[e].coefficients), 1e-12);
    }
    CHECK(objective(lab, sim) < 1e-10);
  }
}

TEST_CASE("target CSV round-trips bit for bit") {
  ScratchDir dir;
  Target t;
  TargetScene four{"four_corner", {}, {}};
  TargetEdge top{"top", TargetKind::Coefficients, {}, {0.1, -0.2, 1.0 / 3.0, 4e-17, -5.5}, {}, {}};
  TargetEdge bottom{"bottom", TargetKind::Points, {}, {}, {}, {}};
  for (int k = 0; k < 7; ++k) {
    bottom.points.s.push_back(k / 6.0);
    bottom.points.d.push_back(std::sin(k + 0.1) / 7.0);
  }
  TargetEdge left{"left", TargetKind::LabPoints, {}, {}, {}, {{0, 0}, {500.25, -3.125}}};
  for (int k = 0; k <= 8; ++k) left.lab_points.push_back({62.5 * k, -40.0 * std::sin(k / 2.5)});
  four.edges = {top, bottom, left};
  TargetScene slack{"two_corner_slack", {}, {{100, 0}, {400, 1}}};
  TargetEdge side{"right", TargetKind::LabPoints, {}, {}, {}, {}};
  for (int k = 0; k < 6; ++k) side.lab_points.push_back({400 - 10.0 * k * k, -80.0 * k});
  slack.edges = {side};
  TargetScene two{"two_corner", {}, {}};
  two.edges = {top};
  t.scenes = {four, slack, two};

  const std::string a = (dir.path / "a.csv").string(), b = (dir.path / "b.csv").string();
  write_target_csv(t, a);
  const Target r = read_target_csv(a);
  REQUIRE(r.scenes.size() == 3);
  for (size_t s = 0; s < 3; ++s) {
    CHECK(r.scenes[s].name == t.scenes[s].name);
    REQUIRE(r.scenes[s].edges.size() == t.scenes[s].edges.size());
    CHECK(r.scenes[s].pins.size() == t.scenes[s].pins.size());
    const std::vector<EdgeFit> fa = fit_target_scene(t.scenes[s]);
    const std::vector<EdgeFit> fb = fit_target_scene(r.scenes[s]);
    for (size_t e = 0; e < fa.size(); ++e) {
      CHECK(fb[e].name == fa[e].name);
      CHECK(fb[e].coefficients == fa[e].coefficients);  // bit for bit
      CHECK(fb[e].points.s == fa[e].points.s);
      CHECK(fb[e].points.d == fa[e].points.d);
    }
  }
  write_target_csv(r, b);
  std::ifstream ia(a), ib(b);
  const std::string ta((std::istreambuf_iterator<char>(ia)), {});
  const std::string tb((std::istreambuf_iterator<char>(ib)), {});
  CHECK(ta == tb);
  CHECK_THROWS_WITH(t.scene("nowhere"), Contains("four_corner, two_corner_slack, two_corner"));

  // validate() on targets built in code.
  Target dup = t;
  dup.scenes[0].edges.push_back(top);
  CHECK_THROWS_WITH(dup.validate(), Contains("edge top: given twice"));
  Target ragged = t;
  ragged.scenes[0].edges[1].points.d.pop_back();
  CHECK_THROWS_WITH(write_target_csv(ragged, b), Contains("7 s values but 6 d values"));
}

TEST_CASE("edges.csv lists points and coefficients") {
  ScratchDir dir;
  const DrapeGrid g = build_drape_grid(grid_params(PinLayout::FourCorner));
  const double W = g.n * g.params.natural_length;
  const std::vector<EdgeFit> fits =
      measure_edges(g, sheet(
                           g, [&](double x, double) { return -0.1 * std::sin(kPi * x / W); },
                           [](double, double) { return 0.0; }));
  const std::string file = (dir.path / "edges.csv").string();
  write_edges_csv(fits, file);
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  CHECK(line == "edge,kind,index,s,d,coefficient");
  int points = 0, coeffs = 0;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream row(line + ",");  // the trailing field may be empty
    for (std::string field; std::getline(row, field, ',');) f.push_back(field);
    REQUIRE(f.size() == 6);
    const size_t edge = f[0] == "top" ? 0 : f[0] == "bottom" ? 1 : f[0] == "left" ? 2 : 3;
    REQUIRE(fits[edge].name == f[0]);
    const size_t index = std::stoul(f[2]);
    if (f[1] == "point") {
      ++points;
      CHECK(f[5].empty());  // 17 digits: the values read back exactly
      CHECK(std::stod(f[3]) == fits[edge].points.s[index]);
      CHECK(std::stod(f[4]) == fits[edge].points.d[index]);
    } else {
      ++coeffs;
      CHECK(f[1] == "coeff");
      CHECK((f[3].empty() && f[4].empty()));
      CHECK(std::stod(f[5]) == fits[edge].coefficients[index]);
    }
  }
  CHECK(points == 4 * (g.n + 1));
  CHECK(coeffs == 4 * 5);
}

TEST_CASE("malformed target files: one line naming file, line and field") {
  ScratchDir dir;
  const std::string head = "scene,edge,kind,a,b\n";
  auto points = [](const std::string& scene, const std::string& edge, int n) {
    std::string rows;
    for (int k = 0; k < n; ++k)
      rows += scene + "," + edge + ",point," + std::to_string(k / 4.0) + ",0.01\n";
    return rows;
  };
  auto coeffs = [](const std::string& scene, const std::string& edge) {
    std::string rows;
    for (int i = 0; i < 5; ++i) rows += scene + "," + edge + ",coeff," + std::to_string(i) + ",0\n";
    return rows;
  };
  auto lab = [](const std::string& scene, const std::string& edge) {
    std::string rows;
    for (int k = 0; k < 5; ++k)
      rows += scene + "," + edge + ",lab_point," + std::to_string(100 * k) + "," +
              std::to_string(-50 * k - 5) + "\n";
    return rows;
  };
  struct Case {
    const char* what;
    std::string text;
    std::string where;  // "LINE: ..." fragment expected after the file name
  };
  const std::vector<Case> cases = {
      {"empty file", "# nothing\n", "empty target file"},
      {"wrong header", "scene,edge,kind,x,y\n", ":1: header = 'scene,edge,kind,x,y'"},
      {"NUL in the header", std::string("ab\0cd\n", 6), ":1: header = 'ab\\x00cd'"},
      {"no rows", head, "no data rows"},
      {"field count", head + "four_corner,top,point,0.1\n", ":2: 4 fields"},
      {"unknown scene", head + "three_corner,top,point,0,0\n", ":2: field scene = 'three_corner'"},
      {"unknown edge", head + "four_corner,middle,point,0,0\n", ":2: field edge = 'middle'"},
      {"empty edge", head + "four_corner,,point,0,0\n", ":2: field edge = ''"},
      {"unknown kind", head + "four_corner,top,points,0,0\n", ":2: field kind = 'points'"},
      {"non-numeric a", head + "four_corner,top,point,0.1x,0\n",
       ":2: field a = '0.1x': not a number"},
      {"empty b", head + "four_corner,top,point,0.1,\n", ":2: field b = '': not a number"},
      {"NaN b", head + "# c\n\nfour_corner,top,point,0.1,nan\n",
       ":4: field b = 'nan': not a finite"},
      {"inf a", head + "four_corner,top,point,inf,0\n", ":2: field a = 'inf': not a finite"},
      {"power 5", head + "four_corner,top,coeff,5,0\n", ":2: field a = '5': a power"},
      {"power 1.5", head + "four_corner,top,coeff,1.5,0\n", ":2: field a = '1.5': a power"},
      {"power twice", head + "four_corner,top,coeff,1,0\nfour_corner,top,coeff,1,0\n",
       ":3: field a = '1': power given twice"},
      {"missing power", head + "four_corner,top,coeff,0,0\nfour_corner,top,coeff,1,0\n",
       ":2: scene four_corner, edge top: field a: 2 coeff rows"},
      {"too few points", head + coeffs("four_corner", "left") + points("four_corner", "top", 4),
       ":7: scene four_corner, edge top: 4 point rows: need at least 5"},
      {"repeated abscissae",
       head + points("four_corner", "top", 4) + "four_corner,top,point,0.5,0\n",
       ":2: scene four_corner, edge top: fit_polynomial: the points have fewer than 5 distinct"},
      {"mixed kinds", head + points("four_corner", "top", 5) + "four_corner,top,coeff,0,0\n",
       ":7: field kind = 'coeff': edge top of four_corner already has point rows"},
      {"two_corner pin on an edge", head + "two_corner,top,pin,0,0\n",
       ":2: field edge = 'top': pins of two_corner belong to the scene"},
      {"four_corner pin without edge", head + "four_corner,,pin,0,0\n", ":2: field edge = ''"},
      {"third pin", head + "two_corner,,pin,0,0\ntwo_corner,,pin,1,0\ntwo_corner,,pin,2,0\n",
       ":4: field kind = 'pin': a third pin for two_corner"},
      {"third corner pin",
       head + "four_corner,top,pin,0,0\nfour_corner,top,pin,1,0\nfour_corner,top,pin,2,0\n",
       ":4: field kind = 'pin': a third pin for edge top"},
      {"lab points without pins", head + lab("two_corner", "left"),
       ":2: scene two_corner: 0 pin rows: lab points need exactly 2"},
      {"corner lab points with one pin",
       head + "four_corner,left,pin,0,0\n" + lab("four_corner", "left"),
       ":2: scene four_corner, edge left: 1 pin rows"},
      {"pins without lab points",
       head + "two_corner,,pin,0,0\ntwo_corner,,pin,1,0\n" + points("two_corner", "top", 5),
       ":2: scene two_corner: pin rows but no lab_point rows"},
      {"corner pins without lab points",
       head + "four_corner,top,pin,0,0\nfour_corner,top,pin,1,0\n",
       ":2: scene four_corner, edge top: pin rows but no lab_point rows"},
      {"point after corner pins", head + "four_corner,top,pin,0,0\nfour_corner,top,point,0,0\n",
       ":3: field kind = 'point': edge already has pin rows"},
      {"coinciding pins",
       head + "two_corner,,pin,7,0\ntwo_corner,,pin,7,0\n" + lab("two_corner", "bottom"),
       ":2: scene two_corner: the two pins coincide"},
      {"pins stacked vertically",
       head + "two_corner,,pin,7,0\ntwo_corner,,pin,7,50\n" + lab("two_corner", "bottom"),
       ":4: scene two_corner, edge bottom: hanging edge: both pins at the same x"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    const std::string file = dir.write("bad.csv", c.text);
    try {
      read_target_csv(file);
      FAIL("no exception");
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      INFO(msg);
      CHECK_THAT(msg, Contains(file + c.where) || Contains(file + ": " + c.where));
      CHECK(msg.find('\n') == std::string::npos);
    }
  }
  CHECK_THROWS_WITH(read_target_csv((dir.path / "missing.csv").string()), Contains("cannot open"));
  // A valid file with every kind reads without complaint.
  const std::string good =
      dir.write("good.csv", head + points("four_corner", "top", 5) + coeffs("four_corner", "left") +
                                "two_corner,,pin,0,0\ntwo_corner,,pin,400,0\n" +
                                lab("two_corner", "right") + "four_corner,right,pin,0,0\n" +
                                "four_corner,right,pin,400,0\n" + lab("four_corner", "right"));
  CHECK(read_target_csv(good).scenes.size() == 2);
}
