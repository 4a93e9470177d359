#include "src/io/textile_outputs.hpp"

#include <cmath>

#include "src/base/text.hpp"

namespace knitsim {

const char* const kFabricUnits =
    "courses_per_cm, wales_per_cm (at the end) and their _rest 1/cm, over the plain knit loops "
    "two or more from every edge (null: the chart is too small, docs/knit.md \"Textile "
    "measures\"); width_change, length_change 1: the wale (course) spacing at the end over "
    "at rest, minus 1; stitch_length_m, stitch_length_rest_m m: the mean yarn length per cell "
    "over the cells two or more from every edge; interior_cells, wale_steps, course_steps: "
    "what was pooled";

std::string stitches_csv(const TextileMeasures& k) {
  std::string out =
      "wale,course,stitch,held_over,x_m,y_m,z_m,x0_m,y0_m,z0_m,loop_height_m,loop_height0_m,"
      "loop_width_m,loop_width0_m,yarn_length_m,yarn_length0_m,float_length_m,float_length0_m,"
      "float_depth_m,float_depth0_m\n";
  out.reserve(out.size() + 300 * k.stitches.size());
  for (const StitchMeasure& s : k.stitches) {
    append_integer(out, s.wale);
    out += ',';
    append_integer(out, s.course);
    out += ',';
    out += static_cast<char>(s.stitch);
    out += ',';
    append_integer(out, s.held_over);
    for (double v : {s.centre.x, s.centre.y, s.centre.z, s.centre_rest.x, s.centre_rest.y,
                     s.centre_rest.z, s.loop_height, s.loop_height_rest, s.loop_width,
                     s.loop_width_rest, s.yarn_length, s.yarn_length_rest, s.float_length,
                     s.float_length_rest, s.float_depth, s.float_depth_rest}) {
      out += ',';
      if (std::isfinite(v)) append_number(out, v);
    }
    out += '\n';
  }
  return out;
}

nlohmann::json fabric_json(const FabricMeasure& f) {
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  return {{"courses_per_cm", number(f.courses_per_cm)},
          {"wales_per_cm", number(f.wales_per_cm)},
          {"courses_per_cm_rest", number(f.courses_per_cm_rest)},
          {"wales_per_cm_rest", number(f.wales_per_cm_rest)},
          {"width_change", number(f.width_change)},
          {"length_change", number(f.length_change)},
          {"stitch_length_m", number(f.stitch_length)},
          {"stitch_length_rest_m", number(f.stitch_length_rest)},
          {"interior_cells", f.interior_cells},
          {"wale_steps", f.wale_steps},
          {"course_steps", f.course_steps}};
}

}  // namespace knitsim
