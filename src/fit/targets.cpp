#include "src/fit/targets.hpp"

#include <cmath>
#include <cerrno>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/measure/measurement.hpp"

namespace knitsim {

namespace {

constexpr const char* kHeader = "scene,edge,kind,a,b";
constexpr size_t kCoefficientCount = kEdgePolynomialDegree + 1;
constexpr size_t kMinPoints = kCoefficientCount;  // a quartic fit needs 5 points

[[noreturn]] void bad(const std::string& message) { throw std::invalid_argument(message); }

const char* kind_name(TargetKind kind) {
  switch (kind) {
    case TargetKind::Points:
      return "point";
    case TargetKind::Coefficients:
      return "coeff";
    case TargetKind::LabPoints:
      return "lab_point";
  }
  return "?";
}

bool hanging_scene(const std::string& scene) { return scene != "four_corner"; }

std::string where(const TargetScene& scene, const TargetEdge& edge) {
  return "scene " + scene.name + ", edge " + edge.name + ": ";
}

bool finite(CameraPoint p) { return std::isfinite(p.x_mm) && std::isfinite(p.z_mm); }

Vec3 camera_to_world(CameraPoint p) { return {p.x_mm, 0.0, p.z_mm}; }

void check_pins(const std::string& prefix, const std::vector<CameraPoint>& pins) {
  if (pins.size() != 2)
    bad(prefix + std::to_string(pins.size()) + " pin rows: lab points need exactly 2");
  for (CameraPoint p : pins)
    if (!finite(p)) bad(prefix + "pin is not finite");
  if (pins[0].x_mm == pins[1].x_mm && pins[0].z_mm == pins[1].z_mm)
    bad(prefix + "the two pins coincide");
}

// Everything about one edge that the reader cannot check line by line.
void check_edge(const TargetScene& scene, const TargetEdge& edge) {
  const std::string at = where(scene, edge);
  if (!edge_side_from_name(edge.name))
    bad("scene " + scene.name + ": edge = '" + edge.name + "': must be top, bottom, left or right");
  const bool has_points = !edge.points.s.empty() || !edge.points.d.empty();
  const bool has_lab = !edge.lab_points.empty() || !edge.pins.empty();
  switch (edge.kind) {
    case TargetKind::Points:
      if (has_lab) bad(at + "point data with lab points or pins: one kind per edge");
      if (edge.points.s.size() != edge.points.d.size())
        bad(at + std::to_string(edge.points.s.size()) + " s values but " +
            std::to_string(edge.points.d.size()) + " d values");
      if (edge.points.s.size() < kMinPoints)
        bad(at + std::to_string(edge.points.s.size()) + " point rows: need at least " +
            std::to_string(kMinPoints));
      for (size_t k = 0; k < edge.points.s.size(); ++k)
        if (!std::isfinite(edge.points.s[k]) || !std::isfinite(edge.points.d[k]))
          bad(at + "point " + std::to_string(k) + " is not finite");
      break;
    case TargetKind::Coefficients:
      if (has_points || has_lab) bad(at + "coefficients with points: one kind per edge");
      for (double c : edge.coefficients)
        if (!std::isfinite(c)) bad(at + "coefficient is not finite");
      break;
    case TargetKind::LabPoints:
      if (has_points) bad(at + "lab points with normalised points: one kind per edge");
      if (edge.lab_points.size() < kMinPoints)
        bad(at + std::to_string(edge.lab_points.size()) + " lab_point rows: need at least " +
            std::to_string(kMinPoints));
      for (CameraPoint p : edge.lab_points)
        if (!finite(p)) bad(at + "lab point is not finite");
      if (hanging_scene(scene.name)) {
        if (!edge.pins.empty()) bad(at + "pins of a " + scene.name + " scene belong to the scene");
      } else {
        check_pins(at, edge.pins);
      }
      break;
  }
}

// Scene-level pins of the hanging scenes: exactly 2 when (and only when) an edge has lab points.
void check_scene_pins(const TargetScene& scene) {
  bool lab = false;
  for (const TargetEdge& e : scene.edges) lab = lab || e.kind == TargetKind::LabPoints;
  const std::string at = "scene " + scene.name + ": ";
  if (!hanging_scene(scene.name)) {
    if (!scene.pins.empty()) bad(at + "four_corner pins belong to an edge");
  } else if (lab) {
    check_pins(at, scene.pins);
  } else if (!scene.pins.empty()) {
    bad(at + "pin rows but no lab_point rows");
  }
}

EdgeFit fit_target_edge(const TargetScene& scene, const TargetEdge& edge) {
  switch (edge.kind) {
    case TargetKind::Points:
      return fit_edge(edge.name, edge.points);
    case TargetKind::Coefficients:
      return EdgeFit{edge.name, {}, edge.coefficients};
    case TargetKind::LabPoints:
      break;
  }
  std::vector<Vec3> points;
  for (CameraPoint p : edge.lab_points) points.push_back(camera_to_world(p));
  if (!hanging_scene(scene.name))
    return fit_edge(edge.name, normalise_span_edge(points, camera_to_world(edge.pins[0]),
                                                   camera_to_world(edge.pins[1])));
  return fit_edge(edge.name, normalise_hanging_edge(*edge_side_from_name(edge.name), points,
                                                    camera_to_world(scene.pins[0]),
                                                    camera_to_world(scene.pins[1])));
}

// Validates one scene (edges, pins, fits) and returns its fits: the one check shared by
// Target::validate, fit_target_scene and the reader. edge_at[k] / pin_at prefix the messages
// with a location (the reader's "FILE:LINE: "); edge_at may be empty.
std::vector<EdgeFit> checked_fits(const TargetScene& scene, const std::vector<std::string>& edge_at,
                                  const std::string& pin_at) {
  std::set<std::string> names;
  std::vector<EdgeFit> fits;
  for (size_t k = 0; k < scene.edges.size(); ++k) {
    const TargetEdge& edge = scene.edges[k];
    try {
      if (!names.insert(edge.name).second) bad(where(scene, edge) + "given twice");
      check_edge(scene, edge);
    } catch (const std::invalid_argument& e) {
      bad((edge_at.empty() ? "" : edge_at[k]) + e.what());
    }
  }
  try {
    check_scene_pins(scene);
  } catch (const std::invalid_argument& e) {
    bad(pin_at + e.what());
  }
  for (size_t k = 0; k < scene.edges.size(); ++k) {
    try {
      fits.push_back(fit_target_edge(scene, scene.edges[k]));
      // Finite but huge points (1e308) can overflow the fit (found by fuzz_target).
      for (double c : fits.back().coefficients)
        if (!std::isfinite(c))
          bad("the fitted coefficients overflow: the edge's values are too large to fit");
    } catch (const std::invalid_argument& e) {
      bad((edge_at.empty() ? "" : edge_at[k]) + where(scene, scene.edges[k]) + e.what());
    }
  }
  return fits;
}

std::string trim(const std::string& text) {
  const size_t first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  const size_t last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) fields.push_back(trim(field));
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

}  // namespace

bool is_target_scene(const std::string& name) {
  return name == "four_corner" || name == "two_corner" || name == "two_corner_slack";
}

void Target::validate() const {
  std::set<std::string> names;
  for (const TargetScene& s : scenes) {
    if (!is_target_scene(s.name))
      bad("scene = '" + s.name + "': must be four_corner, two_corner or two_corner_slack");
    if (!names.insert(s.name).second) bad("scene " + s.name + ": given twice");
    checked_fits(s, {}, "");
  }
}

const TargetScene& Target::scene(const std::string& name) const {
  std::string present;
  for (const TargetScene& s : scenes) {
    if (s.name == name) return s;
    present += (present.empty() ? "" : ", ") + s.name;
  }
  bad("target has no scene " + name + " (it has: " + (present.empty() ? "none" : present) + ")");
}

std::vector<EdgeFit> fit_target_scene(const TargetScene& scene) {
  return checked_fits(scene, {}, "");
}

Target read_target_csv(const std::string& path) {
  std::string text, why;
  if (!read_input_file(path, kMaxTargetFileBytes, text, why))
    bad(path + ": cannot open target file: " + why);
  return parse_target_csv(text, path);
}

Target parse_target_csv(const std::string& csv, const std::string& path) {
  std::istringstream in(csv);
  Target target;
  // Reader bookkeeping per (scene, edge): first line, whether the kind is known, powers seen.
  struct Pending {
    int first_line = 0;
    bool kind_known = false;
    std::set<int> powers;
  };
  std::map<std::pair<std::string, std::string>, Pending> pending;
  std::map<std::string, int> scene_line;  // first pin row of a scene, else its first row
  bool header_seen = false;
  std::string raw;
  for (int line_no = 1; std::getline(in, raw); ++line_no) {
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    const std::string at = path + ":" + std::to_string(line_no) + ": ";
    if (!header_seen) {
      if (line != kHeader) bad(at + "header = '" + printable(line) + "': must be " + kHeader);
      header_seen = true;
      continue;
    }
    const std::vector<std::string> f = split(line);
    if (f.size() != 5)
      bad(at + std::to_string(f.size()) + " fields: each row has 5 (" + kHeader + ")");
    auto field_error = [&](const char* name, const std::string& value, const std::string& why) {
      bad(at + "field " + name + " = '" + printable(value) + "': " + why);
    };
    auto number = [&](const char* name, const std::string& text) {
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size())
        field_error(name, text, "not a number");
      if (!std::isfinite(v)) field_error(name, text, "not a finite number");
      return v;
    };
    const std::string& scene_name = f[0];
    const std::string& edge_name = f[1];
    const std::string& kind = f[2];
    if (!is_target_scene(scene_name))
      field_error("scene", scene_name, "must be four_corner, two_corner or two_corner_slack");
    if (kind != "point" && kind != "coeff" && kind != "lab_point" && kind != "pin")
      field_error("kind", kind, "must be point, coeff, lab_point or pin");
    const bool scene_pin = kind == "pin" && hanging_scene(scene_name);
    if (scene_pin && !edge_name.empty())
      field_error("edge", edge_name, "pins of " + scene_name + " belong to the scene: leave empty");
    if (!scene_pin && !edge_side_from_name(edge_name))
      field_error("edge", edge_name, "must be top, bottom, left or right");
    const double a = number("a", f[3]);
    const double b = number("b", f[4]);

    TargetScene* scene = nullptr;
    for (TargetScene& s : target.scenes)
      if (s.name == scene_name) scene = &s;
    if (!scene) {
      scene = &target.scenes.emplace_back();
      scene->name = scene_name;
      scene_line[scene_name] = line_no;
    }
    if (scene_pin) {
      if (scene->pins.size() == 2) field_error("kind", kind, "a third pin for " + scene_name);
      if (scene->pins.empty()) scene_line[scene_name] = line_no;
      scene->pins.push_back({a, b});
      continue;
    }
    TargetEdge* edge = nullptr;
    for (TargetEdge& e : scene->edges)
      if (e.name == edge_name) edge = &e;
    if (!edge) {
      edge = &scene->edges.emplace_back();
      edge->name = edge_name;
    }
    Pending& p = pending[{scene_name, edge_name}];
    if (p.first_line == 0) p.first_line = line_no;
    if (kind == "pin") {  // a four_corner corner: lab data for this edge
      if (p.kind_known && edge->kind != TargetKind::LabPoints)
        field_error("kind", kind,
                    "edge already has " + std::string(kind_name(edge->kind)) +
                        " rows; pins go with lab_point rows");
      if (edge->pins.size() == 2) field_error("kind", kind, "a third pin for edge " + edge_name);
      edge->pins.push_back({a, b});
      continue;
    }
    const TargetKind row_kind = kind == "point"   ? TargetKind::Points
                                : kind == "coeff" ? TargetKind::Coefficients
                                                  : TargetKind::LabPoints;
    if (!p.kind_known && !edge->pins.empty() && row_kind != TargetKind::LabPoints)
      field_error("kind", kind, "edge already has pin rows; pins go with lab_point rows");
    if (p.kind_known && row_kind != edge->kind)
      field_error("kind", kind,
                  "edge " + edge_name + " of " + scene_name + " already has " +
                      kind_name(edge->kind) + " rows: one kind per edge");
    p.kind_known = true;
    edge->kind = row_kind;
    switch (row_kind) {
      case TargetKind::Points:
        edge->points.s.push_back(a);
        edge->points.d.push_back(b);
        break;
      case TargetKind::Coefficients: {
        if (a != std::floor(a) || a < 0 || a > kEdgePolynomialDegree)
          field_error("a", f[3], "a power must be an integer 0..4");
        const int power = static_cast<int>(a);
        if (!p.powers.insert(power).second) field_error("a", f[3], "power given twice");
        edge->coefficients[power] = b;
        break;
      }
      case TargetKind::LabPoints:
        edge->lab_points.push_back({a, b});
        break;
    }
  }
  if (!header_seen) bad(path + ": empty target file: the header must be " + kHeader);
  if (target.scenes.empty()) bad(path + ": no data rows after the header");

