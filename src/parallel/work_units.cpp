#include "src/parallel/work_units.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#ifdef KNITSIM_HAVE_MPI
#include <mpi.h>
#include <nlohmann/json.hpp>
#endif

namespace knitsim {

namespace {

using json = nlohmann::json;

// The one serialised form of a result: what the checkpoint holds and what travels between
// ranks. Invalid UTF-8 in strings (e.g. an exception message) is replaced, not an error.
std::string serialise(const json& value) {
  return value.dump(-1, ' ', false, json::error_handler_t::replace);
}

// Runs one unit; its result serialised. A std::exception becomes {"error": what}.
std::string run_unit(const WorkUnit& unit) {
  json result;
  try {
    result = unit.run();
  } catch (const std::exception& e) {
    result = {{"error", e.what()}};
  }
  return serialise(result);
}

// A checkpoint that cannot be written is an output failure (exit status 4, src/cli/main.cpp):
// std::filesystem::filesystem_error is the standard type the command line maps to it.
[[noreturn]] void cannot_write(const std::string& path) {
  throw std::filesystem::filesystem_error("cannot write", path,
                                          std::error_code(errno, std::generic_category()));
}

// Appends whole lines to the checkpoint, each flushed to disk (fsync) before the next unit is
// reported done: after a crash the file holds every reported unit, plus at most one partial
// last line.
class CheckpointWriter {
 public:
  // Opens `path` and cuts it to its first `keep` bytes (0: a new file).
  CheckpointWriter(std::string path, off_t keep) : path_(std::move(path)) {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd_ < 0) cannot_write(path_);
    if (::ftruncate(fd_, keep) != 0) {
      ::close(fd_);
      cannot_write(path_);
    }
  }
  ~CheckpointWriter() { ::close(fd_); }
  CheckpointWriter(const CheckpointWriter&) = delete;
  CheckpointWriter& operator=(const CheckpointWriter&) = delete;

  void append(const std::string& line) {
    const std::string text = line + "\n";
    for (std::size_t done = 0; done < text.size();) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) cannot_write(path_);
      done += static_cast<std::size_t>(n);
    }
    if (::fsync(fd_) != 0) cannot_write(path_);
  }

 private:
  std::string path_;
  int fd_ = -1;
};

// Reads a checkpoint for a resume: the completed units' results (by index in `units`) and the
// length of its complete lines. Text after the last newline is an interrupted write and is
// not counted. A missing file, or one without a complete first line, has nothing completed.
struct CheckpointContent {
  std::vector<std::pair<int, json>> completed;
  off_t complete_bytes = 0;
};

CheckpointContent read_checkpoint(const std::string& path, const json& config,
                                  const std::unordered_map<std::string, int>& index_of) {
  CheckpointContent content;
  std::ifstream in(path, std::ios::binary);
  if (!in) return content;
  std::ostringstream text;
  text << in.rdbuf();
  const std::string all = text.str();
  const std::size_t end = all.rfind('\n');
  if (end == std::string::npos) return content;
  auto bad = [&](int line, const std::string& why) {
    throw std::invalid_argument("checkpoint " + path + " line " + std::to_string(line) + ": " +
                                why);
  };
  std::istringstream lines(all.substr(0, end + 1));
  std::string line;
  std::vector<bool> seen(index_of.size(), false);
  for (int number = 1; std::getline(lines, line); ++number) {
    const json j = json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object()) bad(number, "not a JSON object");
    if (number == 1) {
      if (!j.contains("config")) bad(number, "no config (not a knitsim checkpoint)");
      if (j.at("config") != config)
        bad(number, "made with other settings (first difference: " +
                        first_config_difference(j.at("config"), config) +
                        "): resume with the same settings or start afresh");
      continue;
    }
    if (!j.contains("key") || !j.at("key").is_string() || !j.contains("result"))
      bad(number, "not {key, result}");
    const std::string key = j.at("key").get<std::string>();
    const auto it = index_of.find(key);
    if (it == index_of.end()) bad(number, "unit '" + key + "' is not one of this run's units");
    if (seen[it->second]) bad(number, "unit '" + key + "' appears twice");
    seen[it->second] = true;
    content.completed.emplace_back(it->second, j.at("result"));
  }
  content.complete_bytes = static_cast<off_t>(end + 1);
  return content;
}

// "label  12/40 units (8 from the checkpoint)  elapsed 31 s  eta ~72 s" on stderr, rewritten
// after every unit; only when enabled and stderr is a terminal. Cleared on destruction.
class UnitProgress {
 public:
  UnitProgress(std::string label, int total, int resumed, bool enabled)
      : label_(std::move(label)),
        total_(total),
        resumed_(resumed),
        active_(enabled && ::isatty(STDERR_FILENO) == 1) {}
  ~UnitProgress() {
    if (shown_) std::fprintf(stderr, "\r\033[K");
  }
  UnitProgress(const UnitProgress&) = delete;
  UnitProgress& operator=(const UnitProgress&) = delete;

