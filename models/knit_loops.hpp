// KnitLoops: the interlacing-point mass-spring model of weft-knitted fabric (Chang et al. 2024,
// paper 2 Secs. 1-3), built as a SpringNetwork, with the loops' type-value points and NURBS
// centrelines as functions of the interlacing points. The model's definition (the chart's rules,
// points, loops, springs and networks, masses, the loop geometry, the tuck and held-loop
// geometry, the yarn contact's points) and why: docs/knit.md, "The model as built".
//
// Units: SI (m, N/m, kg). State layout: that of SpringNetwork (3 dof per free point, in point-id
// order); point ids are level-major: all points of level 0 by wale, then level 1, ...
//
// Failure modes: a bad chart or parameters throw std::invalid_argument at set-up (chart
// messages name row and column), as does a chart whose estimated memory exceeds what is
// available (knit_memory_cap below). Geometry functions expect positions of every point
// (length points.size()) and throw std::invalid_argument otherwise; a degenerate
// configuration (coincident yarn points) throws std::invalid_argument from the NURBS fit.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "models/knit_clamps.hpp"
#include "models/spring_network.hpp"
#include "models/yarn_contact.hpp"
#include "src/core/vec3.hpp"
#include "src/geometry/nurbs.hpp"

namespace knitsim {

enum class Stitch : char { Knit = 'K', Tuck = 'T', Miss = 'M' };

struct KnitChart {
  int wales = 0;
  int courses = 0;
  std::vector<Stitch> stitches;  // index course * wales + wale; course 0 = bottom (drawn last)
  Stitch at(int wale, int course) const { return stitches[course * wales + wale]; }
  // Throws std::invalid_argument for a chart that breaks the model's rules (docs/knit.md, "The
  // model as built"), naming the row (from the top as drawn), its line in the file where row_lines
  // gives them (top row first), the column and the rule. repeat: the chart is the repeat of a
  // periodic cell (knit.boundary = periodic), which has no edge: no rule on the bottom and top
  // courses and the edge wales.
  void validate(const std::vector<int>* row_lines = nullptr, bool repeat = false) const;
};

// Parses the text of a chart file. Throws std::invalid_argument with one line naming the
// row and column as drawn and the accepted letters. repeat: as KnitChart::validate.
KnitChart parse_knit_chart(const std::string& text, bool repeat = false);

enum class KnitPins { None, Bottom, Top, BottomAndTop };  // which edge levels are held fixed

// The spring network (docs/knit.md, "The model as built"): knit.network = stabilised (default) |
// paper.
enum class KnitNetwork { Stabilised, Paper };
const char* to_string(KnitNetwork network);
// "stabilised" or "paper"; throws std::invalid_argument naming knit.network and the names.
KnitNetwork parse_knit_network(const std::string& name);

struct KnitParams {
  // r, m: 14 wales/cm -> w = 8r = 1/14 cm -> r = 1/1120 cm ~ 8.93e-5 m.
  double loop_radius = 1e-2 / 14.0 / 8.0;
  // k_w, k_c, N/m: a documented choice (paper 2 gives no values). The network's tensile
  // stiffness per unit width (knitsim tensile; docs/knit.md, "Under load") is 128 N/m along the
  // wales and 173 N/m along the courses with the default stabiliser (k_w h/w = 87.5 and
  // k_c w/h = 114 N/m without it). Without external forces only the ratio k_w/k_c shapes the
  // steady state; k sets the time scale.
  double wale_stiffness = 100.0;
  double course_stiffness = 100.0;
  // c, N s/m per point (paper 2: F_d = -K_d V; no value given). Default ~0.2 x the
  // critical damping 2 sqrt(k m) = 2.7e-3 of one default point (m = rho_A w h ~ 1.86e-8 kg)
  // on one default spring: chosen by measurement, the shipped tuck and miss charts settle
  // 2-4x faster with Verlet than at 2e-3 (slow soft modes creep at a rate ~ 1/c).
  double damping = 5e-4;
  double areal_density = 41.65;  // rho_A, g/m^2 (paper 1 Table 2, sample 1)
  bool gravity = false;          // paper 2 ignores external forces; on: g = 9.81 m/s^2 along -y
  KnitPins pins = KnitPins::None;  // shorthand for the common clamps: held before `clamps`
  // Clamps (knit.clamps; models/knit_clamps.hpp, docs/knit.md "Under load").
  std::vector<KnitClampSpec> clamps;
  // Forces on points (knit.forces; models/knit_clamps.hpp), N at the last load step.
  std::vector<KnitPointForce> point_forces;
  // knit.load_steps, [0, 1000]: N equal load steps to load fraction 1, each an equilibrium
  // warm-started from the last, the reactions written per step (src/scene/knit_load_steps.hpp);
  // 0 (the default) = one step, as before (docs/knit.md, "Under load").
  int load_steps = 0;
  // Which network (docs/knit.md, "Networks"): the stabilised default, or paper 2's bare network.
  KnitNetwork network = KnitNetwork::Stabilised;
  // s, dimensionless, in [0, 1]: stiffness of the stabiliser's shear and bending springs
  // relative to k_w, k_c (docs/knit.md, "Networks"; 0.1 from the yarn's bending rigidity); 0 = off,
  // which is paper 2's network whatever `network` says. Ignored for KnitNetwork::Paper.
  double stabiliser_ratio = 0.1;
  // b, dimensionless, in [0, 10]: the out-of-plane bending stencils' rigidity as a multiple of
  // the yarn rigidity s stands for, B = b s k_w h^3 / 12 (docs/knit.md, "Out-of-plane bending"). 0
  // (the default) = off: the chart stays in its plane. Needs the stabiliser (s > 0).
  double bending_ratio = 0.0;
  // c, dimensionless, in [0, 100]: the yarn contact's barrier stiffness kappa = c k_w
  // (docs/knit.md, "Yarn contact"); 10 (the default) keeps yarns a diameter apart on every
  // committed and random chart (docs/knit.md, "Yarn contact"); 0 = off (about 4x less CPU, yarns
  // may pass through each other). Contact needs the stabiliser (ignored without, like the paper
  // network's) and keeps the chart in its plane, so knit.bending > 0 needs knit.contact = 0.
  double contact_ratio = 10.0;
  long max_points = 4'000'000;  // refuse larger charts before allocating

