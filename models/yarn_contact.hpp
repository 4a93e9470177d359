// Yarn contact: a barrier that keeps yarn centrelines of different yarn parts apart, added to a
// SpringNetwork as one MechanicalSystem (ContactNetwork). Paper 2 has none (docs/knit.md,
// "Yarn contact").
//
// Contact points. The yarn is represented by points that are affine in the particles, so the
// barrier has local support and an exact, sparse Jacobian (the knit's NURBS centreline is a
// global interpolant whose inverse is dense):
//     p = sum_i W_i x_i,xy + o      (at most 8 particles, W_i 3 x 2; o a fixed offset, m)
// where x_i,xy is particle i's (x, y): the contact sees the particles' in-plane positions only,
// and a point's depth p.z follows them through W_i's third row (a yarn's depth between its
// interlacing points moves as the in-plane shape changes). That is the model of a chart that
// stays in its plane (the knit default: no force has a z component, the interlacing points stay
// at z = 0); a network whose particles leave the plane must not use it (build_knit refuses contact
// with knit.bending). Each point carries its yarn's id and its arc length along that yarn at rest.
//
// Co-rotated points (turn set; the knit's): a plain map is exact under translations only, so a
// free chart's energy changed as it turned in its plane and the chart drifted round. A
// co-rotated point's map turns with one direction of its own particles, v = x_j - x_i:
//     p = R(phi) (o + sum_i W_i R(phi)^T x_i,xy),   phi = the angle from `axis` to v,
// R(phi) the rotation about z (depth unchanged). At the state where the map was made phi = 0 and
// p is the plain map; p(R x + t) = R p(x) + t exactly for every rotation R about z and
// translation t in the plane (the weights sum to [I; 0]), so the barrier's energy does not change
// under the chart's rigid motions in its plane. Derivatives (q_i = R^T x_i, u = o + sum W_i q_i,
// G and G2 the 3-D and 2-D generators of rotation about z):
//     dp/dx_k = R (W_k R^T + a grad_k(phi)^T),   a = G u - sum_i W_i G2 q_i,
// with grad_j(phi) = G2 v / |v|^2 = -grad_i(phi); the Hessian adds, for the energy's gradient g
// at p (g~ = R^T g), the curvature of the map:
//     n_k grad_l^T + grad_k n_l^T + c grad_k grad_l^T + (g~ . a) d^2 phi / dx_k dx_l,
//     n_k = R2 (G W_k - W_k G2)^T g~,  c = g~ . G a - sum_k (R2^T n_k) . G2 q_k.
//
// Pairs. Two points interact if they lie on different yarns, or on one yarn at least
// same_yarn_gap apart along it (neighbouring pieces of one bend never do). Energy of a pair at
// distance D = |p_a - p_b|, with the gap g = (D - d0) / (d - d0):
//     E = kappa (d - d0)^2 phi(g),  phi(g) = -(g - 1)^2 ln g  for 0 < g < 1,  0 for g >= 1,
// the IPC barrier (Li et al. 2020) shifted to a core: no force at or beyond the touching distance
// d, a repulsion growing without bound as D falls to the core distance d0 < d (E = +inf for
// D <= d0). phi = phi' = phi'' = 0 at g = 1, so E is C^2 where contact begins.
// Gradient and Hessian (in p_a - p_b, 3 x 3): B = dE/dD u, and
//     H = E''(D) u u^T + (E'(D) / D) (I - u u^T),  u = (p_a - p_b) / D,
// mapped onto the particles by the weights (force W_i^T (-B) on a's particle i, in x and y; block
// (i, j) of d^2E/dx^2 gets s_i s_j W_i^T H W_j, s = +1 for a's particles, -1 for b's).
//
// Near pairs (a Verlet list): pairs closer than d + skin are listed at a state and reused while
// no point has moved more than skin / 2 since; the list is rebuilt on a front-view (x, y) grid. The
// sparse pattern is fixed at construction: the network's, plus the particle blocks of every pair
// closer than pattern_radius at the start (between the two points' particles and within each
// point's). A pair that comes into contact later on particles whose block is not in the pattern
// still gets its forces and energy; the Jacobian then misses that block (counted:
// pattern_misses()), which slows Newton but does not change the state reached.
//
// Renewal (refresh; optional): the points approximate positions the caller can compute exactly
// (the knit's centreline vertices), to first order about a state. Given both functions, refresh
// at an accepted state compares each yarn's points with their exact positions and re-linearises
// the yarns whose points stray more than refresh_tol about that state (the run driver calls it at
// each stop check; integrators then forget their history). Each yarn is renewed on its own: its
// points are re-linearised, and move to their exact positions as far as the step filter below
// allows with renew_keep of every pair's gap kept (where it cuts, the fresh map is offset by the
// part not taken, which later checks take up; counted: cut_renewals()). A yarn whose exact
// centreline is already inside a core is so renewed over the next steps while the barrier pushes
// it out, its tangent kept current (refusing such renewals, or blending the old and fresh maps,
// let the points stray further: docs/knit.md, "Yarn contact"). The sparse pattern stays the
// construction's: renewed points should keep their particles (the knit's do), or their missing
// blocks count as pattern misses.
//
// Step filter (admissible_step): a step that moves some point more than step_cap is cut to that;
// then the largest fraction of it along which no pair's distance falls below
// d0 + filter_keep (D_start - d0), found exactly for the straight move of each point from its start
// to its end (a quadratic in the fraction). A co-rotated point's path bends: the step is swept as
// chords between exact states, each turning no point more than kChordTurn, and the admitted end
// is checked exactly (halved while a pair is inside a core). Pairs from the near-pair list where
// no point ends further than skin / 2 from where it was listed (then every pair that can come
// within d is listed), else by their swept boxes on the grid. The equilibrium
// solver and implicit-euler shorten their steps by it, so no step jumps through the barrier.
// The SUNDIALS methods have no such hook: a state inside the core gives a non-finite
// acceleration, which they treat as a recoverable failure (a smaller step).
//
// Failure modes: a bad spec (particle out of range, weights not finite, d0 >= d, non-positive
// kappa) throws std::invalid_argument at construction. Evaluation never throws: a state with a
// pair at or inside the core gives E = +inf and NaN accelerations for the caller to detect.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "models/spring_network.hpp"

