// Synthetic "measured" edges for the reproduction of paper 1 (paper_repro/data/README.md): the
// paper's own edge data are photographs (its Tables 5 and 7), so the targets are made by this code,
// with provenance and fixed seeds.
//   twin  : the drape model at the sample's Table 4 parameters and Table 2 areal density: the
//           built-in scene (four_corner | two_corner, fabric.width 0.50 m) with fabric.
//           areal_density, model.stiffness, model.damping, model.elongation_limit,
//           model.natural_length and model.topology set to the sample's values.
//   cross : the same fabric on a 3x finer grid: spacing L0/3 and 3n cells per side, where n is
//           the twin's cell count, so fabric.width is set to the twin's model width n L0 and the
//           two sheets are the same size and mass (the only difference is the discretisation).
//           Same k: a square spring grid of spacing h has, across a strip of width w, w/h chains
//           in parallel, each of L/h springs k in series, so the strip's stretch stiffness is
//           k (w/h) / (L/h) = k w / L whatever h -- the membrane stiffness per unit width (k,
//           N/m, times w/L) does not depend on the spacing, for the structural and (by the same
//           count along the diagonals) the shear springs. The bending springs (rest 2h) resist
//           a fold only through the shortening of a chord across the kink, which for a given
//           curvature shrinks with h: their bending resistance does not survive refinement,
//           and the finer sheet drapes differently -- the model error the fit has to absorb.
//           Damping c/9: the damper acts per particle and the particle mass falls by 9
//           (interior mass rho_A h^2), so c/m, the damping rate of every mode, is unchanged; the
//           equilibrium does not depend on c anyway. Run option atol = the drape default / 9
//           (1.1e-10): the static residual is normalised by the mean particle weight, 9x
//           smaller.
// Both scenes (four_corner and two_corner) are simulated on the whole sheet to equilibrium from
// the flat state (run_drape, cvode-bdf, rtol 1e-8, atol 1e-10 for the twin, the scene's
// equilibrium_tol 1e-8; why these tolerances: paper_repro/data/README.md, "Tolerances"), their
// edges are measured with measure_edges (src/measure/measurement.hpp: the same normalisation as
// any simulation), and noise is added to every edge point, the pinned corners included:
//   each of the two camera-plane coordinates of a point gets, per photo, an independent
//   Gaussian error of sigma = noise_mm (default 0.5 mm); a point is the mean of `photos`
//   (default 5, the paper's 5 repeats) photos, so its error has sigma / sqrt(photos).
//   In normalised units the camera coordinates are divided by the span of the normalisation
//   (src/measure/measurement.hpp): for a four_corner edge |B - A| (its two corners, 3D), for
//   two_corner the pin distance S in the x-z plane -- both m, at equilibrium -- so s and d each get
//     (noise_mm * 1e-3 / span_m) * (mean of `photos` standard normal draws).
//   (Pins are level in both scenes, so s and d are exactly camera coordinates over the span;
//   the pins themselves are taken as exact: they are known fixed positions.)
// Random numbers: one std::mt19937_64 stream per (sample, set, scene), seeded by
// std::seed_seq{seed, sample, set (0 twin, 1 cross), scene (0 four_corner, 1 two_corner)};
// standard normals by the Box-Muller transform written here (u in (0, 1) from the top 53 bits;
// std::normal_distribution differs between standard libraries). Draw order: edges in grid
// order (top, bottom, left, right), points along the edge, per point the `photos` draws of s
// then the `photos` draws of d. Deterministic: same (sample, set, options) -> the same numbers,
// bit for bit, with the same build (compiler, libm, SUNDIALS/KLU); on another platform the
// drape itself may differ in the last digits (within rtol).
// Cost: a cross target integrates 9x the particles of a twin (run times:
// paper_repro/data/README.md).
#pragma once

#include <string>
#include <vector>

#include "src/paper/paper_data.hpp"
#include "src/scene/scene.hpp"
#include "src/fit/targets.hpp"
#include "src/scene/fit_options.hpp"

namespace knitsim {

enum class SyntheticSet { Twin, Cross };
const char* to_string(SyntheticSet set);  // "twin" | "cross"
// "twin" | "cross"; throws std::invalid_argument "set = X: accepted twin|cross".
SyntheticSet synthetic_set_from_name(const std::string& name);

// The scenes of every synthetic target, in file order: four_corner, two_corner.
const std::vector<std::string>& synthetic_scene_names();

// The drape scene simulated for (sample, set) and scene name (four_corner | two_corner; else
// std::invalid_argument): as described above, with options.rtol = 1e-8, validated.
Scene synthetic_scene(const PaperSample& sample, SyntheticSet set, const std::string& scene);

// The integrator of the synthetic drapes: "cvode-bdf".
const char* synthetic_integrator();

// The target of one sample. Throws std::runtime_error if a drape does not reach equilibrium,
// std::invalid_argument for invalid options.
Target make_synthetic_target(const PaperSample& sample, SyntheticSet set,
                             const SyntheticOptions& options = {});

// The committed file name of a target: "<set>_sample<s>.csv" (e.g. twin_sample3.csv) under
// paper_repro/data/targets/.
std::string synthetic_target_file(SyntheticSet set, int sample);

// The first '#' line `knitsim targets` writes into that file (without the "# "): it names the
// set and the sample, so a reader can tell a file renamed or copied under another sample's name.
std::string synthetic_target_title(SyntheticSet set, int sample);

}  // namespace knitsim
