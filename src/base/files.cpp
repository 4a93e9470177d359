#include "src/base/files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <utility>

#include "src/base/command_line.hpp"

namespace knitsim {

namespace fs = std::filesystem;

namespace {

std::string tmp_name(const fs::path& path) { return path.string() + ".tmp"; }

// The output folders of this process (make_output_dir) and whether this run has marked each
// incomplete yet (its first write). Keyed by the folder's path as make_output_dir returned it,
// which is what the writers are given (dir / "name").
std::mutex g_folders_mutex;
std::string folder_key(const fs::path& dir) {
  fs::path p = dir.lexically_normal();
  if (!p.has_filename() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
  return p.string();
}
std::map<std::string, bool> g_folders;  // folder -> marked

// Test hook: KNITSIM_KILL_AFTER_WRITES=k kills the process (SIGKILL, as `kill -9` would) after
// its k-th write or removal into an output folder (the marker included), so that the tests can
// stop a run at every point of its writing (tests/test_reliability.cpp).
long kill_after_writes() {
  static const long k = [] {
    const char* v = std::getenv("KNITSIM_KILL_AFTER_WRITES");
    return v ? std::atol(v) : -1L;
  }();
  return k;
}

void count_write() {
  static std::atomic<long> done{0};
  const long k = kill_after_writes();
  if (k >= 0 && ++done >= k) ::kill(::getpid(), SIGKILL);
}

// Before the first write into an output folder of this process (or a folder inside one):
// its marker. Returns whether `path` lies in such a folder.
bool before_output_write(const fs::path& path) {
  const std::lock_guard<std::mutex> guard(g_folders_mutex);
  if (g_folders.empty()) return false;
  for (fs::path dir = path.lexically_normal().parent_path(); !dir.empty();
       dir = dir.parent_path()) {
    const auto it = g_folders.find(dir.string());
    if (it == g_folders.end()) {
      if (dir == dir.parent_path()) break;
      continue;
    }
    if (!it->second) {
      const fs::path marker = dir / kIncompleteMarker;
      std::ofstream out(marker, std::ios::binary | std::ios::trunc);
      out << "knitsim " << command_name() << " (process " << ::getpid() << ") began writing "
          << "this folder at " << utc_stamp() << ".\nIt removes this file once manifest.json, "
          << "its last file, is written. If this file is still here and that run has ended, it "
          << "was stopped while writing: the files here may mix two runs, and --continue "
          << "refuses the folder. Run again into it to make it whole.\n";
      out.close();
      if (!out) throw OutputError("cannot write " + marker.string() + ": " + std::strerror(errno));
      it->second = true;
      count_write();
    }
    return true;
  }
  return false;
}

void commit_tmp(const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp_name(path), path, ec);
  if (ec) {
    fs::remove(tmp_name(path), ec);
    throw OutputError("cannot write " + path.string() + ": " + ec.message());
  }
}

std::string local_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", &tm);
  return buf;
}


}  // namespace

std::string utc_stamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

void write_file_atomic(const fs::path& path, const std::string& content) {
  write_file_atomic_with(path, [&content](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << content;
    out.close();
    if (!out) throw std::runtime_error(std::strerror(errno));
  });
}

void write_file_atomic_with(const fs::path& path,
                            const std::function<void(const std::string& tmp)>& write) {
  const bool counted = before_output_write(path);
  try {
    write(tmp_name(path));
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove(tmp_name(path), ec);
    throw OutputError("cannot write " + path.string() + ": " + e.what());
  }
  commit_tmp(path);
  if (counted) count_write();
}

void write_json_atomic(const fs::path& path, const nlohmann::json& value) {
  write_file_atomic(path, value.dump(2) + "\n");
}

void finish_output_folder(const fs::path& dir, const nlohmann::json& manifest) {
  write_json_atomic(dir / "manifest.json", manifest);
  finish_output_folder(dir);
}

void finish_output_folder(const fs::path& dir) {
  const std::lock_guard<std::mutex> guard(g_folders_mutex);
  const auto it = g_folders.find(folder_key(dir));
  if (it == g_folders.end() || !it->second) return;
  std::error_code ec;
  fs::remove(dir / kIncompleteMarker, ec);
  if (ec)
    throw OutputError("cannot remove " + (dir / kIncompleteMarker).string() + ": " + ec.message());
  it->second = false;  // a later write (a fit writing again) marks it anew
  count_write();
}

bool output_folder_complete(const fs::path& dir, std::string& why) {
  std::error_code ec;
  if (fs::exists(dir / kIncompleteMarker, ec)) {
    why = (dir / kIncompleteMarker).string() +
          " is there: the run that wrote the folder was stopped while writing it, so its files "
          "may mix two runs";
    return false;
  }
  if (!fs::is_regular_file(dir / "manifest.json", ec)) {
    why = (dir / "manifest.json").string() +
          " is missing: the run that wrote the folder did not finish writing it";
    return false;
  }
  return true;
}

namespace {

// An existing --out folder is reused only by the command that wrote it: its manifest.json
// naming another command (e.g. a fit's folder given to drape) means results this run would
// overwrite or leave mixed with its own. Folders without a manifest, or whose manifest has no
// "command" field, are reused.
void refuse_other_commands_folder(const fs::path& dir, const std::string& requested) {
  std::error_code ec;
  const fs::path path = dir / "manifest.json";
  if (!fs::is_regular_file(path, ec)) return;
  std::ifstream in(path);
  const nlohmann::json m = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!m.is_object() || !m.contains("command") || !m["command"].is_string()) return;
  const std::string owner = m["command"].get<std::string>();
  if (owner.empty() || owner == command_name()) return;
  throw std::invalid_argument("--out " + requested + ": holds the results of `knitsim " + owner +
                              "` (its manifest.json); give another folder or remove that one");
}

