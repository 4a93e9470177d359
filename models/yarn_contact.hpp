// Yarn contact: a barrier that keeps yarn centrelines of different yarn parts apart, added to a
// SpringNetwork. What it is and why (contact points, co-rotated maps, pairs and the barrier, the
// near-pair list and the fixed pattern, renewal, the step filter): docs/knit.md, "Yarn contact".
//
// Model and run (Drake's System and Context): the points' maps are renewed during a run, and they
// change the energy E(x) itself, so they are state the run owns, not the model's.
//   ContactModel    the network, the barrier's parameters, the points at rest and the fixed
//                   sparse pattern. Const once built: one model serves any number of runs, on
//                   any threads at once.
//   ContactNetwork  one run of a ContactModel: the MechanicalSystem the integrators see. It owns
//                   the points' current maps, changed only by update() (the run driver calls it
//                   between steps, MechanicalSystem::update) and renew(), and caches that are
//                   functions of (t, x) and those maps: the points' positions at the latest
//                   state, the near-pair list (its order is the list's history: a run's results
//                   are the same bytes whenever it runs, not across two lists), scratch, and the
//                   run's counters. One thread at a time; build one per run.
//
// A point p = R(phi) (o + sum_i W_i R(phi)^T x_i,xy) (at most 8 particles, W_i 3 x 2, o a fixed
// offset; R(phi) = I for a plain point) sees its particles' in-plane positions only: a network
// whose particles leave the plane must not use it. Pairs: points of different yarns, or of one
// yarn at least same_yarn_gap apart along it. Energy of a pair at distance D < d (touching) with
// g = (D - d0) / (d - d0): E = kappa (d - d0)^2 (-(g - 1)^2 ln g), +inf for D <= d0 (the core).
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
  // Co-rotation (docs/knit.md, "Yarn contact": co-rotated): the point's map turns with the
  // direction of x_j - x_i, (i, j) = turn (indices into `particles`; -1: the map does not turn), by
  // the angle from `axis` (a unit vector in the plane, that direction where the map was made).
  std::array<int, 2> turn{-1, -1};
  std::array<double, 2> axis{1.0, 0.0};
};

// A point's co-rotation at a state (docs/knit.md, "Yarn contact": co-rotated): R(phi) as (c, s), u
// and a in the turned frame, grad_j(phi) of its second turning particle (the first's is minus
// that), v and |v|^2. A plain point has c = 1, s = 0 and turns = false.
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
  // Renewal (docs/knit.md, "Yarn contact"; both set, or the points are never renewed). `exact`
  // writes every point's exact position (points order) from every particle's position; `linearise`
  // returns yarn y's points (as many as it has, in order) linearised about those positions; it must
  // be a function of the positions alone (the same positions, the same bits): a renewal refused at
  // its check makes the old maps again by calling it, as a run holds one set of maps. Points must
  // be ordered by yarn.
  std::function<void(const std::vector<Vec3>&, std::vector<Vec3>&)> exact;
  std::function<std::vector<ContactPoint>(const std::vector<Vec3>&, int)> linearise;
  double refresh_tol = 0.0;   // m: a yarn is renewed when one of its points strays this far
  double refresh_move = 0.0;  // m: and only checked once a particle moved this far (x or y) since
  double renew_keep = 0.5;    // a renewal keeps at least this fraction of a pair's gap to d0
  // With renewal: the points are `linearise`'s at the start state (every yarn linearised about
  // the network's initial positions reproduces `points`), so the model keeps none once it has
  // built its pattern and each run makes its own (one set of maps in memory per run, not two).
  bool remake_at_start = false;
};

// The model: const once built, shared by runs (see above).
class ContactModel {
 public:
  // Throws std::invalid_argument for a bad spec (see above).
  ContactModel(SpringNetwork network, YarnContactSpec contact);

