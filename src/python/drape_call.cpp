#include "src/python/drape_call.hpp"

#include <cerrno>
#include <cstdlib>
#include <optional>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/fit/targets.hpp"

namespace knitsim {

namespace {

// One run option: its flag, and how text sets it (false: not a value of its type).
struct RunOption {
  std::string name, flag;
  bool (*set)(IntegratorOptions&, const std::string&);
  const char* type;  // for the message of a value that is not of the type
};

bool to_double(const std::string& text, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size();
}

template <typename I>
bool to_integer(const std::string& text, I& out) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE) return false;
  out = static_cast<I>(v);
  return static_cast<long long>(out) == v;
}

template <typename E, std::size_t N>
bool to_enum(const std::string& text, E& out, const E (&all)[N]) {
  for (const E e : all)
    if (text == to_string(e)) return (out = e, true);
  return false;
}

using NS = IntegratorOptions::NewtonSolver;
using GP = IntegratorOptions::GmresPreconditioner;
using FA = IntegratorOptions::Factorization;
constexpr NS kNewtonSolvers[] = {NS::Klu, NS::SchurLdl, NS::SchurCgLdl};
constexpr GP kPreconditioners[] = {GP::None, GP::BlockJacobi, GP::SchurIc, GP::SchurLdl};
constexpr FA kFactorizations[] = {FA::Automatic, FA::Simplicial, FA::Block, FA::Supernodal};

template <typename E, std::size_t N>
std::string names_of(const E (&all)[N]) {
  std::string s = "one of ";
  for (std::size_t i = 0; i < N; ++i) s += (i ? ", " : "") + std::string(to_string(all[i]));
  return s;
}

// The flags of add_run_options (src/cli/cli_options.cpp), the fields copy_run_flags copies.
const std::vector<RunOption>& run_options() {
  using O = IntegratorOptions;
  static const std::string newton = names_of(kNewtonSolvers), gmres = names_of(kPreconditioners),
                           factor = names_of(kFactorizations);
  static const std::vector<RunOption> table = {
      {"rtol", "--rtol", [](O& o, const std::string& t) { return to_double(t, o.rtol); }, "a number"},
      {"atol", "--atol", [](O& o, const std::string& t) { return to_double(t, o.atol); }, "a number"},
      {"velocity_atol", "--velocity-atol",
       [](O& o, const std::string& t) { return to_double(t, o.velocity_atol); }, "a number"},
      {"dt", "--dt", [](O& o, const std::string& t) { return to_double(t, o.dt); }, "a number"},
      {"max_order", "--max-order",
       [](O& o, const std::string& t) { return to_integer(t, o.max_order); }, "an integer"},
      {"max_steps", "--max-steps",
       [](O& o, const std::string& t) { return to_integer(t, o.max_steps); }, "an integer"},
      {"max_wall", "--max-wall",
       [](O& o, const std::string& t) { return to_double(t, o.max_wall_seconds); }, "a number"},
      {"max_restarts", "--max-restarts",
       [](O& o, const std::string& t) { return to_integer(t, o.max_restarts); }, "an integer"},
      {"stall_checks", "--stall-checks",
       [](O& o, const std::string& t) { return to_integer(t, o.stall_checks); }, "an integer"},
      {"newton_solver", "--newton-solver",
       [](O& o, const std::string& t) { return to_enum(t, o.newton_solver, kNewtonSolvers); },
       newton.c_str()},
      {"factorization", "--factorization",
       [](O& o, const std::string& t) { return to_enum(t, o.factorization, kFactorizations); },
       factor.c_str()},
      {"gmres_preconditioner", "--gmres-preconditioner",
       [](O& o, const std::string& t) {
         return to_enum(t, o.gmres_preconditioner, kPreconditioners);
       },
       gmres.c_str()},
      {"krylov_dim", "--krylov-dim",
       [](O& o, const std::string& t) { return to_integer(t, o.krylov_dim); }, "an integer"},
      {"eps_lin", "--eps-lin",
       [](O& o, const std::string& t) { return to_double(t, o.krylov_eps_lin); }, "a number"}};
  return table;
}

}  // namespace

void apply_run_option(IntegratorOptions& o, const std::string& name, const std::string& value) {
  for (const RunOption& r : run_options()) {
    if (r.name != name) continue;
    if (!r.set(o, value))
      throw std::invalid_argument(r.flag + " = " + printable(value) + ": must be " + r.type);
    return;
  }
  std::vector<std::string> names;
  for (const RunOption& r : run_options()) names.push_back(r.name);
  throw std::invalid_argument(unknown_key_message(name, names));
}

const std::vector<std::pair<std::string, std::string>>& run_option_flags() {
  static const std::vector<std::pair<std::string, std::string>> flags = [] {
    std::vector<std::pair<std::string, std::string>> f;
    for (const RunOption& r : run_options()) f.emplace_back(r.name, r.flag);
    return f;
  }();
  return flags;
}

DrapeCall drape_call(const DrapeRequest& request, const std::atomic<bool>* cancel,
                     RunObserver* observer) {
  Scene scene = load_scene(request.scene, request.overrides);
  for (const auto& [name, value] : request.run_options) apply_run_option(scene.options, name, value);
  scene.validate();

  const std::string integrator =
      request.integrator.empty() ? default_integrator() : request.integrator;
  try {
    (void)make_integrator(integrator);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--") + e.what());  // "--integrator = X: ..."
  }
  std::vector<EdgeFit> target_edges;
  if (!request.target.empty()) {
    const Target target = read_target_csv(request.target);
    try {
      target_edges = fit_target_scene(target.scene(target_scene_name(scene)));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("--target " + request.target + ": " + e.what());
    }
  }
  const bool has_target = !request.target.empty();

  scene.options.interrupt = cancel;
  std::optional<DrapeResult> result;
  try {
    result.emplace(run_drape(scene, integrator, observer));
  } catch (const std::invalid_argument& e) {  // an option the model refuses at the start
    rethrow_as_typed(e);
  }
  scene.options.interrupt = nullptr;  // the flag dies with the call
  DrapeReport report = drape_report(scene, *result, has_target ? &target_edges : nullptr);
  return {std::move(scene),        integrator,       std::move(*result), has_target,
          std::move(target_edges), std::move(report)};
}

std::string write_drape_call(const DrapeCall& call, const std::string& folder, bool picture) {
  const std::filesystem::path dir = make_output_dir(folder, "drape-" + call.scene.name);
  write_drape_outputs(dir, call.scene, call.result, call.report,
                      call.has_target ? &call.target_edges : nullptr, picture);
  remove_stale_output(dir / "steps.csv");
  return dir.string();
}

}  // namespace knitsim