// Takes the advisory lock of `dir` for the rest of the process, once per folder: flock on a
// descriptor of the folder itself, kept open until exit, when the kernel releases it. Returns
// false if another process holds it. No file is made for it (a new inode costs more than the
// rest of a small run's file work on some disks); the folder's write permission is asked
// instead (faccessat, effective ids). Throws std::invalid_argument("--out SHOWN: cannot write:
// reason") if the folder takes no files, or "cannot lock" if flock fails otherwise than busy.
bool lock_output_dir(const fs::path& dir, const std::string& shown) {
  static std::mutex mutex;
  static std::map<std::pair<dev_t, ino_t>, int> held;  // folder -> its locked descriptor
  const auto fail = [&shown](const char* what, int err) {
    throw std::invalid_argument("--out " + shown + ": " + what + ": " + std::strerror(err));
  };
  if (::faccessat(AT_FDCWD, dir.c_str(), W_OK | X_OK, AT_EACCESS) != 0) fail("cannot write", errno);
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) fail("cannot write", errno);
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    fail("cannot write", err);
  }
  const std::lock_guard<std::mutex> guard(mutex);
  if (held.count({st.st_dev, st.st_ino})) {
    ::close(fd);
    return true;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd);
    if (err == EWOULDBLOCK) return false;
    fail("cannot lock", err);
  }
  held[{st.st_dev, st.st_ino}] = fd;
  return true;
}

}  // namespace

fs::path make_output_dir(const std::string& requested, const std::string& stem, bool* created_out) {
  std::error_code ec;
  fs::path dir;
  bool created = false;
  if (requested.empty()) {
    const fs::path parent = "out";
    const bool made_parent = fs::create_directories(parent, ec);
    if (ec) throw std::invalid_argument("--out (default out/): cannot create out: " + ec.message());
    const std::string base = stem + "-" + local_stamp();
    for (int k = 1; !created; ++k) {
      dir = parent / (k == 1 ? base : base + "-" + std::to_string(k));
      created = fs::create_directory(dir, ec);
      if (ec) {  // e.g. a name too long: leave no empty out/ behind
        const std::string reason = ec.message();
        if (made_parent) fs::remove(parent, ec);
        throw std::invalid_argument("--out " + dir.string() + ": cannot create: " + reason);
      }
    }
  } else {
    dir = requested;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
      throw std::invalid_argument("--out " + requested + ": exists and is not a folder");
    refuse_other_commands_folder(dir, requested);
    created = !fs::exists(dir, ec);
    fs::create_directories(dir, ec);
    if (ec) throw std::invalid_argument("--out " + requested + ": cannot create: " + ec.message());
  }
  bool locked = false;
  try {
    locked = lock_output_dir(dir, dir.string());
  } catch (const std::invalid_argument&) {
    if (created) fs::remove(dir, ec);
    throw;
  }
  if (locked) {
    const std::lock_guard<std::mutex> guard(g_folders_mutex);
    g_folders.emplace(folder_key(dir), false);
  }
  if (!locked)
    throw OutputFolderBusy(
        "--out " + dir.string() +
        ": in use by another knitsim run (it holds the folder's lock); wait for it to "
        "end, or give another folder");
  if (created_out) *created_out = created;
  return dir;
}

void refuse_fresh_start_over_checkpoint(const std::string& out,
                                        const std::vector<std::string>& checkpoints, bool resume) {
  if (resume || out.empty()) return;
  std::error_code ec;
  for (const std::string& name : checkpoints)
    if (fs::exists(fs::path(out) / name, ec))
      throw std::invalid_argument("--out " + out + ": holds the checkpoint " + name +
                                  " of an earlier run; add --resume to continue it, or remove "
                                  "the file (or give another folder) to start afresh");
}

void remove_stale_output(const fs::path& file) {
  std::error_code ec;
  if (fs::symlink_status(file, ec).type() == fs::file_type::not_found) return;  // no write
  const bool counted = before_output_write(file);
  fs::remove_all(file, ec);
  if (ec) throw OutputError("cannot remove " + file.string() + ": " + ec.message());
  if (counted) count_write();
}

void remove_if_unused(const fs::path& dir, bool created) {
  std::error_code ec;
  if (!created) return;
  if (fs::is_empty(dir, ec) && !ec) fs::remove(dir, ec);
}

bool read_input_file(const std::string& path, std::size_t max_bytes, std::string& text,
                     std::string& why) {
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (ec) return why = ec.message(), false;
  if (std::filesystem::is_directory(st)) return why = "is a directory", false;
  if (!std::filesystem::is_regular_file(st) && !std::filesystem::is_character_file(st)) {
    why = std::filesystem::is_fifo(st)         ? "is a FIFO (a named pipe), not a regular file"
          : std::filesystem::is_socket(st)     ? "is a socket, not a regular file"
          : std::filesystem::is_block_file(st) ? "is a block device, not a regular file"
                                               : "is not a regular file";
    return false;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return why = std::strerror(errno), false;
  text.clear();
  char buffer[1 << 16];
  while (in && text.size() <= max_bytes) {
    in.read(buffer, static_cast<std::streamsize>(
                        std::min<std::size_t>(sizeof buffer, max_bytes + 1 - text.size())));
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) return why = "read error", false;
  if (text.size() > max_bytes) {
    text.clear();
    return why = "larger than " + std::to_string(max_bytes) + " bytes, the limit for this input",
           false;
  }
  return true;
}

}  // namespace knitsim
