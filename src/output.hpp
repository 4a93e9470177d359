// What a run writes and prints (SPEC 2.10, 2.11): output folders, atomic file writes, tables
// (text, CSV, Markdown), legacy VTK, JSON summaries, the manifest, the drape outputs, and the
// progress line on a terminal.
//
// Every file is written atomically: to `<name>.tmp` in the same folder, then renamed over
// `<name>` (POSIX rename: a reader sees the old file or the new one, never half of one).
// Failure modes: bad --out folders are bad input (std::invalid_argument naming --out); a write
// that fails later (disk full, ...) throws std::runtime_error("cannot write PATH: reason").
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "models/drape_grid.hpp"
#include "solvers/integrator.hpp"
#include "src/measurement.hpp"
#include "src/scene.hpp"
#include "src/vec3.hpp"

namespace knitsim {

struct DrapeLmOptions;  // src/lm_fit.hpp (Eigen stays out of this header)

// ---- files and folders -----------------------------------------------------------------------

void write_file_atomic(const std::filesystem::path& path, const std::string& content);
// For writers that take a file name (the PNG renderer): write(tmp) must create the file tmp.
void write_file_atomic_with(const std::filesystem::path& path,
                            const std::function<void(const std::string& tmp)>& write);
// JSON pretty-printed with 2 spaces and a final newline.
void write_json_atomic(const std::filesystem::path& path, const nlohmann::json& value);

// The output folder of a command, created and checked writable (a probe file is created and
// removed) before any work starts.
//   requested empty: a fresh folder out/<stem>-YYYYmmdd-HHMMSS (local time) under the working
//     directory, with -2, -3, ... appended if that name is taken;
//   otherwise `requested`, created with its parents if missing; an existing folder is reused
//     and files of the same names in it are replaced -- unless its manifest.json names another
//     command than this process's (command_name()): that folder holds another command's
//     results, and the call throws rather than overwrite them.
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
// Removes `dir` if `created` and it is still empty: for bad input found only once the run
// starts (an integrator option the model refuses), so that nothing is left behind.
void remove_if_unused(const std::filesystem::path& dir, bool created);

// ---- formatting --------------------------------------------------------------------------------

// printf %.<digits>g (lossless for doubles at digits = 17).
std::string format_number(double value, int digits = 4);
// Appends the shortest decimal text that reads back as exactly `value` (std::to_chars; several
// times faster than a stream at precision 17, for large CSV and VTK files).
void append_number(std::string& out, double value);
// Appends an integer in decimal.
void append_integer(std::string& out, long long value);

// The "linear algebra" line of drape's and knit's summaries: "125 factorisations of S (block
// LDL^T, 2.12e+09 flops each, 265 GFlop in all)"; "" where the run factorised no S by
// SymmetricFactor (the explicit methods, KLU, block-Jacobi GMRES). `static`'s count includes
// the few KLU factorisations of K (the same pattern) of its Newton polish.
std::string linear_algebra_summary(const RunStats& s);

// A table of text cells, printable three ways. Every row has columns.size() cells.
struct Table {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;