  for (const TargetScene& scene : target.scenes) {
    std::vector<std::string> edge_at;
    for (const TargetEdge& edge : scene.edges) {
      const Pending& p = pending.at({scene.name, edge.name});
      edge_at.push_back(path + ":" + std::to_string(p.first_line) + ": ");
      if (!p.kind_known)
        bad(edge_at.back() + where(scene, edge) + "pin rows but no lab_point rows");
      if (edge.kind == TargetKind::Coefficients && p.powers.size() != kCoefficientCount)
        bad(edge_at.back() + where(scene, edge) + "field a: " + std::to_string(p.powers.size()) +
            " coeff rows: need powers 0..4 once each");
    }
    checked_fits(scene, edge_at, path + ":" + std::to_string(scene_line.at(scene.name)) + ": ");
  }
  return target;
}

std::optional<bool> sags_upward(const EdgeFit& edge, const std::string& scene) {
  const bool side = scene != "four_corner" && (edge.name == "left" || edge.name == "right");
  const std::vector<double>& along = side ? edge.points.s : edge.points.d;
  if (!along.empty()) {
    double sum = 0.0;
    for (double v : along) sum += v;
    return sum < 0.0;
  }
  if (side) return std::nullopt;
  double d = 0.0, power = 1.0;  // d(0.5) of the given coefficients
  for (double p : edge.coefficients) d += p * power, power *= 0.5;
  return d < 0.0;
}

