#include "models/drape_grid.hpp"

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "src/core/invalid_field.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim {

const char* to_string(PinLayout layout) {
  return layout == PinLayout::FourCorner ? "four_corner" : "two_corner";
}

const char* to_string(DrapeSymmetry symmetry) {
  switch (symmetry) {
    case DrapeSymmetry::Half:
      return "half";
    case DrapeSymmetry::Quarter:
      return "quarter";
    case DrapeSymmetry::Eighth:
      return "eighth";
    case DrapeSymmetry::Auto:
      return "auto";
    case DrapeSymmetry::None:
      break;
  }
  return "none";
}

int DrapeParams::cells() const {
  return std::max(2, static_cast<int>(std::floor(width / natural_length + 0.5)));
}

void DrapeParams::validate() const {
  if (!(width > 0.0) || !std::isfinite(width)) bad_field("fabric.width", width, "must be > 0 m");
  if (!(areal_density > 0.0) || !std::isfinite(areal_density))
    bad_field("fabric.areal_density", areal_density, "must be > 0 g/m^2");
  if (!(stiffness > 0.0) || !std::isfinite(stiffness))
    bad_field("model.stiffness", stiffness, "must be > 0 N/m");
  if (!(damping >= 0.0) || !std::isfinite(damping))
    bad_field("model.damping", damping, "must be >= 0 N s/m");
  if (!(elongation_limit >= 0.0) || !std::isfinite(elongation_limit))
    bad_field("model.elongation_limit", elongation_limit, "must be >= 0 percent (0 disables it)");
  if (!(natural_length > 0.0) || !std::isfinite(natural_length))
    bad_field("model.natural_length", natural_length, "must be > 0 m");
  if (!(natural_length <= width / 1.5)) {  // round(W / L0) >= 2 cells per side
    std::ostringstream os;
    os << "must be <= fabric.width / 1.5 = " << width / 1.5 << " m (2 cells per side at least)";
    bad_field("model.natural_length", natural_length, os.str());
  }
  if (topology != 'a' && topology != 'b' && topology != 'c')
    throw std::invalid_argument(std::string("model.topology = ") + topology +
                                ": must be one of a, b, c");
  if (!(pin_span > 0.0 && pin_span <= 1.0)) bad_field("pins.span", pin_span, "must be in (0, 1]");
  if (!(pin_move_time >= 0.0) || !std::isfinite(pin_move_time))
    bad_field("pins.move_time", pin_move_time, "must be >= 0 s");
  if (!(perturbation >= 0.0) || !std::isfinite(perturbation))
    bad_field("model.perturbation", perturbation, "must be >= 0 m");
  if ((symmetry == DrapeSymmetry::Quarter || symmetry == DrapeSymmetry::Eighth) &&
      layout != PinLayout::FourCorner)
    throw std::invalid_argument(std::string("model.symmetry = ") + to_string(symmetry) +
                                ": needs pins.layout = four_corner (two_corner is not symmetric "
                                "about the mid-plane y = W/2)");
  if (symmetry != DrapeSymmetry::None && symmetry != DrapeSymmetry::Auto && perturbation != 0.0)
    bad_field("model.perturbation", perturbation,
              std::string("must be 0 with model.symmetry = ") + to_string(symmetry) +
                  " (a perturbed start is not mirror-symmetric)");
  const double n = std::floor(width / natural_length + 0.5);
  if ((n + 1) * (n + 1) > static_cast<double>(max_particles)) {
    std::ostringstream os;
    os << "model.natural_length = " << natural_length << ": gives a " << n + 1 << " x " << n + 1
       << " grid, over the cap of " << max_particles << " particles";
    throw std::invalid_argument(os.str());
  }
}

