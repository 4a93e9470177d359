#include "src/io/json.hpp"

#include <type_traits>
#include <variant>

#include "src/scene/scene.hpp"

namespace knitsim {

nlohmann::json to_json(const DrapeParams& p) {
  return {{"width", p.width},
          {"areal_density", p.areal_density},
          {"stiffness", p.stiffness},
          {"damping", p.damping},
          {"elongation_limit", p.elongation_limit},
          {"natural_length", p.natural_length},
          {"topology", std::string(1, p.topology)},
          {"layout", to_string(p.layout)},
          {"pin_span", p.pin_span},
          {"pin_move_time", p.pin_move_time},
          {"perturbation", p.perturbation},
          {"seed", p.seed},
          {"symmetry", to_string(p.symmetry)}};
}

nlohmann::json to_json(const IntegratorOptions& o) {
  nlohmann::json j = nlohmann::json::object();
  for (const Key& key : key_table()) {  // its IntegratorOptions rows, under their field names
    std::visit(
        [&](auto member) {
          if constexpr (!std::is_same_v<decltype(member), std::monostate>) j[key.field] = o.*member;
        },
        key.option);
    if (key.get_option) j[key.field] = key.get_option(o);
  }
  return j;
}

nlohmann::json to_json(const RunStats& s) {
  return {{"integrator", s.integrator},
          {"status", to_string(s.status)},
          {"message", s.message},
          {"t_final", s.t_final},
          {"residual", s.residual},
          {"residual_floor", s.residual_floor},
          {"dt", s.dt},
          {"dt_predicted", s.dt_predicted},
          {"dt_estimated", s.dt_estimated},
          {"steps", s.steps},
          {"rhs_evals", s.rhs_evals},
          {"jac_evals", s.jac_evals},
          {"lin_setups", s.lin_setups},
          {"factorisations", s.factorisations},
          {"factorization", s.factorization},
          {"ldl_fallbacks", s.ldl_fallbacks},
          {"factor_nonzeros", s.factor_nonzeros},
          {"factor_flops", s.factor_flops},
          {"lin_iters", s.lin_iters},
          {"nonlin_iters", s.nonlin_iters},
          {"nonlin_fails", s.nonlin_fails},
          {"err_test_fails", s.err_test_fails},
          {"restarts", s.restarts},
          {"max_order_used", s.max_order_used},
          {"certificate", s.certificate},
          {"negative_pivots", s.negative_pivots},
          {"min_eigenvalue", s.min_eigenvalue},
          {"eigenvalue_threshold", s.eigenvalue_threshold},
          {"newton_step", s.newton_step},
          {"newton_floor", s.newton_floor},
          {"energy", s.energy},
          {"energy_reference", s.energy_reference},
          {"saddle_escapes", s.saddle_escapes},
          {"fallbacks", s.fallbacks},
          {"stop_factorisations", s.stop_factorisations},
          {"wall_seconds", s.wall_seconds},
          {"cpu_seconds", s.cpu_seconds}};
}

}  // namespace knitsim
