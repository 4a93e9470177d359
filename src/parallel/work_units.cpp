#include "src/parallel/work_units.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <unordered_map>

#include "src/parallel/message_passing.hpp"

namespace knitsim {

namespace {

// MPI, once ProcessGroup has loaded the module (only under an MPI launcher); null in a process
// of its own.
std::unique_ptr<detail::MessagePassing>& message_passing() {
  static std::unique_ptr<detail::MessagePassing> mp;
  return mp;
}

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

// Runs units[share[i]] for every i on `threads` threads and hands each result to take(index,
// result) on the calling thread, in the order of `share`. If take throws, the threads finish the
// unit they are on and start no other; the exception propagates.
void run_share(const std::vector<WorkUnit>& units, const std::vector<int>& share, int threads,
               const std::function<void(int, const std::string&)>& take) {
  const int n = static_cast<int>(share.size());
  if (threads <= 1 || n <= 1) {
    for (int i = 0; i < n; ++i) take(share[i], run_unit(units[share[i]]));
    return;
  }
  std::mutex mutex;
  std::condition_variable finished;
  std::vector<std::string> results(n);
  std::vector<char> done(n, 0);
  std::atomic<int> next{0};
  auto work = [&] {
    for (int i = next++; i < n; i = next++) {
      std::string result = run_unit(units[share[i]]);
      {
        const std::lock_guard<std::mutex> lock(mutex);
        results[i] = std::move(result);
        done[i] = 1;
      }
      finished.notify_one();
    }
  };
  struct Pool {  // joined however the loop below ends
    std::atomic<int>& next;
    int n;
    std::vector<std::thread> threads;
    ~Pool() {
      next = n;
      for (std::thread& t : threads) t.join();
    }
  } pool{next, n, {}};
  for (int t = 0; t < std::min(threads, n); ++t) pool.threads.emplace_back(work);
  for (int i = 0; i < n; ++i) {
    std::string result;
    {
      std::unique_lock<std::mutex> lock(mutex);
      finished.wait(lock, [&] { return done[i] != 0; });
      result = std::move(results[i]);
    }
    take(share[i], result);
  }
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

}  // namespace

// ---- messages between ranks (no-ops in one process) -------------------------------------------

void broadcast(std::string& text) {
  if (process_count() > 1) message_passing()->broadcast(text);
}

namespace {

// A unit's serialised result on its way to rank 0: "[index,result]".
std::string result_message(int index, const std::string& result) {
  return "[" + std::to_string(index) + "," + result + "]";
}

// Rank 0: the next message of another rank, if one has arrived (wait = false) or when it does.
bool receive_result(bool wait, std::string& message) {
  return process_count() > 1 && message_passing()->receive(wait, message);
}

// Ends every rank after an error on rank 0 that the others cannot know of (they would wait
// forever); in one process it is an ordinary exception.
[[noreturn]] void fail_everywhere(const std::exception& e) {
  if (process_count() > 1) {
    std::fprintf(stderr, "knitsim: error: %s\n", e.what());
    std::fflush(stderr);
    message_passing()->abort_all(1);
  }
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

  int recorded() const { return recorded_; }  // units recorded by this call, every rank's
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
  std::vector<int> share;
  for (int j = rank; j < n; j += size) share.push_back(pending[j]);
  if (rank != 0) {  // only under MPI: send each result without waiting for rank 0 to take it
    run_share(units, share, options.threads, [](int index, const std::string& result) {
      message_passing()->send_to_root(result_message(index, result));
    });
    message_passing()->complete_sends();
    return {};
  }
  try {
    std::string message;
    run_share(units, share, options.threads, [&](int index, const std::string& result) {
      collector.record(index, result);
      while (receive_result(false, message)) collector.record_message(message);
    });
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

int process_rank() { return message_passing() ? message_passing()->rank() : 0; }

int process_count() { return message_passing() ? message_passing()->size() : 1; }

std::string mpi_library_version() {
  return message_passing() ? message_passing()->library_version() : KNITSIM_MPI_LIBRARY;
}

namespace {

// Whether an MPI launcher started this process (Open MPI's mpirun, MPICH/Intel hydra, PMIx
// launchers such as srun --mpi=pmix). A plain `knitsim ...` never loads MPI.
bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(name) != nullptr) return true;
  return false;
}

}  // namespace

ProcessGroup::ProcessGroup(int& argc, char**& argv) {
#ifdef KNITSIM_MPI_MODULE
  if (!launched_by_mpi()) return;
  // RTLD_GLOBAL: Open MPI's own plug-ins, which it dlopens in turn, look for libmpi's symbols
  // in the global scope. The module stays loaded until the process ends.
  void* module = dlopen(KNITSIM_MPI_MODULE, RTLD_NOW | RTLD_GLOBAL);
  void* open = module ? dlsym(module, detail::open_message_passing_symbol) : nullptr;
  if (open == nullptr) {  // a broken build folder: the module is built with every binary
    std::fprintf(stderr, "knitsim: error: cannot load the MPI module %s: %s\n", KNITSIM_MPI_MODULE,
                 dlerror());
    std::exit(1);
  }
  message_passing().reset(reinterpret_cast<detail::OpenMessagePassing>(open)(&argc, &argv));
#else
  (void)argc;
  (void)argv;
#endif
}

ProcessGroup::~ProcessGroup() { message_passing().reset(); }

}  // namespace knitsim
