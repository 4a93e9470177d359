// Reliability where nobody had looked (docs/reliability.md): signals that act within a second
// at any size, a folder that holds one run, results checked against the model's own limits,
// charts refused up front or run to a status, and messages that name what is wrong. Each case
// failed before its fix.
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "models/drape_grid.hpp"
#include "models/knit_loops.hpp"
#include "solvers/integrator.hpp"
#include "solvers/symmetric_factor.hpp"
#include "src/base/files.hpp"
#include "src/cli/interrupt.hpp"
#include "src/core/stop_request.hpp"
#include "src/fit/targets.hpp"
#include "src/scene/scene.hpp"
#include "tests/cli_runner.hpp"

using namespace knitsim;
using namespace knitsim::test;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

int count_lines(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

nlohmann::json read_json(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }

// A folder a run left: nothing, or one whole run (manifest.json, no incomplete.txt).
bool consistent(const fs::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return true;
  std::string why;
  return fs::is_empty(dir, ec) || output_folder_complete(dir, why);
}

// 3.7 M particles, inside the documented cap: about a minute of set-up (issue 47).
const std::string kLargeDrape =
    "drape --scene four_corner --set model.natural_length=0.00026 --quiet --no-pictures";

}  // namespace

// ---- signals ----------------------------------------------------------------------------------

TEST_CASE("a second signal does not kill a run that stops everywhere; the flag reaches the loops",
          "[signals]") {
  {
    const InterruptScope scope;  // drape, knit, demo
    CHECK_FALSE(stop_requested());
    ::raise(SIGTERM);
    ::raise(SIGTERM);  // was SA_RESETHAND: this one killed the process
    CHECK(scope.signal() == SIGTERM);
    CHECK(scope.exit_code() == 143);
    CHECK(stop_requested());
  }
  CHECK_FALSE(stop_requested());  // cleared with the scope
  {
    const InterruptScope scope(InterruptScope::Reach::BetweenUnits);  // a fit's decades
    ::raise(SIGINT);
    CHECK(scope.flag()->load());
    CHECK_FALSE(stop_requested());  // the evaluations in flight are not cut short
  }
}

TEST_CASE("a stop request ends a run after its current step, and a factorisation in its loop",
          "[signals]") {
  const Scene scene = load_scene("four_corner", {"model.symmetry=none"});
  const DrapeGrid grid = build_drape_grid(scene.params);
  IntegratorOptions opt = scene.options;
  std::vector<double> x, v;
  g_stop_requested = true;
  const RunStats s = run_to_equilibrium(grid.network, "equilibrium", opt, x, v);
  // The block LDL^T sees the request at its first column: the factorisation fails.
  detail::SymmetricFactor factor(IntegratorOptions::Factorization::Block);
  Eigen::SparseMatrix<double> S(6, 6);  // two nodes' 3 x 3 blocks, positive definite
  for (int i = 0; i < 6; ++i)
    for (int j = 3 * (i / 3); j < 3 * (i / 3) + 3; ++j) S.insert(i, j) = i == j ? 4.0 : 1.0;
  S.makeCompressed();
  factor.analyze(S);
  const bool factored = factor.factorize(S);
  g_stop_requested = false;
  CHECK(s.status == RunStatus::Interrupted);
  CHECK(s.steps <= 1);
  CHECK_FALSE(factored);
  CHECK(factor.factorize(S));  // and works again once the request is gone
}

TEST_CASE("SIGTERM during a 3.7 M-particle drape's set-up ends it within 2 s", "[signals][large]") {
  TempDir tmp("reliability-sigterm");
  const fs::path out = tmp.path / "out";
  const pid_t pid = start_knitsim(kLargeDrape + " --out '" + out.string() + "'", tmp);
  const auto started = Clock::now();
  while (!knitsim_handles(pid, SIGTERM) && seconds_since(started) < 10)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  std::this_thread::sleep_for(std::chrono::seconds(3));  // building the grid and its reduction
  const auto signalled = Clock::now();
  ::kill(pid, SIGTERM);
  int st = 0;
  while (::waitpid(pid, &st, WNOHANG) == 0 && seconds_since(signalled) < 60)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const double latency = seconds_since(signalled);
  if (latency >= 60) ::kill(pid, SIGKILL), ::waitpid(pid, &st, 0);
  CAPTURE(latency);
  const std::string err = slurp(tmp.path / "background-stderr.txt");
  CAPTURE(err);
#ifdef KNITSIM_SANITIZED
  const double bound = 10.0;  // ASan's teardown of the set-up's memory (2.3 s measured, loaded)
#else
  const double bound = 2.0;
#endif
  CHECK(latency < bound);  // was 199 s: the request was read at the next residual check
  REQUIRE(WIFEXITED(st));
  CHECK(WEXITSTATUS(st) == 143);
  CHECK(err.find("interrupted by SIGTERM") != std::string::npos);
  CHECK(count_lines(err) == 1);
  CHECK(consistent(out));
}

