// The textile measures of a knit run as files (src/measure/knit_measures.hpp; definitions:
// docs/knit.md, "Textile measures"): stitches.csv and summary.json's `fabric` block.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "src/measure/knit_measures.hpp"

namespace knitsim {

// stitches.csv: a header line, then one row per chart cell, bottom course first, by wale:
//   wale,course,stitch,held_over,x_m,y_m,z_m,x0_m,y0_m,z0_m,loop_height_m,loop_height0_m,
//   loop_width_m,loop_width0_m,yarn_length_m,yarn_length0_m,float_length_m,float_length0_m,
//   float_depth_m,float_depth0_m
// stitch K, T or M; "0" columns at rest; lengths in m, shortest exact text; a measure a cell does
// not have (a miss's loop, a loop's float) is an empty field.
std::string stitches_csv(const TextileMeasures& k);

// summary.json's `fabric` block (NaN as null: a chart too small for the interior).
nlohmann::json fabric_json(const FabricMeasure& f);

// Its entry in summary.json's `units`.
extern const char* const kFabricUnits;

}  // namespace knitsim
