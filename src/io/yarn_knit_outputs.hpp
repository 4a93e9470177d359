// summary.json's additions for a knit run with knit.model = yarn (docs/yarn_model.md, "What a
// run writes"): the `yarn` block gains the yarn's own measures, and `model`, `dof` and
// `yarn_model` say what ran.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>

#include "src/scene/yarn_knit_run.hpp"

namespace knitsim {

void add_yarn_knit_summary(const YarnKnitRun& run, std::size_t dof, nlohmann::json& summary);

}  // namespace knitsim
