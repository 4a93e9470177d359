#include "models/knit_loops.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "src/core/invalid_field.hpp"

namespace knitsim {

namespace {

// A tuck's head lies this many loop radii behind the head of the held loop, kStackedTuckStep
// more for each course above it on the same needle up to the next knit (a tuck or a miss: the
// lowest tuck of a stack deepest, a tuck under a float behind it); its legs come forward by
// kTuckLegForward r (a knit loop's by 2 r). Header: "Tuck and held-loop geometry".
constexpr double kTuckHeadDepth = 3.0;
constexpr double kStackedTuckStep = 2.0;
constexpr double kTuckLegForward = 1.0;
constexpr double kKnitLegForward = 2.0;

const char* const kAcceptedLetters = "accepted letters: K knit, T tuck, M miss";
const char* const kChartRules =
    "chart rules: no tuck or miss in the bottom course or on an edge wale, no miss in the top "
    "course";

// "chart row R (line L), column C: <what> (<accepts>)" with R counted from the top as drawn,
// L the row's line in the file (row_lines, top row first; without them no line).
[[noreturn]] void bad_stitch(const KnitChart& chart, int wale, int course, const std::string& what,
                             const char* accepts, const std::vector<int>* row_lines) {
  const int row = chart.courses - course;
  std::ostringstream os;
  os << "chart row " << row;
  if (row_lines != nullptr && row <= static_cast<int>(row_lines->size()))
    os << " (line " << (*row_lines)[row - 1] << ")";
  os << ", column " << wale + 1 << ": " << what << " (" << accepts << ")";
  throw std::invalid_argument(os.str());
}

std::string describe_char(char c) {
  const auto u = static_cast<unsigned char>(c);
  std::ostringstream os;
  if (c == ' ') {
    os << "a space";
  } else if (c == '\t') {
    os << "a tab";
  } else if (u >= 33 && u < 127) {
    os << "'" << c << "'";
  } else {
    os << "byte 0x" << std::hex << static_cast<int>(u);
  }
  return os.str();
}

Vec3 unit(Vec3 v) {
  const double l = norm(v);
  return l > 0.0 ? (1.0 / l) * v : v;
}
Vec3 lerp(Vec3 a, Vec3 b, double t) { return a + t * (b - a); }

// Local frame of wale i in one course (see the header).
struct Frame {
  Vec3 B, ex, ey, n;
};

// Frames of every wale of course j and its W + 1 sinker points (sinker k lies between wales
// k - 1 and k; sinkers 0 and W are the course ends).
struct CourseGeometry {
  std::vector<Frame> frames;
  std::vector<Vec3> sinkers;
};

CourseGeometry course_geometry(const KnitModel& m, const std::vector<Vec3>& x, int j) {
  const int W = m.chart.wales;
  const double r = m.params.loop_radius;
  CourseGeometry g;
  g.frames.resize(W);
  auto is_knit = [&](int i) { return m.chart.at(i, j) == Stitch::Knit; };
  // Nearest knits to the left and right (the edge wales are knits) and the weight of the right.
  std::vector<int> left(W), right(W);
  for (int i = 0, last = 0; i < W; ++i) left[i] = last = is_knit(i) ? i : last;
  for (int i = W - 1, last = W - 1; i >= 0; --i) right[i] = last = is_knit(i) ? i : last;
  auto weight = [&](int i) {
    return right[i] == left[i] ? 0.0 : double(i - left[i]) / double(right[i] - left[i]);
  };

  for (int i = 0; i < W; ++i)
    if (is_knit(i)) g.frames[i].B = x[m.loops[m.loop(i, j)].lower];
  for (int i = 0; i < W; ++i)
    if (!is_knit(i)) g.frames[i].B = lerp(g.frames[left[i]].B, g.frames[right[i]].B, weight(i));

  for (int i = 0; i < W; ++i) {
    const int l = m.loop(i, j);
    if (l < 0) continue;  // misses: interpolated below
    Frame& f = g.frames[i];
    // Planar tuck: the frame of the course between its knits, not of U - B, which the held loop
    // shrinks to zero in the top course (see the header).
    if (m.chart.at(i, j) == Stitch::Tuck && !m.params.out_of_plane_bending()) {
      const Vec3 d = g.frames[right[i]].B - g.frames[left[i]].B;
      f.ex = unit(Vec3{d.x, d.y, 0.0});
      f.ey = cross(Vec3{0.0, 0.0, 1.0}, f.ex);
      f.n = cross(f.ex, f.ey);
      continue;
    }
    f.ey = unit(x[m.loops[l].upper] - f.B);
    // Planar (no out-of-plane bending): e_x is e_y turned by -90 degrees in the plane, so n = +z
    // always; from the course direction d, a loop whose e_y turns past it (its upper point pulled
    // below its base) would be mirrored through the fabric (n = -z), its yarn jumping through its
    // neighbours. With the bending the points leave the plane and e_x follows d (the planar e_x
    // where d is degenerate).
    Vec3 ex = cross(f.ey, Vec3{0.0, 0.0, 1.0});
    if (m.params.out_of_plane_bending()) {
      Vec3 d{1.0, 0.0, 0.0};
      if (W > 1) d = g.frames[std::min(i + 1, W - 1)].B - g.frames[std::max(i - 1, 0)].B;
      const Vec3 across = d - dot(d, f.ey) * f.ey;
      if (norm(across) > 1e-12 * norm(d)) ex = across;
    }
    f.ex = unit(ex);
    f.n = cross(f.ex, f.ey);
  }
  for (int i = 0; i < W; ++i) {
    if (m.loop(i, j) >= 0) continue;
    const Frame &a = g.frames[left[i]], &b = g.frames[right[i]];
    Frame& f = g.frames[i];
    f.ex = unit(lerp(a.ex, b.ex, weight(i)));
    f.ey = unit(lerp(a.ey, b.ey, weight(i)));
    f.n = unit(lerp(a.n, b.n, weight(i)));
  }

  g.sinkers.resize(W + 1);
  const Frame &first = g.frames.front(), &last = g.frames.back();
  g.sinkers[0] = first.B - 4.0 * r * first.ex - r * first.ey - r * first.n;
  g.sinkers[W] = last.B + 4.0 * r * last.ex - r * last.ey - r * last.n;
  for (int k = 1; k < W; ++k) {
    const Frame &a = g.frames[k - 1], &b = g.frames[k];
    g.sinkers[k] = 0.5 * (a.B + b.B) - (0.5 * r) * (a.ey + b.ey) - (0.5 * r) * (a.n + b.n);
  }
  return g;
}

// T0..T8 of loop l (T1, T7 only for knits), in ascending k.
LoopTypeValues loop_type_values(const KnitModel& m, const CourseGeometry& g,
                                const std::vector<Vec3>& x, int l) {
  const KnitLoop& loop = m.loops[l];
  const double r = m.params.loop_radius;
  const Frame& f = g.frames[loop.wale];
  const Vec3 P = x[loop.upper];
  // Courses above a tuck on its needle up to the next knit (tucks or misses; they hang from, or
  // float past, the same upper point): their yarns pass in front of its legs.
  int above = 0;
  if (loop.kind == Stitch::Tuck)
    for (int c = loop.course + 1; c < m.chart.courses && m.chart.at(loop.wale, c) != Stitch::Knit;
         ++c)
      ++above;
  const double back =
      loop.kind == Stitch::Tuck ? (kTuckHeadDepth + kStackedTuckStep * above) * r : 0.0;
  const double forward = loop.kind == Stitch::Tuck ? kTuckLegForward : kKnitLegForward;
  const Vec3 T0 = g.sinkers[loop.wale], T8 = g.sinkers[loop.wale + 1];
  const Vec3 T3 = P - 3.0 * r * f.ex - back * f.n;
  const Vec3 T4 = P + r * f.ey - (r + back) * f.n;
  const Vec3 T5 = P + 3.0 * r * f.ex - back * f.n;
  const Vec3 T2 = 0.5 * (T0 + T4) + forward * r * f.n;
  const Vec3 T6 = 0.5 * (T4 + T8) + forward * r * f.n;
  // Leg points: s per leg for a knit loop spanning s courses, |P - B| / s apart along e_y and
  // centred on T2 (T6); one for a tuck.
  const int legs = loop.kind == Stitch::Knit ? m.points[loop.upper].level - loop.course : 1;
  const Vec3 stride = (norm(P - f.B) / legs) * f.ey;
  auto leg = [&](Vec3 middle, int q) { return middle + (q - 0.5 * (legs - 1)) * stride; };
  LoopTypeValues out;
  auto put = [&](int k, Vec3 t) {
    out.k.push_back(k);
    out.t.push_back(t);
  };
  put(0, T0);
  if (loop.kind == Stitch::Knit) put(1, f.B - r * f.ex);
  for (int q = 0; q < legs; ++q) put(2, leg(T2, q));
  put(3, T3);
  put(4, T4);
  put(5, T5);
  for (int q = legs - 1; q >= 0; --q) put(6, leg(T6, q));
  if (loop.kind == Stitch::Knit) put(7, f.B + r * f.ex);
  put(8, T8);
  return out;
}

void check_positions(const KnitModel& m, const std::vector<Vec3>& x) {
  if (x.size() != m.points.size()) {
    std::ostringstream os;
    os << "knit geometry: " << x.size() << " positions given, the model has " << m.points.size()
       << " points";
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

void KnitChart::validate(const std::vector<int>* row_lines, bool repeat) const {
  if (wales < 1 || courses < 1)
    throw std::invalid_argument(std::string("chart: no stitch rows (one line per course, top "
                                            "course first; ") +
                                kAcceptedLetters + ")");
  if (stitches.size() != static_cast<size_t>(wales) * courses) {
    std::ostringstream os;
    os << "chart: " << stitches.size() << " stitches for " << wales << " wales x " << courses
       << " courses";
    throw std::invalid_argument(os.str());
  }
  for (int j = 0; j < courses; ++j)
    for (int i = 0; i < wales; ++i) {
      const Stitch s = at(i, j);
      if (s != Stitch::Knit && s != Stitch::Tuck && s != Stitch::Miss)
        bad_stitch(*this, i, j, "not a stitch", kAcceptedLetters, row_lines);
      if (s == Stitch::Knit || repeat) continue;
      const std::string name = s == Stitch::Tuck ? "a tuck" : "a miss";
      auto broken = [&](const std::string& what) {
        bad_stitch(*this, i, j, name + what, kChartRules, row_lines);
      };
      if (j == 0) broken(" in the bottom course has no loop below to hold");
      if (i == 0 || i == wales - 1) broken(" on an edge wale leaves the yarn no loop to turn at");
      if (s == Stitch::Miss && j == courses - 1)
        broken(" in the top course leaves the held loop without an upper point");
    }
}

KnitChart parse_knit_chart(const std::string& text, bool repeat) {
  struct Row {
    std::string stitches;
    int line;
  };
  std::vector<Row> rows;
  std::istringstream in(text);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line = line.substr(0, line.find('#'));
    const size_t begin = line.find_first_not_of(" \t\r");
    if (begin == std::string::npos) continue;
    const size_t end = line.find_last_not_of(" \t\r");
    rows.push_back({line.substr(begin, end - begin + 1), number});
  }
  KnitChart chart;
  chart.courses = static_cast<int>(rows.size());
  chart.wales = rows.empty() ? 0 : static_cast<int>(rows[0].stitches.size());
  if (rows.empty()) chart.validate();  // throws: no rows
  chart.stitches.resize(static_cast<size_t>(chart.wales) * chart.courses);
  for (int row = 0; row < chart.courses; ++row) {
    const Row& r = rows[row];
    const int course = chart.courses - 1 - row;
    for (int col = 0; col < static_cast<int>(r.stitches.size()); ++col) {
      const char c = r.stitches[col];
      if (c != 'K' && c != 'T' && c != 'M') {
        std::ostringstream os;
        os << "chart row " << row + 1 << " (line " << r.line << "), column " << col + 1 << ": "
           << describe_char(c) << " is not a stitch (" << kAcceptedLetters << ")";
        throw std::invalid_argument(os.str());
      }
    }
    if (static_cast<int>(r.stitches.size()) != chart.wales) {
      std::ostringstream os;
      os << "chart row " << row + 1 << " (line " << r.line << "): " << r.stitches.size()
         << " stitches, row 1 has " << chart.wales << "; every row needs one letter per wale ("
         << kAcceptedLetters << ")";
      throw std::invalid_argument(os.str());
    }
    for (int col = 0; col < chart.wales; ++col)
      chart.stitches[static_cast<size_t>(course) * chart.wales + col] =
          static_cast<Stitch>(r.stitches[col]);
  }
  std::vector<int> row_lines;
  for (const Row& r : rows) row_lines.push_back(r.line);
  chart.validate(&row_lines, repeat);
  return chart;
}

void KnitParams::validate() const {
  if (!(loop_radius > 0.0) || !std::isfinite(loop_radius))
    bad_field("knit.loop_radius", loop_radius, "must be > 0 m");
  if (!(wale_stiffness > 0.0) || !std::isfinite(wale_stiffness))
    bad_field("knit.wale_stiffness", wale_stiffness, "must be > 0 N/m");
  if (!(course_stiffness > 0.0) || !std::isfinite(course_stiffness))
    bad_field("knit.course_stiffness", course_stiffness, "must be > 0 N/m");
  if (!(damping >= 0.0) || !std::isfinite(damping))
    bad_field("knit.damping", damping, "must be >= 0 N s/m");
  if (!(areal_density > 0.0) || !std::isfinite(areal_density))
    bad_field("knit.areal_density", areal_density, "must be > 0 g/m^2");
  if (!(stabiliser_ratio >= 0.0 && stabiliser_ratio <= 1.0))
    bad_field("knit.stabiliser", stabiliser_ratio, "must be in [0, 1]");
  if (!(bending_ratio >= 0.0 && bending_ratio <= 10.0))
    bad_field("knit.bending", bending_ratio, "must be in [0, 10]");
  if (!(contact_ratio >= 0.0 && contact_ratio <= 100.0))
    bad_field("knit.contact", contact_ratio, "must be in [0, 100]");
  if (contact_ratio > 0.0 && bending_ratio > 0.0 && !mechanism())
    bad_field("knit.bending", bending_ratio,
              "must be 0 with knit.contact > 0 (the contact, on by default, keeps the chart in its "
              "plane; set knit.contact=0 to bend it out of the plane)");
  if (!(load_steps >= 0 && load_steps <= 1000))
    bad_field("knit.load_steps", load_steps, "must be a whole number in [0, 1000]");
  if (max_points < 1) bad_field("max_points", static_cast<double>(max_points), "must be >= 1");
}

const char* to_string(KnitNetwork network) {
  return network == KnitNetwork::Paper ? "paper" : "stabilised";
}

KnitNetwork parse_knit_network(const std::string& name) {
  if (name == "stabilised") return KnitNetwork::Stabilised;
  if (name == "paper") return KnitNetwork::Paper;
  throw std::invalid_argument("knit.network = " + name +
                              ": must be stabilised (the default) or paper (paper 2's network)");
}

const char* to_string(KnitSpringKind kind) {
  switch (kind) {
    case KnitSpringKind::Wale:
      return "wale";
    case KnitSpringKind::Course:
      return "course";
    case KnitSpringKind::Tuck:
      return "tuck";
    case KnitSpringKind::Float:
      return "float";
    case KnitSpringKind::Shear:
      return "shear";
    case KnitSpringKind::Bending:
      return "bending";
  }
  return "unknown";
}

int KnitModel::count(KnitSpringKind kind) const {
  return static_cast<int>(std::count(spring_kind.begin(), spring_kind.end(), kind));
}

double knit_memory_estimate(int wales, int courses, bool contact) {
  const double stitches = static_cast<double>(wales) * courses;
  return kKnitMemoryBase +
         stitches * (contact ? kKnitMemoryPerStitchContact : kKnitMemoryPerStitch);
}

namespace {

// A "Key:   N kB" line of a /proc file, in bytes; -1 if absent.
double proc_kb(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + ":", 0) == 0) {
      std::istringstream fields(line.substr(key.size() + 1));
      double kb = -1.0;
      fields >> kb;
      return kb >= 0.0 ? 1024.0 * kb : -1.0;
    }
  return -1.0;
}

}  // namespace

MemoryCap knit_memory_cap() {
  MemoryCap cap{std::numeric_limits<double>::infinity(), "no limit known"};
  const double available = proc_kb("/proc/meminfo", "MemAvailable");
  if (available >= 0.0) cap = {available, "MemAvailable"};
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    const double used = std::max(0.0, proc_kb("/proc/self/status", "VmSize"));
    const double room = static_cast<double>(as.rlim_cur) - used - kKnitVirtualAllowance;
    if (room < cap.bytes) cap = {std::max(0.0, room), "the address-space limit (ulimit -v)"};
  }
  return cap;
}

