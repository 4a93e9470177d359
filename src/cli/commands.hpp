// The knitsim subcommands (docs/commands.md). Each lives in its own src/cli/cmd_<name>.cpp and
// registers itself on the CLI11 application; main.cpp only calls these.
//
// Contract for every command: exit status 0 on success; on bad input one line on stderr
// naming the field and its accepted range, exit status 2; on a numerical failure of the run
// itself the outputs are still written with the status, exit status 3 (drape and knit: 128 + the
// signal after Ctrl-C or SIGTERM, outputs written; src/cli/interrupt.hpp); an output that cannot
// be written exits 4, an --out folder held by another running knitsim 5 (src/cli/main.cpp has
// the whole list; docs/commands.md is the user's).
#pragma once

namespace CLI {
class App;
}

namespace knitsim {

void register_drape_command(CLI::App& app);
void register_knit_command(CLI::App& app);
void register_list_command(CLI::App& app);
void register_demo_command(CLI::App& app);
void register_optimize_command(CLI::App& app);
void register_taguchi_command(CLI::App& app);
void register_fit_command(CLI::App& app);
void register_targets_command(CLI::App& app);
void register_repro_command(CLI::App& app);
void register_tensile_command(CLI::App& app);

}  // namespace knitsim
