// The targets a reproduction fits: the committed files, checked against their sample, or made in
// memory where none is committed.
#include <fstream>
#include <iostream>
#include <set>
#include <stdexcept>

#include "src/base/text.hpp"
#include "src/paper/paper_data.hpp"
#include "src/repro/repro.hpp"
#include "src/repro/repro_internal.hpp"

namespace knitsim {

namespace fs = std::filesystem;

std::vector<std::pair<SyntheticSet, int>> repro_internal::needed_targets(const ReproOptions& o) {
  std::set<std::pair<SyntheticSet, int>> need;
  const bool tables =
      o.task == ReproTask::Table4 || o.task == ReproTask::Table6 || o.task == ReproTask::All;
  if (tables)
    for (SyntheticSet set : o.sets)
      for (int s : o.samples) need.insert({set, s});
  if (o.task == ReproTask::Fig13 || o.task == ReproTask::All)
    need.insert({o.fig13_set, o.fig13_sample});
  if (o.task == ReproTask::Taguchi || o.task == ReproTask::All)
    need.insert({o.taguchi_set, o.taguchi_sample});
  return {need.begin(), need.end()};
}

namespace {

// A target file written by `knitsim targets` names its set and sample in its first line; one
// that names another (a file renamed or copied under this sample's name) would fit this
// sample's fabric to another sample's edges: refused. Files without that line are read as
// they are.
void refuse_other_samples_target(const fs::path& file, SyntheticSet set, int sample) {
  std::ifstream in(file);
  std::string first;
  std::getline(in, first);
  const std::string title_start = "# Synthetic target ";
  if (first.rfind(title_start, 0) != 0) return;
  if (first != "# " + synthetic_target_title(set, sample))
    throw std::invalid_argument("--targets: " + file.string() + " is not the target of " +
                                to_string(set) + " sample " + std::to_string(sample) +
                                ": its first line says \"" + first.substr(2) + "\"");
}

}  // namespace

ReproTargets::ReproTargets(const ReproOptions& options) : synthetic_(options.synthetic) {
  for (const auto& [set, sample] : repro_internal::needed_targets(options)) {
    Entry& e = entries_[{set, sample}];
    if (options.targets_dir.empty()) continue;
    const fs::path file = fs::path(options.targets_dir) / synthetic_target_file(set, sample);
    if (!fs::exists(file)) continue;
    refuse_other_samples_target(file, set, sample);
    e.target = read_target_csv(file.string());
    e.loaded = true;
    e.source = file.string();
  }
}

void ReproTargets::generate_missing(bool progress) {
  for (auto& [key, e] : entries_) {
    if (e.loaded) continue;
    if (progress)
      std::cout << "generating target " << to_string(key.first) << "_sample" << key.second
                << " (no committed file; make_synthetic_target)\n"
                << std::flush;
    try {
      e.target = make_synthetic_target(paper_sample(key.second), key.first, synthetic_);
    } catch (const std::runtime_error& error) {
      e.source = std::string("unavailable: ") + error.what();
      if (progress) std::cout << e.source << "\n" << std::flush;
      continue;
    }
    e.loaded = true;
    e.source = "generated in memory by make_synthetic_target (seed " +
               std::to_string(synthetic_.seed) + ", noise " + format_number(synthetic_.noise_mm) +
               " mm, " + std::to_string(synthetic_.photos) + " photos)";
  }
}

const ReproTargets::Entry& ReproTargets::entry(SyntheticSet set, int sample) const {
  const auto it = entries_.find({set, sample});
  if (it == entries_.end() || !it->second.loaded)
    throw std::logic_error(std::string("ReproTargets: target ") + to_string(set) + "_sample" +
                           std::to_string(sample) + " not needed or not generated");
  return it->second;
}

bool ReproTargets::available(SyntheticSet set, int sample) const {
  const auto it = entries_.find({set, sample});
  return it != entries_.end() && it->second.loaded;
}

const Target& ReproTargets::get(SyntheticSet set, int sample) const {
  return entry(set, sample).target;
}

std::string ReproTargets::provenance(SyntheticSet set, int sample) const {
  const auto it = entries_.find({set, sample});
  return it == entries_.end() ? std::string("not needed") : it->second.source;
}

}  // namespace knitsim