TEST_CASE(
    "under GNU timeout (a signal to the program, then one to its group) the run still ends "
    "with its message",
    "[signals][large]") {
  TempDir tmp("reliability-timeout");
  const fs::path out = tmp.path / "out";
  const auto started = Clock::now();
  const std::string cmd = "timeout --preserve-status -s TERM 3 '" + std::string(KNITSIM_EXE) +
                          "' " + kLargeDrape + " --out '" + out.string() + "' 2>'" +
                          (tmp.path / "err.txt").string() + "' </dev/null";
  const int raw = std::system(cmd.c_str());
  const double wall = seconds_since(started);
  const std::string err = slurp(tmp.path / "err.txt");
  CAPTURE(wall, err);
  REQUIRE(WIFEXITED(raw));
  CHECK(WEXITSTATUS(raw) == 143);  // was killed by the second SIGTERM (SA_RESETHAND), silently
  CHECK(wall < 5.0);
  CHECK(err.find("interrupted by SIGTERM") != std::string::npos);
  CHECK(consistent(out));
}

// ---- one run per folder -----------------------------------------------------------------------

TEST_CASE("a rerun killed at any point of its writing leaves no mix of two runs", "[folder]") {
  TempDir tmp("reliability-folder");
  const fs::path out = tmp.path / "out";
  const std::string base =
      "drape --scene four_corner --quiet --no-pictures --out '" + out.string() + "'";
  REQUIRE(run_knitsim(base, tmp).status == 0);  // run A: k = 852
  CHECK_FALSE(fs::exists(out / kIncompleteMarker));
  const auto stiffness_of = [](const nlohmann::json& params) {
    return params.at("stiffness").get<double>();
  };
  int killed = 0;
  for (int k = 1; k <= 20; ++k) {
    CAPTURE(k);
    // Run B (k = 500) into the same folder, killed (SIGKILL) after its k-th file operation.
    const Run r = run_knitsim(base + " --set model.stiffness=500", tmp,
                              {{"KNITSIM_KILL_AFTER_WRITES", std::to_string(k)}});
    std::string why;
    if (r.status == 0) {  // k beyond its last write: a whole run B
      CHECK(output_folder_complete(out, why));
      CHECK(stiffness_of(read_json(out / "manifest.json")["options"]["params"]) == 500);
      break;
    }
    ++killed;
    if (!output_folder_complete(out, why)) {
      // Marked: --continue refuses it, in one line.
      const Run c = run_knitsim("drape --scene four_corner --quiet --continue '" + out.string() +
                                    "' --out '" + (tmp.path / "next").string() + "'",
                                tmp);
      CHECK(c.status == 2);
      CHECK(count_lines(c.err) == 1);
      CHECK(c.err.find(kIncompleteMarker) != std::string::npos);
      continue;
    }
    // Not marked: every file is of one run (A's, untouched, or B's, whole).
    const double k_manifest = stiffness_of(read_json(out / "manifest.json")["options"]["params"]);
    CHECK(stiffness_of(read_json(out / "summary.json")["params"]) == k_manifest);
    CHECK(read_json(out / "state.json")["model"]["model.stiffness"].get<double>() == k_manifest);
  }
  CHECK(killed >= 8);  // the marker, 7 files and removals, the manifest
}

TEST_CASE("a folder without its manifest is not continued; a whole one is", "[folder]") {
  TempDir tmp("reliability-continue");
  const fs::path out = tmp.path / "out";
  REQUIRE(run_knitsim("drape --scene four_corner --quiet --no-pictures --out '" + out.string() +
                          "' --max-steps 3 --integrator cvode-bdf",
                      tmp)
              .status == 3);
  fs::remove(out / "manifest.json");
  const Run r =
      run_knitsim("drape --scene four_corner --quiet --integrator cvode-bdf --continue '" +
                      out.string() + "' --out '" + (tmp.path / "b").string() + "'",
                  tmp);
  CHECK(r.status == 2);
  CHECK(count_lines(r.err) == 1);
  CHECK(r.err.find("manifest.json is missing") != std::string::npos);
  CHECK_FALSE(fs::exists(tmp.path / "b"));
}

// ---- results against the model's own limits ---------------------------------------------------

