// knitsim optimize (docs/commands.md): the ICA (src/fit/ica.hpp) on a standard test function
// (src/fit/test_functions.hpp), to check and tune the optimiser without any drape.
//
// Prints the run's settings, one line per decade (decade 0 = the initial empires: best and
// mean imperialist cost, empires left, cumulative evaluations), the best point, and ends with
// exactly the two lines `best: <cost>` (17 significant digits) and `evaluations: <n>`.
// Options default to IcaOptions (paper 1's Taguchi-best settings); --seed defaults to 1.
// Bad option values: std::invalid_argument "--option = value: accepted range" (exit 2).
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/commands.hpp"
#include "src/fit/ica.hpp"
#include "src/fit/test_functions.hpp"

namespace knitsim {

namespace {

struct OptimizeArgs {
  std::string problem;
  int dim = 0;
  IcaOptions options;
};


void run(OptimizeArgs args) {
  IcaOptions& o = args.options;
  Problem problem;
  try {
    o.validate();
    problem = make_test_problem(args.problem, args.dim);
  } catch (const std::invalid_argument& e) {
    rethrow_with_flag_names(e, {{"problem", "--problem"}, {"dim", "--dim"}});
  }
  std::cout << "ICA on " << args.problem << ", D = " << args.dim << ": " << o.countries
            << " countries, " << o.imperialists << " imperialists, " << o.decades
            << " decades, beta " << format_number(o.beta) << ", gamma " << format_number(o.gamma)
            << " rad, revolution " << format_number(o.revolution_rate) << ", xi "
            << format_number(o.xi) << ", seed " << o.seed << ", jobs " << o.jobs
            << (o.stop_when_one_empire ? ", stop when one empire is left" : ", all decades")
            << "\n\n";
  const IcaResult r = run_ica(problem, o);

  Table t;
  t.columns = {"decade", "best", "mean", "empires", "evaluations"};
  for (const IcaDecade& d : r.history)
    t.rows.push_back({std::to_string(d.decade), format_number(d.best_cost, 8),
                      format_number(d.mean_cost, 8), std::to_string(d.empires),
                      std::to_string(d.evaluations)});
  std::cout << t.text() << "\nstatus: " << r.message
            << "\nwall: " << format_number(r.wall_seconds, 3) << " s\nx:";
  for (double x : r.best_x) std::cout << ' ' << format_number(x, 8);
  std::cout << "\nbest: " << format_number(r.best_cost, 17) << "\nevaluations: " << r.evaluations
            << std::endl;
}

}  // namespace

void register_optimize_command(CLI::App& app) {
  auto args = std::make_shared<OptimizeArgs>();
  IcaOptions& o = args->options;
  CLI::App* cmd = app.add_subcommand(
      "optimize", "Run the Imperialist Competitive Algorithm on a standard test function");
  cmd->add_option("--problem", args->problem, "sphere | rastrigin | rosenbrock | griewank | ackley")
      ->required();
  cmd->add_option("--dim", args->dim, "dimension D, 1.." + std::to_string(max_test_dim))
      ->required();
  add_ica_options(cmd, o);
  cmd->callback([args] { run(*args); });
}

}  // namespace knitsim
