// knitsim knit with knit.model = yarn and knit.boundary = periodic: the chart as one repeat of a
// fabric without edges, relaxed as a periodic cell whose size is free (src/scene/yarn_cell_run.hpp,
// docs/yarn_model.md "Periodic cell"); writes summary.json (its `cell` block), cell_yarn.csv and
// manifest.json into --out. Bad input (the network model, pins, clamps, gravity, --continue)
// writes nothing and exits 2; a run that ends in any status but equilibrium writes its files and
// exits 3.
#pragma once

#include <string>

#include "src/scene/knit_scene.hpp"

namespace knitsim {

void run_knit_cell(const KnitScene& scene, const std::string& integrator, const std::string& out,
                   bool quiet, const std::string& continue_from);

}  // namespace knitsim
