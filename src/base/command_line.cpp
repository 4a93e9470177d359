#include "src/base/command_line.hpp"

namespace knitsim {

namespace {

std::string& command_line_store() {
  static std::string line;
  return line;
}
std::string& command_name_store() {
  static std::string name;
  return name;
}

}  // namespace

const std::string& command_name() { return command_name_store(); }

const std::string& command_line() { return command_line_store(); }

void set_command_line(int argc, const char* const* argv) {
  // knitsim has no options before its subcommand (--help and --version stop there).
  command_name_store() = argc > 1 && argv[1][0] != '-' ? argv[1] : "";
  std::string line;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    const bool plain =
        !arg.empty() && arg.find_first_of(" \t\n'\"\\$`*?;&|<>()") == std::string::npos;
    if (!plain) {  // shell-quoted, so the line can be pasted back
      std::string q = "'";
      for (char ch : arg) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
      arg = q + "'";
    }
    line += (i ? " " : "") + arg;
  }
  command_line_store() = line;
}

}  // namespace knitsim
