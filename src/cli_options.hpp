// Command-line pieces shared by several subcommands.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "src/ica.hpp"

namespace CLI {
class App;
}

namespace knitsim {

// The ICA flags (SPEC 2.10): --seed --jobs --decades --countries --imperialists --beta --gamma
// --revolution --xi --stop-one-empire, bound to `o`.
void add_ica_options(CLI::App* cmd, IcaOptions& o);

// Validation messages name struct fields ("revolution_rate = 2: ..."); the user typed flags.
// Rethrows `e` with the field replaced by its flag ("--revolution = 2: ..."), for the ICA
// fields and the extra (field, flag) pairs given; unchanged if no name matches.
[[noreturn]] void rethrow_with_flag_names(
    const std::invalid_argument& e,
    const std::vector<std::pair<std::string, std::string>>& extra = {});

}  // namespace knitsim