  const SpringNetwork& network() const { return net_; }
  // The parameters and closures, defaults filled in; its points are those at rest (empty with
  // remake_at_start: each run makes them).
  const YarnContactSpec& spec() const { return spec_; }
  int point_count() const { return point_count_; }
  const CscPattern& stiffness_pattern() const { return pattern_; }

 private:
  friend class ContactNetwork;
  SpringNetwork net_;
  YarnContactSpec spec_;
  int point_count_ = 0;
  double reach_ = 0.0;           // d + skin
  CscPattern nodes_;             // the free particles' block pattern
  CscPattern pattern_;           // nodes_ expanded to 3 x 3 blocks
  std::vector<int> net_entry_;   // per value of the network's pattern, its place in pattern_
  std::vector<int> yarn_begin_;  // per yarn, its first point (and the end last); empty: no renewal
  std::vector<Vec3> start_;      // every particle's position in the initial state, m
};

// One run of a ContactModel (see above): a MechanicalSystem that owns the points' current maps.
class ContactNetwork final : public MechanicalSystem, public HeldPoints {
 public:
  explicit ContactNetwork(std::shared_ptr<const ContactModel> model);
  // A run of a model of its own.
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
  const CscPattern& stiffness_pattern() const override { return model_->pattern_; }
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
  // Renewal at an accepted state (docs/knit.md, "Yarn contact"): the yarns whose points stray
  // more than refresh_tol from their exact positions are re-linearised about (t, x), as far as
  // the step filter allows. True if any was (the functions changed there).
  bool update(double t, const double* x) override;
  bool has_run_state() const override { return true; }
  std::string describe() const override;
  HeldPoints* held_points() override { return this; }
  const HeldPoints* held_points() const override { return this; }
  // HeldPoints: the network's pins (SpringNetwork's), moved in this run's copy of the network;
  // the reactions include the contact's forces on held points.
  int held_count() const override { return net_.held_count(); }
  int held_particle(int k) const override { return net_.held_particle(k); }
  std::vector<Vec3> held_positions(double t) const override { return net_.held_positions(t); }
  void set_held_positions(const std::vector<Vec3>& p) override;
  void held_reactions(double t, const double* x, std::vector<Vec3>& out) const override;
  // Every yarn's points re-linearised about (t, x), whole (no step filter): for a run that
  // starts from a saved state (--continue), whose points at rest would not stand for the yarn
  // there. False, with the points left as they were, if the state is not finite, renewal is
  // not set up, or the renewed points put a pair inside its core.
  bool renew(double t, const double* x);

  const ContactModel& model() const { return *model_; }
  const std::shared_ptr<const ContactModel>& shared_model() const { return model_; }
  const SpringNetwork& network() const { return net_; }
  // The model's parameters (its points: model().spec(); this run's: points()).
  const YarnContactSpec& contact() const { return spec_; }
  const std::vector<ContactPoint>& points() const { return points_; }  // the current maps
  // Contact energy alone at (t, x), J (+inf inside a core).
  double contact_energy(double t, const double* x) const;
  // Smallest distance between two pairing points at (t, x), m (closer than d + skin; else
  // +inf), and how many pairs are in contact (closer than d).
  double min_distance(double t, const double* x, int* in_contact = nullptr) const;
  // Counters over the run. Pairs in contact whose Jacobian blocks were not all in the pattern,
  // over all evaluations:
  long pattern_misses() const { return pattern_misses_; }
  long list_rebuilds() const { return rebuilds_; }
  // Step-filter and renewal sweeps that found their pairs in the near-pair list (sweep_fraction).
  long list_sweeps() const { return list_sweeps_; }
  long refreshes() const { return refreshes_; }        // yarns renewed, over all updates
  long cut_renewals() const { return cut_renewals_; }  // renewals the step filter cut short