TEST_CASE("the limits of the drape model: strain past the elongation limit, a sag past the sheet",
          "[limits]") {
  DrapeParams p;                                            // 5 % limit, a 0.49 m model sheet
  CHECK(drape_limit_violation(p, 0.0024, 0.0129).empty());  // sample 1's equilibrium
  CHECK(drape_limit_violation(p, 0.0549, 0.1).empty());     // within the 10 % tolerance
  CHECK(drape_limit_violation(p, 0.0551, 0.1).find("elongation limit") != std::string::npos);
  CHECK(drape_limit_violation(p, 0.01, 0.6).find("larger than the sheet") != std::string::npos);
  CHECK(drape_limit_violation(p, std::nan(""), 0.1).find("not finite") != std::string::npos);
  p.elongation_limit = 0.0;  // no limit: strain alone is no violation
  CHECK(drape_limit_violation(p, 0.5, 0.1).empty());
}

TEST_CASE("an equilibrium far past the elongation limit is not reported as an equilibrium",
          "[limits]") {
  TempDir tmp("reliability-limits");
  const fs::path out = tmp.path / "out";
  // Was: equilibrium, exit 0, a 68.6 m sag and 93 790 % strain under a 5 % limit.
  const Run r = run_knitsim(
      "drape --scene four_corner --quiet --no-pictures --set "
      "model.stiffness=1e-6 --out '" +
          out.string() + "'",
      tmp);
  CHECK(r.status == 3);
  CHECK(count_lines(r.err) == 1);
  CHECK(r.err.find("outside the model's limits") != std::string::npos);
  const nlohmann::json s = read_json(out / "summary.json");
  CHECK(s["status"] == "outside_model_limits");
  CHECK(s["certificate"] == "stable_minimum");  // the solver's own stop did pass
  CHECK(s["model_limits"].get<std::string>().find("elongation limit") != std::string::npos);
  // Sample 1 is inside its limits: no flag.
  REQUIRE(run_knitsim(
              "drape --scene four_corner --quiet --no-pictures --out '" + out.string() + "'", tmp)
              .status == 0);
  CHECK_FALSE(read_json(out / "summary.json").contains("model_limits"));
}

TEST_CASE("a diverged drape reports no figures; a very light fabric is certified", "[limits]") {
  TempDir tmp("reliability-figures");
  const fs::path out = tmp.path / "out";
  // Was: diverged, with centre_sag_m 1398 m.
  const Run r = run_knitsim(
      "drape --scene four_corner --quiet --no-pictures --set "
      "model.stiffness=1e-320 --out '" +
          out.string() + "'",
      tmp);
  CHECK(r.status == 3);
  const nlohmann::json s = read_json(out / "summary.json");
  CHECK(s["status"] == "diverged");
  CHECK(s["centre_sag_m"].is_null());
  CHECK(s["max_strain"].is_null());
  // Was: time_limit at t_max = 1e7 s after 0.39 s, never certified (its residual's round-off
  // floor lies above the level where the stop was first tested).
  const Run light = run_knitsim(
      "drape --scene four_corner --quiet --no-pictures --set "
      "fabric.areal_density=1e-6 --out '" +
          out.string() + "'",
      tmp);
  CHECK(light.status == 0);
  CHECK(read_json(out / "summary.json")["status"] == "equilibrium");
}

// ---- charts refused up front ------------------------------------------------------------------

namespace {

// A chart file: `rows` top course first.
fs::path write_chart(const TempDir& tmp, const std::string& name,
                     const std::vector<std::string>& rows) {
  const fs::path p = tmp.path / name;
  std::ofstream out(p);
  for (const std::string& r : rows) out << r << "\n";
  return p;
}

}  // namespace

TEST_CASE(
    "charts whose yarns overlap at rest, or whose floats the contact cannot hold, are "
    "refused naming the row and the column",
    "[charts]") {
  TempDir tmp("reliability-charts");
  std::vector<std::string> stack = {"KKKKK"};
  for (int i = 0; i < 10; ++i) stack.push_back("KKTKK");  // tucks ten high in wale 3
  stack.push_back("KKKKK");
  std::vector<std::string> block = {"KKKKKK", "KKKKKK"};
  for (int i = 0; i < 10; ++i) block.push_back("KTTTTK");  // a 10-course block of tucks
  block.push_back("KKKKKK");
  const std::vector<std::string> floats = {"KKKKKKKKKKKK", "KMMMMMMMMMMK", "KKKKKKKKKKKK"};
  struct Case {
    std::string name;
    std::vector<std::string> rows;
    std::string says;
  };
  for (const Case& c :
       {Case{"stack.chart", stack, ", column 3: two stretches of the yarn of course"},
        Case{"block.chart", block, "inside the yarn contact's core"},
        Case{"float.chart", floats, "chart row 2, column 2: a float of more than 7 misses"}}) {
    CAPTURE(c.name);
    const fs::path chart = write_chart(tmp, c.name, c.rows);
    // Was: solver_failure at t = 0 (CV_FIRST_RHSFUNC_ERR), or at residual 4.5e12.
    const auto t0 = Clock::now();
    const Run r = run_knitsim(
        "knit --quiet --chart '" + chart.string() + "' --out '" + (tmp.path / "out").string() + "'",
        tmp);
    CHECK(seconds_since(t0) < 5.0);
    CHECK(r.status == 2);
    CHECK(count_lines(r.err) == 1);
    CHECK(r.err.find(c.says) != std::string::npos);
    CHECK(r.err.find("knit.contact = 0") != std::string::npos);
    CHECK_FALSE(fs::exists(tmp.path / "out"));
  }
  // Without contact the float is the model's to hold.
  KnitParams no_contact;
  no_contact.contact_ratio = 0.0;
  CHECK_NOTHROW(
      build_knit(parse_knit_chart("KKKKKKKKKKKK\nKMMMMMMMMMMK\nKKKKKKKKKKKK\n"), no_contact));
}

