// The reproduction's options: task and optimizer names, validation, presets, seeds, budgets.
#include <algorithm>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "src/base/text.hpp"
#include "src/core/invalid_field.hpp"
#include "src/repro/repro.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

const char* to_string(ReproTask task) {
  switch (task) {
    case ReproTask::Table4:
      return "table4";
    case ReproTask::Table6:
      return "table6";
    case ReproTask::Taguchi:
      return "taguchi";
    case ReproTask::Fig13:
      return "fig13";
    case ReproTask::All:
      return "all";
  }
  return "?";
}

ReproTask repro_task_from_name(const std::string& name) {
  for (ReproTask t :
       {ReproTask::Table4, ReproTask::Table6, ReproTask::Taguchi, ReproTask::Fig13, ReproTask::All})
    if (name == to_string(t)) return t;
  throw std::invalid_argument("task = " + name + ": accepted table4|table6|taguchi|fig13|all");
}

const char* to_string(ReproOptimizer optimizer) {
  return optimizer == ReproOptimizer::Ica ? "ica" : "lm";
}

ReproOptimizer repro_optimizer_from_name(const std::string& name) {
  for (ReproOptimizer o : {ReproOptimizer::Ica, ReproOptimizer::Lm})
    if (name == to_string(o)) return o;
  throw std::invalid_argument("optimizers = " + name + ": accepted ica|lm");
}

DrapeSymmetry four_corner_symmetry_from_name(const std::string& name) {
  for (DrapeSymmetry d : {DrapeSymmetry::None, DrapeSymmetry::Quarter, DrapeSymmetry::Eighth})
    if (name == to_string(d)) return d;
  throw std::invalid_argument("four_corner_symmetry = " + name + ": accepted none|quarter|eighth");
}

namespace {

void check_sample(const std::string& field, int s) {
  if (s < 1 || s > static_cast<int>(paper_samples().size()))
    bad_field(field, std::to_string(s), "accepted 1.." + std::to_string(paper_samples().size()));
}

}  // namespace

void ReproOptions::validate() const {
  if (samples.empty()) bad_field("samples", "(none)", "accepted a non-empty list of samples 1..9");
  std::set<int> seen;
  for (int s : samples) {
    check_sample("samples", s);
    if (!seen.insert(s).second) bad_field("samples", std::to_string(s), "each sample at most once");
  }
  if (sets.empty() || (sets.size() == 2 && sets[0] == sets[1]) || sets.size() > 2)
    bad_field("sets", std::to_string(sets.size()) + " sets",
              "accepted twin, cross or both, once each");
  if (optimizers.empty() || optimizers.size() > 2 ||
      (optimizers.size() == 2 && optimizers[0] == optimizers[1]))
    bad_field("optimizers", std::to_string(optimizers.size()) + " optimizers",
              "accepted ica, lm or both, once each");
  const bool lm_used =
      std::find(optimizers.begin(), optimizers.end(), ReproOptimizer::Lm) != optimizers.end();
  if (lm_used && (task == ReproTask::Taguchi || task == ReproTask::Fig13))
    bad_field("optimizers", "lm",
              std::string("accepted for the tasks table4|table6|all only (") + to_string(task) +
                  " studies the ICA)");
  if (runs < 1) bad_field("runs", std::to_string(runs), "accepted >= 1");
  if (jobs < 1) bad_field("jobs", std::to_string(jobs), "accepted >= 1");
  check_sample("fig13_sample", fig13_sample);
  check_sample("taguchi_sample", taguchi_sample);
  if (taguchi_replicates < 1)
    bad_field("taguchi_replicates", std::to_string(taguchi_replicates), "accepted >= 1");
  for (int d : taguchi_decades)
    if (d < 1) bad_field("taguchi_decades", std::to_string(d), "accepted >= 1 each");
  if (!(rtol > 0.0 && rtol <= 0.1)) bad_field("rtol", format_number(rtol), "accepted (0, 0.1]");
  if (four_corner_symmetry == DrapeSymmetry::Half)
    bad_field("four_corner_symmetry", to_string(four_corner_symmetry),
              "accepted none|quarter|eighth");
  DrapeFitOptions fit;  // the ICA options and the integrator name
  fit.ica = ica;
  fit.integrator = repro_integrator(*this);
  fit.validate();
  lm.validate();
  synthetic.validate();
}

std::string repro_default_integrator() { return default_integrator(); }

std::string repro_integrator(const ReproOptions& o) {
  return o.integrator.empty() ? repro_default_integrator() : o.integrator;
}

ReproOptions repro_preset(const std::string& name) {
  ReproOptions o;
  o.preset = name;
  if (name == "paper") return o;
  if (name != "quick") bad_field("preset", name, "accepted quick|paper");
  o.runs = 2;
  o.ica.countries = 10;
  o.ica.decades = 6;
  o.taguchi_replicates = 1;
  o.taguchi_decades = {1, 2, 4};
  return o;
}

std::uint64_t unit_seed(std::uint64_t base, const std::string& key) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a 64
  for (unsigned char c : key) {
    h ^= c;
    h *= 1099511628211ull;
  }
  std::uint64_t z = base ^ (h + 0x9e3779b97f4a7c15ull + (base << 6) + (base >> 2));
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;  // splitmix64 finaliser
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

long ica_evaluation_estimate(const IcaOptions& o) {
  const int colonies = std::max(o.countries - o.imperialists, o.imperialists);
  return static_cast<long>(o.imperialists + colonies) + static_cast<long>(o.decades) * colonies;
}

}  // namespace knitsim
