#include "src/cli/cli_options.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <type_traits>

#include "src/base/command_line.hpp"
#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

template <typename T>
CLI::Option* add_seed_option(CLI::App* cmd, T& seed, const std::string& help) {
  static_assert(std::is_unsigned_v<T>, "a seed is an unsigned integer");
  const std::string range = "0.." + std::to_string(std::numeric_limits<T>::max());
  auto check = [range](const std::string& text) -> std::string {
    const bool digits = !text.empty() && std::all_of(text.begin(), text.end(),
                                                     [](char c) { return c >= '0' && c <= '9'; });
    if (digits) {
      errno = 0;
      const unsigned long long v = std::strtoull(text.c_str(), nullptr, 10);
      if (errno != ERANGE && v <= std::numeric_limits<T>::max()) return "";
    }
    return "must be a decimal integer in " + range;
  };
  return cmd->add_option("--seed", seed, help)->check(check);
}
template CLI::Option* add_seed_option(CLI::App*, std::uint64_t&, const std::string&);
template CLI::Option* add_seed_option(CLI::App*, unsigned&, const std::string&);

namespace {

// Length of the '-' of `text` (0 or 1) if it is a decimal integer ([-]digits; no '-' when
// `is_unsigned`), -1 otherwise.
int decimal_sign(const std::string& text, bool is_unsigned) {
  const size_t sign = !is_unsigned && !text.empty() && text[0] == '-' ? 1 : 0;
  if (text.size() == sign || text.find_first_not_of("0123456789", sign) != std::string::npos)
    return -1;
  return static_cast<int>(sign);
}

}  // namespace

void require_well_formed_values(CLI::App& app) {
  // A transform runs before every check: the checks of an option (--seed's own) see "10".
  const auto drop_leading_zeros = [](bool is_unsigned) {
    return CLI::Validator(
        [is_unsigned](std::string& text) {
          const int sign = decimal_sign(text, is_unsigned);
          if (sign >= 0) {  // CLI11 would read a leading 0 as octal
            const size_t first = std::min(text.find_first_not_of('0', sign), text.size() - 1);
            text.erase(sign, first - sign);
          }
          return std::string();
        },
        "");
  };
  const auto integer = [](bool is_unsigned) {
    return CLI::Validator(
        [is_unsigned](const std::string& text) -> std::string {
          if (decimal_sign(text, is_unsigned) < 0)
            return is_unsigned ? "must be a decimal integer >= 0" : "must be a decimal integer";
          errno = 0;
          if (is_unsigned)
            (void)std::strtoull(text.c_str(), nullptr, 10);
          else
            (void)std::strtoll(text.c_str(), nullptr, 10);
          return errno == ERANGE ? "out of range: " + text : "";
        },
        "");
  };
  const CLI::Validator not_empty(
      [](const std::string& text) { return text.empty() ? "must not be empty" : ""; }, "");
  for (CLI::App* cmd : app.get_subcommands([](CLI::App*) { return true; }))
    for (CLI::Option* opt : cmd->get_options([](CLI::Option*) { return true; })) {
      const std::string type = opt->get_type_name();
      if (type == "INT" || type == "UINT") {
        opt->transform(drop_leading_zeros(type == "UINT"));
        opt->check(integer(type == "UINT"));
      }
      if (type == "TEXT") opt->check(not_empty);
    }
}

void add_ica_options(CLI::App* cmd, IcaOptions& o) {
  add_seed_option(cmd, o.seed, "random seed")->capture_default_str();
  cmd->add_option("--jobs", o.jobs, "threads evaluating costs (same result for any value)")
      ->capture_default_str();
  cmd->add_option("--decades", o.decades, "MaxIt, number of decades (>= 1)")
      ->capture_default_str()
      ->group(kIcaOptionGroup);
  cmd->add_option("--countries", o.countries,
                  "number of countries (> imperialists, <= " +
                      std::to_string(IcaOptions::max_countries) + ")")
      ->capture_default_str()
      ->group(kIcaOptionGroup);
  cmd->add_option("--imperialists", o.imperialists, "number of imperialists (>= 1)")
      ->capture_default_str()
      ->group(kIcaOptionGroup);
  cmd->add_option("--beta", o.beta, "assimilation coefficient (> 0)")
      ->capture_default_str()
      ->group(kIcaOptionGroup);
  cmd->add_option("--gamma", o.gamma, "assimilation angle bound, rad (0 .. pi)")
      ->capture_default_str()
      ->group(kIcaOptionGroup);
  cmd->add_option("--revolution", o.revolution_rate, "revolution rate (0 .. 1)")
      ->capture_default_str()
      ->group(kIcaOptionGroup);
  cmd->add_option("--xi", o.xi, "colonies' share of the empire cost (>= 0)")
      ->capture_default_str()
      ->group(kIcaOptionGroup);
  cmd->add_flag("--stop-one-empire", o.stop_when_one_empire,
                "stop as soon as one empire is left (paper's literal step 9; default: run all "
                "decades)")
      ->group(kIcaOptionGroup);
}

