// model.symmetry = auto's check of a reduced drape on the whole sheet (docs/scenes.md,
// "Symmetry"; paper 1's drape and the material model's share it).
#pragma once

#include <string>
#include <vector>

#include "solvers/integrator.hpp"

namespace knitsim {

// A mirror reduction cannot see the antisymmetric modes, so the equilibrium it reached,
// unfolded onto the whole sheet as x (the whole model's unknowns at stats.t_final), is certified
// on the whole sheet: its K is factorised (inertia and smallest eigenvalue). Positive definite:
// stats takes the whole sheet's smallest eigenvalue and threshold, and false is returned. Else
// the run goes on over the whole sheet -- from x moved 1 mm along K's most negative mode, or,
// where none is found (K singular or nearly so), from the whole sheet's start at t_start --
// with `integ` and `options`; stats becomes that run's, the reduced run's counters added and
// its message saying so ("the <reduction>'s equilibrium ..."), x and v its end state, and true
// is returned.
bool continue_on_whole_sheet(const MechanicalSystem& whole, Integrator& integ,
                             const IntegratorOptions& options, RunObserver* observer,
                             double t_start, const std::string& reduction, std::vector<double>& x,
                             std::vector<double>& v, RunStats& stats);

}  // namespace knitsim