std::vector<Vec3> KnitModel::rest_positions() const {
  std::vector<Vec3> x(points.size());
  for (size_t k = 0; k < points.size(); ++k) x[k] = points[k].rest;
  return x;
}

namespace {

// build_knit's steps (docs/knit.md, "The model as built"), in order.

// The chart and parameters checked, and what the model would need refused before allocating.
void check_buildable(const KnitChart& chart, const KnitParams& p) {
  p.validate();
  chart.validate();
  if (p.yarn_contact())  // floats longer than the contact can hold: refused up front
    for (int j = 0; j < chart.courses; ++j)
      for (int i = 0, run = 0; i < chart.wales; ++i) {
        run = chart.at(i, j) == Stitch::Miss ? run + 1 : 0;
        if (run > kMaxContactFloat)
          bad_stitch(chart, i - run + 1, j,
                     "a float of more than " + std::to_string(kMaxContactFloat) +
                         " misses from here on, with yarn contact",
                     "the model holds floats of at most 7 wales with contact; longer ones end "
                     "in solver_failure; knit.contact = 0 runs them without contact",
                     nullptr);
      }
  const int W = chart.wales, C = chart.courses;
  if (static_cast<double>(W) * (C + 1) > static_cast<double>(p.max_points)) {
    std::ostringstream os;
    os << "chart: " << W << " wales x " << C << " courses gives up to " << W * (C + 1.0)
       << " points, over the cap of " << p.max_points;
    throw std::invalid_argument(os.str());
  }
  // refused before any of it is allocated (docs/knit.md, "Memory")
  const double need = knit_memory_estimate(W, C, p.yarn_contact());
  const MemoryCap cap = knit_memory_cap();
  if (need > cap.bytes) {
    std::ostringstream os;
    os << "chart: " << W << " wales x " << C << " courses needs about "
       << std::llround(need / 1048576.0) << " MB" << (p.yarn_contact() ? " with yarn contact" : "")
       << ", more than the " << std::llround(cap.bytes / 1048576.0) << " MB available ("
       << cap.source << "; docs/knit.md, \"Memory\")";
    if (p.yarn_contact())
      os << "; with knit.contact = 0 about "
         << std::llround(knit_memory_estimate(W, C, false) / 1048576.0) << " MB";
    throw std::invalid_argument(os.str());
  }
}

// The interlacing points: every point of the edge levels, and a knit's lower point inside.
void make_points(const KnitChart& chart, const KnitParams& p, std::vector<KnitPoint>& points,
                 std::vector<int>& point_at) {
  const int W = chart.wales, C = chart.courses;
  const double w = p.wale_spacing(), h = p.course_spacing();
  point_at.assign(static_cast<size_t>(W) * (C + 1), -1);
  for (int L = 0; L <= C; ++L)
    for (int i = 0; i < W; ++i)
      if (L == 0 || L == C || chart.at(i, L) == Stitch::Knit) {
        point_at[static_cast<size_t>(L) * W + i] = static_cast<int>(points.size());
        points.push_back({i, L, Vec3{i * w, L * h, 0.0}});
      }
}

// The loops: one per knit or tuck, from its lower point (a knit's) to the next level that has
// a point on its wale (a held loop's upper point lies above the next level).
void make_loops(const KnitChart& chart, const std::vector<int>& point_at,
                std::vector<KnitLoop>& loops, std::vector<int>& loop_at) {
  const int W = chart.wales, C = chart.courses;
  auto point = [&](int i, int L) { return point_at[static_cast<size_t>(L) * W + i]; };
  loop_at.assign(static_cast<size_t>(W) * C, -1);
  for (int j = 0; j < C; ++j)
    for (int i = 0; i < W; ++i) {
      const Stitch s = chart.at(i, j);
      if (s == Stitch::Miss) continue;
      int L = j + 1;
      while (point(i, L) < 0) ++L;  // the top level always exists
      loop_at[static_cast<size_t>(j) * W + i] = static_cast<int>(loops.size());
      loops.push_back({i, j, s, s == Stitch::Knit ? point(i, j) : -1, point(i, L)});
    }
}

// A spring of the network and its family.
struct SpringsBuilder {
  SpringNetworkSpec& spec;
  std::vector<KnitSpringKind>& kinds;
  void add(int a, int b, double rest, double k, KnitSpringKind kind) {
    spec.springs.push_back({a, b, rest, k});
    kinds.push_back(kind);
  }
};

// Paper 2's springs: a wale spring per knit loop, and along each course a course, tuck or float
// spring between neighbouring loops' anchors.
void add_yarn_springs(const KnitChart& chart, const KnitParams& p,
                      const std::vector<KnitLoop>& loops, const std::vector<int>& loop_at,
                      SpringsBuilder& net) {
  const int W = chart.wales, C = chart.courses;
  const double w = p.wale_spacing(), h = p.course_spacing();
  const double k_tuck = 1.0 / (1.0 / p.wale_stiffness + 1.0 / p.course_stiffness);
  for (int j = 0; j < C; ++j) {
    const KnitLoop* prev = nullptr;
    for (int i = 0; i < W; ++i) {
      const int l = loop_at[static_cast<size_t>(j) * W + i];
      if (l < 0) continue;
      const KnitLoop& cur = loops[l];
      if (cur.kind == Stitch::Knit)
        net.add(cur.lower, cur.upper, h, p.wale_stiffness, KnitSpringKind::Wale);
      if (prev != nullptr) {
        auto anchor = [](const KnitLoop& a) { return a.kind == Stitch::Knit ? a.lower : a.upper; };
        auto nominal_height = [&](const KnitLoop& a) {
          return (a.kind == Stitch::Knit ? j : j + 1) * h;
        };
        const bool tuck = prev->kind == Stitch::Tuck || cur.kind == Stitch::Tuck;
        const KnitSpringKind kind = cur.wale - prev->wale > 1 ? KnitSpringKind::Float
                                    : tuck                    ? KnitSpringKind::Tuck
                                                              : KnitSpringKind::Course;
        net.add(anchor(*prev), anchor(cur),
                std::hypot(w, nominal_height(cur) - nominal_height(*prev)),
                tuck ? k_tuck : p.course_stiffness, kind);
      }
      prev = &cur;
    }
  }
}

// The stabiliser (docs/knit.md, "Networks"): shear springs across each cell, bending springs
// over two levels and two wales, and with knit.bending > 0 the out-of-plane stencils.
void add_stabiliser(const KnitChart& chart, const KnitParams& p,
                    const std::vector<KnitPoint>& points, const std::vector<int>& point_at,
                    SpringsBuilder& net) {
  const int W = chart.wales, C = chart.courses;
  const double w = p.wale_spacing(), h = p.course_spacing();
  auto point = [&](int i, int L) { return point_at[static_cast<size_t>(L) * W + i]; };
  const double s = p.stabiliser_ratio;
  auto link = [&](int a, int b, double k, KnitSpringKind kind) {
    net.add(a, b, norm(points[b].rest - points[a].rest), k, kind);
  };
  // Out of the plane (knit.bending = b > 0): the yarn's bending rigidity B = b s k_w h^3 / 12
  // (s's basis, above) as quadratic stencils on the same triples and quads, zero on every rigid
  // motion of the flat rest lattice: second differences along wales (B / h^3) and levels
  // (B / w^3), and each quad's twist, B (w + h) / (w h)^2 (a torsional rigidity of order B in
  // the wale and course legs of one cell).
  const double B =
      p.out_of_plane_bending() ? p.bending_ratio * s * p.wale_stiffness * h * h * h / 12.0 : 0.0;
  auto stencil = [&](std::array<int, 4> ids, std::array<double, 4> weights, double k) {
    if (B > 0.0) net.spec.stencils.push_back({ids, weights, k});
  };
  for (int L = 0; L <= C; ++L)
    for (int i = 0; i < W; ++i) {
      const int a = point(i, L);
      if (a < 0) continue;
      if (i + 1 < W && L + 1 <= C) {
        const int b = point(i + 1, L), c = point(i, L + 1), d = point(i + 1, L + 1);
        if (b >= 0 && c >= 0 && d >= 0) {
          const double k = s * 0.5 * (p.wale_stiffness + p.course_stiffness);
          link(a, d, k, KnitSpringKind::Shear);
          link(b, c, k, KnitSpringKind::Shear);
          stencil({a, b, c, d}, {1.0, -1.0, -1.0, 1.0}, B * (w + h) / (w * h * w * h));
        }
      }
      if (L + 2 <= C && point(i, L + 1) >= 0 && point(i, L + 2) >= 0) {
        link(a, point(i, L + 2), s * p.wale_stiffness, KnitSpringKind::Bending);
        stencil({a, point(i, L + 1), point(i, L + 2), -1}, {1.0, -2.0, 1.0, 0.0}, B / (h * h * h));
      }
      if (i + 2 < W && point(i + 1, L) >= 0 && point(i + 2, L) >= 0) {
        link(a, point(i + 2, L), s * p.course_stiffness, KnitSpringKind::Bending);
        stencil({a, point(i + 1, L), point(i + 2, L), -1}, {1.0, -2.0, 1.0, 0.0}, B / (w * w * w));
      }
    }
}

// The clamps (knit.pins' edges first, then knit.clamps; models/knit_clamps.hpp) as the network's
// pins, at rest: each clamp's points not held by an earlier one, in point order. Throws
// InvalidField of knit.clamps for a selection the chart does not have.
std::vector<Clamp> hold_points(const KnitChart& chart, const KnitParams& p,
                               const std::vector<KnitPoint>& points, SpringNetworkSpec& spec) {
  const int W = chart.wales, C = chart.courses;
  using Where = KnitClampSpec::Where;
  std::vector<KnitClampSpec> specs;
  auto edge = [](Where where, const char* name) {
    KnitClampSpec c;
    c.where = where;
    c.text = name;
    return c;
  };
  if (p.pins == KnitPins::Bottom || p.pins == KnitPins::BottomAndTop)
    specs.push_back(edge(Where::Bottom, "bottom"));
  if (p.pins == KnitPins::Top || p.pins == KnitPins::BottomAndTop)
    specs.push_back(edge(Where::Top, "top"));
  const size_t from_pins = specs.size();
  specs.insert(specs.end(), p.clamps.begin(), p.clamps.end());
  std::vector<char> held(points.size(), 0);
  std::vector<Clamp> clamps;
  for (size_t c = 0; c < specs.size(); ++c) {
    const KnitClampSpec& k = specs[c];
    const bool edge_clamp = k.where != Where::Wales && k.where != Where::Courses;
    if (c >= from_pins && edge_clamp && C < 2)
      throw InvalidField("knit.clamps", k.text,
                         "a chart of one course has no edge apart from its loops: clamp a chart "
                         "of 2 or more courses (this one has 1)");
    if (k.where == Where::Wales && k.last >= W)
      throw InvalidField("knit.clamps", k.text,
                         "wales must be in 0 to " + std::to_string(W - 1) + " (the chart has " +
                             std::to_string(W) + ")");
    if (k.where == Where::Courses && k.last >= C)
      throw InvalidField("knit.clamps", k.text,
                         "courses must be in 0 to " + std::to_string(C - 1) + " (the chart has " +
                             std::to_string(C) + ")");
    Clamp clamp{k.text, {}, k.path, k.force};
    for (size_t id = 0; id < points.size(); ++id) {
      const KnitPoint& q = points[id];
      const bool in = k.where == Where::Bottom    ? q.level == 0
                      : k.where == Where::Top     ? q.level == C
                      : k.where == Where::Left    ? q.wale == 0
                      : k.where == Where::Right   ? q.wale == W - 1
                      : k.where == Where::Wales   ? q.wale >= k.first && q.wale <= k.last
                                                  : q.level >= k.first && q.level <= k.last + 1;
      if (!in || held[id]) continue;
      held[id] = 1;
      clamp.held.push_back(static_cast<int>(spec.pinned.size()));
      spec.pinned.push_back(static_cast<int>(id));
      spec.pin_paths.push_back({points[id].rest, points[id].rest, 0.0});
    }
    if (clamp.held.empty())
      throw InvalidField("knit.clamps", k.text,
                         "selects no point that an earlier clamp does not hold already");
    clamps.push_back(std::move(clamp));
  }
  if (spec.pinned.size() == points.size())
    throw InvalidField("knit.clamps", knit_clamps_text(p.clamps),
                       "the clamps hold every point of the chart; leave some free");
  return clamps;
}

// Masses (the areal density spread evenly over the points), damping, gravity along -y, and the
// static residual's force scale.
void set_masses_and_loads(const KnitChart& chart, const KnitParams& p, SpringNetworkSpec& spec,
                          const std::vector<KnitPoint>& points) {
  const int W = chart.wales, C = chart.courses;
  const double r = p.loop_radius, w = p.wale_spacing(), h = p.course_spacing();
  const int count = static_cast<int>(points.size());
  const double total_mass = p.areal_density * 1e-3 * (W * w) * (C * h);  // kg
  spec.positions.resize(count);
  for (int k = 0; k < count; ++k) spec.positions[k] = points[k].rest;
  spec.masses.assign(count, total_mass / count);
  spec.damping = p.damping;
  spec.elongation_limit = 0.0;
  const double g = 9.81;
  spec.gravity = p.gravity ? Vec3{0.0, -g, 0.0} : Vec3{0.0, 0.0, 0.0};
  spec.residual_force_scale = p.wale_stiffness * r;
  if (p.gravity)
    spec.residual_force_scale = std::min(spec.residual_force_scale, total_mass / count * g);
}

// The yarn contact (docs/knit.md, "Yarn contact") on the built network.
void attach_contact(KnitModel& m) {
  const double r = m.params.loop_radius;
  const KnitParams& p = m.params;
  YarnContactSpec contact;
  contact.points = knit_contact_points(m);
  // Renewal: the points are re-linearised about the current state where they stray from the
  // centreline's vertices by more than kContactRefreshTol r (models/yarn_contact.hpp).
  // Renewed points keep the particles they have at rest, so their Jacobian blocks stay in the
  // contact's fixed pattern.
  auto geometry = std::make_shared<const KnitModel>(m);
  using Particles = std::array<int, kContactParticles>;
  auto rest_particles = std::make_shared<std::vector<Particles>>();
  rest_particles->reserve(contact.points.size());
  for (const ContactPoint& q : contact.points) rest_particles->push_back(q.particles);
  auto course_start = std::make_shared<std::vector<std::size_t>>(m.chart.courses + 1, 0);
  for (const ContactPoint& q : contact.points) ++(*course_start)[q.yarn + 1];
  for (int j = 0; j < m.chart.courses; ++j) (*course_start)[j + 1] += (*course_start)[j];
  contact.exact = [geometry](const std::vector<Vec3>& positions, std::vector<Vec3>& out) {
    out.clear();
    for (const std::vector<Vec3>& course :
         yarn_polylines(*geometry, positions, kContactSamplesPerInterval).vertices)
      out.insert(out.end(), course.begin(), course.end());
  };
  contact.linearise = [geometry, rest_particles, course_start](const std::vector<Vec3>& positions,
                                                               int course) {
    return knit_contact_points(*geometry, positions, course,
                               rest_particles->data() + (*course_start)[course]);
  };
  // Linearised about the rest state (the network's initial one) they are these points: each
  // run makes its own, and the model keeps none (models/yarn_contact.hpp).
  contact.remake_at_start = true;
  contact.refresh_tol = kContactRefreshTol * r;
  contact.refresh_move = kContactRefreshMove * r;
  contact.step_cap = kContactStepCap * r;
  contact.touching = r;
  contact.core = kContactCore * r;
  contact.stiffness = p.contact_ratio * p.wale_stiffness;
  contact.same_yarn_gap = kSameYarnGap * r;
  m.contact = std::make_shared<ContactNetwork>(m.network, std::move(contact));
}

}  // namespace