CLI::Option* add_atol_options(CLI::App* cmd, double& atol, double& velocity_atol) {
  cmd->add_option("--atol", atol,
                  "Absolute tolerance, m (positions) and m/s (velocities, unless --velocity-atol)")
      ->capture_default_str();
  return cmd
      ->add_option("--velocity-atol", velocity_atol,
                   "Absolute tolerance of the velocities, m/s (0 = --atol); ~ atol x the rate "
                   "(rad/s) of the motion to resolve")
      ->capture_default_str();
}

namespace {

// --flag NAME for an enum option: NAME is one of to_string(value) over `all`.
template <typename E, size_t N>
void add_named_option(CLI::App* cmd, const std::string& flag, E& which, const E (&all)[N],
                      const std::string& help) {
  std::vector<std::string> names;
  for (const E e : all) names.emplace_back(to_string(e));
  cmd->add_option_function<std::string>(
         flag,
         [&which, &all](const std::string& name) {
           for (const E e : all)
             if (name == to_string(e)) which = e;
         },
         help)
      ->check(CLI::IsMember(names))
      ->default_str(to_string(which));
}

}  // namespace

void add_newton_solver_option(CLI::App* cmd, IntegratorOptions::NewtonSolver& which) {
  using NS = IntegratorOptions::NewtonSolver;
  static const NS all[] = {NS::Klu, NS::SchurLdl, NS::SchurCgLdl};
  add_named_option(cmd, "--newton-solver", which, all,
                   "Newton linear solver of cvode-bdf, arkode-dirk, arkode-imex: klu (2n LU), ldl "
                   "(velocity block eliminated, 3n symmetric LDL^T) or cg-ldl (the same, with "
                   "Jacobi-CG instead of the factorisation at small steps)");
}

void add_factorization_option(CLI::App* cmd, IntegratorOptions::Factorization& which) {
  using F = IntegratorOptions::Factorization;
  static const F all[] = {F::Automatic, F::Simplicial, F::Block, F::Supernodal};
  add_named_option(
      cmd, "--factorization", which, all,
      "sparse factorisation of the 3n symmetric matrix (implicit-euler, ldl, cg-ldl, "
      "schur-ldl): simplicial (Eigen LDL^T), block (LDL^T in 3 x 3 particle blocks, 2 x 2 "
      "where z couples to nothing; simplicial where the matrix has none), supernodal (CHOLMOD "
      "LL^T, LDL^T where not positive definite) or auto (block, supernodal from 33000 "
      "unknowns)");
}

void add_gmres_options(CLI::App* cmd, IntegratorOptions& o) {
  using GP = IntegratorOptions::GmresPreconditioner;
  static const GP all[] = {GP::None, GP::BlockJacobi, GP::SchurIc, GP::SchurLdl};
  add_named_option(cmd, "--gmres-preconditioner", o.gmres_preconditioner, all,
                   "cvode-bdf-gmres: none, block-jacobi (6 x 6 per particle), schur-ic "
                   "(incomplete Cholesky of the 3n Schur matrix) or schur-ldl (its LDL^T, lagged "
                   "between set-ups)");
  cmd->add_option("--krylov-dim", o.krylov_dim,
                  "cvode-bdf-gmres: Krylov dimension (0 = SUNDIALS' 5)")
      ->capture_default_str();
  cmd->add_option(
         "--eps-lin", o.krylov_eps_lin,
         "cvode-bdf-gmres: linear tolerance factor (CVodeSetEpsLin); with block-jacobi the "
         "residual a run can reach is proportional to it")
      ->capture_default_str();
}

CLI::Option* add_run_options(CLI::App* cmd, IntegratorOptions& o) {
  cmd->add_option("--rtol", o.rtol, "Relative tolerance (adaptive methods)")->capture_default_str();
  CLI::Option* velocity_atol = add_atol_options(cmd, o.atol, o.velocity_atol);
  cmd->add_option("--dt", o.dt, "Fixed step, s (fixed-step methods; 0 = automatic)")
      ->capture_default_str();
  cmd->add_option("--max-order", o.max_order, "Cap on the method order (0 = default)")
      ->capture_default_str();
  cmd->add_option("--max-steps", o.max_steps, "Step cap")->capture_default_str();
  cmd->add_option("--max-wall", o.max_wall_seconds,
                  "Wall-clock cap, s (0 = none); the run then ends with status wall_limit")
      ->capture_default_str();
  cmd->add_option("--max-restarts", o.max_restarts,
                  "Restarts from the last accepted state after CVODE's or ARKODE's repeated "
                  "error-test or corrector failures (0 = the run ends with solver_failure)")
      ->capture_default_str();
  add_newton_solver_option(cmd, o.newton_solver);
  add_factorization_option(cmd, o.factorization);
  add_gmres_options(cmd, o);
  return velocity_atol;
}

