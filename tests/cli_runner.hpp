// Running the built `knitsim` binary from tests: a temporary folder and a runner that captures
// exit status, stdout and stderr. KNITSIM_EXE (the binary's path) is defined by the build.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#ifndef KNITSIM_EXE
#error "KNITSIM_EXE (the path of the knitsim binary) must be defined by the build"
#endif

namespace knitsim::test {

namespace fs = std::filesystem;

// A fresh temporary folder, removed at the end of the test.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& tag) {
    path = fs::temp_directory_path() / ("knitsim-test-" + tag + "-" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

struct Run {
  int status = -1;
  std::string out, err;
};

// Runs `knitsim <args>` (args already shell-quoted) with stdout/stderr captured in `tmp`, and
// `env` (name, value: no single quotes) added to its environment.
inline Run run_knitsim(const std::string& args, const TempDir& tmp,
                       const std::vector<std::pair<std::string, std::string>>& env = {}) {
  const fs::path out = tmp.path / "stdout.txt", err = tmp.path / "stderr.txt";
  std::string vars;
  for (const auto& [name, value] : env) vars += name + "='" + value + "' ";
  const std::string cmd = vars + "'" + KNITSIM_EXE + "' " + args + " >'" + out.string() + "' 2>'" +
                          err.string() + "' </dev/null";
  const int raw = std::system(cmd.c_str());
  Run r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

// Starts `knitsim <args>` in the background (stdout/stderr to background-*.txt in `tmp`) and
// returns its process id, for tests that signal a run (the shell execs knitsim: same pid).
// The caller must waitpid() it.
inline pid_t start_knitsim(const std::string& args, const TempDir& tmp) {
  const std::string cmd = std::string("exec '") + KNITSIM_EXE + "' " + args + " >'" +
                          (tmp.path / "background-stdout.txt").string() + "' 2>'" +
                          (tmp.path / "background-stderr.txt").string() + "' </dev/null";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

// Sends `signal` to the background run `pid` (start_knitsim) once `ready()` holds -- an event
// the run itself produces (a file written, a checkpoint line, a handler installed) -- and waits
// for the run to end. ready() is evaluated while the run is stopped by SIGSTOP and the signal
// is sent before SIGCONT, so the run can neither finish nor move on between the check and the
// signal: the outcome does not depend on the machine's speed, its load or a sanitizer's
// slowdown. `signalled` is false if the run ended before ready() held, or if ready() had not held
// after `timeout`; `status` is the run's wait status, -1 if it had not ended after `timeout`
// (it is then killed).
struct SignalledRun {
  bool signalled = false;
  int status = -1;
};
inline SignalledRun signal_when(pid_t pid, int signal, const std::function<bool()>& ready,
                                std::chrono::seconds timeout = std::chrono::seconds(600)) {
  SignalledRun r;
  const auto give_up = std::chrono::steady_clock::now() + timeout;
  int st = 0;
  while (!r.signalled) {
    if (std::chrono::steady_clock::now() > give_up) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &st, 0);
      return r;
    }
    ::kill(pid, SIGSTOP);
    if (::waitpid(pid, &st, WUNTRACED) != pid) return r;
    if (!WIFSTOPPED(st)) {  // it ended before ready() held
      r.status = st;
      return r;
    }
    r.signalled = ready();
    if (r.signalled) ::kill(pid, signal);  // delivered when the run continues
    ::kill(pid, SIGCONT);
    if (!r.signalled) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  pid_t done = 0;
  while ((done = ::waitpid(pid, &st, WNOHANG)) == 0 && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  if (done == 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &st, 0);
    return r;
  }
  r.status = st;
  return r;
}

// Whether process `pid` runs the knitsim binary (not yet the forked test process or the shell
// of start_knitsim, which have handlers of their own) and has installed a handler for `signal`
// (the SigCgt mask of /proc/<pid>/status; Linux).
inline bool knitsim_handles(pid_t pid, int signal) {
  const std::string proc = "/proc/" + std::to_string(pid);
  std::error_code ec;
  if (fs::read_symlink(proc + "/exe", ec) != fs::canonical(KNITSIM_EXE) || ec) return false;
  std::ifstream in(proc + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("SigCgt:", 0) == 0)
      return (std::stoull(line.substr(7), nullptr, 16) >> (signal - 1)) & 1ULL;
  return false;
}

// CPU seconds (user + system) process `pid` has used so far (/proc/<pid>/stat; Linux), -1 if it
// cannot be read. A test that must signal a run after its set-up waits for some: the set-up
// itself stops at a signal and writes nothing (docs/reliability.md, "Signals"), and under the
// sanitizers it takes far longer than in a Release build.
inline double cpu_seconds_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t close = stat.rfind(')');  // the command name may hold spaces
  if (close == std::string::npos) return -1.0;
  std::istringstream fields(stat.substr(close + 2));
  std::string f;
  unsigned long long utime = 0, stime = 0;
  for (int k = 3; k <= 15 && fields >> f; ++k) {  // fields 14 and 15: utime, stime (ticks)
    if (k == 14) utime = std::stoull(f);
    if (k == 15) stime = std::stoull(f);
  }
  return static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// Newline-terminated lines in `p` so far (a line being written is not counted).
inline long complete_lines(const fs::path& p) {
  const std::string text = slurp(p);
  return static_cast<long>(std::count(text.begin(), text.end(), '\n'));
}

}  // namespace knitsim::test
