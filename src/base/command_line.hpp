// The process's command line, recorded once by main(): the subcommand it runs (which an
// output folder's manifest names, src/base/files.hpp) and the whole line (the manifests).
#pragma once

#include <string>

namespace knitsim {

// Records argv (main() calls it once, before any subcommand runs).
void set_command_line(int argc, const char* const* argv);
// The subcommand of that line (argv[1]: drape, fit, ...), "" before set_command_line.
const std::string& command_name();
// The whole line, each argument shell-quoted where needed so it can be pasted back.
const std::string& command_line();

}  // namespace knitsim
