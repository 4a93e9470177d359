#include "models/knit_clamps.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "src/core/invalid_field.hpp"

namespace knitsim {

namespace {

constexpr const char* kKey = "knit.clamps";
constexpr const char* kSyntax =
    "each clamp (separated by ';') is bottom, top, left, right, wales A-B or courses A-B, "
    "then fixed, move DX,DY (m), path S:DX,DY ... with 0 < S <= 1 increasing, or force "
    "FX,FY[,FZ] (N)";
constexpr const char* kForcesKey = "knit.forces";
constexpr const char* kForcesSyntax =
    "each force (separated by ';') is wale W course C lower|upper FX,FY[,FZ] (N)";

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

[[noreturn]] void refuse(const std::string& clamp, const std::string& why,
                         const char* key = kKey) {
  throw InvalidField(key, clamp, why);
}

bool read_number(const std::string& s, double& v) {
  if (s.empty()) return false;
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(v);
}

bool read_index(const std::string& s, int& v) {
  if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos)
    return false;
  v = std::atoi(s.c_str());
  return true;
}

// "DX,DY" -> (DX, DY, 0), m.
Vec3 read_displacement(const std::string& clamp, const std::string& s) {
  const auto comma = s.find(',');
  double dx = 0.0, dy = 0.0;
  if (comma == std::string::npos || !read_number(s.substr(0, comma), dx) ||
      !read_number(s.substr(comma + 1), dy))
    refuse(clamp, "a displacement is DX,DY in m (two finite numbers), not \"" + s + "\"");
  return {dx, dy, 0.0};
}

// "FX,FY[,FZ]" -> N, each component finite and within kMaxKnitForce, not all zero.
Vec3 read_force(const std::string& what, const std::string& s, const char* key) {
  std::vector<double> f;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = std::min(s.find(',', start), s.size());
    double v = 0.0;
    if (!read_number(s.substr(start, comma - start), v) || f.size() == 3) {
      f.clear();
      break;
    }
    f.push_back(v);
    if (comma == s.size()) break;
    start = comma + 1;
  }
  std::ostringstream range;
  range << kMaxKnitForce;
  if (f.size() < 2)
    refuse(what, "a force is FX,FY or FX,FY,FZ in N (finite numbers), not \"" + s + "\"", key);
  f.resize(3, 0.0);
  for (double v : f)
    if (!(std::abs(v) <= kMaxKnitForce))
      refuse(what, "a force's components must be in [-" + range.str() + ", " + range.str() +
                       "] N", key);
  if (f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0)
    refuse(what, "a force needs a non-zero component (its loaded directions); a clamp without "
                 "one is fixed", key);
  return {f[0], f[1], f[2]};
}

KnitClampSpec parse_one(const std::string& clamp) {
  KnitClampSpec c;
  c.text = clamp;
  std::istringstream in(clamp);
  std::string word;
  in >> word;
  using W = KnitClampSpec::Where;
  if (word == "bottom") c.where = W::Bottom;
  else if (word == "top") c.where = W::Top;
  else if (word == "left") c.where = W::Left;
  else if (word == "right") c.where = W::Right;
  else if (word == "wales" || word == "wale" || word == "courses" || word == "course") {
    c.where = word[0] == 'w' ? W::Wales : W::Courses;
    std::string range;
    in >> range;
    const auto dash = range.find('-');
    const bool ok = dash == std::string::npos
                        ? read_index(range, c.first) && (c.last = c.first, true)
                        : read_index(range.substr(0, dash), c.first) &&
                              read_index(range.substr(dash + 1), c.last);
    if (!ok || c.last < c.first)
      refuse(clamp, word + " takes A-B or A, whole numbers from 0 with A <= B");
  } else {
    refuse(clamp, kSyntax);
  }
  std::string how;
  if (!(in >> how) || how == "fixed") {
    if (in >> word) refuse(clamp, kSyntax);
    return c;
  }
  if (how == "move") {
    std::string u;
    if (!(in >> u) || (in >> word)) refuse(clamp, "move takes one displacement DX,DY (m)");
    c.path.s = {1.0};
    c.path.u = {read_displacement(clamp, u)};
    return c;
  }
  if (how == "force") {
    std::string f;
    if (!(in >> f) || (in >> word)) refuse(clamp, "force takes one force FX,FY[,FZ] (N)");
    c.force = read_force(clamp, f, kKey);
    return c;
  }
  if (how != "path") refuse(clamp, kSyntax);
  std::string knot;
  while (in >> knot) {
    const auto colon = knot.find(':');
    double s = 0.0;
    if (colon == std::string::npos || !read_number(knot.substr(0, colon), s))
      refuse(clamp, "a path's knot is S:DX,DY, not \"" + knot + "\"");
    const double before = c.path.s.empty() ? 0.0 : c.path.s.back();
    if (!(s > before && s <= 1.0))
      refuse(clamp, "a path's load fractions S must increase within (0, 1]; " +
                        knot.substr(0, colon) + " follows " + (c.path.s.empty() ? "0" : [&] {
                          std::ostringstream os;
                          os << before;
                          return os.str();
                        }()));
    c.path.s.push_back(s);
    c.path.u.push_back(read_displacement(clamp, knot.substr(colon + 1)));
  }
  if (c.path.s.empty()) refuse(clamp, "path takes one or more knots S:DX,DY");
  return c;
}

KnitPointForce parse_point_force(const std::string& text) {
  KnitPointForce f;
  f.text = text;
  std::istringstream in(text);
  std::string w, wale, c, course, which, force, extra;
  if (!(in >> w >> wale >> c >> course >> which >> force) || (in >> extra) || w != "wale" ||
      c != "course" || !read_index(wale, f.wale) || !read_index(course, f.course) ||
      (which != "lower" && which != "upper"))
    refuse(text, kForcesSyntax, kForcesKey);
  f.upper = which == "upper";
  f.force = read_force(text, force, kForcesKey);
  return f;
}

// The ';'-separated items of text, trimmed, empty ones dropped.
std::vector<std::string> items(const std::string& text) {
  std::vector<std::string> out;
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t end = std::min(text.find(';', start), text.size());
    const std::string item = trim(text.substr(start, end - start));
    if (!item.empty()) out.push_back(item);
    start = end + 1;
  }
  return out;
}

}  // namespace

std::vector<KnitPointForce> parse_knit_point_forces(const std::string& text) {
  std::vector<KnitPointForce> out;
  for (const std::string& item : items(text)) out.push_back(parse_point_force(item));
  return out;
}

std::string knit_point_forces_text(const std::vector<KnitPointForce>& forces) {
  std::string s;
  for (std::size_t k = 0; k < forces.size(); ++k) s += (k ? "; " : "") + forces[k].text;
  return s;
}

std::vector<KnitClampSpec> parse_knit_clamps(const std::string& text) {
  std::vector<KnitClampSpec> out;
  for (const std::string& clamp : items(text)) out.push_back(parse_one(clamp));
  return out;
}

std::string knit_clamps_text(const std::vector<KnitClampSpec>& clamps) {
  std::string s;
  for (std::size_t k = 0; k < clamps.size(); ++k) s += (k ? "; " : "") + clamps[k].text;
  return s;
}

}  // namespace knitsim
