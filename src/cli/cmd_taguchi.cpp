// knitsim taguchi (docs/commands.md): S/N, main effects, optimal levels and ANOVA of an L27
// experiment (src/fit/taguchi.hpp).
//
//   knitsim taguchi --responses FILE.csv [--columns 1,2,5,9,10,12,13] [--out DIR]
//
// FILE.csv: 27 lines (runs in the standard L27 order), each with the r replicate responses
// separated by commas; optional header line (a first column named "run" numbers the runs
// 1..27 and is not a replicate); blank and '#' lines ignored. Prints the tables
// and writes sn.csv, effects.csv, anova.csv and manifest.json into --out, by default the
// folder <FILE stem>_taguchi next to FILE. Bad input (file, runs, values, columns): one line
// naming the line / run / column, exit 2, nothing written.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/commands.hpp"
#include "src/fit/taguchi.hpp"
#include "src/io/manifest.hpp"

namespace knitsim {

namespace {

struct TaguchiArgs {
  std::string responses;
  std::vector<int> columns = default_l27_columns();
  std::string out;
};

void run(const TaguchiArgs& args) {
  namespace fs = std::filesystem;
  std::ifstream in(args.responses);
  if (!in) throw std::invalid_argument("--responses " + args.responses + ": cannot open");
  TaguchiAnalysis a;
  try {
    a = analyze_l27(read_responses_csv(in), args.columns);
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    if (msg.rfind("columns", 0) == 0) throw std::invalid_argument("--" + msg);
    throw std::invalid_argument("--responses " + args.responses + ": " + msg);
  }
  const fs::path input(args.responses);
  const std::string out =
      args.out.empty() ? (input.parent_path() / (input.stem().string() + "_taguchi")).string()
                       : args.out;
  const fs::path dir = make_output_dir(out, "taguchi");

  const Table sn = taguchi_sn_table(a);
  const Table effects = taguchi_effects_table(a);
  const Table anova = taguchi_anova_table(a);
  std::cout << "L27 experiment " << args.responses << ": " << a.factors.size()
            << " factors on columns";
  for (int c : a.columns) std::cout << ' ' << c;
  std::cout << ", " << a.replicates << " replicate(s) per run\n"
            << "smaller-the-better S/N eta = -10 log10(mean y^2), dB; mean eta = "
            << format_number(a.mean_sn, 6) << "\n\n"
            << sn.text() << "\nmain effects (mean eta per level, dB)\n"
            << effects.text() << "\noptimal levels: " << a.optimal_levels() << "\n\n"
            << "ANOVA on eta (error = unassigned columns + pooled factors)\n"
            << anova.text() << "\noutputs: " << dir.string() << "/\n";
  write_file_atomic(dir / "sn.csv", sn.csv());
  write_file_atomic(dir / "effects.csv", effects.csv());
  write_file_atomic(dir / "anova.csv", anova.csv());
  finish_output_folder(dir, manifest({{"responses", fs::absolute(input).string()},
                                      {"columns", a.columns},
                                      {"replicates", a.replicates},
                                      {"optimal_levels", a.optimal_levels()}}));
}

}  // namespace

void register_taguchi_command(CLI::App& app) {
  auto args = std::make_shared<TaguchiArgs>();
  CLI::App* cmd = app.add_subcommand(
      "taguchi", "Taguchi L27 analysis: S/N, main effects, optimal levels, ANOVA");
  cmd->add_option("--responses", args->responses,
                  "CSV: 27 runs x r replicate responses (header optional; a first column named run "
                  "numbers the runs 1..27)")
      ->required();
  cmd->add_option("--columns", args->columns, "L27 columns of the factors A, B, ...")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--out", args->out, "output folder (default: <FILE stem>_taguchi next to FILE)");
  cmd->callback([args] { run(*args); });
}

}  // namespace knitsim
