// knitsim command line (docs/commands.md). Each subcommand registers itself (src/cli/commands.hpp);
// this file only parses and maps what a command throws to the exit status of the contract:
//   0  success (and --help)
//   2  bad input: a CLI11 parse error or std::invalid_argument, printed as ONE line
//      "knitsim: error: <message>" on stderr (commands validate all input before writing)
//   3  a run that ended in another status than equilibrium: the command throws
//      CLI::RuntimeError(3) after writing its outputs (CLI11 prints nothing for it)
//   130, 143  drape or knit stopped by SIGINT or SIGTERM (128 + the signal): the run ended with
//      status interrupted and its outputs were written (src/cli/interrupt.hpp)
//   4  an output that could not be written once the run had started (disk full, quota, a file
//      size limit): one line "knitsim: error: cannot write PATH: reason" (OutputError, or a
//      std::filesystem::filesystem_error from making an output folder or checkpoint)
//   5  the --out folder is in use by another knitsim run still going (the folder is flock'ed,
//      src/base/files.hpp): one line, nothing written
//   2  also a model too large for the memory available: refused at set-up by its estimate
//      (docs/knit.md, "Memory"), or, where an estimate missed, std::bad_alloc, one line
//   1  anything else (an internal error), one line on stderr
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "src/base/command_line.hpp"
#include "src/base/files.hpp"
#include "src/base/text.hpp"
#include "src/cli/cli_options.hpp"
#include "src/cli/commands.hpp"
#include "src/io/manifest.hpp"
#include "src/parallel/work_units.hpp"

namespace {

int fail(int status, std::string message) {
  std::replace(message.begin(), message.end(), '\n', ' ');
  std::cerr << "knitsim: error: " << message << std::endl;
  return status;
}

// The subcommands and the names they register under.
struct Command {
  const char* name;
  void (*add)(CLI::App&);
};
constexpr Command kCommands[] = {{"drape", knitsim::register_drape_command},
                                 {"knit", knitsim::register_knit_command},
                                 {"list", knitsim::register_list_command},
                                 {"demo", knitsim::register_demo_command},
                                 {"optimize", knitsim::register_optimize_command},
                                 {"taguchi", knitsim::register_taguchi_command},
                                 {"fit", knitsim::register_fit_command},
                                 {"targets", knitsim::register_targets_command},
                                 {"repro", knitsim::register_repro_command},
                                 {"tensile", knitsim::register_tensile_command}};

// The application with every subcommand, or only with those `wanted` says. CLI11 builds every
// option, default and validator of every subcommand it is given (~10 % of a four_corner drape's
// process), and a run uses one subcommand's: a command line naming one gets that one, plain
// `knitsim --version` none, anything else (--help, an unknown name) all. A run parses as with
// all: a subcommand takes its values before any sibling's name is looked at (`drape --out demo`
// writes into demo/), and a stray word after them is "not expected" either way.
std::unique_ptr<CLI::App> make_app(const std::function<bool(const Command&)>& wanted) {
  auto app = std::make_unique<CLI::App>("knitsim: stiff mass-spring models of knitted fabric");
  app->require_subcommand(1);
  for (const Command& c : kCommands)
    if (wanted(c)) c.add(*app);
  knitsim::require_well_formed_values(*app);
  app->set_version_flag("--version", knitsim::version_string());
  return app;
}

}  // namespace

int main(int argc, char** argv) {
#ifdef __GLIBC__
  // A fit builds and frees a drape's model per evaluation, on every thread; glibc's defaults hand
  // the freed pages back each time and the next drape faults them in again: 2.4 M page faults,
  // 12 s of system time in `repro table6 --preset paper --jobs 2` (2.5 s with these bounds).
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
#endif
  // MPI_Init/MPI_Finalize when started by mpirun (src/parallel/work_units.hpp); nothing otherwise.
  knitsim::ProcessGroup processes(argc, argv);
  knitsim::set_command_line(argc, argv);
  const Command* named = nullptr;
  if (argc > 1)
    for (const Command& c : kCommands)
      if (std::strcmp(argv[1], c.name) == 0) named = &c;
  const bool version_only = argc == 2 && std::strcmp(argv[1], "--version") == 0;
  std::unique_ptr<CLI::App> made =
      make_app([&](const Command& c) { return named != nullptr ? &c == named : !version_only; });
  if (named != nullptr &&
      made->get_subcommands([&](CLI::App* sub) { return sub->check_name(argv[1]); }).empty()) {
    named = nullptr;  // registered under another name than kCommands says: treat as unknown
    made = make_app([](const Command&) { return true; });
  }
  CLI::App& app = *made;
  // CLI11 reports an unknown command as "A subcommand is required": name it instead.
  if (argc > 1 && argv[1][0] != '-' && named == nullptr) {
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      known = known || sub->check_name(argv[1]);
    }
    if (!known)
      return fail(2, "unknown command '" + knitsim::printable(argv[1]) + "': one of " + names +
                         " (see knitsim --help)");
  }
  // Under mpirun only repro distributes its work; any other command would run once per process
  // and every process would write the same files.
  if (knitsim::process_count() > 1 && (argc < 2 || std::string(argv[1]) != "repro")) {
    const std::string why = "only `knitsim repro` runs under mpirun (" +
                            std::to_string(knitsim::process_count()) +
                            " processes); run this command as one process";
    return knitsim::process_rank() == 0 ? fail(2, why) : 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();
  } catch (const CLI::ExtrasError&) {
    // CLI11 lists the extras last-first ("lm --optimizer"): name them in order, and the
    // command whose flags they are not.
    const std::vector<CLI::App*> subs = app.get_subcommands();
    const CLI::App* run = subs.empty() ? &app : subs.front();
    std::string words;
    for (const std::string& w : run->remaining()) words += (words.empty() ? "" : " ") + w;
    const std::string name = subs.empty() ? "knitsim" : "knitsim " + run->get_name();
    return fail(2, name + " does not take '" + knitsim::printable(words) + "' (its flags: " + name +
                       " --help)");
  } catch (const CLI::ParseError& e) {
    return fail(2, std::string(e.what()) + " (see knitsim --help)");
  } catch (const std::invalid_argument& e) {
    return fail(2, e.what());
  } catch (const knitsim::OutputError& e) {
    return fail(4, e.what());
  } catch (const knitsim::OutputFolderBusy& e) {
    return fail(5, e.what());
  } catch (const std::filesystem::filesystem_error& e) {
    std::string what = e.what();  // libstdc++: "filesystem error: cannot write: reason [path]"
    const std::string prefix = "filesystem error: ";
    if (what.rfind(prefix, 0) == 0) what.erase(0, prefix.size());
    return fail(4, what);
  } catch (const std::bad_alloc&) {  // the set-up estimates missed (docs/knit.md, "Memory")
    return fail(2, "out of memory: the model does not fit in the memory available");
  } catch (const std::exception& e) {
    return fail(1, e.what());
  }
  return 0;
}