// ---- messages ---------------------------------------------------------------------------------

TEST_CASE("binary bytes in state.json name the file as not JSON", "[messages]") {
  TempDir tmp("reliability-binary");
  const fs::path dir = tmp.path / "run";
  fs::create_directories(dir);
  std::ofstream(dir / "state.json", std::ios::binary) << std::string("\0\x01\x02PNG", 6);
  std::ofstream(dir / "manifest.json") << "{}\n";
  const Run r = run_knitsim("drape --quiet --continue '" + dir.string() + "'", tmp);
  CHECK(r.status == 2);
  CHECK(count_lines(r.err) == 1);
  // Was: "unexpected end of input" at column 1.
  CHECK(r.err.find("state.json: not a JSON file: byte 1 is 0x00") != std::string::npos);
}

TEST_CASE("a FIFO given as an input file is refused at once, never read", "[messages]") {
  TempDir tmp("reliability-fifo");
  const fs::path fifo = tmp.path / "pipe";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const fs::path run_dir = tmp.path / "run";
  fs::create_directories(run_dir);
  REQUIRE(::mkfifo((run_dir / "state.json").c_str(), 0600) == 0);
  std::ofstream(run_dir / "manifest.json") << "{}\n";
  for (const std::string& args :
       {"knit --chart '" + fifo.string() + "'", "drape --scene '" + fifo.string() + "'",
        "drape --target '" + fifo.string() + "'", "drape --continue '" + run_dir.string() + "'"}) {
    CAPTURE(args);
    const auto t0 = Clock::now();
    // Was: --chart blocked forever.
    const Run r = run_knitsim(args + " --quiet --out '" + (tmp.path / "out").string() + "'", tmp);
    CHECK(seconds_since(t0) < 5.0);
    CHECK(r.status == 2);
    CHECK(count_lines(r.err) == 1);
    CHECK(r.err.find("FIFO") != std::string::npos);
    CHECK_FALSE(fs::exists(tmp.path / "out"));
  }
}

TEST_CASE("a failed start leaves nothing behind, not even an empty out/", "[messages]") {
  TempDir tmp("reliability-nothing");
  const std::string name(300, 'n');
  // No --out: the default out/drape-<name>-<stamp> is too long a file name.
  const std::string cmd = "cd '" + tmp.path.string() + "' && '" + KNITSIM_EXE +
                          "' drape --quiet --set scene.name=" + name + " >/dev/null 2>err.txt";
  const int raw = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(raw));
  CHECK(WEXITSTATUS(raw) == 2);
  CHECK(count_lines(slurp(tmp.path / "err.txt")) == 1);
  CHECK_FALSE(fs::exists(tmp.path / "out"));  // was: an empty out/
}

TEST_CASE("the size caps the docs give are the code's", "[messages]") {
  // docs/reliability.md and docs/commands.md: "(1 MiB scene, 16 MiB chart, 64 MiB target)".
  const std::regex caps(R"(\((\d+) MiB scene, (\d+) MiB chart, (\d+) MiB target\))");
  TempDir tmp("reliability-caps");
  for (const char* page : {"reliability.md", "commands.md"}) {
    CAPTURE(page);
    const std::string text = slurp(fs::path(KNITSIM_DOCS_DIR) / page);
    std::smatch m;
    REQUIRE(std::regex_search(text, m, caps));
    const std::size_t mib = std::size_t{1} << 20;
    CHECK(std::stoul(m[1]) * mib == kMaxSceneFileBytes);
    CHECK(std::stoul(m[3]) * mib == kMaxTargetFileBytes);
    // The chart's cap is the knit command's own: its message names it.
    const Run r = run_knitsim("knit --chart /dev/zero --quiet", tmp);
    CHECK(r.err.find("larger than " + std::to_string(std::stoul(m[2]) * mib) + " bytes") !=
          std::string::npos);
  }
}
