#include "src/cli_options.hpp"

#include <CLI/CLI.hpp>

namespace knitsim {

void add_ica_options(CLI::App* cmd, IcaOptions& o) {
  cmd->add_option("--seed", o.seed, "random seed")->capture_default_str();
  cmd->add_option("--jobs", o.jobs, "threads evaluating costs (same result for any value)")
      ->capture_default_str();
  cmd->add_option("--decades", o.decades, "MaxIt, number of decades (>= 1)")->capture_default_str();
  cmd->add_option("--countries", o.countries, "number of countries (> imperialists)")
      ->capture_default_str();
  cmd->add_option("--imperialists", o.imperialists, "number of imperialists (>= 1)")
      ->capture_default_str();
  cmd->add_option("--beta", o.beta, "assimilation coefficient (> 0)")->capture_default_str();
  cmd->add_option("--gamma", o.gamma, "assimilation angle bound, rad (0 .. pi)")
      ->capture_default_str();
  cmd->add_option("--revolution", o.revolution_rate, "revolution rate (0 .. 1)")
      ->capture_default_str();
  cmd->add_option("--xi", o.xi, "colonies' share of the empire cost (>= 0)")->capture_default_str();
  cmd->add_flag("--stop-one-empire", o.stop_when_one_empire,
                "stop as soon as one empire is left (paper's literal step 9; default: run all "
                "decades)");
}

void rethrow_with_flag_names(const std::invalid_argument& e,
                             const std::vector<std::pair<std::string, std::string>>& extra) {
  static const std::vector<std::pair<std::string, std::string>> ica = {
      {"countries", "--countries"}, {"imperialists", "--imperialists"},
      {"decades", "--decades"},     {"beta", "--beta"},
      {"gamma", "--gamma"},         {"revolution_rate", "--revolution"},
      {"xi", "--xi"},               {"jobs", "--jobs"}};
  const std::string msg = e.what();
  for (const auto* names : {&ica, &extra})
    for (const auto& [field, flag] : *names)
      if (msg.rfind(field + " = ", 0) == 0)
        throw std::invalid_argument(flag + msg.substr(field.size()));
  throw e;
}

}  // namespace knitsim
