#include "src/measure/measurement.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <stdexcept>

#include "src/base/text.hpp"

namespace knitsim {

namespace {

[[noreturn]] void bad(const std::string& message) { throw std::invalid_argument(message); }

void require_finite(Vec3 p, const char* what) {
  if (!is_finite(p)) bad(std::string(what) + ": non-finite coordinate (did the run diverge?)");
}

}  // namespace

const char* to_string(EdgeSide side) {
  switch (side) {
    case EdgeSide::Top:
      return "top";
    case EdgeSide::Bottom:
      return "bottom";
    case EdgeSide::Left:
      return "left";
    case EdgeSide::Right:
      return "right";
  }
  return "?";
}

std::optional<EdgeSide> edge_side_from_name(const std::string& name) {
  for (EdgeSide side : {EdgeSide::Top, EdgeSide::Bottom, EdgeSide::Left, EdgeSide::Right})
    if (name == to_string(side)) return side;
  return std::nullopt;
}

EdgePoints normalise_span_edge(const std::vector<Vec3>& points, Vec3 a, Vec3 b) {
  require_finite(a, "span edge corner A");
  require_finite(b, "span edge corner B");
  const double length = norm(b - a);
  if (!(length > 0.0)) bad("span edge: corners A and B coincide");
  const Vec3 e = (1.0 / length) * (b - a);
  EdgePoints out;
  out.s.reserve(points.size());
  out.d.reserve(points.size());
  for (const Vec3& x : points) {
    require_finite(x, "span edge point");
    const double s = dot(x - a, e) / length;
    const double z_line = a.z + s * (b.z - a.z);
    out.s.push_back(s);
    out.d.push_back(-(x.z - z_line) / length);
  }
  return out;
}

EdgePoints normalise_hanging_edge(EdgeSide side, const std::vector<Vec3>& points, Vec3 pin1,
                                  Vec3 pin2) {
  require_finite(pin1, "hanging edge pin1");
  require_finite(pin2, "hanging edge pin2");
  const double span = std::hypot(pin2.x - pin1.x, pin2.z - pin1.z);
  if (pin2.x == pin1.x)
    bad("hanging edge: both pins at the same x; the front view needs them side by side");
  const double sigma = pin2.x > pin1.x ? 1.0 : -1.0;
  const double z_ref = 0.5 * (pin1.z + pin2.z);
  EdgePoints out;
  out.s.reserve(points.size());
  out.d.reserve(points.size());
  for (const Vec3& x : points) {
    require_finite(x, "hanging edge point");
    double s = 0.0, d = 0.0;
    switch (side) {
      case EdgeSide::Top:
      case EdgeSide::Bottom:
        s = sigma * (x.x - pin1.x) / span;
        d = (z_ref - x.z) / span;
        break;
      case EdgeSide::Left:
        s = (pin1.z - x.z) / span;
        d = sigma * (x.x - pin1.x) / span;
        break;
      case EdgeSide::Right:
        s = (pin2.z - x.z) / span;
        d = -sigma * (x.x - pin2.x) / span;
        break;
    }
    out.s.push_back(s);
    out.d.push_back(d);
  }
  return out;
}

std::vector<double> fit_polynomial(const std::vector<double>& s, const std::vector<double>& d,
                                   int degree) {
  if (degree < 0) bad("fit_polynomial: degree = " + std::to_string(degree) + ": must be >= 0");
  if (s.size() != d.size())
    bad("fit_polynomial: " + std::to_string(s.size()) + " abscissae but " +
        std::to_string(d.size()) + " values");
  const int m = static_cast<int>(s.size());
  const int cols = degree + 1;
  if (m < cols)
    bad("fit_polynomial: " + std::to_string(m) + " points: a degree-" + std::to_string(degree) +
        " fit needs at least " + std::to_string(cols));
  Eigen::MatrixXd V(m, cols);
  Eigen::VectorXd rhs(m);
  for (int k = 0; k < m; ++k) {
    if (!std::isfinite(s[k]) || !std::isfinite(d[k]))
      bad("fit_polynomial: point " + std::to_string(k) + " is not finite");
    double power = 1.0;
    for (int c = 0; c < cols; ++c, power *= s[k]) V(k, c) = power;
    rhs(k) = d[k];
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(V);
  if (qr.rank() < cols)
    bad("fit_polynomial: the points have fewer than " + std::to_string(cols) +
        " distinct abscissae (rank " + std::to_string(qr.rank()) + ")");
  const Eigen::VectorXd c = qr.solve(rhs);
  return std::vector<double>(c.data(), c.data() + cols);
}

EdgeFit fit_edge(const std::string& name, EdgePoints points) {
  const std::vector<double> c = fit_polynomial(points.s, points.d, kEdgePolynomialDegree);
  EdgeFit fit{name, std::move(points), {}};
  std::copy(c.begin(), c.end(), fit.coefficients.begin());
  return fit;
}

std::vector<EdgeFit> measure_edges(const DrapeGrid& grid, const std::vector<Vec3>& all_positions) {
  const int count = grid.network.particle_count();
  if (static_cast<int>(all_positions.size()) != count)
    bad("measure_edges: " + std::to_string(all_positions.size()) + " positions for a grid of " +
        std::to_string(count) + " particles");
  for (Vec3 p : all_positions) require_finite(p, "measure_edges: a particle position");
  const Vec3 pin1 = all_positions[grid.index(0, 0)];
  const Vec3 pin2 = all_positions[grid.index(0, grid.n)];
  std::vector<EdgeFit> fits;
  for (const GridEdge& edge : grid.edges) {
    std::vector<Vec3> points;
    points.reserve(edge.particles.size());
    for (int p : edge.particles) points.push_back(all_positions[p]);
    if (grid.params.layout == PinLayout::FourCorner) {
      fits.push_back(
          fit_edge(edge.name, normalise_span_edge(points, points.front(), points.back())));
    } else {
      const std::optional<EdgeSide> side = edge_side_from_name(edge.name);
      if (!side) throw std::logic_error("measure_edges: DrapeGrid edge named " + edge.name);
      fits.push_back(fit_edge(edge.name, normalise_hanging_edge(*side, points, pin1, pin2)));
    }
  }
  return fits;
}

double objective(const std::vector<EdgeFit>& measured, const std::vector<EdgeFit>& simulated) {
  if (measured.empty()) bad("objective: no measured edges");
  std::set<std::string> seen;
  double sum = 0.0;
  for (const EdgeFit& m : measured) {
    if (!seen.insert(m.name).second) bad("objective: measured edge " + m.name + " given twice");
    const EdgeFit* match = nullptr;
    for (const EdgeFit& s : simulated)
      if (s.name == m.name) match = &s;
    if (!match) bad("objective: measured edge " + m.name + " is not among the simulated edges");
    for (size_t i = 0; i < m.coefficients.size(); ++i) {
      const double diff = m.coefficients[i] - match->coefficients[i];
      sum += diff * diff;
    }
  }
  const double terms = static_cast<double>(measured.size() * (kEdgePolynomialDegree + 1));
  return 100.0 * std::sqrt(sum / terms);
}

void write_edges_csv(const std::vector<EdgeFit>& edges, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  // %.17g, as the stream at precision 17 wrote them, through std::to_chars.
  std::string text = "edge,kind,index,s,d,coefficient\n";
  for (const EdgeFit& e : edges) {
    for (size_t k = 0; k < e.points.s.size(); ++k) {
      text += e.name + ",point,";
      append_integer(text, static_cast<long long>(k));
      text += ',';
      append_general(text, e.points.s[k], 17);
      text += ',';
      append_general(text, e.points.d[k], 17);
      text += ",\n";
    }
    for (size_t i = 0; i < e.coefficients.size(); ++i) {
      text += e.name + ",coeff,";
      append_integer(text, static_cast<long long>(i));
      text += ",,,";
      append_general(text, e.coefficients[i], 17);
      text += '\n';
    }
  }
  out << text;
  out.close();  // buffered text that cannot be written fails here (a full disk)
  if (!out) throw std::runtime_error(std::strerror(errno));  // the caller names the file
}

}  // namespace knitsim