KnitModel build_knit(const KnitChart& chart, const KnitParams& p) {
  check_buildable(chart, p);
  std::vector<KnitPoint> points;
  std::vector<int> point_at, loop_at;
  std::vector<KnitLoop> loops;
  make_points(chart, p, points, point_at);
  make_loops(chart, point_at, loops, loop_at);

  SpringNetworkSpec spec;
  std::vector<KnitSpringKind> kinds;
  SpringsBuilder net{spec, kinds};
  add_yarn_springs(chart, p, loops, loop_at, net);
  if (!p.mechanism()) add_stabiliser(chart, p, points, point_at, net);
  // Without the bending stencils the model is planar: the plane holds the points with k_w
  // (SpringNetwork's "Planar"; the value only sets the z block's scale, as z stays 0).
  if (!p.out_of_plane_bending()) spec.plane_stiffness = p.wale_stiffness;
  // The stabilised network's only zero-energy modes are its rigid motions (6 with the stencils,
  // the 3 in the plane without): a chart without pins or gravity is certified on the rest
  // (MechanicalSystem::free_floating, planar). Paper 2's mechanism has more.
  spec.free_floating = !p.mechanism();
  set_masses_and_loads(chart, p, spec, points);
  std::vector<Clamp> clamps = hold_points(chart, p, points, spec);

  KnitModel m{chart,
              p,
              std::move(points),
              std::move(loops),
              std::move(kinds),
              std::move(point_at),
              std::move(loop_at),
              SpringNetwork(std::move(spec)),
              nullptr,
              std::move(clamps)};
  if (p.yarn_contact()) attach_contact(m);
  return m;
}

