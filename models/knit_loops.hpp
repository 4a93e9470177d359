// KnitLoops: the interlacing-point mass-spring model of weft-knitted fabric (Chang et al.
// 2024, paper 2 Secs. 1-3; SPEC 2.9), built as a SpringNetwork, with the loops' type-value
// points and NURBS centrelines as functions of the interlacing points.
//
// Chart (SPEC 2.9): one text line per course, top course first as drawn, one character per
// wale: K knit, T tuck, M miss (float); blank lines and '#' comments (to the line's end) are
// ignored, as are spaces and tabs around a row. Course j = 0 is the bottom course (the last
// row drawn), wale i = 0 the leftmost column. Rules of this model (checked, with the row
// (1-based, counted from the top as drawn) and column (1-based) in the message):
//   - tucks and misses are knitted in neither the bottom course (no loop below to hold) nor an
//     edge wale (the yarn would have no loop to turn at), and no miss is in the top course
//     (the held loop would have no upper point); stacked tucks are allowed (below).
//
// Geometry: loop radius r (m), wale spacing w = 8r, course spacing h = 7r (paper 2 Sec. 1.2).
// Points ("levels"): the interlacing point of wale i at level L sits at rest at
// (i w, L h, 0); level j holds O(i,j), the lower point of loop (i,j), which is also P(i,j-1),
// the upper point of the loop below (one particle). A level-L point exists iff L = 0 (bottom
// course, all knits), L = courses (top) or loop (i,L) is a knit (a tuck or miss has no lower
// point).
// Loops: every knit and tuck (i,j) is a loop; its upper point U(i,j) is the first existing
// point above level j in wale i: P(i,j) itself, or, for a loop held by tucks/misses above
// it, the next existing upper point (the held loop is elongated).
// Springs (paper 2 Sec. 2.2, Figs. 4-6; no shear or bending springs):
//   wale     each knit loop: O(i,j) - U(i,j), rest h, stiffness k_w (a held loop starts
//            stretched over 2h, 3h, ...: that pull is the deformation paper 2 simulates);
//   course   consecutive loops of a course joined at their "anchors" (a knit's lower point
//            O(i,j); a tuck's upper point U(i,j), where the open arc hangs), stiffness k_c;
//   tuck     a course link with a tuck at one end (the paper's "combined wale/course
//            spring"), stiffness 1/(1/k_w + 1/k_c) (a course spring and a wale spring in
//            series);
//   float    a course link across missed wales (the float of a miss), stiffness k_c.
//   Course-link rest length: sqrt(w^2 + d^2), d the difference of the anchors' nominal
//   heights (a knit's O at j h, a tuck's head at (j+1) h): w between knits, sqrt(w^2 + h^2)
//   from a knit to a tuck's head (unstretched at the start), and w for a float whatever the
//   number of missed wales (SPEC 2.9: the float links O(i-1,j) - O(i+1,j) with rest w, so it
//   starts stretched and draws the fabric in). Stacked tucks all hang from the first existing
//   point above them; each starts stretched by its own distance from it.
// Masses: total areal density x chart area (wales w x courses h), shared equally by the
//   points. Forces: springs and absolute damping c per point (paper 2 Sec. 3.3, F = -K_s L -
//   K_d V); gravity (along -y, the fabric hanging in the x-y plane) and pins optional.
// Static residual scale (SPEC 2.3): F_ref = k_w r, the force of a wale spring stretched by one
//   loop radius (paper 2 has no external force, so the SpringNetwork default m g is
//   meaningless); with gravity on, min(k_w r, mean point weight).
// Mechanics of paper 2's network (shown by tests/test_knit.cpp): with wale and course
//   springs only, the square network is a mechanism (rows and columns shear and swing at no
//   energy; z is free). A tuck or miss is taken up without strain: at the steady state every
//   spring is at its rest length, and the misfit is absorbed by rigid motions of blocks of
//   the fabric that do not decay with distance. The steady state is therefore not unique: it
//   is where the damped dynamics from the start ends, and integrators agree only to their
//   path error (implicit-euler converges to Verlet's state as dt -> 0). Large charts with
//   many tucks or misses creep slowly towards it (soft modes), and implicit-euler's large
//   steps wander along the zero-energy modes.
// Networks (KnitParams::network; `knit --set knit.network=stabilised|paper`):
//   stabilised (the default; a departure from paper 2 Sec. 2.2, which has no such springs)
//            paper 2's springs plus a stabiliser that removes the in-plane mechanism, with
//            s = KnitParams::stabiliser_ratio (default 0.1), between existing interlacing points:
//   shear    both diagonals of every quad (i,L) (i+1,L) (i,L+1) (i+1,L+1) whose four corners
//            exist, stiffness s (k_w + k_c)/2;
//   bending  (i,L) - (i,L+2) along a wale, stiffness s k_w, and (i,L) - (i+2,L) along a level,
//            stiffness s k_c, where the point between them exists too (no bending spring
//            spans a held loop or a float: those keep the paper's pull).
//            Rest lengths are the rest distances, so a plain chart stays exactly at rest. With it
//            the in-plane steady state is unique and a tuck's displacement decays with distance
//            (tests/test_knit.cpp, paper_repro/knit/README.md); the pull a tuck exerts is then
//            shared with these springs.
//            Basis of s (docs/knit.md): the yarn's bending rigidity B. A loop's leg of length h
//            held at both interlacing points resists a sideways (shearing) displacement with the
//            guided-beam stiffness 12 B / h^3; s = 12 B / (k h^3). B of a yarn of diameter d = r
//            whose fibres slip freely (the lower bound of a yarn's rigidity): n_f fibres,
//            n_f = phi (d / d_f)^2, each E_f pi d_f^4 / 64; cotton E_f ~ 7 GPa, d_f ~ 12 um,
//            packing phi ~ 0.5 give n_f ~ 28 and B ~ 2.0e-10 N m^2, hence s ~ 0.10 at the default
//            r and k = 100 N/m. An estimate to a factor of a few (fibre modulus and packing
//            vary): s is a key, knit.stabiliser in [0, 1].
//            Out of the plane: every spring of a flat chart lies in z = 0, so at rest no spring
//            resists a z displacement to first order (the stiffness's z block is zero; tension
//            stiffens it, compression softens it below zero). No force has a z component at
//            z = 0, so every integrator keeps a flat start flat: the chart stays in its plane.
//   bending  (knit.bending = b > 0, off by default; needs knit.contact = 0) the yarn's
//            out-of-plane bending as quadratic stencils (SpringNetwork's Stencil) on the bending
//            springs' triples and the shear springs' quads, B = b s k_w h^3 / 12: second
//            differences along wales (B/h^3) and levels (B/w^3), each quad's twist
//            (B (w + h) / (w h)^2). Zero at rest and on every rigid motion; with them the only
//            zero modes are the 6 rigid motions (without them, in the plane, the 3 in-plane
//            ones), and a free chart declares them (MechanicalSystem::free_floating, planar).
//            Measured consequence (docs/knit.md): a tuck's or miss's flat steady state is then
//            a saddle, and the fabric puckers; its yarns pass through each other there.
//   paper    paper 2's network exactly (wale, course, tuck and float springs; s is ignored):
//            a mechanism, see above. knit.stabiliser = 0 gives the same network. `knitsim knit`
//            prints one warning line for it.
// State layout: that of SpringNetwork (3 dof per free point, in point-id order); point ids
//   are level-major: all points of level 0 by wale, then level 1, ...
//
// Loop geometry (paper 2 Sec. 1.1, Fig. 1; SPEC 2.9): type-value points T0..T8 per loop are
// a fixed function of the current points. Per course and wale a local frame (B, e_x, e_y, n):
//   B    the loop's lower point (knit) or, for tucks and misses, the linear interpolation
//        between the nearest knits' lower points of the course;
//   e_y  unit(U - B) (knit; tuck with the bending); for a miss interpolated like B; for a tuck
//        in the planar model z x e_x (below): a tuck's U is not tied to B by a spring, and in
//        the top course the held loop pulls U down through B, where unit(U - B) turns the loop
//        by 180 degrees (random charts 014 and 020: yarns through each other mid-run);
//   e_x  e_y x z, e_y turned -90 degrees in the plane (the planar model, knit.bending = 0); for a
//        planar tuck the in-plane unit direction between the knits its B interpolates; with
//        the out-of-plane bending the unit component of B(i+1) - B(i-1) orthogonal to e_y
//        (one-sided at the edges). All agree at rest; with the bending, a loop whose e_y turns
//        past the course direction is mirrored through the fabric (the planar e_x's reason);
//   n    e_x x e_y (+z at rest: towards the viewer of the front view; always +z when planar).
// Knit loop, with P = U(i,j):
//   T1 = B - r e_x,  T7 = B + r e_x                (feet, z = 0)
//   T3 = P - 3r e_x, T5 = P + 3r e_x, T4 = P + r e_y - r n   (head, behind)
//   T0, T8 = the sinker points shared with the neighbours:
//        S(i,i+1) = (B_i + B_{i+1})/2 - r (e_y,i + e_y,i+1)/2 - r (n_i + n_i+1)/2,
//        at the course ends B -/+ 4r e_x - r e_y - r n
//   T2 = (T0 + T4)/2 + 2r n, T6 = (T4 + T8)/2 + 2r n   (legs in front; paper: T2, T6 are the
//        midpoints of T0-T4 and T4-T8 in the front view, T4 and T0/T8 symmetric about them)
// At rest (O at the origin, P = (0, h, 0)) this is exactly SPEC 2.9's
//   T0 (-4r,-r,-r) T1 (-r,0,0) T2 (-2r,3.5r,r) T3 (-3r,7r,0) T4 (0,8r,-r) T5 (3r,7r,0)
//   T6 (2r,3.5r,r) T7 (r,0,0) T8 (4r,-r,-r),
// so the head of loop (i,j-1) passes behind the legs of loop (i,j) near its feet, and its
// upper legs in front of that loop's sinker arcs: the new loop passes through the old one,
// the courses intermesh. A tuck loop is the open arc T0 T2 T3 T4 T5 T6 T8 (no feet) with
// its head T3..T5 pushed back by 3r behind the head of the held loop it shares the needle
// with (SPEC 2.9 leaves the two coincident; on the face the tuck hides behind it), 2r more for
// each course above it on the same needle up to the next knit in its wale (a tuck, which hangs
// from the same upper point, or a miss, whose float passes the needle), and its legs T2, T6
// forward by r (not 2r) of the midpoints. A knit loop spanning s courses (held over s - 1, so
// U = P(i,j+s-1)) has s points T2 on its left leg and s points T6 on its right, |U - B| / s
// apart along e_y and centred on the midpoints above (s = 1: SPEC's one each). A float passes
// behind each missed wale at F_i = B_i - r e_y - r n. Each course's yarn is one C^2 cubic NURBS
// through its points in wale order (T8 of a loop = T0 of the next), centripetal parameters
// (src/geometry/nurbs.hpp).
// Tuck and held-loop geometry, made so that yarns start at least one yarn diameter
// (d = r) apart: the yarn of every course above a tuck on its needle (a stacked tuck's legs, a
// float) passes in front of the tuck's legs, which run back from its sinkers to its head; each
// such course puts the head 2r further back, so the lowest tuck of a stack is the deepest and a
// float over a tuck stays clear of its legs. A held loop's legs get one point per course: with
// one interval from each foot to a midpoint several courses up, the cubic swings the legs into
// each other just above the feet. The tuck's legs r forward and the centripetal parameters
// (which damp the cubic's overshoot at uneven intervals) do the rest. Clearance at rest
// (src/measure/yarn_measures.hpp): 1.212 r on plain jersey, single_tuck and tucks40, 1.150 r on
// several_misses, 1.199 r on several_tucks, >= 1.12 r on the 50 random charts of
// experiments/random_charts; figures and limits: docs/knit.md, "Rest geometry of tucks and
// misses".
//
// Yarn contact (knit.contact = c > 0; c = 10 by default; docs/knit.md, "Yarn contact"): the
// barrier of models/yarn_contact.hpp between the yarn polylines' rest vertices (below), each the
// first-order Taylor map of its vertex about the rest state in the (x, y) of the (up to 8)
// interlacing points it depends on most (weights by central differences at set-up, the rest
// lumped onto the largest so in-plane translations are exact; its depth follows too), co-rotated
// with the direction from that largest particle to the farthest of its particles (so in-plane
// rotations are exact too).
// Touching distance d = r (the yarn diameter), core d0 = kContactCore r, kappa = c k_w; yarns are
// one course each, and pieces of one course pair if kSameYarnGap r apart along it.
//
// Failure modes: a bad chart or parameters throw std::invalid_argument at set-up (chart
// messages name row and column). Geometry functions expect positions of every point
// (length points.size()) and throw std::invalid_argument otherwise; a degenerate
// configuration (coincident yarn points) throws std::invalid_argument from the NURBS fit.
#pragma once