  // Throws std::invalid_argument naming the field by its `knit --set` key (knit.loop_radius,
  // knit.wale_stiffness, knit.course_stiffness, knit.damping, knit.areal_density,
  // knit.stabiliser, knit.bending, knit.load_steps; max_points has none) and the accepted range
  // with units.
  void validate() const;
  // True when the network has no stabiliser (paper 2's mechanism): network Paper or s = 0.
  bool mechanism() const { return network == KnitNetwork::Paper || stabiliser_ratio == 0.0; }
  // True when the network has the out-of-plane bending stencils: a stabiliser and b > 0.
  bool out_of_plane_bending() const { return !mechanism() && bending_ratio > 0.0; }
  // True when the model has yarn contact: a stabiliser and c > 0.
  bool yarn_contact() const { return !mechanism() && contact_ratio > 0.0; }
  double wale_spacing() const { return 8.0 * loop_radius; }    // w, m
  double course_spacing() const { return 7.0 * loop_radius; }  // h, m
};

struct KnitPoint {
  int wale = 0;
  int level = 0;  // 0..courses: O(i,level), = P(i,level-1)
  Vec3 rest;      // (i w, level h, 0), m: the initial position
};

struct KnitLoop {
  int wale = 0;
  int course = 0;
  Stitch kind = Stitch::Knit;  // Knit or Tuck (a miss has no loop)
  int lower = -1;              // point id of O(i,j); -1 for a tuck
  int upper = -1;              // point id of U(i,j) (P(i,j), or higher for a held loop)
};

enum class KnitSpringKind { Wale, Course, Tuck, Float, Shear, Bending };
const char* to_string(KnitSpringKind kind);

struct KnitModel {
  KnitChart chart;
  KnitParams params;
  std::vector<KnitPoint> points;            // index = point id = SpringNetwork particle
  std::vector<KnitLoop> loops;              // by course (bottom first), then wale
  std::vector<KnitSpringKind> spring_kind;  // parallel to network.spec().springs
  std::vector<int> point_at;                // level * wales + wale -> point id, -1 if absent
  std::vector<int> loop_at;                 // course * wales + wale -> loop index, -1 (miss)
  SpringNetwork network;
  // The network with yarn contact (params.yarn_contact()), else null; system() is what runs.
  // One run of the contact's model (models/yarn_contact.hpp): a second run of the same model,
  // e.g. on another thread, is ContactNetwork(contact->shared_model()).
  std::shared_ptr<ContactNetwork> contact;
  // The clamps (knit.pins' edges, then knit.clamps): their points are the network's pins, in
  // this order (Clamp::held indexes system().held_points()).
  std::vector<Clamp> clamps;
  const MechanicalSystem& system() const {
    return contact ? static_cast<const MechanicalSystem&>(*contact) : network;
  }
  MechanicalSystem& system() {
    return contact ? static_cast<MechanicalSystem&>(*contact) : network;
  }