DrapeGrid build_drape_grid(const DrapeParams& p) {
  p.validate();
  const int n = p.cells();
  const int side = n + 1;
  const double L0 = p.natural_length;
  const double model_width = n * L0;
  auto index = [side](int i, int j) { return i * side + j; };

  SpringNetworkSpec spec;
  spec.positions.resize(side * side);
  spec.masses.resize(side * side);
  const double total_mass = p.areal_density * 1e-3 * model_width * model_width;  // kg
  const double unit = total_mass / (static_cast<double>(n) * n);
  std::mt19937 rng(p.seed);
  // A grid near max_particles takes seconds to build: a stop request (Ctrl-C) is read every
  // 64 rows and ends the set-up (StopRequested).
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      if (j == 0 && i % 64 == 0) throw_if_stop_requested();
      double z = 0.0;
      if (p.perturbation > 0.0)  // uniform in [-1, 1), generator-defined (portable) bits
        z = p.perturbation * (2.0 * (rng() / 4294967296.0) - 1.0);
      spec.positions[index(i, j)] = {j * L0, i * L0, z};
      const double wi = (i == 0 || i == n) ? 0.5 : 1.0;
      const double wj = (j == 0 || j == n) ? 0.5 : 1.0;
      spec.masses[index(i, j)] = wi * wj * unit;
    }

  auto add = [&](int a, int b, double rest) { spec.springs.push_back({a, b, rest, p.stiffness}); };
  const bool shear = p.topology == 'a' || p.topology == 'b';
  const bool bending = p.topology == 'a' || p.topology == 'c';
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j) {
      if (j == 0 && i % 64 == 0) throw_if_stop_requested();
      if (j + 1 < side) add(index(i, j), index(i, j + 1), L0);
      if (i + 1 < side) add(index(i, j), index(i + 1, j), L0);
      if (shear && i + 1 < side && j + 1 < side) {
        add(index(i, j), index(i + 1, j + 1), std::sqrt(2.0) * L0);
        add(index(i, j + 1), index(i + 1, j), std::sqrt(2.0) * L0);
      }
      if (bending && j + 2 < side) add(index(i, j), index(i, j + 2), 2.0 * L0);
      if (bending && i + 2 < side) add(index(i, j), index(i + 2, j), 2.0 * L0);
    }

  auto pin_fixed = [&](int particle) {
    spec.pinned.push_back(particle);
    spec.pin_paths.push_back({spec.positions[particle], spec.positions[particle], 0.0});
  };
  if (p.layout == PinLayout::FourCorner) {
    for (int particle : {index(0, 0), index(0, n), index(n, 0), index(n, n)}) pin_fixed(particle);
  } else {
    const double inset = 0.5 * (1.0 - p.pin_span) * model_width;
    const int left = index(0, 0), right = index(0, n);
    const double move = p.pin_span < 1.0 ? p.pin_move_time : 0.0;
    spec.pinned = {left, right};
    spec.pin_paths = {{spec.positions[left], spec.positions[left] + Vec3{inset, 0, 0}, move},
                      {spec.positions[right], spec.positions[right] - Vec3{inset, 0, 0}, move}};
  }
  // Pins start where the particles start (the perturbation does not move them).
  for (size_t k = 0; k < spec.pinned.size(); ++k) {
    spec.positions[spec.pinned[k]].z = 0.0;
    spec.pin_paths[k].start.z = spec.pin_paths[k].end.z = 0.0;
  }
  spec.damping = p.damping;
  spec.elongation_limit = p.elongation_limit / 100.0;

  std::vector<GridEdge> edges(4);
  edges[0].name = "top";     // i = 0
  edges[1].name = "bottom";  // i = n
  edges[2].name = "left";    // j = 0
  edges[3].name = "right";   // j = n
  for (int k = 0; k < side; ++k) {
    edges[0].particles.push_back(index(0, k));
    edges[1].particles.push_back(index(n, k));
    edges[2].particles.push_back(index(k, 0));
    edges[3].particles.push_back(index(k, n));
  }
  return DrapeGrid{p, n, SpringNetwork(std::move(spec)), std::move(edges)};
}

std::string drape_limit_violation(const DrapeParams& p, double max_strain, double centre_sag) {
  std::ostringstream os;
  os.precision(4);
  const double width = p.cells() * p.natural_length;
  if (!std::isfinite(max_strain) || !std::isfinite(centre_sag)) {
    os << "the end state's max strain (" << max_strain << ") or centre sag (" << centre_sag
       << " m) is not finite";
  } else if (p.elongation_limit > 0.0 &&
             max_strain > (1.0 + kStrainLimitTolerance) * p.elongation_limit / 100.0) {
    os << "max strain " << 100.0 * max_strain << " % is past the elongation limit "
       << p.elongation_limit << " % (tolerance " << 100.0 * kStrainLimitTolerance
       << " % of it): the springs are far softer than the load";
  } else if (std::abs(centre_sag) > width) {
    os << "centre sag " << centre_sag << " m is larger than the sheet (" << width << " m wide)";
  }
  return os.str();
}

const char* to_string(DrapeParameter p) {
  switch (p) {
    case DrapeParameter::Stiffness:
      return "stiffness";
    case DrapeParameter::Damping:
      return "damping";
    case DrapeParameter::ElongationLimit:
      return "elongation_limit";
    case DrapeParameter::NaturalLength:
      return "natural_length";
  }
  return "?";
}

SpringNetworkTangent drape_tangent(const DrapeGrid& grid, DrapeParameter p, double t) {
  const SpringNetworkSpec& spec = grid.network.spec();
  SpringNetworkTangent d;
  switch (p) {
    case DrapeParameter::Stiffness:
      d.stiffness.assign(spec.springs.size(), 1.0);
      break;
    case DrapeParameter::Damping:
      break;
    case DrapeParameter::ElongationLimit:
      d.elongation_limit = 0.01;
      break;
    case DrapeParameter::NaturalLength: {
      const double L0 = grid.params.natural_length;
      for (const Spring& s : spec.springs) d.rest.push_back(s.rest / L0);
      for (double m : spec.masses) d.mass.push_back(2.0 * m / L0);
      for (const PinPath& pin : spec.pin_paths) d.pin_position.push_back((1.0 / L0) * pin.at(t));
      break;
    }
  }
  return d;
}

}  // namespace knitsim
