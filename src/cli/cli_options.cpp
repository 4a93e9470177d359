#include "src/cli/cli_options.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <any>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <type_traits>
#include <variant>

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

namespace {

// The flag of `key` (a row of key_table() with a flag), bound to `field`: CLI11 parses it as
// the field's type (INT for the integers: require_well_formed_values), help shows the default.
template <typename T>
CLI::Option* add_flag_of(CLI::App* cmd, const Key& key, T& field) {
  return cmd->add_option(key.flag, field, key.meaning)->capture_default_str();
}

// The flag of an IntegratorOptions row, bound to its field in `o`: a number, or one of the
// row's choices.
CLI::Option* add_option_flag(CLI::App* cmd, const Key& key, IntegratorOptions& o) {
  if (const auto* d = std::get_if<double IntegratorOptions::*>(&key.option))
    return add_flag_of(cmd, key, o.*(*d));
  if (const auto* i = std::get_if<int IntegratorOptions::*>(&key.option))
    return add_flag_of(cmd, key, o.*(*i));
  if (const auto* l = std::get_if<long IntegratorOptions::*>(&key.option))
    return add_flag_of(cmd, key, o.*(*l));
  return cmd
      ->add_option_function<std::string>(
          key.flag, [&o, &key](const std::string& name) { key.set_option(o, name); }, key.meaning)
      ->check(CLI::IsMember(key.choices))
      ->default_str(key.get_option(o));
}

}  // namespace

template <class S>
std::vector<CLI::Option*> add_row_flags(CLI::App* cmd, S& o) {
  std::vector<CLI::Option*> added;
  for (const Key& key : key_table()) {
    const std::string range = key_range(key);
    const std::string help = key.meaning + (range.empty() ? "" : " (" + range + ")");
    if (const auto* i = std::any_cast<int S::*>(&key.member))
      added.push_back(cmd->add_option(key.flag, o.*(*i), help)->capture_default_str());
    else if (const auto* d = std::any_cast<double S::*>(&key.member))
      added.push_back(cmd->add_option(key.flag, o.*(*d), help)->capture_default_str());
    else if (const auto* b = std::any_cast<bool S::*>(&key.member))
      added.push_back(cmd->add_flag(key.flag, o.*(*b), help));
  }
  return added;
}
template std::vector<CLI::Option*> add_row_flags(CLI::App*, IcaOptions&);
template std::vector<CLI::Option*> add_row_flags(CLI::App*, LmOptions&);
template std::vector<CLI::Option*> add_row_flags(CLI::App*, LmStartOptions&);
template std::vector<CLI::Option*> add_row_flags(CLI::App*, SyntheticOptions&);

void add_ica_options(CLI::App* cmd, IcaOptions& o) {
  add_seed_option(cmd, o.seed, "random seed")->capture_default_str();
  for (CLI::Option* opt : add_row_flags(cmd, o))
    if (opt->get_name() != "--jobs") opt->group(kIcaOptionGroup);  // other optimizers read it
}

CLI::Option* add_atol_options(CLI::App* cmd, double& atol, double& velocity_atol) {
  add_flag_of(cmd, key_of_flag("--atol"), atol);
  return add_flag_of(cmd, key_of_flag("--velocity-atol"), velocity_atol);
}

CLI::Option* add_run_options(CLI::App* cmd, IntegratorOptions& o,
                             std::map<std::string, std::string>* typed) {
  CLI::Option* velocity_atol = nullptr;
  for (const Key& key : key_table()) {
    if (key.flag.empty() || (key.option.index() == 0 && !key.set_option)) continue;
    CLI::Option* opt = add_option_flag(cmd, key, o);
    if (typed != nullptr)
      opt->each([typed, &key](const std::string& text) { (*typed)[key.flag] = text; });
    if (key.flag == "--velocity-atol") velocity_atol = opt;
  }
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
  for (const Key& key : key_table()) {
    if (key.flag.empty()) continue;
    std::visit(
        [&](auto member) {
          if constexpr (!std::is_same_v<decltype(member), std::monostate>)
            into.*member = flags.*member;
        },
        key.option);
    if (key.set_option) key.set_option(into, key.get_option(flags));
  }
}

void rethrow_with_flag_names(const std::invalid_argument& e,
                             const std::vector<std::pair<std::string, std::string>>& names) {
  const std::string msg = e.what();
  for (const auto& [field, flag] : names)
    if (msg.rfind(field + " = ", 0) == 0)
      throw std::invalid_argument(flag + msg.substr(field.size()));
  rethrow_as_typed(e);
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
  rethrow_as_typed(e);
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
