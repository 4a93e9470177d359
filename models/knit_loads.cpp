#include "models/knit_loads.hpp"

#include <string>

#include "src/core/invalid_field.hpp"

namespace knitsim {

namespace {

double& component(Vec3& v, int c) { return c == 0 ? v.x : c == 1 ? v.y : v.z; }
double component(const Vec3& v, int c) { return c == 0 ? v.x : c == 1 ? v.y : v.z; }

// The particle a point force acts on; throws InvalidField of knit.forces.
int force_particle(const KnitModel& m, const KnitPointForce& f) {
  auto refuse = [&](const std::string& why) { throw InvalidField("knit.forces", f.text, why); };
  if (f.wale >= m.chart.wales || f.course >= m.chart.courses)
    refuse("the cell must be in wales 0 to " + std::to_string(m.chart.wales - 1) +
           " and courses 0 to " + std::to_string(m.chart.courses - 1));
  const int l = m.loop(f.wale, f.course);
  if (l < 0) refuse("the cell is a miss: it has no loop to load");
  const int p = f.upper ? m.loops[l].upper : m.loops[l].lower;
  if (p < 0) refuse("a tuck has no lower point: load its upper one");
  if (m.network.free_index(p) < 0) refuse("the point is held by a clamp: load the clamp instead");
  return p;
}

}  // namespace

void validate_knit_loads(const KnitModel& m) {
  for (const KnitPointForce& f : m.params.point_forces) force_particle(m, f);
}

bool knit_loaded(const KnitModel& m) {
  for (const Clamp& c : m.clamps)
    if (c.forced()) return true;
  return !m.params.point_forces.empty();
}

std::unique_ptr<ForceControl> knit_force_control(KnitModel& m) {
  std::vector<ForceBar> bars;
  for (const Clamp& c : m.clamps)
    if (c.forced()) bars.push_back({c.name, c.held, c.force});
  std::vector<PointLoad> loads;
  for (const KnitPointForce& f : m.params.point_forces)
    loads.push_back({3 * m.network.free_index(force_particle(m, f)), f.force});
  return std::make_unique<ForceControl>(m.system(), std::move(bars), std::move(loads),
                                        m.network.residual_force_scale(),
                                        1e-4 * m.params.loop_radius);
}

KnitBalance knit_balance(const KnitModel& m, double t, const std::vector<double>& x, double load) {
  KnitBalance b;
  std::vector<Vec3> each;
  m.system().held_points()->held_reactions(t, x.data(), each);
  for (const Clamp& c : m.clamps) {
    Vec3 r{};
    for (int k : c.held) r = r + each[k];
    for (int i = 0; i < 3; ++i)
      if (component(c.force, i) != 0.0) component(r, i) = 0.0;
    b.reactions = b.reactions + r;
    b.applied = b.applied + load * c.force;
  }
  for (const KnitPointForce& f : m.params.point_forces) b.applied = b.applied + load * f.force;
  const SpringNetworkSpec& spec = m.network.spec();
  double mass = 0.0;
  for (double q : spec.masses) mass += q;
  b.weight = mass * spec.gravity;
  b.sum = b.reactions + b.applied + b.weight;
  return b;
}

}  // namespace knitsim