namespace knitsim {

constexpr int kContactParticles = 8;  // particles a contact point may depend on

inline std::array<int, kContactParticles> filled(int v) {
  std::array<int, kContactParticles> a;
  a.fill(v);
  return a;
}

struct ContactPoint {
  std::array<int, kContactParticles> particles = filled(-1);  // -1 ends
  // Per particle a 3 x 2 matrix W_i (row-major: xx, xy, yx, yy, zx, zy), dimensionless.
  std::array<std::array<double, 6>, kContactParticles> weights{};
  Vec3 offset;       // o, m (its z is the point's depth)
  int yarn = 0;      // which yarn the point lies on
  double arc = 0.0;  // arc length along its yarn at rest, m
  // Co-rotation (see "Co-rotated points" above): the point's map turns with the direction of
  // x_j - x_i, (i, j) = turn (indices into `particles`; -1: the map does not turn), by the angle
  // from `axis` (a unit vector in the plane, that direction where the map was made).
  std::array<int, 2> turn{-1, -1};
  std::array<double, 2> axis{1.0, 0.0};
};

// A point's co-rotation at a state (see "Co-rotated points" above): R(phi) as (c, s), u and a in
// the turned frame, grad_j(phi) of its second turning particle (the first's is minus that), v and
// |v|^2. A plain point has c = 1, s = 0 and turns = false.
struct PointTurn {
  double c = 1.0, s = 0.0;
  Vec3 u, a;                            // m
  double gx = 0.0, gy = 0.0;            // 1/m
  double vx = 0.0, vy = 0.0, v2 = 1.0;  // m, m^2
  bool turns = false;
};

// p(x) of a contact point (plain or co-rotated), given the positions of all particles (m).
Vec3 position_of(const ContactPoint& point, const std::vector<Vec3>& particles);

struct YarnContactSpec {
  std::vector<ContactPoint> points;
  double touching = 0.0;        // d, m: no force at or beyond it
  double core = 0.0;            // d0, m: E -> +inf as D -> d0 (0 < d0 < d)
  double stiffness = 0.0;       // kappa, N/m
  double same_yarn_gap = 0.0;   // m: points of one yarn closer than this along it never pair
  double skin = 0.0;            // m: the near-pair list's margin (0: (d - d0))
  double pattern_radius = 0.0;  // m: pairs this close at the start have Jacobian blocks (0: 6 d)
  double filter_keep = 0.2;     // a step keeps at least this fraction of a pair's gap to d0
  double step_cap = 0.0;        // m: a step moves no point further than this (0: 4 d)
  // Renewal (see above; both set, or the points are never renewed). `exact` writes every point's
  // exact position (points order) from every particle's position; `linearise` returns yarn y's
  // points (as many as it has, in order) linearised about those positions. Points must be
  // ordered by yarn.
  std::function<void(const std::vector<Vec3>&, std::vector<Vec3>&)> exact;
  std::function<std::vector<ContactPoint>(const std::vector<Vec3>&, int)> linearise;
  double refresh_tol = 0.0;   // m: a yarn is renewed when one of its points strays this far
  double refresh_move = 0.0;  // m: and only checked once a particle moved this far (x or y) since
  double renew_keep = 0.5;    // a renewal keeps at least this fraction of a pair's gap to d0
};

class ContactNetwork final : public MechanicalSystem {
 public:
  ContactNetwork(SpringNetwork network, YarnContactSpec contact);