#include <memory>
#include <string>
#include <vector>

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
  // Throws std::invalid_argument for a chart that breaks the model's rules (see above), naming
  // the row (from the top as drawn), its line in the file where row_lines gives them (top row
  // first), the column and the rule.
  void validate(const std::vector<int>* row_lines = nullptr) const;
};

// Parses the text of a chart file. Throws std::invalid_argument with one line naming the
// row and column as drawn and the accepted letters.
KnitChart parse_knit_chart(const std::string& text);

enum class KnitPins { None, Bottom, Top, BottomAndTop };  // which edge levels are held fixed

// The spring network (see above): knit.network = stabilised (default) | paper.
enum class KnitNetwork { Stabilised, Paper };
const char* to_string(KnitNetwork network);
// "stabilised" or "paper"; throws std::invalid_argument naming knit.network and the names.
KnitNetwork parse_knit_network(const std::string& name);

struct KnitParams {
  // r, m: 14 wales/cm -> w = 8r = 1/14 cm -> r = 1/1120 cm ~ 8.93e-5 m.
  double loop_radius = 1e-2 / 14.0 / 8.0;
  // k_w, k_c, N/m: a documented choice (paper 2 gives no values). With springs in series
  // along each wale and course, the fabric's tensile stiffness per unit width is
  // k_w h/w ~ 88 N/m along the wales and k_c w/h ~ 114 N/m along the courses. Without
  // external forces only the ratio k_w/k_c shapes the steady state; k sets the time scale.
  double wale_stiffness = 100.0;
  double course_stiffness = 100.0;
  // c, N s/m per point (paper 2: F_d = -K_d V; no value given). Default ~0.2 x the
  // critical damping 2 sqrt(k m) = 2.7e-3 of one default point (m = rho_A w h ~ 1.86e-8 kg)
  // on one default spring: chosen by measurement, the shipped tuck and miss charts settle
  // 2-4x faster with Verlet than at 2e-3 (slow soft modes creep at a rate ~ 1/c).
  double damping = 5e-4;
  double areal_density = 41.65;  // rho_A, g/m^2 (paper 1 Table 2, sample 1)
  bool gravity = false;          // paper 2 ignores external forces; on: g = 9.81 m/s^2 along -y
  KnitPins pins = KnitPins::None;
  // Which network (see above): the stabilised default, or paper 2's bare network.
  KnitNetwork network = KnitNetwork::Stabilised;
  // s, dimensionless, in [0, 1]: stiffness of the stabiliser's shear and bending springs
  // relative to k_w, k_c (see above; 0.1 from the yarn's bending rigidity); 0 = off, which is
  // paper 2's network whatever `network` says. Ignored for KnitNetwork::Paper.
  double stabiliser_ratio = 0.1;
  // b, dimensionless, in [0, 10]: the out-of-plane bending stencils' rigidity as a multiple of
  // the yarn rigidity s stands for, B = b s k_w h^3 / 12 (see "Out of the plane" above). 0 (the
  // default) = off: the chart stays in its plane. Needs the stabiliser (s > 0).
  double bending_ratio = 0.0;
  // c, dimensionless, in [0, 100]: the yarn contact's barrier stiffness kappa = c k_w (see
  // "Yarn contact" above); 10 (the default) keeps yarns a diameter apart on every committed and
  // random chart (docs/knit.md, "Yarn contact"); 0 = off (about 4x less CPU, yarns may pass
  // through each other). Contact needs the stabiliser (ignored without, like the paper
  // network's) and keeps the chart in its plane, so knit.bending > 0 needs knit.contact = 0.
  double contact_ratio = 10.0;
  long max_points = 4'000'000;  // refuse larger charts before allocating

