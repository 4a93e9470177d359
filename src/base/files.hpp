// Files and folders: atomic writes, the output folder of a command, inputs read with a size cap.
//
// Every file is written atomically: to `<name>.tmp` in the same folder, then renamed over
// `<name>` (POSIX rename: a reader sees the old file or the new one, never half of one).
// The set of files is made whole by a marker: the first write (or removal) of a run into its
// output folder (make_output_dir) first creates `incomplete.txt` there, and
// finish_output_folder writes manifest.json last and only then removes it. So a folder holding
// incomplete.txt, or no manifest.json, holds no whole run -- a rerun killed while writing may
// have left files of two runs side by side -- and output_folder_complete says so
// (`--continue` refuses it). A run that writes nothing (bad input found at its start, a stop
// during set-up) leaves a reused folder exactly as it was. Why a marker and not a fresh folder
// renamed into place: rename(2) cannot replace a non-empty folder in one step, the flock is on
// the folder itself, and a user's --out may hold files of their own (docs/reliability.md).
// Failure modes: bad --out folders are bad input (std::invalid_argument naming --out); a write
// that fails later (disk full, a file size limit, ...) throws OutputError("cannot write PATH:
// reason"), which the command line maps to exit status 4; an --out folder that another running
// knitsim holds throws OutputFolderBusy (exit status 5). src/cli/main.cpp has the exit codes.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace knitsim {

// An output that could not be written once the run had started (disk full, quota, a file size
// limit, a path that became unwritable): "cannot write PATH: reason".
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The --out folder is in use by another knitsim process that is still running.
struct OutputFolderBusy : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The time now in UTC as ISO 8601, "2026-12-07T21:18:22Z" (manifests, the in-progress marker).
std::string utc_stamp();

void write_file_atomic(const std::filesystem::path& path, const std::string& content);
// For writers that take a file name (the PNG renderer): write(tmp) must create the file tmp.
void write_file_atomic_with(const std::filesystem::path& path,
                            const std::function<void(const std::string& tmp)>& write);
// JSON pretty-printed with 2 spaces and a final newline.
void write_json_atomic(const std::filesystem::path& path, const nlohmann::json& value);

// The marker of an output folder being written (see the top of this file).
inline constexpr const char* kIncompleteMarker = "incomplete.txt";
// Writes `manifest` as dir/manifest.json, the last file of a run's set, then removes dir's
// incomplete.txt: the folder holds one whole run. Every command ends its writing with it; a
// folder that is not an output folder of this process (a demo's per-scene folder) just gets its
// manifest.json.
void finish_output_folder(const std::filesystem::path& dir, const nlohmann::json& manifest);
// The same for a command whose folder has no manifest (knitsim targets: each file carries its
// provenance): removes the marker.
void finish_output_folder(const std::filesystem::path& dir);
// Whether dir holds one whole run: manifest.json present and no incomplete.txt. If not, `why`
// says which (one line, naming the file).
bool output_folder_complete(const std::filesystem::path& dir, std::string& why);

// The output folder of a command, created and checked writable (the folder's write permission,
// effective ids) before any work starts.
//   requested empty: a fresh folder out/<stem>-YYYYmmdd-HHMMSS (local time) under the working
//     directory, with -2, -3, ... appended if that name is taken;
//   otherwise `requested`, created with its parents if missing; an existing folder is reused
//     and files of the same names in it are replaced -- unless its manifest.json names another
//     command than this process's (command_name()): that folder holds another command's
//     results, and the call throws rather than overwrite them.
// The folder is then locked for the life of the process: an advisory flock(LOCK_EX) on the
// folder itself (a descriptor of it; no lock file is made, and the kernel drops the lock when the
// process ends, however it ends, so a killed run leaves no stale lock). A second knitsim given
// the same folder while the first runs throws OutputFolderBusy, before it writes anything; the
// same process may ask for its own folder again.
// Throws std::invalid_argument("--out DIR: cannot create|write ...: reason"). `created`, if
// given, says whether the folder is new (for remove_if_unused).
std::filesystem::path make_output_dir(const std::string& requested, const std::string& stem,
                                      bool* created = nullptr);
// For the commands that checkpoint (fit, repro): throws std::invalid_argument if `out` names a
// folder holding one of `checkpoints` and the run is not `resume`d -- starting afresh would
// overwrite the earlier run's work, which a forgotten --resume should not cost.
void refuse_fresh_start_over_checkpoint(const std::string& out,
                                        const std::vector<std::string>& checkpoints, bool resume);
// Removes `file` if it exists: an optional output this run does not write (a picture under
// --no-pictures, steps.csv without --step-history, ...). Left in a reused --out folder, an
// earlier run's file would read as this run's.
void remove_stale_output(const std::filesystem::path& file);
// Removes `dir` if `created` and it holds nothing: for bad input found only
// once the run starts (an integrator option the model refuses), so that nothing is left behind.
void remove_if_unused(const std::filesystem::path& dir, bool created);

// Reads an input file named on the command line (scene, chart, target) into `text`. Returns
// false with `why` set ("No such file or directory", "is a directory", "is not a regular file (a
// FIFO)", "larger than N bytes, the limit for this input", ...) if it cannot be read or holds
// more than max_bytes: reading stops at max_bytes + 1, so /dev/zero or a runaway file is refused
// without filling memory. Only regular files and character devices (/dev/null, /dev/zero, a
// terminal) are read; a FIFO (a named pipe, or a shell's `<(...)`), socket or block device is
// refused without opening it (opening a FIFO with no writer blocks).
bool read_input_file(const std::string& path, std::size_t max_bytes, std::string& text,
                     std::string& why);

}  // namespace knitsim