  // All points at (t, x), m: the free ones from x, the held ones where the running system holds
  // them (its held points are run state: src/core/held_points.hpp).
  void all_positions(double t, const double* x, std::vector<Vec3>& out) const {
    (contact ? contact->network() : network).all_positions(t, x, out);
  }

  int point(int wale, int level) const { return point_at[level * chart.wales + wale]; }
  int loop(int wale, int course) const { return loop_at[course * chart.wales + wale]; }
  int count(KnitSpringKind kind) const;  // springs of one kind
  // Loop l is held by tucks or misses above it: its upper point lies above level course + 1.
  bool held(int l) const { return points[loops[l].upper].level > loops[l].course + 1; }
  // Rest positions of all points (length points.size()).
  std::vector<Vec3> rest_positions() const;
};

// With yarn contact (params.yarn_contact()) build_knit refuses a chart with a float (misses in a
// row of one course) longer than this, naming its row and first column: a single course's float
// of 8 wales or more ended in solver_failure (7 settled), whereas without contact 16 settle.
inline constexpr int kMaxContactFloat = 7;
// Memory (docs/knit.md, "Memory"). build_knit refuses, with one line naming the size, a chart
// whose estimated peak memory exceeds knit_memory_cap(), before allocating any of it. The
// estimate is an upper one, linear in the stitches (measured: docs/knit.md): kKnitMemoryBase plus
// per stitch kKnitMemoryPerStitchContact with yarn contact (its ~128 contact points' maps,
// caches and a renewal's fresh maps), else kKnitMemoryPerStitch. Bytes.
constexpr double kKnitMemoryBase = 64.0 * 1048576.0;
constexpr double kKnitMemoryPerStitchContact = 256.0 * 1024.0;
constexpr double kKnitMemoryPerStitch = 32.0 * 1024.0;
// Under an address-space limit (ulimit -v) this much stays free for what the estimate does not
// count: thread stacks and allocator arenas, libraries mapped later. Bytes.
constexpr double kKnitVirtualAllowance = 256.0 * 1048576.0;
double knit_memory_estimate(int wales, int courses, bool contact);
struct MemoryCap {
  double bytes;        // +inf if nothing is known
  const char* source;  // "MemAvailable", "the address-space limit (ulimit -v)", ...
};
// The smaller of the machine's MemAvailable (/proc/meminfo) and, under an address-space limit,
// that limit less the process's size (VmSize) and kKnitVirtualAllowance.
MemoryCap knit_memory_cap();

KnitModel build_knit(const KnitChart& chart, const KnitParams& params);

// Type-value points of one loop in yarn order: k lists which T_k the loop has (0..8 for a knit,
// with 2 and 6 repeated s times for a loop spanning s courses; 0, 2, 3, 4, 5, 6, 8 for a tuck)
// and t their positions, m.
struct LoopTypeValues {
  std::vector<int> k;
  std::vector<Vec3> t;
};
// One entry per model.loops, at the given positions of all points.
std::vector<LoopTypeValues> type_value_points(const KnitModel& model,
                                              const std::vector<Vec3>& positions);

// Per course (bottom first), the yarn's interpolation points in wale order: the loops' type-
// value points with shared sinkers once, and a float point behind each missed wale.
std::vector<std::vector<Vec3>> course_yarn_points(const KnitModel& model,
                                                  const std::vector<Vec3>& positions);

// The yarn's interpolation parameters (docs/knit.md, "The model as built": tuck and held-loop
// geometry).
constexpr Parametrization kYarnParametrization = Parametrization::Centripetal;

// Per course, the C^2 cubic NURBS through course_yarn_points (centripetal parameters).
std::vector<NurbsCurve> course_curves(const KnitModel& model, const std::vector<Vec3>& positions);

// Per course, its centreline sampled uniformly in arc length with samples_per_point samples
// per interpolation interval (>= 1).
std::vector<CurveSamples> course_centerlines(const KnitModel& model,
                                             const std::vector<Vec3>& positions,
                                             int samples_per_point = 8);

// Yarn polylines: each course's centreline sampled at S points per interpolation interval,
// uniformly in the curve parameter between the interval's ends ubar_k, ubar_k+1 (the curve passes
// through yarn point k at ubar_k): vertex k S + m is at ubar_k + (m / S)(ubar_k+1 - ubar_k), so a
// vertex's label (course, k S + m) names the same piece of yarn in every state. With S = 8 the
// polyline lies within ~0.035 r of the curve. The yarn measures (src/measure/yarn_measures.hpp)
// and the contact points (knit_contact_points) are these vertices.
constexpr int kYarnSamplesPerInterval = 8;  // S
// Pieces of one yarn this far apart along it (in r) count as different parts (clearance,
// contact): a yarn of diameter d = r bent round a circle of radius d/2 comes back within d of
// itself only after an arc of pi d/2; pi r is twice that, so the neighbouring pieces of one
// bend never count while a loop's two legs (~20 r apart along the yarn) do.
constexpr double kSameYarnGap = 3.14159265358979323846;

struct YarnPolylines {
  int samples_per_interval = kYarnSamplesPerInterval;
  std::vector<std::vector<Vec3>> vertices;  // per course (bottom first): segment k = k to k+1
  std::vector<std::vector<double>> arc;     // per course: arc length at each vertex, m
};

YarnPolylines yarn_polylines(const KnitModel& m, const std::vector<Vec3>& positions,
                             int samples_per_interval = kYarnSamplesPerInterval);

// The yarn contact's points (docs/knit.md, "Yarn contact"): the rest yarn polylines' vertices, each
// affine in the interlacing points around it; yarn = course, arc = the polyline's rest arc.
std::vector<ContactPoint> knit_contact_points(const KnitModel& m);
// Course j's contact points linearised about the given positions of every point (their vertices
// there, first-order in the points' x and y), each on the (up to 8) particles it depends on most,
// or, given particles_of (course j's points, in order), on the particles of its namesake there.
// Throws std::invalid_argument for a bad course, positions or particle.
std::vector<ContactPoint> knit_contact_points(
    const KnitModel& m, const std::vector<Vec3>& positions, int j,
    const std::array<int, kContactParticles>* particles_of = nullptr);
// The contact's sampling and renewal, in units of r (docs/knit.md, "Yarn contact"): points at
// kContactSamplesPerInterval per interpolation interval (twice the measuring polyline's: the
// barrier keeps points apart, and segments between points spaced s can pass within
// sqrt(D^2 - s^2 / 2) of each other); a course is re-linearised when one of its points strays
// kContactRefreshTol from its vertex, checked once an interlacing point has moved
// kContactRefreshMove since the last renewal; a solver step moves no point more than
// kContactStepCap (the points stray ~quadratically in the step).
// The barrier's core: points never come closer than kContactCore; with points at most ~0.3 r
// apart along the yarn the centreline's segments then stay >= ~0.93 r apart (the contact target
// is 0.9 r; touching distance d = r).
constexpr double kContactCore = 0.95;
constexpr int kContactSamplesPerInterval = 16;
constexpr double kContactRefreshTol = 0.01;
constexpr double kContactRefreshMove = 0.05;
constexpr double kContactStepCap = 0.5;

}  // namespace knitsim
