// A knit run under load (docs/knit.md, "Under load"): the clamps moved along their paths and the
// loads (clamps under force, forces on points; models/knit_loads.hpp) applied in N equal load
// steps (knit.load_steps; 0 = one), each an equilibrium from the last one's (the unknowns of the
// bars under force included), with each step's reactions and balance. What run_knit runs when
// the chart carries loads or knit.load_steps > 0; its per-step rows are loads.csv
// (src/io/knit_load_outputs.hpp).
//
// The driver sees the model through its contract (MechanicalSystem + HeldPoints, through
// ForceControl), as the tensile test does; a model that offers both serves it.
//
// Failure modes: bad input throws std::invalid_argument (knit_force_control: InvalidField of
// knit.forces); a step that does not reach equilibrium ends the run with its status, the steps
// so far kept.
#pragma once

#include <vector>

#include "models/knit_loads.hpp"
#include "solvers/integrator.hpp"
#include "src/scene/knit_run.hpp"

namespace knitsim {

// True when a run of `params` steps through loads: knit.load_steps > 0, a clamp under force or a
// force on a point. Otherwise run_knit runs as without them (the same outputs, byte for byte).
bool knit_load_stepped(const KnitParams& params);

// Steps `model` (its clamps at rest) to load fraction 1 from state (x, v) (the free points'; on
// return the end state's, the bars' positions held by the model), appending one row per step to
// `steps`. The statistics are the last step's, the counters and times summed over the steps.
RunStats run_knit_load_steps(KnitModel& model, Integrator& integ, const IntegratorOptions& opt,
                             std::vector<double>& x, std::vector<double>& v, RunObserver* observer,
                             std::vector<KnitLoadStep>& steps);

}  // namespace knitsim
