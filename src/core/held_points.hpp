// HeldPoints: the points a model holds at prescribed positions (pins, clamps) -- not degrees of
// freedom -- as run state a driver may move between steps, and the force that holds each one.
// What the clamps, reactions and the tensile test (src/scene/clamps.hpp, src/scene/tensile_run.hpp;
// docs/knit.md, "Under load") need of a model, and all they see of it: a model offers it through
// MechanicalSystem::held_points().
//
// Run state (src/core/mechanical_system.hpp, header): set_held_positions() changes the model's
// functions, like update(); the driver calls it between runs to equilibrium through a non-const
// reference, and an integrator must be started afresh after it. Held positions set this way are
// fixed in time (a path in time given at construction, e.g. a drape's pin move, is replaced).
//
// Units: SI (m, N). Failure modes: set_held_positions with the wrong count or a non-finite
// position throws std::invalid_argument and changes nothing.
#pragma once

#include <string>
#include <vector>

#include "src/core/vec3.hpp"

namespace knitsim {

class HeldPoints {
 public:
  virtual ~HeldPoints() = default;
  // Number of held points, and the model's particle each one is (its own numbering).
  virtual int held_count() const = 0;
  virtual int held_particle(int k) const = 0;
  // Every held point's position at time t, m (length held_count()).
  virtual std::vector<Vec3> held_positions(double t) const = 0;
  // Holds every point at p[k] from now on, at all t (run state; see the header).
  virtual void set_held_positions(const std::vector<Vec3>& p) = 0;
  // The reaction on each held point at (t, x): the force the hold exerts on it, N, minus the sum
  // of every force of the model on it (springs, stencils, contact, its own weight), so that at an
  // equilibrium the reactions, the applied loads and the weight of the whole sum to zero.
  virtual void held_reactions(double t, const double* x, std::vector<Vec3>& out) const = 0;
};

}  // namespace knitsim

namespace knitsim {

// A clamp's prescribed displacement from its rest position as a function of the load fraction s
// in [0, 1] (a run's load steps): piecewise linear through (0, 0) and the knots (s_k, u_k),
// 0 < s_1 < ... <= 1, held at the last knot's after it. No knots: a fixed clamp.
struct ClampPath {
  std::vector<double> s;  // load fractions, increasing, in (0, 1]
  std::vector<Vec3> u;    // displacements, m
  bool fixed() const { return s.empty(); }
  Vec3 at(double load) const;
};

// A clamp: a set of held points (indices into HeldPoints) moved together along a path, or a
// rigid bar under a force (force control, models/force_control.hpp): its non-zero components are
// loaded (the bar's position along them an unknown), the others held where the path puts them.
struct Clamp {
  std::string name;       // as the user named it ("top", "wales 0-3")
  std::vector<int> held;  // indices into the model's held points
  ClampPath path;
  Vec3 force{};  // N at load fraction 1 (applied as load x force); zero: displacement control
  bool forced() const { return force.x != 0.0 || force.y != 0.0 || force.z != 0.0; }
};

// Holds every clamp's points at rest[k] + path.at(load) (rest: every held point's rest position,
// m): run state, set between runs to equilibrium (see the header).
void move_clamps(HeldPoints& held, const std::vector<Clamp>& clamps,
                 const std::vector<Vec3>& rest, double load);
// Each clamp's reaction at (t, x), N: the sum of its points' (HeldPoints::held_reactions).
std::vector<Vec3> clamp_reactions(const HeldPoints& held, const std::vector<Clamp>& clamps,
                                  double t, const double* x);

}  // namespace knitsim