std::vector<LoopTypeValues> type_value_points(const KnitModel& m,
                                              const std::vector<Vec3>& positions) {
  check_positions(m, positions);
  std::vector<LoopTypeValues> out(m.loops.size());
  for (int j = 0; j < m.chart.courses; ++j) {
    const CourseGeometry g = course_geometry(m, positions, j);
    for (int i = 0; i < m.chart.wales; ++i) {
      const int l = m.loop(i, j);
      if (l >= 0) out[l] = loop_type_values(m, g, positions, l);
    }
  }
  return out;
}

namespace {

// Course j's yarn points (course_yarn_points, one course; positions already checked).
std::vector<Vec3> course_yarn(const KnitModel& m, const std::vector<Vec3>& positions, int j) {
  const double r = m.params.loop_radius;
  const CourseGeometry g = course_geometry(m, positions, j);
  std::vector<Vec3> yarn;
  yarn.push_back(g.sinkers[0]);
  for (int i = 0; i < m.chart.wales; ++i) {
    const int l = m.loop(i, j);
    if (l >= 0) {
      const LoopTypeValues t = loop_type_values(m, g, positions, l);
      yarn.insert(yarn.end(), t.t.begin() + 1, t.t.end() - 1);  // without the sinkers
    } else {
      const Frame& f = g.frames[i];
      yarn.push_back(f.B - r * f.ey - r * f.n);  // the float behind the missed wale
    }
    yarn.push_back(g.sinkers[i + 1]);
  }
  return yarn;
}

}  // namespace

