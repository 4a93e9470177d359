#include "src/scene/knit_load_steps.hpp"

#include <algorithm>
#include <memory>

namespace knitsim {

bool knit_load_stepped(const KnitParams& params) {
  if (params.load_steps > 0 || !params.point_forces.empty()) return true;
  return std::any_of(params.clamps.begin(), params.clamps.end(), [](const KnitClampSpec& c) {
    return c.force.x != 0.0 || c.force.y != 0.0 || c.force.z != 0.0;
  });
}

RunStats run_knit_load_steps(KnitModel& model, Integrator& integ, const IntegratorOptions& opt,
                             std::vector<double>& x, std::vector<double>& v, RunObserver* observer,
                             std::vector<KnitLoadStep>& steps) {
  std::unique_ptr<ForceControl> fc = knit_force_control(model);  // validates knit.forces
  const int n = model.system().dof(), N = std::max(1, model.params.load_steps);
  std::vector<Vec3> rest(fc->held_count());
  for (int k = 0; k < fc->held_count(); ++k) rest[k] = model.points[fc->held_particle(k)].rest;
  std::vector<double> xs(fc->dof()), vs(fc->dof(), 0.0), x0(fc->dof()), v0(fc->dof());
  fc->initial_state(x0.data(), v0.data());
  std::copy(x.begin(), x.end(), xs.begin());
  std::copy(x0.begin() + n, x0.end(), xs.begin() + n);  // the bars at rest
  RunStats total;
  double cpu = 0.0, wall = 0.0;
  for (int k = 1; k <= N; ++k) {
    const double load = static_cast<double>(k) / N;
    move_clamps(*fc, model.clamps, rest, load);  // the clamps under force stay at rest
    fc->set_load(load);
    std::fill(vs.begin(), vs.end(), 0.0);
    RunStats s = run_to_equilibrium(*fc, integ, opt, xs, vs, observer, 0.0);
    fc->hold_at(xs.data());  // the model holds the bars where the step ended
    KnitLoadStep row{k, load, s, knit_clamp_reactions(model, s.t_final, xs), {}};
    row.balance = knit_balance(model, s.t_final, xs, load);
    cpu += s.cpu_seconds, wall += s.wall_seconds;
    add_counters(s, total);  // the last step's status, the counters so far
    s.cpu_seconds = cpu, s.wall_seconds = wall;
    total = s;
    steps.push_back(std::move(row));
    if (s.status != RunStatus::Equilibrium) break;
  }
  x.assign(xs.begin(), xs.begin() + n);
  v.assign(vs.begin(), vs.begin() + n);
  return total;
}

}  // namespace knitsim