  // Throws std::invalid_argument naming the field by its `knit --set` key (knit.loop_radius,
  // knit.wale_stiffness, knit.course_stiffness, knit.damping, knit.areal_density,
  // knit.stabiliser, knit.bending; max_points has none) and the accepted range with units.
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
  const MechanicalSystem& system() const {
    return contact ? static_cast<const MechanicalSystem&>(*contact) : network;
  }
  MechanicalSystem& system() { return contact ? static_cast<MechanicalSystem&>(*contact) : network; }

  int point(int wale, int level) const { return point_at[level * chart.wales + wale]; }
  int loop(int wale, int course) const { return loop_at[course * chart.wales + wale]; }
  int count(KnitSpringKind kind) const;  // springs of one kind
  // Loop l is held by tucks or misses above it: its upper point lies above level course + 1.
  bool held(int l) const { return points[loops[l].upper].level > loops[l].course + 1; }
  // Rest positions of all points (length points.size()).
  std::vector<Vec3> rest_positions() const;
};

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

// The yarn's interpolation parameters (see "Tuck and held-loop geometry" above).
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

// The yarn contact's points (see "Yarn contact" above): the rest yarn polylines' vertices, each
// affine in the interlacing points around it; yarn = course, arc = the polyline's rest arc.
std::vector<ContactPoint> knit_contact_points(const KnitModel& m);
// Course j's contact points linearised about the given positions of every point (their vertices
// there, first-order in the points' x and y), each on the (up to 8) particles it depends on most,
// or, given particles_of (course j's points, in order), on the particles of its namesake there.
// Throws std::invalid_argument for a bad course, positions or particle.
std::vector<ContactPoint> knit_contact_points(const KnitModel& m,
                                              const std::vector<Vec3>& positions, int j,
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
