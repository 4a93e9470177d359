// Which drape parameters can the edge data determine? (twin targets: paper_repro/data/README.md)
//
// For each paper sample s (Tables 2 and 4), each target set (twin, and with --sets also cross)
// and each data set D in {four_corner, two_corner, both}:
//   * the target <set>_sample<s> (paper_repro/data/targets/<set>_sample<s>.csv if present, else
//     made by make_synthetic_target with its default seed -- the same numbers);
//   * at the generating parameters p* (the twin's true ones; for cross those of the 3x finer
//     sheet, which the coarse model can only approximate), the residuals r = P_target -
//     P_model(p*) (twin: noise only; cross: noise + model error) and the analytic Jacobian
//     J = dr/dp (src/fit/sensitivity.hpp), per scene; "both" stacks the two scenes' rows (40
//     residuals). J depends on the model and p* only, so rank, structural zeros and the
//     k-L0 correlation are the same for both sets; sigma and the standard errors scale with
//     the residuals;
//   * the Gauss-Newton analysis of src/fit/lm_fit.hpp (identifiability()): rank, condition number,
//     standard errors, conditional standard errors, correlation of k and L0, the error of k/L0;
//   * objective slices E(p) = 100 rms(r) along each parameter with the others at p*, and along
//     the valley k = k* L0 / L0* (k / L0 held), where the grid size n = round(W / L0) jumps.
// Outputs in --out (default out/identifiability): identifiability.csv, profiles.csv (both with
// a leading `set` column), manifest.json. Usage:
//   build/knitsim_identifiability [--out DIR] [--samples 1,2,...] [--sets twin,cross]
//                                 [--targets DIR]
// Cost: 2 scenes x (1 + 60 slice points) drape runs per sample and set (about 25 s CPU).
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "src/base/command_line.hpp"
#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/io/manifest.hpp"
#include "src/fit/lm_fit.hpp"
#include "src/measure/measurement.hpp"
#include "src/paper/paper_data.hpp"
#include "src/scene/scene.hpp"
#include "src/fit/synthetic_targets.hpp"

using namespace knitsim;

namespace {

struct SceneData {
  std::string name;
  std::unique_ptr<DrapeFitProblem> problem;
};

std::string num(double v) { return format_number(v, 6); }

// Stacks the scenes' residuals (failed if any failed).
DrapeResiduals stack(const std::vector<DrapeResiduals>& parts) {
  DrapeResiduals out;
  out.failed = false;
  int m = 0;
  for (const DrapeResiduals& p : parts) {
    if (p.failed) return p;
    m += static_cast<int>(p.r.size());
  }
  out.r.resize(m);
  out.J.resize(m, kDrapeContinuous);
  int row = 0;
  for (const DrapeResiduals& p : parts) {
    out.r.segment(row, p.r.size()) = p.r;
    out.J.middleRows(row, p.r.size()) = p.J;
    row += static_cast<int>(p.r.size());
  }
  for (int c = 0; c < kDrapeContinuous; ++c) {
    out.structural_zero[c] = true;
    for (const DrapeResiduals& p : parts) out.structural_zero[c] &= p.structural_zero[c];
  }
  out.objective = 100.0 * std::sqrt(out.r.squaredNorm() / m);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  set_command_line(argc, argv);
  std::string out_dir = "out/identifiability";
  std::string targets_dir = "paper_repro/data/targets";
  std::vector<int> samples;
  std::vector<SyntheticSet> sets;
  const auto usage = [&](std::ostream& os) {
    os << "usage: " << argv[0]
       << " [--out DIR] [--samples 1,2,...] [--sets twin,cross] [--targets DIR]\n";
  };
  for (int i = 1; i < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      usage(std::cout);
      return 0;
    }
    if (i + 1 == argc) {  // a flag without its value
      std::cerr << argv[0] << ": " << flag << " needs a value\n";
      usage(std::cerr);
      return 2;
    }
    const std::string value = argv[i + 1];
    if (flag == "--out") {
      out_dir = value;
    } else if (flag == "--targets") {
      targets_dir = value;
    } else if (flag == "--samples") {
      samples = parse_sample_list(value);
    } else if (flag == "--sets") {
      std::stringstream ss(value);
      for (std::string item; std::getline(ss, item, ',');)
        sets.push_back(synthetic_set_from_name(item));
    } else {
      usage(std::cerr);
      return 2;
    }
  }
  if (samples.empty())
    for (const PaperSample& s : paper_samples()) samples.push_back(s.sample);
  if (sets.empty()) sets.push_back(SyntheticSet::Twin);
  std::filesystem::create_directories(out_dir);