 private:
  struct Pair {
    int a, b;
  };
  // Particles, then points, into pos_, pts_ (and turns_); kept for the next call at the same
  // (t, x) (cached_x_, cached_t_) until points_changed().
  void positions(double t, const double* x) const;
  // The points' maps changed: positions and near pairs are stale, yarn_of_ and arc_of_ renewed.
  void points_changed();
  void refresh_pairs() const;                      // the near-pair list at pos_, if stale
  bool pairs_of(double t, const double* x) const;  // positions + list; false if not finite
  bool may_pair(int a, int b) const;
  // Yarn y's points linearised about the particles' positions (spec linearise, its count checked).
  std::vector<ContactPoint> linearised(const std::vector<Vec3>& particles, int y) const;
  // Yarn y's current maps made again into points_ from their recipe (made_at_, cut_offsets_;
  // the same bits): a renewal that fails its check restores the old maps so, not from a copy.
  void remake(int y);
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
  // The largest fraction in [0, 1] of the points' straight moves (move(k), a Vec3 per point k;
  // computed where it is asked for, not an array of its own) from start along which no pair
  // comes closer than d0 + keep (min(D_start, d) - d0): exact (a quadratic per pair), pairs by
  // their swept boxes, or the near-pair list where it holds every pair the moves can bring
  // within d. The step filter keeps filter_keep, a renewal renew_keep.
  template <class MoveOf>
  double sweep_fraction(const std::vector<Vec3>& start, MoveOf move, double keep) const;
  double turn_angle(int k) const;  // point k's phi at pts_'s state (0 for a plain point), rad
  PointTurn turn_of(int k) const;  // point k's PointTurn at pts_'s state (its u left unset)
  static constexpr double kChordTurn = 0.02;  // rad: the largest turn of a point per swept chord
  static constexpr int kMaxChords = 64;

  std::shared_ptr<const ContactModel> model_;
  // A copy of model_'s network (its structure shared): its held positions are this run's state,
  // changed only by set_held_positions().
  SpringNetwork net_;
  const YarnContactSpec& spec_;  // model_'s parameters (not its points)
  double reach_ = 0.0;           // d + skin

  // The run's state: changed only by update() and renew() (and set up by the constructor).
  std::vector<ContactPoint> points_;  // the current maps
  std::vector<int> yarn_of_;          // per point, its yarn (may_pair reads these, not points_)
  std::vector<double> arc_of_;        // per point, its arc length, m
  std::vector<Vec3> renewed_at_;      // every particle's position at the latest whole renewal
  // Per yarn the recipe of its current maps: linearised about *made_at_[y] (null: the model's
  // points), then, after a renewal cut short, these offsets (empty otherwise). The yarns renewed
  // at one update share one vector of positions.
  std::vector<std::shared_ptr<const std::vector<Vec3>>> made_at_;
  std::vector<std::vector<Vec3>> cut_offsets_;
  long refreshes_ = 0, cut_renewals_ = 0;

  // Caches, functions of the state evaluated last and points_ (positions()), and of the list's
  // history (refresh_pairs()); evaluations at the same (t, x) give the same values whatever
  // they hold. Mutable as they are refilled by const evaluations.
  mutable std::vector<Vec3> pos_, pts_;  // particles and points at cached_x_
  // Per point the part of its PointTurn at pts_'s state that is kept (56 bytes, not 112: turn_of
  // makes v from pos_ again, the same bits, and u is not needed).
  struct TurnCache {
    double c, s;
    Vec3 a;
    double gx, gy;
  };
  mutable std::vector<TurnCache> turns_;
  mutable std::vector<double> cached_x_;  // the state pos_, pts_ and turns_ describe, if cached_
  mutable double cached_t_ = 0.0;
  mutable bool cached_ = false;
  mutable std::vector<Vec3> listed_at_;  // the points where the near-pair list was made
  mutable std::vector<Pair> pairs_;      // the near-pair list
  // Scratch of one evaluation.
  mutable std::vector<double> net_values_, force_;
  // Counters of the const evaluations.
  mutable long pattern_misses_ = 0, rebuilds_ = 0, list_sweeps_ = 0;
};

}  // namespace knitsim