void write_target_csv(const Target& target, const std::string& path,
                      const std::vector<std::string>& comment) {
  target.validate();
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out.precision(17);
  for (const std::string& c : comment) out << "# " << c << '\n';
  out << kHeader << '\n';
  for (const TargetScene& scene : target.scenes) {
    for (CameraPoint p : scene.pins)
      out << scene.name << ",,pin," << p.x_mm << ',' << p.z_mm << '\n';
    for (const TargetEdge& edge : scene.edges) {
      const std::string row = scene.name + "," + edge.name + ",";
      for (CameraPoint p : edge.pins) out << row << "pin," << p.x_mm << ',' << p.z_mm << '\n';
      for (CameraPoint p : edge.lab_points)
        out << row << "lab_point," << p.x_mm << ',' << p.z_mm << '\n';
      if (edge.kind == TargetKind::Coefficients)
        for (size_t i = 0; i < edge.coefficients.size(); ++i)
          out << row << "coeff," << i << ',' << edge.coefficients[i] << '\n';
      for (size_t k = 0; k < edge.points.s.size(); ++k)
        out << row << "point," << edge.points.s[k] << ',' << edge.points.d[k] << '\n';
    }
  }
  out.close();  // buffered text that cannot be written fails here (a full disk)
  if (!out) throw std::runtime_error(std::strerror(errno));  // the caller names the file
}

}  // namespace knitsim
