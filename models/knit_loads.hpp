// The loads of a knit chart (docs/knit.md, "Under load"): its clamps under force (knit.clamps'
// `force`) and its forces on points (knit.forces) as force control over the running system
// (models/force_control.hpp), and the balance of reactions, applied loads and weight.
//
// Failure modes: knit_force_control throws InvalidField of knit.forces (one line naming the
// force and the accepted range) for a cell outside the chart, a miss (no loop), a tuck's lower
// point (it has none) or a held point.
#pragma once

#include <memory>
#include <vector>

#include "models/force_control.hpp"
#include "models/knit_loops.hpp"

namespace knitsim {

// Throws what knit_force_control would (InvalidField of knit.forces), building nothing.
void validate_knit_loads(const KnitModel& m);

// True when the chart carries loads: a clamp under force or a force on a point.
bool knit_loaded(const KnitModel& m);

// Force control over m.system() (which must outlive it): m's clamps under force as bars, its
// point forces as point loads, at load fraction 1. The finite-difference step is 1e-4 r.
std::unique_ptr<ForceControl> knit_force_control(KnitModel& m);

// The balance on the fabric at (t, x) (free points' x; the held ones where the running system
// holds them) and load fraction `load`, N: the clamps' reactions, a clamp under force counted
// with its applied force along its loaded components (its reaction there at an equilibrium),
// the forces on points, and the weight; `sum` vanishes at an equilibrium, to the residual.
struct KnitBalance {
  Vec3 reactions;  // the clamps' reactions, the loaded components of clamps under force left out
  Vec3 applied;    // load x (the clamps' forces + the points' forces)
  Vec3 weight;
  Vec3 sum;  // reactions + applied + weight
};
KnitBalance knit_balance(const KnitModel& m, double t, const std::vector<double>& x, double load);

}  // namespace knitsim
