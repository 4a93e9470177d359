// Independent units of work (repro: target set x sample x ICA run; Taguchi experiment x
// replicate), each run exactly once, checkpointed as it completes, resumable after an
// interruption, and distributed over MPI ranks (docs/commands.md).
//
// Determinism: a unit's result must depend only on the unit itself (its key, its own seed),
// never on which rank ran it, how many threads it used, or what ran before. Results are JSON;
// doubles survive the checkpoint bit for bit (nlohmann writes max_digits10 digits), so a
// resumed run returns exactly what an uninterrupted one would.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace knitsim {

struct WorkUnit {
  std::string key;                      // unique within a run, e.g. "twin/s3/run07"
  std::function<nlohmann::json()> run;  // computes the unit's result (may throw: see below)
};

struct WorkUnitOptions {
  std::string checkpoint;  // JSON-lines file of completed units; empty = no checkpoint
  bool resume = false;     // read `checkpoint` first and skip the units it holds
  nlohmann::json config;   // what must match for a resume to be valid (preset, seeds, ...)
  bool progress = false;   // a progress line with ETA on stderr (rank 0, terminal only)
  std::string label;       // progress label
  // Units run at once by each process, on their own threads (>= 1). Results, the checkpoint's
  // lines and the progress stay in unit order: a finished unit waits for those before it.
  int threads = 1;
};

// Runs every unit not already completed and returns all results in the order of `units`, on
// rank 0 (other ranks get an empty vector). Every rank must call it with the same units. With
// options.threads > 1 units run concurrently: WorkUnit::run must then be reentrant.
// Failure modes: a unit that throws std::exception is an error result {"error": what} (it is
// not retried on resume); a checkpoint whose config differs from options.config, or that names
// unknown units, throws std::invalid_argument before any unit runs.
std::vector<nlohmann::json> run_work_units(const std::vector<WorkUnit>& units,
                                           const WorkUnitOptions& options);

// Where two configs first differ, as a JSON pointer ("/ica/seed"; "" when equal), for the error
// a resume with other settings gives (here and in knitsim fit --resume).
std::string first_config_difference(const nlohmann::json& saved, const nlohmann::json& now);

// MPI ranks once ProcessGroup has started MPI; otherwise one process of rank 0 of 1.
int process_rank();
int process_count();
// The MPI library, for manifests ("Open MPI v4.1.4"; "none" when built without MPI): under an
// MPI launcher the loaded library's own MPI_Get_library_version, otherwise the same string of
// the library found when the build was configured (a plain run does not load MPI).
std::string mpi_library_version();
// Rank 0's `text` on every rank (nothing to do in one process). Collective: every rank calls
// it, at the same point. For a decision only rank 0 can make (it alone owns the output folder)
// that every rank must then act on alike.
void broadcast(std::string& text);
// Owns MPI_Init/MPI_Finalize for main(). Only when an MPI launcher started the process
// (OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK set) does it load MPI, as the module
// libknitsim_mpi.so of the build folder (src/parallel/message_passing.hpp); otherwise, or when
// built without MPI, it does nothing. A missing module under a launcher ends the process
// (exit 1, one line on stderr).
class ProcessGroup {
 public:
  ProcessGroup(int& argc, char**& argv);
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;
};

}  // namespace knitsim
