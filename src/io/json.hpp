// JSON of the model parameters, run options and run statistics, as summaries and manifests
// record them (nlohmann_json stays out of models/ and solvers/).
#pragma once

#include <nlohmann/json.hpp>

#include "models/drape_grid.hpp"
#include "solvers/integrator.hpp"

namespace knitsim {

nlohmann::json to_json(const DrapeParams& p);        // field names as in DrapeParams
nlohmann::json to_json(const IntegratorOptions& o);  // field names as in IntegratorOptions
nlohmann::json to_json(const RunStats& s);           // status as to_string(RunStatus)

}  // namespace knitsim