std::vector<std::vector<Vec3>> course_yarn_points(const KnitModel& m,
                                                  const std::vector<Vec3>& positions) {
  check_positions(m, positions);
  std::vector<std::vector<Vec3>> yarns(m.chart.courses);
  for (int j = 0; j < m.chart.courses; ++j) yarns[j] = course_yarn(m, positions, j);
  return yarns;
}

std::vector<NurbsCurve> course_curves(const KnitModel& m, const std::vector<Vec3>& positions) {
  std::vector<NurbsCurve> curves;
  for (const auto& yarn : course_yarn_points(m, positions))
    curves.push_back(interpolate_cubic(yarn, kYarnParametrization));
  return curves;
}

std::vector<CurveSamples> course_centerlines(const KnitModel& m, const std::vector<Vec3>& positions,
                                             int samples_per_point) {
  if (samples_per_point < 1) bad_field("samples_per_point", samples_per_point, "must be >= 1");
  std::vector<CurveSamples> out;
  for (const NurbsCurve& c : course_curves(m, positions)) {
    const int intervals = static_cast<int>(c.control.size()) - 1;
    out.push_back(sample_curve(c, samples_per_point * intervals + 1, Spacing::ArcLength));
  }
  return out;
}

namespace {

// C(u) of an interpolated (non-rational: weights 1) curve by de Boor's algorithm on the stack:
// the measure samples ~100k points per state of a 40 x 40 chart, and evaluate() also forms
// two derivatives. Equal to evaluate(curve, u).point to round-off.
Vec3 point_on(const NurbsCurve& c, double u) {
  const int p = c.degree;
  u = std::min(std::max(u, c.u_min()), c.u_max());
  const int s = find_span(static_cast<int>(c.control.size()), p, c.knots, u);
  Vec3 d[kMaxNurbsDegree + 1];
  for (int j = 0; j <= p; ++j) d[j] = c.control[s - p + j];
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      const int i = s - p + j;
      const double span = c.knots[i + p - r + 1] - c.knots[i];
      const double alpha = span == 0.0 ? 0.0 : (u - c.knots[i]) / span;
      d[j] = (1.0 - alpha) * d[j - 1] + alpha * d[j];
    }
  return d[p];
}

}  // namespace

