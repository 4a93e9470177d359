#include "src/python/fit_call.hpp"

#include <algorithm>
#include <any>
#include <cerrno>
#include <cstdlib>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

struct FitOption {
  std::string name, flag;
  std::function<bool(Scene&, IcaOptions&, const std::string&)> set;
  const char* type;
};

bool to_double(const std::string& text, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size();
}

template <typename I>
bool to_integer(const std::string& text, I& out) {
  if (text.empty() || text.find_first_not_of("-0123456789") != std::string::npos) return false;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (end != text.c_str() + text.size() || errno == ERANGE) return false;
  out = static_cast<I>(v);
  return static_cast<long long>(out) == v && (v >= 0 || I(-1) < I(0));
}

// The keyword arguments of knitsim.fit: the run tolerances and --seed of `knitsim fit`, then the
// flags of the rows of key_table() bound to an IcaOptions field, each named as its flag without
// "--" and with "_" for "-" (--stop-one-empire: stop_one_empire).
const std::vector<FitOption>& fit_options() {
  using S = Scene;
  using I = IcaOptions;
  using T = const std::string&;
  static const std::vector<FitOption> table = [] {
    std::vector<FitOption> all = {
        {"rtol", "--rtol", [](S& s, I&, T t) { return to_double(t, s.options.rtol); }, "a number"},
        {"atol", "--atol", [](S& s, I&, T t) { return to_double(t, s.options.atol); }, "a number"},
        {"velocity_atol", "--velocity-atol",
         [](S& s, I&, T t) { return to_double(t, s.options.velocity_atol); }, "a number"},
        {"seed", "--seed", [](S&, I& o, T t) { return to_integer(t, o.seed); },
         "a decimal integer >= 0"}};
    for (const Key& key : key_table()) {
      if (key.flag.empty()) continue;
      std::string name = key.flag.substr(2);
      std::replace(name.begin(), name.end(), '-', '_');
      if (const auto* i = std::any_cast<int I::*>(&key.member)) {
        const auto m = *i;
        all.push_back({name, key.flag, [m](S&, I& o, T text) { return to_integer(text, o.*m); },
                       "an integer"});
      } else if (const auto* d = std::any_cast<double I::*>(&key.member)) {
        const auto m = *d;
        all.push_back(
            {name, key.flag, [m](S&, I& o, T text) { return to_double(text, o.*m); }, "a number"});
      } else if (const auto* b = std::any_cast<bool I::*>(&key.member)) {
        const auto m = *b;
        all.push_back({name, key.flag,
                       [m](S&, I& o, T text) {
                         if (text != "True" && text != "False") return false;
                         o.*m = text == "True";
                         return true;
                       },
                       "True or False"});
      }
    }
    return all;
  }();
  return table;
}

}  // namespace

const std::vector<std::pair<std::string, std::string>>& fit_option_flags() {
  static const std::vector<std::pair<std::string, std::string>> flags = [] {
    std::vector<std::pair<std::string, std::string>> f;
    for (const FitOption& o : fit_options()) f.emplace_back(o.name, o.flag);
    return f;
  }();
  return flags;
}

FitCall fit_call(const FitRequest& request, const std::function<bool()>& stop) {
  if (request.target.empty())
    throw std::invalid_argument("--target: required (the target edges CSV, docs/fitting.md)");
  Scene base = load_scene(request.scene, request.overrides);
  base.options.rtol = 1e-8;  // knitsim fit's default (src/fit/drape_fit.hpp)
  DrapeFitOptions options;
  for (const auto& [name, value] : request.options) {
    const FitOption* found = nullptr;
    for (const FitOption& o : fit_options())
      if (o.name == name) found = &o;
    if (!found) {
      std::vector<std::string> names;
      for (const FitOption& o : fit_options()) names.push_back(o.name);
      throw std::invalid_argument(unknown_key_message(name, names));
    }
    if (!found->set(base, options.ica, value))
      throw std::invalid_argument(found->flag + " = " + printable(value) + ": must be " +
                                  found->type);
  }
  for (const auto& [gene, lower, upper] : request.bounds) {
    int g = 0;
    while (g < kDrapeGenes && gene != drape_gene_names()[g]) ++g;
    if (g == kDrapeGenes) {
      std::vector<std::string> genes(drape_gene_names().begin(), drape_gene_names().end());
      throw std::invalid_argument("bounds: " + unknown_key_message(gene, genes));
    }
    options.bounds.lower[g] = lower;
    options.bounds.upper[g] = upper;
  }
  base.validate();
  const Target target = read_target_csv(request.target);
  options.integrator = request.integrator;
  options.ica.stop_requested = stop;
  std::unique_ptr<DrapeFitProblem> problem;
  try {
    problem = std::make_unique<DrapeFitProblem>(base, target, options);
  } catch (const std::invalid_argument& e) {
    // The integrator registry names its choice "integrator" (as knitsim fit does: --integrator);
    // the ICA's fields are refused under their flags (rows of key_table()).
    if (std::string(e.what()).rfind("integrator = ", 0) == 0)
      throw std::invalid_argument(std::string("--") + e.what());
    rethrow_as_typed(e);
  }

  FitCall call{fit_drape(*problem), problem->integrator(), problem->target_scene(), nullptr, {}};
  if (call.fit.status != IcaStatus::Interrupted) {
    Scene fitted = problem->scene_of(call.fit.best_x);
    DrapeResult drape = run_drape(fitted, problem->integrator());
    DrapeReport report = drape_report(fitted, drape, &problem->measured());
    call.drape = std::make_shared<DrapeCall>(DrapeCall{std::move(fitted), problem->integrator(),
                                                       std::move(drape), true, problem->measured(),
                                                       std::move(report)});
  }
  call.report = ica_fit_report(base, request.overrides, request.target, *problem, call.fit,
                               call.drape ? &call.drape->result : nullptr);
  return call;
}

std::string write_fit_call(const FitCall& call, const std::string& folder, bool picture) {
  const std::filesystem::path dir =
      make_output_dir(folder, "fit-" + call.report.settings.at("scene").get<std::string>());
  if (!call.drape) {
    write_fit_outputs(dir, call.report, nullptr, picture);
  } else {
    const DrapeCall& d = *call.drape;
    const FittedDrapeOutputs drape{d.scene, d.result, d.report, d.target_edges};
    write_fit_outputs(dir, call.report, &drape, picture);
  }
  return dir.string();
}

}  // namespace knitsim
