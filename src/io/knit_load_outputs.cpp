#include "src/io/knit_load_outputs.hpp"

#include "src/base/text.hpp"

namespace knitsim {

std::string knit_loads_csv(const KnitResult& r) {
  std::string out = "step,load,status,newton_steps,residual";
  for (std::size_t k = 0; k < r.model.clamps.size(); ++k)
    for (const char* what : {"displacement", "reaction"})
      for (const char* c : {"x", "y", "z"})
        out +=
            ",clamp_" + std::to_string(k) + "_" + what + "_" + c + (what[0] == 'd' ? "_m" : "_N");
  for (const char* what : {"applied", "weight", "balance"})
    for (const char* c : {"x", "y", "z"}) out += std::string(",") + what + "_" + c + "_N";
  out += '\n';
  auto add = [&out](const Vec3& v) {
    for (double q : {v.x, v.y, v.z}) {
      out += ',';
      append_number(out, q);
    }
  };
  for (const KnitLoadStep& s : r.load_steps) {
    out += std::to_string(s.step) + ',';
    append_number(out, s.load);
    out += std::string(",") + to_string(s.stats.status) + ',' + std::to_string(s.stats.steps) + ',';
    append_number(out, s.stats.residual);
    for (const ClampReaction& c : s.clamps) {
      add(c.displacement);
      add(c.reaction);
    }
    add(s.balance.applied);
    add(s.balance.weight);
    add(s.balance.sum);
    out += '\n';
  }
  return out;
}

nlohmann::json knit_loads_json(const KnitResult& r) {
  auto vec = [](Vec3 v) { return nlohmann::json::array({v.x, v.y, v.z}); };
  // (the last step's balance, at the run's end: knit_summary's clamps take applied_N and balance_N
  // from here)
  nlohmann::json out = {{"steps", r.load_steps.size()}, {"load_steps", r.model.params.load_steps}};
  if (r.load_steps.empty()) return out;
  const KnitLoadStep& s = r.load_steps.back();
  out["load"] = s.load;
  out["reactions_N"] = vec(s.balance.reactions);
  out["applied_N"] = vec(s.balance.applied);
  out["weight_N"] = vec(s.balance.weight);
  out["balance_N"] = vec(s.balance.sum);
  return out;
}

std::string knit_balance_text(const KnitBalance& b) {
  auto xy = [](Vec3 v) { return "(" + format_number(v.x, 4) + ", " + format_number(v.y, 4) + ")"; };
  return "reactions " + xy(b.reactions) + " + applied " + xy(b.applied) + " + weight " +
         xy(b.weight) + " = " + xy(b.sum) + " N";
}

}  // namespace knitsim
