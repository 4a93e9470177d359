#include "src/core/held_points.hpp"

#include <cstddef>

namespace knitsim {

Vec3 ClampPath::at(double load) const {
  double s0 = 0.0;
  Vec3 u0{};
  for (std::size_t k = 0; k < s.size(); ++k) {
    if (load <= s[k]) return u0 + ((load - s0) / (s[k] - s0)) * (u[k] - u0);
    s0 = s[k], u0 = u[k];
  }
  return u0;
}

void move_clamps(HeldPoints& held, const std::vector<Clamp>& clamps,
                 const std::vector<Vec3>& rest, double load) {
  std::vector<Vec3> p = held.held_positions(0.0);
  for (const Clamp& c : clamps) {
    const Vec3 u = c.path.at(load);
    for (int k : c.held) p[k] = rest[k] + u;
  }
  held.set_held_positions(p);
}

std::vector<Vec3> clamp_reactions(const HeldPoints& held, const std::vector<Clamp>& clamps,
                                  double t, const double* x) {
  std::vector<Vec3> each;
  held.held_reactions(t, x, each);
  std::vector<Vec3> out(clamps.size());
  for (std::size_t c = 0; c < clamps.size(); ++c)
    for (int k : clamps[c].held) out[c] = out[c] + each[k];
  return out;
}

}  // namespace knitsim
