// Synthetic targets (see src/fit/synthetic_targets.hpp for the definitions).
#include "src/fit/synthetic_targets.hpp"

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>

#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

constexpr double kRtol = 1e-8;  // the fit's tolerance (src/fit/drape_fit.hpp)
// Absolute tolerance of the twin, m and m/s: below the drape default, at which BDF's corrector
// floor can hold a drape just above equilibrium_tol until t_max (paper_repro/data/README.md,
// "Tolerances").
constexpr double kAtol = 1e-10;
constexpr int kRefinement = 3;  // cross: spacing L0 / 3
constexpr double kMmToM = 1e-3;
constexpr double kPi = 3.14159265358979323846;

// Standard normal numbers from a std::mt19937_64 (whose sequence the C++ standard fixes) by the
// Box-Muller transform: z1 = r cos(2 pi u2), z2 = r sin(2 pi u2), r = sqrt(-2 ln u1), both used.
class NormalStream {
 public:
  explicit NormalStream(std::seed_seq& seeds) : engine_(seeds) {}

  double next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double r = std::sqrt(-2.0 * std::log(uniform()));
    const double angle = 2.0 * kPi * uniform();
    spare_ = r * std::sin(angle);
    has_spare_ = true;
    return r * std::cos(angle);
  }

 private:
  // Uniform in the open interval (0, 1): the top 53 bits, shifted by half a unit.
  double uniform() { return (static_cast<double>(engine_() >> 11) + 0.5) * 0x1p-53; }

  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// The length every normalised coordinate of `edge` is divided by (src/measure/measurement.hpp), m.
double normalisation_span(const DrapeGrid& grid, const GridEdge& edge,
                          const std::vector<Vec3>& positions) {
  if (grid.params.layout == PinLayout::FourCorner)
    return norm(positions[edge.particles.back()] - positions[edge.particles.front()]);
  const Vec3 pin1 = positions[grid.index(0, 0)], pin2 = positions[grid.index(0, grid.n)];
  return std::hypot(pin2.x - pin1.x, pin2.z - pin1.z);
}

int scene_index(const std::string& scene) {
  const std::vector<std::string>& names = synthetic_scene_names();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == scene) return static_cast<int>(i);
  throw std::invalid_argument("scene = " + scene + ": accepted four_corner|two_corner");
}

// One scene of the target: drape, measure, add the photo noise.
TargetScene synthetic_scene_target(const PaperSample& sample, SyntheticSet set,
                                   const std::string& name, const SyntheticOptions& options) {
  const Scene scene = synthetic_scene(sample, set, name);
  const DrapeResult drape = run_drape(scene, synthetic_integrator());
  if (drape.stats.status != RunStatus::Equilibrium)
    throw std::runtime_error("synthetic target: " + std::string(to_string(set)) + " sample " +
                             std::to_string(sample.sample) + " " + name +
                             " did not reach equilibrium: " + drape.stats.message);
  const std::vector<EdgeFit> fits = measure_edges(drape.grid, drape.positions);

  std::seed_seq seeds{options.seed, static_cast<unsigned>(sample.sample),
                      static_cast<unsigned>(set), static_cast<unsigned>(scene_index(name))};
  NormalStream normal(seeds);
  const auto photo_mean = [&] {
    double sum = 0.0;
    for (int p = 0; p < options.photos; ++p) sum += normal.next();
    return sum / options.photos;
  };

  TargetScene target{name, {}, {}};
  for (size_t e = 0; e < fits.size(); ++e) {
    const double sigma = options.noise_mm * kMmToM /
                         normalisation_span(drape.grid, drape.grid.edges[e], drape.positions);
    TargetEdge edge;
    edge.name = fits[e].name;
    edge.kind = TargetKind::Points;
    edge.points = fits[e].points;
    for (size_t k = 0; k < edge.points.s.size(); ++k) {
      edge.points.s[k] += sigma * photo_mean();
      edge.points.d[k] += sigma * photo_mean();
    }
    target.edges.push_back(std::move(edge));
  }
  return target;
}

}  // namespace

const char* to_string(SyntheticSet set) { return set == SyntheticSet::Twin ? "twin" : "cross"; }

SyntheticSet synthetic_set_from_name(const std::string& name) {
  if (name == "twin") return SyntheticSet::Twin;
  if (name == "cross") return SyntheticSet::Cross;
  throw std::invalid_argument("set = " + name + ": accepted twin|cross");
}

const std::vector<std::string>& synthetic_scene_names() {
  static const std::vector<std::string> names = {"four_corner", "two_corner"};
  return names;
}

const char* synthetic_integrator() { return "cvode-bdf"; }

Scene synthetic_scene(const PaperSample& sample, SyntheticSet set, const std::string& name) {
  scene_index(name);  // rejects other scenes
  Scene scene = load_scene(name);
  DrapeParams& p = scene.params;
  p.areal_density = sample.areal_density;
  p.stiffness = sample.stiffness;
  p.damping = sample.damping;
  p.elongation_limit = sample.elongation_limit;
  p.natural_length = sample.natural_length;
  p.topology = sample.topology;
  // The reference data come from the whole sheet by the dynamics: a path independent of the
  // fits' (the equilibrium solver, on a mirror reduction).
  p.symmetry = DrapeSymmetry::None;
  scene.options.atol = kAtol;
  if (set == SyntheticSet::Cross) {
    const int n = p.cells();
    p.width = n * sample.natural_length;
    p.natural_length = sample.natural_length / kRefinement;
    p.damping = sample.damping / (kRefinement * kRefinement);
    // The static residual is normalised by the mean particle weight, 9x smaller here, so the
    // absolute tolerance is the drape default / 9 (paper_repro/data/README.md, "Tolerances").
    scene.options.atol = IntegratorOptions{}.atol / (kRefinement * kRefinement);
    if (p.cells() != kRefinement * n)
      throw std::logic_error("synthetic_scene: cross grid has " + std::to_string(p.cells()) +
                             " cells, expected " + std::to_string(kRefinement * n));
  }
  scene.options.rtol = kRtol;
  scene.validate();
  return scene;
}

Target make_synthetic_target(const PaperSample& sample, SyntheticSet set,
                             const SyntheticOptions& options) {
  options.validate();
  Target target;
  for (const std::string& name : synthetic_scene_names())
    target.scenes.push_back(synthetic_scene_target(sample, set, name, options));
  target.validate();
  return target;
}

std::string synthetic_target_file(SyntheticSet set, int sample) {
  return std::string(to_string(set)) + "_sample" + std::to_string(sample) + ".csv";
}

std::string synthetic_target_title(SyntheticSet set, int sample) {
  // A file format's fixed first line, kept byte for byte: every committed target file carries
  // it and repro compares it, so the path in it names the format, not a file of the tree.
  return std::string("Synthetic target (SPEC 2.8, src/synthetic_targets.hpp): ") + to_string(set) +
         ", sample " + std::to_string(sample) +
         " of paper 1 (Mozafary & Payvandy 2017, Tables 2 and 4).";
}

}  // namespace knitsim