  // MechanicalSystem
  int dof() const override { return net_.dof(); }
  void initial_state(double* x, double* v) const override { net_.initial_state(x, v); }
  void conservative_acceleration(double t, const double* x, double* a) const override;
  void constant_acceleration(double t, double* a) const override {
    net_.constant_acceleration(t, a);
  }
  const std::vector<double>& damping_rate() const override { return net_.damping_rate(); }
  const std::vector<double>& mass() const override { return net_.mass(); }
  const CscPattern& stiffness_pattern() const override { return pattern_; }
  void stiffness_values(double t, const double* x, double* values) const override;
  double static_residual(double t, const double* x) const override;
  double residual_roundoff(double t, const double* x) const override {
    return net_.residual_roundoff(t, x);
  }
  double equilibrium_start_time() const override { return net_.equilibrium_start_time(); }
  bool free_floating() const override { return net_.free_floating(); }
  bool planar() const override { return net_.planar(); }
  bool project(double t, double* x, double* v) const override { return net_.project(t, x, v); }
  double potential_energy(double t, const double* x) const override;
  double admissible_step(double t, const double* x, const double* dx) const override;
  bool refresh(double t, const double* x) const override;
  std::string describe() const override;
  // Every yarn's points re-linearised about (t, x), whole (no step filter): for a run that
  // starts from a saved state (--continue), whose points at rest would not stand for the yarn
  // there. False, with the points left as they were, if the state is not finite, renewal is
  // not set up, or the renewed points put a pair inside its core.
  bool renew(double t, const double* x);

  const SpringNetwork& network() const { return net_; }
  const YarnContactSpec& contact() const { return spec_; }
  // Contact energy alone at (t, x), J (+inf inside a core).
  double contact_energy(double t, const double* x) const;
  // Smallest distance between two pairing points at (t, x), m (closer than d + skin; else
  // +inf), and how many pairs are in contact (closer than d).
  double min_distance(double t, const double* x, int* in_contact = nullptr) const;
  // Pairs in contact whose Jacobian blocks were not all in the pattern, over all evaluations.
  long pattern_misses() const { return pattern_misses_; }
  long list_rebuilds() const { return rebuilds_; }
  // Step-filter and renewal sweeps that found their pairs in the near-pair list (sweep_fraction).
  long list_sweeps() const { return list_sweeps_; }
  long refreshes() const { return refreshes_; }  // yarns renewed, over all refreshes
  long cut_renewals() const { return cut_renewals_; }  // renewals the step filter cut short

