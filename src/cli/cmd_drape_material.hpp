// knitsim drape on a scene with model.kind = material (docs/material_drape.md): the same command
// line as paper 1's model, its own run and outputs (src/scene/material_run.hpp,
// src/io/material_outputs.hpp). --continue and --target are paper 1's (state.json, the Eq. 5
// edges) and refused here.
#pragma once

#include <string>

#include "src/scene/scene.hpp"

namespace knitsim {

struct MaterialDrapeCommand {
  std::string out, target, continue_from;
  bool step_history = false, quiet = false;
  IntegratorOptions flags;  // the run flags as given (for warnings)
};

// Runs the validated `scene` with `integrator`, writes the outputs, prints the summary; throws
// CLI::RuntimeError with the run's exit code where it did not end at equilibrium (as drape).
void run_material_drape_command(Scene& scene, const std::string& integrator,
                                const MaterialDrapeCommand& args);

}  // namespace knitsim
