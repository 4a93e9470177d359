#include "src/io/json.hpp"

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
  return {{"rtol", o.rtol},
          {"atol", o.atol},
          {"velocity_atol", o.velocity_atol},
          {"dt", o.dt},
          {"dt_safety", o.dt_safety},
          {"max_order", o.max_order},
          {"max_steps", o.max_steps},
          {"t_max", o.t_max},
          {"equilibrium_tol", o.equilibrium_tol},
          {"max_wall_seconds", o.max_wall_seconds},
          {"check_every", o.check_every},
          {"runaway_position", o.runaway_position},
          {"position_tol", o.position_tol},
          {"max_restarts", o.max_restarts},
          {"newton_solver", to_string(o.newton_solver)},
          {"krylov_dim", o.krylov_dim},
          {"krylov_eps_lin", o.krylov_eps_lin},
          {"gmres_preconditioner", to_string(o.gmres_preconditioner)},
          {"factorization", to_string(o.factorization)}};
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