  std::string text() const;      // columns aligned with two spaces, for terminals
  std::string csv() const;       // RFC 4180: cells holding , " or a newline are quoted
  std::string markdown() const;  // GitHub pipe table
};

// Legacy VTK (ASCII, DATASET POLYDATA), opened by ParaView and VisIt.
struct VtkPolyData {
  std::string title;  // one line
  std::vector<Vec3> points;
  std::vector<std::vector<int>> polygons;  // point indices, any number >= 3 per polygon
  std::vector<std::pair<std::string, std::vector<int>>> point_ints;      // SCALARS int
  std::vector<std::pair<std::string, std::vector<Vec3>>> point_vectors;  // VECTORS double
};
std::string to_vtk(const VtkPolyData& data);

// ---- JSON ------------------------------------------------------------------------------------

nlohmann::json to_json(const DrapeParams& p);        // field names as in DrapeParams
nlohmann::json to_json(const IntegratorOptions& o);  // field names as in IntegratorOptions
nlohmann::json to_json(const RunStats& s);           // status as to_string(RunStatus)
nlohmann::json to_json(const DrapeLmOptions& o);     // field names as in DrapeLmOptions, lm

// ---- provenance --------------------------------------------------------------------------------

// The process command line, recorded once by main() for the manifests.
void set_command_line(int argc, const char* const* argv);
// "knitsim <version> (commit <hash>, <build type>)", for --version.
std::string version_string();
// The subcommand of that line (argv[1]: drape, fit, ...), "" before set_command_line.
const std::string& command_name();
// manifest.json: program and version, git commit (at configure time), build type, command
// (command_name()) and command line, `options` as given, library versions (SUNDIALS, Eigen, cairo,
// toml++, CLI11, nlohmann-json, SuiteSparse, MPI), compiler, UTC creation time. No host or user
// names.
nlohmann::json manifest(const nlohmann::json& options);

// ---- drape outputs -----------------------------------------------------------------------------

// summary.json's "units": what each number of a run summary is measured in, for a reader
// without the source. `model` maps the model's own numbers (drape or knit: the residual's
// scale, centre_sag_m, params, ...) to their units; times, steps and cost figures are shared.
nlohmann::json summary_units(const nlohmann::json& model);

// summary.json: scene, source, status, message, integrator, t_final, residual, wall time, all
// RunStats counters, grid size and counts, max strain, centre sag, params, options.
nlohmann::json drape_summary(const Scene& scene, const DrapeResult& result);

// Writes into `dir` (which must exist): summary.json, nodes.csv (id,i,j,x,y,z,pinned; all
// particles at t_final, m), drape.vtk (the grid's quads, point data `pinned` and
// `displacement` = position - rest position, m), drape.png (render_mesh_png, oblique view) and
// manifest.json (options: scene, integrator, params, run options), and state.json
// (write_run_state: the integrated unknowns at t_final; omitted if not finite).
// Writes summary.json, nodes.csv, drape.vtk, drape.png, and edges.csv (the measured edges,
// SPEC 2.5) when the final state is finite. With `target` (the measured edges of the matching
// target scene, e.g. fit_target_scene(...)), summary.json also gets `objective` (Eq. 5, %) and
// the per-edge coefficients of both, and target_edges.csv is written. picture = false skips
// drape.png (`--no-pictures`: the rendering costs about as much as a four_corner solve).
void write_drape_outputs(const std::filesystem::path& dir, const Scene& scene,
                         const DrapeResult& result, const std::vector<EdgeFit>* target = nullptr,
                         bool picture = true);

// ---- run state: knitsim drape|knit --continue ----------------------------------------------

// What `--continue DIR` starts from: DIR/state.json, the integrated state at t_final of a drape
// or knit run with what a continuation must match.
struct SavedRun {
  std::string command;  // "drape" or "knit": the command that wrote it
  RunState state;       // t_final, and x, v: the integrated unknowns
  std::string integrator;
  double dt = 0.0;       // the run's fixed step (euler, verlet, implicit-euler), else 0
  nlohmann::json model;  // {"model.stiffness": 852, ...}: what was integrated, keyed as the user
                         // sets it (--set keys; "chart" for the knit chart)
};
// A drape's SavedRun::model: to_json(params) with its keys as --set names them ("model.KEY",
// "fabric.width", "pins.layout", ...).
nlohmann::json drape_model_keys(const DrapeParams& params);
// Writes DIR/state.json (format "knitsim run state 2", shortest round-trip decimals); does
// nothing if x or v is not finite (there is nothing to continue from).
void write_run_state(const std::filesystem::path& dir, const SavedRun& saved);
// The text of a state.json written by `command`: throws std::invalid_argument (one line) naming
// what is missing or malformed (x, v not finite or not integrated_dof long, t or dt negative),
// or that another command or format wrote it. Fuzzed (tests/fuzz/fuzz_state.cpp).
SavedRun parse_run_state(const std::string& text, const std::string& command);
// Reads DIR/state.json (at most 256 MiB) with parse_run_state; the message names the file.
SavedRun read_run_state(const std::filesystem::path& dir, const std::string& command);
// --continue DIR of `command`: the saved state, checked against this run -- `model` (keyed as
// SavedRun::model) must equal the saved one key by key (the message names the first that differs,
// "model.stiffness = 900 here, 852 in the run being continued; give the same <same_what>"), its
// t must be below options.t_max ("raise run.t_max"). A fixed-step run continued by the same
// integrator keeps the saved step unless options.dt is set, so an interrupted euler run
// continues on the same step sequence. Throws std::invalid_argument (one line, starting
// "--continue"). The caller checks the state's size against what it integrates.
RunState continue_state(const std::string& dir, const std::string& command,
                        const nlohmann::json& model, const std::string& same_what,
                        const std::string& integrator, IntegratorOptions& options);

// ---- progress ----------------------------------------------------------------------------------

// One self-overwriting status line on stderr -- only when stderr is a terminal, and at most 10
// times a second: label, t, static residual against the tolerance, elapsed wall time and a
// rough ETA (extrapolating log(residual) linearly in wall time). Cleared on destruction.
class ProgressLine final : public RunObserver {
 public:
  ProgressLine(std::string label, double equilibrium_tol, bool enabled = true);
  ~ProgressLine() override;
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  void on_check(double t, const double* x, const double* v, double residual) override;

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  double tol_;
  bool active_;
  bool shown_ = false;
  double first_residual_ = -1.0;
  Clock::time_point start_, last_;
};

}  // namespace knitsim
