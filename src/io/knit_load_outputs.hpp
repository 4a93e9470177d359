// What a knit run under load adds to its outputs (docs/knit.md, "Under load";
// docs/summary_json.md): loads.csv, one row per load step, and summary.json's `loads`.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "src/scene/knit_run.hpp"

namespace knitsim {

// loads.csv: step,load,status,newton_steps,residual, then per clamp K (summary.json's
// clamps.each[K], in order) clamp_K_displacement_{x,y,z}_m and clamp_K_reaction_{x,y,z}_N, then
// applied_{x,y,z}_N, weight_{x,y,z}_N and balance_{x,y,z}_N (models/knit_loads.hpp) -- one row
// per load step; numbers the shortest exact text.
std::string knit_loads_csv(const KnitResult& r);

// summary.json's `loads`: the steps run of knit.load_steps, and the last step's load fraction and
// balance (reactions_N, applied_N, weight_N, balance_N).
nlohmann::json knit_loads_json(const KnitResult& r);

// The console's row: "reactions (x, y) + applied (x, y) + weight (x, y) = (x, y) N".
std::string knit_balance_text(const KnitBalance& b);

}  // namespace knitsim
