// What `knitsim tensile` writes (docs/knit.md, "Under load"): tensile.csv, tensile.png (force
// against extension), step_NNN/ (the knit outputs of the kept steps), summary.json and
// manifest.json.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "src/scene/tensile_run.hpp"

namespace knitsim {

// tensile.csv: step,strain,displacement_m,force_N,force_per_width_N_per_m,lateral_strain,
// energy_J,status,newton_steps,reaction_fixed_x_N,reaction_fixed_y_N,reaction_moving_x_N,
// reaction_moving_y_N -- one row per step, rest (step 0) first; numbers the shortest exact text.
std::string tensile_csv(const TensileResult& r);

// summary.json of a tensile test: the specimen, the options, per step the status, Newton steps
// and reactions, the initial stiffness (N/m per unit strain, from step 1) and the timings.
nlohmann::json tensile_summary(const KnitScene& scene, const TensileOptions& options,
                               const TensileResult& r);

// Writes tensile.csv, tensile.png (unless pictures = false), summary.json and manifest.json into
// `dir` (which must exist), the last file of the set.
void write_tensile_outputs(const std::filesystem::path& dir, const KnitScene& scene,
                           const TensileOptions& options, const TensileResult& r,
                           bool pictures = true);

}  // namespace knitsim