 private:
  struct Pair {
    int a, b;
  };
  // Particles, then points, into pos_, pts_ (and turns_); kept for the next call at the same
  // (t, x) (cached_x_, cached_t_) until points_changed().
  void positions(double t, const double* x) const;
  // The points' maps changed: positions and near pairs are stale, yarn_of_ and arc_of_ renewed.
  void points_changed() const;
  void refresh_pairs() const;                       // the near-pair list at pos_, if stale
  bool pairs_of(double t, const double* x) const;   // positions + list; false if not finite
  bool may_pair(int a, int b) const;
  // Yarn y's points linearised about the particles' positions (spec linearise, its count checked).
  std::vector<ContactPoint> linearised(const std::vector<Vec3>& particles, int y) const;
  void check_points() const;  // throws std::invalid_argument on a bad point
  // Calls on_contact(pair, p_a - p_b, D, dE/dD, d2E/dD2) for every pair closer than d at (t, x);
  // false (stopping) if the state is not finite or a pair is inside its core.
  template <class OnContact>
  bool for_each_contact(double t, const double* x, OnContact on_contact) const;
  // Adds the contact forces at (t, x) to out (divided by the dofs' masses if `mass`); false if
  // the state is not finite or a pair is inside its core.
  bool add_contact_forces(double t, const double* x, double* out,
                          const std::vector<double>* mass) const;
  // Barrier energy and its first two derivatives in D.
  void barrier(double D, double& e, double& de, double& d2e) const;
  // The largest fraction in [0, 1] of the points' straight moves from start along which no pair
  // comes closer than d0 + keep (min(D_start, d) - d0): exact (a quadratic per pair), pairs by
  // their swept boxes, or the near-pair list where it holds every pair the moves can bring
  // within d. The step filter keeps filter_keep, a renewal renew_keep.
  double sweep_fraction(const std::vector<Vec3>& start, const std::vector<Vec3>& move,
                        double keep) const;
  double turn_angle(int k) const;  // point k's phi at pts_'s state (0 for a plain point), rad
  static constexpr double kChordTurn = 0.02;  // rad: the largest turn of a point per swept chord
  static constexpr int kMaxChords = 64;

  SpringNetwork net_;
  mutable YarnContactSpec spec_;  // its points are renewed by refresh
  double reach_ = 0.0;            // d + skin
  CscPattern nodes_;            // the free particles' block pattern
  CscPattern pattern_;          // nodes_ expanded to 3 x 3 blocks
  std::vector<int> net_entry_;  // per value of the network's pattern, its place in pattern_
  std::vector<int> yarn_begin_;  // per yarn, its first point (and the end last)
  mutable std::vector<Vec3> pos_, pts_, listed_at_, exact_, renewed_at_;  // listed_at_: points
  mutable std::vector<PointTurn> turns_;  // per point, at pts_'s state
  mutable std::vector<double> cached_x_;  // the state pos_, pts_ and turns_ describe, if cached_
  mutable double cached_t_ = 0.0;
  mutable bool cached_ = false;
  mutable std::vector<int> yarn_of_;    // per point, its yarn (may_pair reads these, not points)
  mutable std::vector<double> arc_of_;  // per point, its arc length, m
  mutable std::vector<Vec3> grad_;  // per point, dE/dp summed over its pairs (stiffness_values)
  mutable std::vector<Pair> pairs_;
  mutable std::vector<double> net_values_, force_;
  mutable long pattern_misses_ = 0, rebuilds_ = 0, refreshes_ = 0, cut_renewals_ = 0,
               list_sweeps_ = 0;
};

}  // namespace knitsim