namespace {

// The vertices of intervals k0..k1 - 1 of the polyline through yarn (see the header), and
// vertex k1 S, into v (v[0] is vertex k0 S).
void polyline_vertices(const std::vector<Vec3>& yarn, int S, int k0, int k1, std::vector<Vec3>& v) {
  const NurbsCurve curve = interpolate_cubic(yarn, kYarnParametrization);
  const std::vector<double> ubar = interpolation_parameters(yarn, kYarnParametrization);
  v.clear();
  v.reserve(S * (k1 - k0) + 1);
  for (int k = k0; k < k1; ++k)
    for (int s = 0; s < S; ++s)
      v.push_back(point_on(curve, ubar[k] + (ubar[k + 1] - ubar[k]) * s / S));
  v.push_back(point_on(curve, ubar[k1]));
}

// Course j's yarn polyline (see the header) into v, its arc lengths into arc.
void course_polyline(const std::vector<Vec3>& yarn, int S, std::vector<Vec3>& v,
                     std::vector<double>& arc) {
  polyline_vertices(yarn, S, 0, static_cast<int>(yarn.size()) - 1, v);
  arc.assign(v.size(), 0.0);
  for (size_t k = 1; k < v.size(); ++k) arc[k] = arc[k - 1] + norm(v[k] - v[k - 1]);
}

}  // namespace

