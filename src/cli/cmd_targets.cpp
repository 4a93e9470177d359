// knitsim targets (paper_repro/data/README.md): the synthetic "measured" edges of paper 1's 9
// samples (src/fit/synthetic_targets.hpp), one CSV per (set, sample): DIR/<set>_sample<s>.csv in
// the src/fit/targets.hpp format, opened by '#' lines giving the command that regenerates that
// file, the seed and noise, the sample's parameters, and per scene the grid and the equivalent
// `knitsim drape` run (its noise-free edges are the target's before the noise).
//
// Order of work: parse and check every flag (bad input: one line naming the flag, exit 2,
// nothing written), create --out, then make and write the files in order (set, then sample),
// each atomically, with a progress line on stderr per file unless --quiet. A drape that does
// not reach equilibrium is reported on stderr, its file is not written, the others are, and the
// exit status is 3.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/commands.hpp"
#include "src/fit/synthetic_targets.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

struct TargetsArgs {
  std::string set = "all";
  std::string samples = "1-9";
  SyntheticOptions options;
  std::string out;
  bool quiet = false;
};

// The shortest %g text that reads back as the same double (so 0.049 prints as 0.049).
std::string shortest(double value) {
  for (int digits = 1; digits < 17; ++digits) {
    const std::string text = format_number(value, digits);
    if (std::strtod(text.c_str(), nullptr) == value) return text;
  }
  return format_number(value, 17);
}

std::vector<SyntheticSet> parse_sets(const std::string& text) {
  if (text == "all") return {SyntheticSet::Twin, SyntheticSet::Cross};
  if (text == "twin" || text == "cross") return {synthetic_set_from_name(text)};
  throw std::invalid_argument("--set = " + text + ": accepted twin|cross|all");
}

// The '#' lines of one file.
std::vector<std::string> provenance(SyntheticSet set, const PaperSample& sample,
                                    const SyntheticOptions& o) {
  const std::string seed = std::to_string(o.seed);
  std::vector<std::string> lines = {
      synthetic_target_title(set, sample.sample),
      std::string("Regenerate: knitsim targets --set ") + to_string(set) + " --samples " +
          std::to_string(sample.sample) + " --seed " + seed + " --noise-mm " +
          shortest(o.noise_mm) + " --photos " + std::to_string(o.photos) + " --out DIR",
      "Seed " + seed + ": one std::mt19937_64 per scene, std::seed_seq{" + seed + ", " +
          std::to_string(sample.sample) + ", " + std::to_string(static_cast<int>(set)) +
          ", scene (0 four_corner, 1 two_corner)}; Box-Muller normals.",
      "Noise: sigma " + shortest(o.noise_mm) +
          " mm per camera-plane coordinate and photo, mean of " + std::to_string(o.photos) +
          " photos (sigma " + format_number(o.noise_mm / std::sqrt(double(o.photos)), 4) +
          " mm per point), divided by the normalisation span (four_corner: the edge's corner "
          "distance; two_corner: the pin distance).",
      "Sample: areal_density " + shortest(sample.areal_density) + " g/m^2, stiffness " +
          shortest(sample.stiffness) + " N/m, damping " + shortest(sample.damping) +
          " N s/m, elongation_limit " + shortest(sample.elongation_limit) + " %, natural_length " +
          shortest(sample.natural_length) + " m, topology " + std::string(1, sample.topology) + ".",
  };
  for (const std::string& name : synthetic_scene_names()) {
    const Scene scene = synthetic_scene(sample, set, name);
    const DrapeParams& p = scene.params;
    const int n = p.cells();
    lines.push_back(name + ": " + std::to_string(n) + " x " + std::to_string(n) + " cells (" +
                    std::to_string((n + 1) * (n + 1)) + " particles), spacing " +
                    shortest(p.natural_length) + " m, model width " +
                    shortest(n * p.natural_length) + " m, damping " + shortest(p.damping) +
                    " N s/m; " + synthetic_integrator() + " rtol " + shortest(scene.options.rtol) +
                    " atol " + shortest(scene.options.atol) + ", equilibrium_tol " +
                    shortest(scene.options.equilibrium_tol) + ".");
    lines.push_back(name + " noise-free edges = knitsim drape --scene " + name +
                    " --set fabric.width=" + shortest(p.width) + " --set fabric.areal_density=" +
                    shortest(p.areal_density) + " --set model.stiffness=" + shortest(p.stiffness) +
                    " --set model.damping=" + shortest(p.damping) +
                    " --set model.elongation_limit=" + shortest(p.elongation_limit) +
                    " --set model.natural_length=" + shortest(p.natural_length) +
                    " --set model.topology=" + std::string(1, p.topology) + " --rtol " +
                    shortest(scene.options.rtol) + " --atol " + shortest(scene.options.atol));
  }
  return lines;
}

void run(const TargetsArgs& args) {
  const std::vector<SyntheticSet> sets = parse_sets(args.set);
  const std::vector<int> samples = parse_sample_list(args.samples);
  try {
    args.options.validate();
  } catch (const std::invalid_argument& e) {
    rethrow_as_typed(e);  // under the flags of their rows of key_table()
  }
  const std::filesystem::path dir = make_output_dir(args.out, "targets");

  const size_t total = sets.size() * samples.size();
  size_t done = 0;
  bool failed = false;
  for (SyntheticSet set : sets)
    for (int s : samples) {
      const PaperSample& sample = paper_sample(s);
      const std::filesystem::path path = dir / synthetic_target_file(set, s);
      const std::clock_t cpu0 = std::clock();
      const auto wall0 = std::chrono::steady_clock::now();
      ++done;
      Target target;
      try {
        target = make_synthetic_target(sample, set, args.options);
      } catch (const std::runtime_error& e) {  // a drape that did not settle: the next sample
        std::cerr << "knitsim: error: " << e.what() << "\n";
        failed = true;
        continue;
      }
      // A write that fails ends the command (OutputError, exit 4): the next file would too.
      write_file_atomic_with(path, [&](const std::string& tmp) {
        write_target_csv(target, tmp, provenance(set, sample, args.options));
      });
      if (!args.quiet) {
        const double wall =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
        std::cerr << "targets: [" << done << "/" << total << "] " << path.string() << " ("
                  << format_number(double(std::clock() - cpu0) / CLOCKS_PER_SEC, 3) << " s CPU, "
                  << format_number(wall, 3) << " s wall)" << std::endl;
      }
    }
  finish_output_folder(dir);  // every target written (a failed one is not retried)
  if (failed) throw CLI::RuntimeError(3);
}

}  // namespace

void register_targets_command(CLI::App& app) {
  auto args = std::make_shared<TargetsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "targets",
      "Make the synthetic targets of paper 1's samples (twin: the model at Table 4's "
      "parameters; cross: the same fabric on a 3x finer grid), with seeded photo noise; "
      "writes <set>_sample<s>.csv into --out");
  cmd->add_option("--set", args->set, "Target set: twin|cross|all")->capture_default_str();
  cmd->add_option("--samples", args->samples, "Samples: list or ranges within 1..9, e.g. 2,5-7")
      ->capture_default_str();
  add_seed_option(cmd, args->options.seed, "Base seed of the noise")->capture_default_str();
  add_row_flags(cmd, args->options);  // --noise-mm, --photos
  cmd->add_option("--out", args->out,
                  "Output folder (default: a fresh out/targets-<YYYYmmdd-HHMMSS>)");
  cmd->add_flag("--quiet", args->quiet, "No progress lines on stderr");
  cmd->callback([args] { run(*args); });
}

}  // namespace knitsim
