// Running the built `knitsim` binary from tests: a temporary folder and a runner that captures
// exit status, stdout and stderr. KNITSIM_EXE (the binary's path) is defined by the build.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
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

// Runs `knitsim <args>` (args already shell-quoted) with stdout/stderr captured in `tmp`.
inline Run run_knitsim(const std::string& args, const TempDir& tmp) {
  const fs::path out = tmp.path / "stdout.txt", err = tmp.path / "stderr.txt";
  const std::string cmd = std::string("'") + KNITSIM_EXE + "' " + args + " >'" + out.string() +
                          "' 2>'" + err.string() + "' </dev/null";
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

}  // namespace knitsim::test