YarnPolylines yarn_polylines(const KnitModel& m, const std::vector<Vec3>& positions,
                             int samples_per_interval) {
  if (samples_per_interval < 1)
    throw std::invalid_argument("yarn_polylines: samples_per_interval must be >= 1");
  YarnPolylines out;
  out.samples_per_interval = samples_per_interval;
  for (const std::vector<Vec3>& yarn : course_yarn_points(m, positions)) {
    out.vertices.emplace_back();
    out.arc.emplace_back();
    course_polyline(yarn, samples_per_interval, out.vertices.back(), out.arc.back());
  }
  return out;
}

std::vector<ContactPoint> knit_contact_points(
    const KnitModel& m, const std::vector<Vec3>& positions, int j,
    const std::array<int, kContactParticles>* particles_of) {
  check_positions(m, positions);
  if (j < 0 || j >= m.chart.courses)
    throw std::invalid_argument("knit_contact_points: no such course");
  const int W = m.chart.wales, C = m.chart.courses, S = kContactSamplesPerInterval;
  const double h = 1e-4 * m.params.loop_radius;  // central-difference step, m
  // A perturbed yarn point moves the interpolant by a factor ~0.27 less per interpolation point
  // away (a cubic's cardinal functions), so the differences interpolate only the yarn points the
  // particle moves and kWindow either side, and take the vertices within kReach of them: the
  // window's own ends change those derivatives by ~0.27^(kWindow - kReach) relative, and the
  // vertices further away have derivatives below ~0.27^kReach of the largest (~2e-6).
  constexpr int kWindow = 20, kReach = 10;
  std::vector<Vec3> pos = positions;
  std::vector<ContactPoint> out;
  std::vector<Vec3> v, vp, vm;
  std::vector<double> arc;
  const std::vector<Vec3> yarn = course_yarn(m, pos, j);
  const int n = static_cast<int>(yarn.size()) - 1;  // yarn points 0..n
  course_polyline(yarn, S, v, arc);
  // The particles course j's yarn depends on: levels j to the highest upper point of its loops.
  int top = j + 1;
  for (int i = 0; i < W; ++i)
    if (m.loop(i, j) >= 0) top = std::max(top, m.points[m.loops[m.loop(i, j)].upper].level);
  std::vector<int> ids;
  for (int L = j; L <= std::min(top, C); ++L)
    for (int i = 0; i < W; ++i)
      if (m.point(i, L) >= 0) ids.push_back(m.point(i, L));
  // Given particles_of (a renewal), each vertex's particles as indices into ids, in its order.
  std::vector<std::array<int, kContactParticles>> given(particles_of ? v.size() : 0, filled(-1));
  std::vector<char> used(ids.size(), particles_of == nullptr);
  for (std::size_t k = 0; k < given.size(); ++k)
    for (int i = 0; i < kContactParticles && particles_of[k][i] >= 0; ++i) {
      const auto at = std::find(ids.begin(), ids.end(), particles_of[k][i]);
      if (at == ids.end())
        throw std::invalid_argument("knit_contact_points: a given particle is not the course's");
      given[k][i] = static_cast<int>(at - ids.begin());
      used[given[k][i]] = 1;
    }
  // d vertex / d particle (x, y) by central differences, a 3 x 2 per vertex and particle. At
  // set-up every particle of the course is a candidate (the largest are kept): each coordinate's
  // derivatives are kept for the vertices it moves (a window along the yarn), and a vertex's row
  // over all candidates is assembled when its largest are chosen, so memory stays linear in the
  // course's length. Given particles_of, only each vertex's given particles, in their slots.
  const std::size_t columns = particles_of ? kContactParticles : ids.size();
  struct Window {
    int first = 0;        // the first vertex moved
    std::vector<Vec3> d;  // d vertex (first + t) / d coordinate
  };
  std::vector<Window> windows(particles_of ? 0 : 2 * ids.size());
  std::vector<std::array<double, 6>> J(particles_of ? v.size() * columns : 0,
                                       std::array<double, 6>{});
  auto entry = [&](int k, std::size_t q) -> std::array<double, 6>* {
    for (int i = 0; i < kContactParticles; ++i)
      if (given[k][i] == static_cast<int>(q)) return &J[k * columns + i];
    return nullptr;
  };
  for (std::size_t q = 0; q < ids.size(); ++q)
    for (int c = 0; c < 2 && used[q]; ++c) {
      double& coord = c == 0 ? pos[ids[q]].x : pos[ids[q]].y;
      const double keep = coord;
      coord = keep + h;
      const std::vector<Vec3> plus = course_yarn(m, pos, j);
      coord = keep - h;
      const std::vector<Vec3> minus = course_yarn(m, pos, j);
      coord = keep;
      auto moved = [&](int k) {
        return plus[k].x != yarn[k].x || plus[k].y != yarn[k].y || plus[k].z != yarn[k].z ||
               minus[k].x != yarn[k].x || minus[k].y != yarn[k].y || minus[k].z != yarn[k].z;
      };
      int a = n + 1, b = -1;  // the yarn points the particle moves
      for (int k = 0; k <= n; ++k)
        if (moved(k)) a = std::min(a, k), b = k;
      if (b < 0) continue;
      const int lo = std::max(0, a - kWindow), hi = std::min(n, b + kWindow);
      const int first = std::max(0, a - kReach), last = std::min(n, b + kReach);
      polyline_vertices({plus.begin() + lo, plus.begin() + hi + 1}, S, first - lo, last - lo, vp);
      polyline_vertices({minus.begin() + lo, minus.begin() + hi + 1}, S, first - lo, last - lo, vm);
      Window* w = particles_of ? nullptr : &windows[2 * q + c];
      if (w != nullptr) w->first = first * S, w->d.resize((last - first) * S + 1);
      for (int k = first * S; k <= last * S; ++k) {
        const int t = k - first * S;  // the vertex's index in vp, vm
        const Vec3 d{(vp[t].x - vm[t].x) / (2.0 * h), (vp[t].y - vm[t].y) / (2.0 * h),
                     (vp[t].z - vm[t].z) / (2.0 * h)};
        if (w != nullptr) {
          w->d[t] = d;
          continue;
        }
        std::array<double, 6>* e = entry(k, q);
        if (e == nullptr) continue;
        (*e)[c] = d.x, (*e)[2 + c] = d.y, (*e)[4 + c] = d.z;  // d v / d c
      }
    }
  // Vertex k's row over the candidates (set-up): zero where a coordinate does not move it.
  std::vector<std::array<double, 6>> dense(particles_of ? 0 : columns);
  auto row_of = [&](std::size_t k) -> const std::array<double, 6>* {
    if (particles_of) return &J[k * columns];
    for (std::size_t q = 0; q < columns; ++q) {
      dense[q] = std::array<double, 6>{};
      for (int c = 0; c < 2; ++c) {
        const Window& w = windows[2 * q + c];
        const long t = static_cast<long>(k) - w.first;
        if (t < 0 || t >= static_cast<long>(w.d.size())) continue;
        dense[q][c] = w.d[t].x, dense[q][2 + c] = w.d[t].y, dense[q][4 + c] = w.d[t].z;
      }
    }
    return dense.data();
  };
  out.reserve(v.size());
  // Per vertex the kContactParticles particles of largest |W|; the rest is added to the
  // largest, so the weights sum to [I; 0] (translations in the plane carried exactly).
  std::vector<int> order(columns);
  for (std::size_t k = 0; k < v.size(); ++k) {
    const std::array<double, 6>* row = row_of(k);
    auto size = [&](int q) {
      double s = 0.0;
      for (double w : row[q]) s += w * w;
      return s;
    };
    for (std::size_t q = 0; q < columns; ++q) order[q] = static_cast<int>(q);
    std::size_t keep = std::min<std::size_t>(kContactParticles, ids.size());
    if (particles_of != nullptr) {  // the given point's particles, in its order (its slots)
      keep = 0;
      while (keep < kContactParticles && given[k][keep] >= 0) ++keep;
    } else {
      std::partial_sort(order.begin(), order.begin() + keep, order.end(),
                        [&](int a, int b) { return size(a) > size(b); });
    }
    ContactPoint p;
    p.yarn = j;
    p.arc = arc[k];
    std::array<double, 6> rest_sum{};
    for (std::size_t q = 0; q < keep; ++q) {
      p.particles[q] = ids[particles_of ? given[k][q] : order[q]];
      p.weights[q] = row[order[q]];
      for (int e = 0; e < 6; ++e) rest_sum[e] += row[order[q]][e];
    }
    const std::array<double, 6> identity{1.0, 0.0, 0.0, 1.0, 0.0, 0.0};
    for (int e = 0; e < 6; ++e) p.weights[0][e] += identity[e] - rest_sum[e];
    // Co-rotated (models/yarn_contact.hpp): the map turns with the direction from its largest
    // particle to the one farthest from it.
    double far = 0.0;
    for (std::size_t q = 1; q < keep; ++q) {
      const Vec3 e = pos[p.particles[q]] - pos[p.particles[0]];
      const double len = std::hypot(e.x, e.y);
      if (len > far) far = len, p.turn = {0, static_cast<int>(q)}, p.axis = {e.x / len, e.y / len};
    }
    p.offset = Vec3{0.0, 0.0, 0.0};
    const Vec3 at_rest = position_of(p, pos);
    p.offset = v[k] - at_rest;
    out.push_back(p);
  }
  return out;
}

std::vector<ContactPoint> knit_contact_points(const KnitModel& m) {
  const std::vector<Vec3> rest = m.rest_positions();
  std::vector<ContactPoint> out;
  std::size_t count = 0;  // S vertices per interpolation interval and the last (no regrowth)
  for (int j = 0; j < m.chart.courses; ++j)
    count += kContactSamplesPerInterval * (course_yarn(m, rest, j).size() - 1) + 1;
  out.reserve(count);
  for (int j = 0; j < m.chart.courses; ++j) {
    const std::vector<ContactPoint> course = knit_contact_points(m, rest, j);
    out.insert(out.end(), course.begin(), course.end());
  }
  return out;
}

}  // namespace knitsim
