// Command-line pieces shared by several subcommands.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "solvers/integrator.hpp"
#include "src/cli/interrupt.hpp"
#include "src/scene/fit_options.hpp"
#include "src/scene/scene.hpp"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace knitsim {

// Makes every integer option of `app`'s subcommands (CLI11 type INT or UINT) take decimal text
// only: CLI11 alone reads "010" as octal 8, "0x10" as 16, "-1" into an unsigned option as its
// maximum and a value past 64 bits as the largest one (--max-steps 1e20 digits), all silently.
// Leading zeros are dropped (010 is ten); anything else that is not a decimal integer, or does
// not fit 64 bits, is refused with one line naming the option. Text options (TEXT) refuse an
// empty value: `--integrator ""` silently meant the default. Call once, after registering.
void require_well_formed_values(CLI::App& app);

// The --help group of the ICA's own flags (all of add_ica_options but --seed and --jobs, which
// other optimizers read too): how `fit --optimizer lm` finds the ICA flags it ignores.
inline constexpr const char* kIcaOptionGroup = "ICA options";

// The ICA flags (docs/commands.md): --seed, then the rows of key_table() bound to an IcaOptions
// field (--jobs --decades --countries --imperialists --beta --gamma --revolution --xi
// --stop-one-empire), bound to `o`, all but --seed and --jobs in kIcaOptionGroup.
void add_ica_options(CLI::App* cmd, IcaOptions& o);

// The flags of the rows of key_table() bound to a field of `o` (S: IcaOptions, LmOptions,
// LmStartOptions, SyntheticOptions; src/scene/fit_options.hpp), in the table's order, each with
// its row's meaning and range as --help text and its default shown. Returns them, to be grouped.
template <class S>
std::vector<CLI::Option*> add_row_flags(CLI::App* cmd, S& o);

// --seed bound to `seed` (std::uint64_t or unsigned): a decimal integer from 0 to the type's
// maximum. CLI11 alone reads "-1" as the maximum (wrapped) and a value past it as the maximum
// (saturated), both silently; these are refused with one line naming the range.
template <typename T>
CLI::Option* add_seed_option(CLI::App* cmd, T& seed, const std::string& help);

// The absolute-tolerance flags of fit (their rows of key_table(), src/scene/scene.hpp): --atol
// and --velocity-atol, bound to `atol` and `velocity_atol`; help shows their current values.
// Returns the --velocity-atol option.
CLI::Option* add_atol_options(CLI::App* cmd, double& atol, double& velocity_atol);

// The run flags of drape and knit: one per row of key_table() with a flag, in the table's order
// (--rtol, --atol, --velocity-atol, --dt, --max-order, --max-steps, --max-wall, --max-restarts,
// --newton-solver, --factorization, the cvode-bdf-gmres flags), bound to the IntegratorOptions
// field of the row; each value as typed goes into `typed` (flag -> text, for Scene::typed's
// messages) if given. Returns the --velocity-atol option (knit appends its own default rule to
// the description).
CLI::Option* add_run_options(CLI::App* cmd, IntegratorOptions& o,
                             std::map<std::string, std::string>* typed = nullptr);
// --step-history (bound to `step_history`) and --continue DIR (to `continue_from`) of drape and
// knit; `inputs` names what a continuation must repeat ("--scene and --set").
void add_history_and_continue_options(CLI::App* cmd, bool& step_history, std::string& continue_from,
                                      const std::string& inputs);
// Copies into `into` exactly the fields add_run_options binds (the rows with a flag; not t_max,
// equilibrium_tol: scene keys), so a scene's run settings and the command line combine in one
// place.
void copy_run_flags(const IntegratorOptions& flags, IntegratorOptions& into);

// A validation error in the user's words: a message whose "FIELD = " is one of `names` (the
// choices that are no parameter: --integrator, a registry's name; optimize's --problem and
// --dim; repro's study selection) with FIELD replaced by its flag; otherwise rethrow_as_typed
// (an InvalidField of a row of key_table() under the row's flag, anything else unchanged).
[[noreturn]] void rethrow_with_flag_names(
    const std::invalid_argument& e,
    const std::vector<std::pair<std::string, std::string>>& names = {});

// One line on stderr, "knitsim <command>: warning: <message>": input that is valid but will not
// do what it seems to. The run goes on.
void warn(const std::string& message);
// One line on stderr, "knitsim <command>: note: <message>": what the run assumed without being
// told. The run goes on.
void note(const std::string& message);
// For a scene read from a file: one note naming the keys of `among` the file and --set left
// out, with the values they keep (sample 1's defaults). Silent for a built-in scene.
void note_keys_not_given(const Scene& scene, const std::vector<std::string>& among);
// The keys drape notes: those that change the physics (fabric, material, topology, pins).
const std::vector<std::string>& physical_scene_keys();

// drape's and knit's warnings before a run: no damping (`damping_key` is 0: only
// implicit-euler's numerical damping settles such a run, any other integrator goes on to
// `t_max`, for hours with the defaults), and --dt given (`flags.dt` > 0) to an adaptive
// integrator, which ignores it.
void warn_about_run(const std::string& damping_key, double damping, const IntegratorInfo& integ,
                    const IntegratorOptions& flags, double t_max);

// Bad input found only once a run has started (an option the integrator refuses for this
// model, e.g. --max-order 9 with cvode-bdf): removes the run's --out folder `dir` if the run
// `created` it and it is still empty, then rethrows `e` with the run options' flag names
// (rethrow_as_typed).
[[noreturn]] void refuse_at_run_start(const std::invalid_argument& e,
                                      const std::filesystem::path& dir, bool created);

// The end of drape and knit once their outputs are written (src/cli/main.cpp's exit contract):
// returns at equilibrium; a run stopped by `interrupt`'s signal prints one line on stderr
// ("knitsim <command>: interrupted by SIGINT at t = ... s; outputs written to DIR/; the same
// command with --continue DIR goes on from there") and exits 128 + the signal; one stopped by
// --max-steps or --max-wall prints the same line ("stopped by --max-wall ...") and exits 3, as
// does any other status (silently: the reason is in summary.json and the stdout summary).
void exit_with_run_status(const char* command, const RunStats& stats,
                          const InterruptScope& interrupt, const std::string& dir);

}  // namespace knitsim