  void completed() {
    ++done_;
    if (!active_) return;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    const double eta = elapsed / done_ * (total_ - resumed_ - done_);
    std::fprintf(stderr, "\r\033[K%s  %d/%d units", label_.c_str(), resumed_ + done_, total_);
    if (resumed_ > 0) std::fprintf(stderr, " (%d from the checkpoint)", resumed_);
    std::fprintf(stderr, "  elapsed %.0f s  eta ~%.0f s", elapsed, eta);
    std::fflush(stderr);
    shown_ = true;
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  int total_, resumed_, done_ = 0;
  bool active_, shown_ = false;
  Clock::time_point start_ = Clock::now();
};

// ---- messages between ranks (no-ops in one process) -------------------------------------------

#ifdef KNITSIM_HAVE_MPI
constexpr int kResultTag = 7301;

bool mpi_running() {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  return initialized && !finalized;
}
#endif

}  // namespace

void broadcast(std::string& text) {
#ifdef KNITSIM_HAVE_MPI
  if (process_count() == 1) return;
  long long size = static_cast<long long>(text.size());
  MPI_Bcast(&size, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  text.resize(static_cast<std::size_t>(size));
  MPI_Bcast(text.data(), static_cast<int>(size), MPI_CHAR, 0, MPI_COMM_WORLD);
#else
  (void)text;
#endif
}

namespace {

// A unit's serialised result on its way to rank 0: "[index,result]".
std::string result_message(int index, const std::string& result) {
  return "[" + std::to_string(index) + "," + result + "]";
}

// Sends from ranks > 0 without waiting for rank 0 (which polls between its own units); every
// send is complete when the object is destroyed.
class ResultSender {
 public:
  void send(std::string message) {
#ifdef KNITSIM_HAVE_MPI
    buffers_.push_back(std::move(message));
    requests_.emplace_back();
    MPI_Isend(buffers_.back().data(), static_cast<int>(buffers_.back().size()), MPI_CHAR, 0,
              kResultTag, MPI_COMM_WORLD, &requests_.back());
#else
    (void)message;
#endif
  }
  ~ResultSender() {
#ifdef KNITSIM_HAVE_MPI
    if (!requests_.empty())
      MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
#endif
  }

 private:
#ifdef KNITSIM_HAVE_MPI
  std::deque<std::string> buffers_;  // stable addresses while the sends are under way
  std::vector<MPI_Request> requests_;
#endif
};

// Rank 0: the next message of another rank, if one has arrived (wait = false) or when it does.
bool receive_result(bool wait, std::string& message) {
#ifdef KNITSIM_HAVE_MPI
  if (process_count() == 1) return false;
  MPI_Status status;
  int arrived = 1;
  if (wait)
    MPI_Probe(MPI_ANY_SOURCE, kResultTag, MPI_COMM_WORLD, &status);
  else
    MPI_Iprobe(MPI_ANY_SOURCE, kResultTag, MPI_COMM_WORLD, &arrived, &status);
  if (!arrived) return false;
  int size = 0;
  MPI_Get_count(&status, MPI_CHAR, &size);
  message.resize(static_cast<std::size_t>(size));
  MPI_Recv(message.data(), size, MPI_CHAR, status.MPI_SOURCE, kResultTag, MPI_COMM_WORLD,
           MPI_STATUS_IGNORE);
  return true;
#else
  (void)wait;
  (void)message;
  return false;
#endif
}

// Ends every rank after an error on rank 0 that the others cannot know of (they would wait
// forever); in one process it is an ordinary exception.
[[noreturn]] void fail_everywhere(const std::exception& e) {
#ifdef KNITSIM_HAVE_MPI
  if (process_count() > 1) {
    std::fprintf(stderr, "knitsim: error: %s\n", e.what());
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
#endif
  throw;
}

// Rank 0's part: reads the checkpoint (resume), opens it for appending, runs its own units,
// collects the others', writes each as it arrives. Returns the results in unit order.
class Collector {
 public:
  Collector(const std::vector<WorkUnit>& units, const WorkUnitOptions& options)
      : units_(units), options_(options), results_(units.size()), done_(units.size(), false) {}

  // The indices still to run; throws (std::invalid_argument) on a checkpoint that does not fit.
  std::vector<int> open(const std::unordered_map<std::string, int>& index_of) {
    const json config = json::parse(serialise(options_.config));
    CheckpointContent content;
    if (options_.resume && !options_.checkpoint.empty())
      content = read_checkpoint(options_.checkpoint, config, index_of);
    for (auto& [index, result] : content.completed) {
      results_[index] = std::move(result);
      done_[index] = true;
    }
    if (!options_.checkpoint.empty()) {
      writer_ = std::make_unique<CheckpointWriter>(options_.checkpoint, content.complete_bytes);
      if (content.complete_bytes == 0) writer_->append(serialise({{"config", config}}));
    }
    std::vector<int> pending;
    for (int i = 0; i < static_cast<int>(units_.size()); ++i)
      if (!done_[i]) pending.push_back(i);
    progress_ = std::make_unique<UnitProgress>(options_.label, static_cast<int>(units_.size()),
                                               static_cast<int>(content.completed.size()),
                                               options_.progress);
    return pending;
  }

  void record(int index, const std::string& result) {
    results_[index] = json::parse(result);
    if (writer_)
      writer_->append(serialise({{"key", units_[index].key}, {"result", results_[index]}}));
    progress_->completed();
    ++recorded_;
  }
  void record_message(const std::string& message) {
    const json m = json::parse(message);
    record(m.at(0).get<int>(), serialise(m.at(1)));
  }

  int recorded() const { return recorded_; }  // units recorded in this session
  std::vector<json> take() { return std::move(results_); }

 private:
  const std::vector<WorkUnit>& units_;
  const WorkUnitOptions& options_;
  std::vector<json> results_;
  std::vector<bool> done_;
  std::unique_ptr<CheckpointWriter> writer_;
  std::unique_ptr<UnitProgress> progress_;
  int recorded_ = 0;
};

}  // namespace

std::string first_config_difference(const json& saved, const json& now) {
  const json patch = json::diff(saved, now);
  return patch.empty() ? "" : patch[0].value("path", std::string());
}

std::vector<json> run_work_units(const std::vector<WorkUnit>& units,
                                 const WorkUnitOptions& options) {
  const int rank = process_rank(), size = process_count();
  std::unordered_map<std::string, int> index_of;
  for (int i = 0; i < static_cast<int>(units.size()); ++i)
    if (!index_of.emplace(units[i].key, i).second)
      throw std::invalid_argument("work unit key '" + units[i].key + "' appears twice");

  // Rank 0 reads the checkpoint and tells every rank what is left to do (or why not).
  Collector collector(units, options);
  std::string setup;
  if (rank == 0) {
    try {
      setup = serialise({{"pending", collector.open(index_of)}});
    } catch (const std::invalid_argument& e) {
      setup = serialise({{"error", e.what()}, {"bad_input", true}});
    } catch (const std::exception& e) {
      setup = serialise({{"error", e.what()}, {"bad_input", false}});
    }
  }
  broadcast(setup);
  const json plan = json::parse(setup);
  if (plan.contains("error")) {
    const std::string what = plan.at("error").get<std::string>();
    if (plan.at("bad_input").get<bool>()) throw std::invalid_argument(what);
    throw std::runtime_error(what);
  }
  const std::vector<int> pending = plan.at("pending").get<std::vector<int>>();

  // Static split of what is left: pending[j] runs on rank j % size.
  const int n = static_cast<int>(pending.size());
  if (rank != 0) {
    ResultSender sender;
    for (int j = rank; j < n; j += size)
      sender.send(result_message(pending[j], run_unit(units[pending[j]])));
    return {};
  }
  try {
    std::string message;
    for (int j = 0; j < n; j += size) {
      collector.record(pending[j], run_unit(units[pending[j]]));
      while (receive_result(false, message)) collector.record_message(message);
    }
    while (collector.recorded() < n) {
      receive_result(true, message);
      collector.record_message(message);
    }
  } catch (const std::exception& e) {
    fail_everywhere(e);
  }
  return collector.take();
}

// ---- processes -------------------------------------------------------------------------------

int process_rank() {
#ifdef KNITSIM_HAVE_MPI
  if (mpi_running()) {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
  }
#endif
  return 0;
}

std::string mpi_library_version() {
#ifdef KNITSIM_HAVE_MPI
  char text[MPI_MAX_LIBRARY_VERSION_STRING];
  int length = 0;
  MPI_Get_library_version(text, &length);  // allowed before MPI_Init
  const std::string version(text, static_cast<std::size_t>(length));
  return version.substr(0, version.find_first_of(",\n"));  // "Open MPI v4.1.4, package: ..."
#else
  return "none";
#endif
}

int process_count() {
#ifdef KNITSIM_HAVE_MPI
  if (mpi_running()) {
    int size = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    return size;
  }
#endif
  return 1;
}

namespace {

// Whether an MPI launcher started this process (Open MPI's mpirun, MPICH/Intel hydra, PMIx
// launchers such as srun --mpi=pmix). A plain `knitsim ...` never initialises MPI.
bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(name) != nullptr) return true;
  return false;
}

}  // namespace

ProcessGroup::ProcessGroup(int& argc, char**& argv) {
#ifdef KNITSIM_HAVE_MPI
  if (launched_by_mpi()) {
    int provided = 0;
    // Only the main thread calls MPI (the ICA's worker threads only evaluate costs).
    MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  }
#else
  (void)argc;
  (void)argv;
#endif
}

ProcessGroup::~ProcessGroup() {
#ifdef KNITSIM_HAVE_MPI
  if (mpi_running()) MPI_Finalize();
#endif
}

}  // namespace knitsim