  Table ident, profiles;
  ident.columns = {"set",
                   "sample",
                   "data",
                   "objective_at_truth",
                   "rank",
                   "condition",
                   "sigma",
                   "se_k_rel",
                   "se_L0_rel",
                   "cse_k_rel",
                   "cse_L0_rel",
                   "corr_k_L0",
                   "k_over_L0_rel_error",
                   "damping_zero",
                   "elongation_zero"};
  profiles.columns = {"set", "sample", "data", "parameter", "value", "objective"};
  const char* names[] = {"four_corner", "two_corner"};
  for (SyntheticSet set : sets)
    for (int s : samples) {
      const PaperSample& sample = paper_sample(s);
      const std::filesystem::path file =
          std::filesystem::path(targets_dir) / synthetic_target_file(set, s);
      const Target target = std::filesystem::exists(file) ? read_target_csv(file.string())
                                                          : make_synthetic_target(sample, set);
      std::vector<SceneData> scenes;
      for (const char* name : names) {
        Scene base = synthetic_scene(sample, SyntheticSet::Twin, name);
        DrapeFitOptions options;  // Table 3 box; the twin's topology only
        options.bounds.lower[kGeneTopology] = sample.topology - 'a';
        options.bounds.upper[kGeneTopology] = sample.topology - 'a' + 1;
        scenes.push_back({name, std::make_unique<DrapeFitProblem>(base, target, options)});
      }
      const std::vector<double> truth = {sample.stiffness, sample.damping, sample.elongation_limit,
                                         sample.natural_length, sample.topology - 'a' + 0.5};
      auto evaluate_all = [&](const std::vector<double>& x) {
        std::vector<DrapeResiduals> parts;
        for (const SceneData& sd : scenes) parts.push_back(drape_residuals(*sd.problem, x));
        return parts;
      };
      auto record_identifiability = [&](const std::string& data, const DrapeResiduals& at) {
        if (at.failed) {
          std::cerr << to_string(set) << " sample " << s << " " << data << ": " << at.message
                    << "\n";
          return;
        }
        const DrapeIdentifiability id = identifiability(at, truth);
        const auto& k = id.parameters[kGeneStiffness];
        const auto& L = id.parameters[kGeneNaturalLength];
        ident.rows.push_back(
            {to_string(set), std::to_string(s), data, num(at.objective), std::to_string(id.rank),
             num(id.condition_number), num(id.sigma), num(k.standard_error / k.value),
             num(L.standard_error / L.value), num(k.conditional_standard_error / k.value),
             num(L.conditional_standard_error / L.value), num(id.correlation_stiffness_length),
             num(id.ratio_relative_error), id.parameters[kGeneDamping].structural_zero ? "1" : "0",
             id.parameters[kGeneElongation].structural_zero ? "1" : "0"});
      };
      const std::vector<DrapeResiduals> at = evaluate_all(truth);
      record_identifiability("four_corner", at[0]);
      record_identifiability("two_corner", at[1]);
      record_identifiability("both", stack(at));

      // Slices: (parameter label, gene, values); "natural_length_at_fixed_ratio" moves k with L0.
      struct Slice {
        std::string label;
        int gene;
        std::vector<double> values;
      };
      std::vector<Slice> slices = {{"stiffness", kGeneStiffness, {}},
                                   {"damping", kGeneDamping, {10.0, 15.0, 20.0}},
                                   {"elongation_limit", kGeneElongation, {5.0, 10.0, 20.0}},
                                   {"natural_length", kGeneNaturalLength, {}},
                                   {"natural_length_at_fixed_ratio", kGeneNaturalLength, {}}};
      for (double k = 500.0; k <= 1200.0 + 1e-9; k += 50.0) slices[0].values.push_back(k);
      for (int i = 0; i <= 20; ++i) {
        slices[3].values.push_back(0.040 + 0.001 * i);
        slices[4].values.push_back(0.040 + 0.001 * i);
      }
      for (const Slice& sl : slices)
        for (double v : sl.values) {
          std::vector<double> x = truth;
          x[sl.gene] = v;
          if (sl.label == "natural_length_at_fixed_ratio")
            x[kGeneStiffness] = truth[kGeneStiffness] * v / truth[kGeneNaturalLength];
          const std::vector<DrapeResiduals> parts = evaluate_all(x);
          const DrapeResiduals both = stack(parts);
          const double objectives[3] = {parts[0].failed ? NAN : parts[0].objective,
                                        parts[1].failed ? NAN : parts[1].objective,
                                        both.failed ? NAN : both.objective};
          const char* data[3] = {"four_corner", "two_corner", "both"};
          for (int d = 0; d < 3; ++d)
            profiles.rows.push_back({to_string(set), std::to_string(s), data[d], sl.label, num(v),
                                     format_number(objectives[d], 8)});
        }
      std::cout << to_string(set) << " sample " << s << " done\n" << std::flush;
    }
  std::vector<std::string> set_names;
  for (SyntheticSet set : sets) set_names.push_back(to_string(set));
  write_file_atomic(std::filesystem::path(out_dir) / "identifiability.csv", ident.csv());
  write_file_atomic(std::filesystem::path(out_dir) / "profiles.csv", profiles.csv());
  write_json_atomic(
      std::filesystem::path(out_dir) / "manifest.json",
      manifest({{"samples", samples}, {"sets", set_names}, {"targets", targets_dir}}));
  std::cout << ident.text();
  return 0;
}
