#include "src/scene/whole_sheet_check.hpp"

#include "solvers/equilibrium_check.hpp"

namespace knitsim {

bool continue_on_whole_sheet(const MechanicalSystem& whole, Integrator& integ,
                             const IntegratorOptions& options, RunObserver* observer,
                             double t_start, const std::string& reduction, std::vector<double>& x,
                             std::vector<double>& v, RunStats& stats) {
  const double t = stats.t_final;
  detail::StiffnessProbe probe(whole, options.factorization);
  // Its inertia and smallest eigenvalue: the stop (the Newton correction) was the reduction's.
  const detail::StiffnessProbe::Result p =
      probe.probe(t, x.data(), detail::StiffnessProbe::Measure::Spectrum);
  if (p.factored && !p.singular && p.negative_pivots == 0) {
    stats.min_eigenvalue = p.min_eigenvalue;  // the whole sheet's, not the reduction's
    stats.eigenvalue_threshold = p.threshold;
    return false;
  }
  v.assign(x.size(), 0.0);
  double from = t;
  std::string how = "is not a minimum of the whole sheet: continued on it";
  if (!probe.leave_saddle(t, x.data(), 1e-3)) {  // m
    // No negative mode to leave along (a singular K, or a negative pivot too small for the
    // power iteration): the flow would stay on the symmetric state, which the stop cannot
    // certify. The whole sheet is solved from its own start instead.
    whole.initial_state(x.data(), v.data());
    from = t_start;
    how =
        "is not certified on the whole sheet (K singular or nearly so): the whole sheet was "
        "solved from its start";
  }
  const RunStats reduced = stats;
  stats = run_to_equilibrium(whole, integ, options, x, v, observer, from);
  add_counters(stats, reduced);
  stats.message += "; the " + reduction + "'s equilibrium " + how;
  return true;
}

}  // namespace knitsim