void add_history_and_continue_options(CLI::App* cmd, bool& step_history, std::string& continue_from,
                                      const std::string& inputs) {
  cmd->add_flag("--step-history", step_history,
                "Also write steps.csv: t, step size, order and residual of every step (thinned "
                "evenly beyond 2e5 rows)");
  cmd->add_option("--continue", continue_from,
                  "Start from the final state (state.json) of the run in this folder, at its "
                  "t_final: continues an interrupted or capped run (same " +
                      inputs + "; integrator and run options may change)");
}

void copy_run_flags(const IntegratorOptions& flags, IntegratorOptions& into) {
  into.rtol = flags.rtol;
  into.atol = flags.atol;
  into.velocity_atol = flags.velocity_atol;
  into.dt = flags.dt;
  into.max_order = flags.max_order;
  into.max_steps = flags.max_steps;
  into.max_wall_seconds = flags.max_wall_seconds;
  into.max_restarts = flags.max_restarts;
  into.newton_solver = flags.newton_solver;
  into.factorization = flags.factorization;
  into.gmres_preconditioner = flags.gmres_preconditioner;
  into.krylov_dim = flags.krylov_dim;
  into.krylov_eps_lin = flags.krylov_eps_lin;
}

void rethrow_with_flag_names(const std::invalid_argument& e,
                             const std::vector<std::pair<std::string, std::string>>& extra) {
  static const std::vector<std::pair<std::string, std::string>> ica = {
      {"countries", "--countries"},
      {"imperialists", "--imperialists"},
      {"decades", "--decades"},
      {"beta", "--beta"},
      {"gamma", "--gamma"},
      {"revolution_rate", "--revolution"},
      {"xi", "--xi"},
      {"jobs", "--jobs"}};
  std::vector<std::pair<std::string, std::string>> names = ica;
  names.insert(names.end(), extra.begin(), extra.end());
  rethrow_renamed(e, names);
}

void warn(const std::string& message) {
  std::cerr << "knitsim " << command_name() << ": warning: " << message << std::endl;
}

void note(const std::string& message) {
  std::cerr << "knitsim " << command_name() << ": note: " << message << std::endl;
}

void note_keys_not_given(const Scene& scene, const std::vector<std::string>& among) {
  if (scene.source == "built-in") return;
  const std::vector<std::string> missing = keys_not_given(scene, among);
  if (missing.empty()) return;
  std::string list;
  for (const std::string& key : missing)
    list += (list.empty() ? "" : ", ") + key + " = " + scene_key_value(scene, key);
  note(scene.source + " leaves " + list +
       " at sample 1's values (set them in the file or with --set; knitsim list keys)");
}

const std::vector<std::string>& physical_scene_keys() {
  static const std::vector<std::string> keys = {
      "fabric.width",           "fabric.areal_density",   "model.stiffness", "model.damping",
      "model.elongation_limit", "model.natural_length",   "model.topology",  "pins.layout"};
  return keys;
}

void warn_about_run(const std::string& damping_key, double damping, const IntegratorInfo& integ,
                    const IntegratorOptions& flags, double t_max) {
  if (damping == 0.0 && !integ.damps_numerically)
    warn(damping_key + " = 0: with no damping nothing comes to rest (only implicit-euler's " +
         "numerical damping settles it); " + integ.name + " runs on to run.t_max = " +
         format_number(t_max, 6) + " s, hours with the defaults: cap it with --max-wall");
  if (flags.dt > 0.0 && integ.adaptive)
    warn("--dt is for the fixed-step integrators; " + integ.name +
         " chooses its own steps and ignores it");
}

void refuse_at_run_start(const std::invalid_argument& e, const std::filesystem::path& dir,
                         bool created) {
  remove_if_unused(dir, created);
  rethrow_with_flag_names(e, run_option_names());
}

void exit_with_run_status(const char* command, const RunStats& stats,
                          const InterruptScope& interrupt, const std::string& dir) {
  if (stats.status == RunStatus::Equilibrium) return;
  const char* why = stats.status == RunStatus::Interrupted ? interrupt.signal_name()
                    : stats.status == RunStatus::StepLimit ? "--max-steps"
                    : stats.status == RunStatus::WallLimit ? "--max-wall"
                                                           : nullptr;
  if (why != nullptr)  // a run cut short, not a failed one: say how to go on
    std::cerr << "knitsim " << command << ": "
              << (stats.status == RunStatus::Interrupted ? "interrupted by " : "stopped by ") << why
              << " at t = " << stats.t_final << " s; outputs written to " << dir
              << "/; the same command with --continue " << dir << " goes on from there"
              << std::endl;
  throw CLI::RuntimeError(stats.status == RunStatus::Interrupted ? interrupt.exit_code() : 3);
}

}  // namespace knitsim
