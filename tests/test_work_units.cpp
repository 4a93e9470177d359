// run_work_units (src/parallel/work_units.hpp): results in unit order (on threads too), the
// checkpoint's lines, resume (completed units are not run again, a half-written last line is
// dropped, other settings or unknown units are refused), exact doubles through the
// checkpoint, and -- when mpirun was
// found at configure time -- 2 MPI ranks giving the same results as one process ([mpi], hidden:
// ctest runs it as test_work_units_mpi, label mpi).
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "src/parallel/work_units.hpp"

namespace {

namespace fs = std::filesystem;
using knitsim::run_work_units;
using knitsim::WorkUnit;
using knitsim::WorkUnitOptions;
using nlohmann::json;

fs::path temp_file(const std::string& name) {
  return fs::temp_directory_path() /
         ("knitsim-test-work-units-" + std::to_string(::getpid()) + "-" + name);
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// The first `n` lines of `text`, each with its newline.
std::string first_lines(const std::string& text, int n) {
  std::size_t end = 0;
  for (int k = 0; k < n; ++k) end = text.find('\n', end) + 1;
  return text.substr(0, end);
}

// Unit i's result: doubles that need all 17 digits, a subnormal, an integer, a string.
json toy_result(int i) {
  return {{"i", i},
          {"third", (i + 1) / 3.0},
          {"tiny", std::ldexp(1.0 + i, -1060)},
          {"sum", 0.1 * i + 0.2},
          {"name", "unit " + std::to_string(i)}};
}

// n toy units "u0".."u<n-1>", counting their executions in `runs` (one slot per unit).
std::vector<WorkUnit> toy_units(int n, std::vector<int>& runs) {
  runs.assign(n, 0);
  std::vector<WorkUnit> units;
  for (int i = 0; i < n; ++i)
    units.push_back({"u" + std::to_string(i), [i, &runs] {
                       ++runs[i];
                       return toy_result(i);
                     }});
  return units;
}

WorkUnitOptions with_checkpoint(const fs::path& path, bool resume, json config = {{"seed", 1}}) {
  WorkUnitOptions o;
  o.checkpoint = path.string();
  o.resume = resume;
  o.config = std::move(config);
  return o;
}

int total(const std::vector<int>& runs) {
  int sum = 0;
  for (int r : runs) sum += r;
  return sum;
}

}  // namespace

TEST_CASE("every unit runs once; results come back in unit order", "[work_units]") {
  std::vector<int> runs;
  const auto units = toy_units(7, runs);
  const std::vector<json> results = run_work_units(units, WorkUnitOptions{});
  REQUIRE(results.size() == 7);
  for (int i = 0; i < 7; ++i) {
    CHECK(results[i] == toy_result(i));
    CHECK(runs[i] == 1);
  }
}

TEST_CASE("the checkpoint: the config, then one {key, result} line per unit", "[work_units]") {
  const fs::path path = temp_file("content.jsonl");
  std::vector<int> runs;
  const auto units = toy_units(5, runs);
  run_work_units(units, with_checkpoint(path, false));
  const std::vector<std::string> lines = lines_of(slurp(path));
  REQUIRE(lines.size() == 1 + 5);
  CHECK(json::parse(lines[0]) == json{{"config", {{"seed", 1}}}});
  for (int i = 0; i < 5; ++i) {
    const json line = json::parse(lines[1 + i]);  // one process: completion order = unit order
    CHECK(line.at("key") == "u" + std::to_string(i));
    CHECK(line.at("result") == toy_result(i));
    // Bit for bit: the doubles read back are the ones computed.
    CHECK(line.at("result").at("third").get<double>() == (i + 1) / 3.0);
    CHECK(line.at("result").at("tiny").get<double>() == std::ldexp(1.0 + i, -1060));
  }
  // A fresh run (no resume) starts the file over.
  run_work_units(units, with_checkpoint(path, false));
  CHECK(lines_of(slurp(path)).size() == 1 + 5);
  fs::remove(path);
}

TEST_CASE("units on threads: each runs once; results and checkpoint lines in unit order",
          "[work_units]") {
  const fs::path path = temp_file("threads.jsonl");
  const int n = 9;
  std::vector<int> runs(n, 0);
  std::vector<WorkUnit> units;
  for (int i = 0; i < n; ++i)  // the later units finish first
    units.push_back({"u" + std::to_string(i), [i, &runs] {
                       std::this_thread::sleep_for(std::chrono::milliseconds(4 * (n - i)));
                       ++runs[i];
                       return toy_result(i);
                     }});
  WorkUnitOptions o = with_checkpoint(path, false);
  o.threads = 3;
  const std::vector<json> results = run_work_units(units, o);
  REQUIRE(results.size() == static_cast<size_t>(n));
  const std::vector<std::string> lines = lines_of(slurp(path));
  REQUIRE(lines.size() == static_cast<size_t>(1 + n));
  for (int i = 0; i < n; ++i) {
    CHECK(runs[i] == 1);
    CHECK(results[i] == toy_result(i));
    CHECK(json::parse(lines[1 + i]).at("key") == "u" + std::to_string(i));
  }
  fs::remove(path);
}

TEST_CASE("resume runs only the units the checkpoint lacks", "[work_units]") {
  const fs::path path = temp_file("resume.jsonl");
  std::vector<int> runs;
  const auto units = toy_units(8, runs);
  const std::vector<json> full = run_work_units(units, with_checkpoint(path, false));
  const std::string text = slurp(path);

  SECTION("an interruption after 3 units") {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << first_lines(text, 1 + 3);
  }
  SECTION("killed while writing the 4th unit: a truncated last line is ignored") {
    const std::string fourth = lines_of(text)[4];
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        << first_lines(text, 1 + 3) << fourth.substr(0, fourth.size() / 2);
  }
  runs.assign(8, 0);
  const std::vector<json> resumed = run_work_units(units, with_checkpoint(path, true));
  CHECK(resumed == full);
  for (int i = 0; i < 8; ++i) CHECK(runs[i] == (i < 3 ? 0 : 1));
  // The checkpoint is whole again: config + 8 units, every line JSON, each key once.
  const std::vector<std::string> lines = lines_of(slurp(path));
  REQUIRE(lines.size() == 1 + 8);
  std::vector<int> seen(8, 0);
  for (std::size_t k = 1; k < lines.size(); ++k)
    ++seen[std::stoi(json::parse(lines[k]).at("key").get<std::string>().substr(1))];
  CHECK(seen == std::vector<int>(8, 1));

  // Resuming a finished run runs nothing and returns the same results.
  runs.assign(8, 0);
  CHECK(run_work_units(units, with_checkpoint(path, true)) == full);
  CHECK(total(runs) == 0);
  fs::remove(path);
}

TEST_CASE("resume without a checkpoint, or with only a half-written config line, starts afresh",
          "[work_units]") {
  const fs::path path = temp_file("fresh.jsonl");
  std::vector<int> runs;
  const auto units = toy_units(3, runs);
  fs::remove(path);
  CHECK(run_work_units(units, with_checkpoint(path, true)).size() == 3);
  CHECK(total(runs) == 3);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << "{\"conf";
  runs.assign(3, 0);
  CHECK(run_work_units(units, with_checkpoint(path, true)).size() == 3);
  CHECK(total(runs) == 3);
  CHECK(lines_of(slurp(path)).size() == 1 + 3);
  fs::remove(path);
}

TEST_CASE("a checkpoint of other settings or other units is refused before any unit runs",
          "[work_units]") {
  const fs::path path = temp_file("refuse.jsonl");
  std::vector<int> runs;
  const auto units = toy_units(4, runs);
  run_work_units(units, with_checkpoint(path, false, {{"preset", "quick"}, {"seed", 1}}));
  const std::string text = slurp(path);
  runs.assign(4, 0);

  std::vector<int> fewer_runs;
  auto resume_with = [&](int n, int seed) {
    return run_work_units(toy_units(n, n == 4 ? runs : fewer_runs),
                          with_checkpoint(path, true, {{"preset", "quick"}, {"seed", seed}}));
  };
  CHECK_THROWS_AS(resume_with(4, 2), std::invalid_argument);
  CHECK_THROWS_WITH(resume_with(4, 2),
                    Catch::Contains("other settings") && Catch::Contains("difference: /seed"));
  CHECK_THROWS_AS(resume_with(3, 1), std::invalid_argument);
  CHECK_THROWS_WITH(resume_with(3, 1), Catch::Contains("'u3' is not one of this run's units"));
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      << first_lines(text, 2) << "not json\n"
      << first_lines(text, 4).substr(first_lines(text, 3).size());
  CHECK_THROWS_AS(resume_with(4, 1), std::invalid_argument);
  CHECK_THROWS_WITH(resume_with(4, 1), Catch::Contains("line 3: not a JSON object"));
  CHECK(total(runs) == 0);
  CHECK(total(fewer_runs) == 0);
  CHECK(slurp(path).find("not json") != std::string::npos);  // a refused file is left alone
  fs::remove(path);
}

TEST_CASE("a unit that throws is an error result, kept on resume; duplicate keys are refused",
          "[work_units]") {
  const fs::path path = temp_file("errors.jsonl");
  int runs = 0;
  std::vector<WorkUnit> units = {{"good", [&runs] { return json(++runs); }},
                                 {"bad", [&runs]() -> json {
                                    ++runs;
                                    throw std::runtime_error("no equilibrium");
                                  }}};
  const std::vector<json> results = run_work_units(units, with_checkpoint(path, false));
  CHECK(results[0] == 1);
  CHECK(results[1] == json{{"error", "no equilibrium"}});
  CHECK(run_work_units(units, with_checkpoint(path, true)) == results);
  CHECK(runs == 2);

  units.push_back({"good", [] { return json(0); }});
  CHECK_THROWS_AS(run_work_units(units, WorkUnitOptions{}), std::invalid_argument);
  CHECK_THROWS_WITH(run_work_units(units, WorkUnitOptions{}), "work unit key 'good' appears twice");
  fs::remove(path);
}

TEST_CASE("results are what the checkpoint returns: NaN is null on every path", "[work_units]") {
  const fs::path path = temp_file("nan.jsonl");
  const std::vector<WorkUnit> units = {
      {"nan", [] { return json(std::numeric_limits<double>::quiet_NaN()); }}};
  const std::vector<json> first = run_work_units(units, with_checkpoint(path, false));
  CHECK(first[0].is_null());
  CHECK(run_work_units(units, with_checkpoint(path, true)) == first);
  fs::remove(path);
}

#ifdef KNITSIM_MPIEXEC
namespace {

struct Probe {
  int status = -1;
  std::string out;
};

// Runs tests/work_units_probe (N units, checkpoint, resume flag, log folder), under
// `mpirun -np 2` when `ranks` = 2.
Probe run_probe(int ranks, int n, const fs::path& checkpoint, bool resume, const fs::path& logs) {
  fs::create_directories(logs);
  std::string cmd;
  if (ranks > 1)
    cmd = std::string("'") + KNITSIM_MPIEXEC + "' -np " + std::to_string(ranks) +
          " --oversubscribe" + (::geteuid() == 0 ? " --allow-run-as-root" : "") + " ";
  const fs::path out = logs / "stdout.txt";
  cmd += std::string("'") + KNITSIM_WORK_UNITS_PROBE + "' " + std::to_string(n) + " '" +
         checkpoint.string() + "' " + (resume ? "1" : "0") + " '" + logs.string() + "' >'" +
         out.string() + "' 2>'" + (logs / "stderr.txt").string() + "' </dev/null";
  const int raw = std::system(cmd.c_str());
  Probe p;
  p.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  p.out = slurp(out);
  return p;
}

// The unit indices rank `rank` ran, from its log.
std::vector<int> ran_on(const fs::path& logs, int rank) {
  std::vector<int> ran;
  for (const std::string& l : lines_of(slurp(logs / ("rank" + std::to_string(rank) + ".txt"))))
    ran.push_back(std::stoi(l));
  return ran;
}

}  // namespace

TEST_CASE("mpirun -np 2: units split i % 2, rank 0 returns what one process does", "[.][mpi]") {
  const fs::path dir = temp_file("mpi");
  fs::remove_all(dir);
  const Probe one = run_probe(1, 9, dir / "one.jsonl", false, dir / "one");
  REQUIRE(one.status == 0);
  REQUIRE(json::parse(one.out).size() == 9);
  CHECK(ran_on(dir / "one", 0) == std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8});

  const Probe two = run_probe(2, 9, dir / "two.jsonl", false, dir / "two");
  INFO(slurp(dir / "two" / "stderr.txt"));
  REQUIRE(two.status == 0);
  CHECK(two.out == one.out);  // the same text: every double bit for bit
  CHECK(ran_on(dir / "two", 0) == std::vector<int>{0, 2, 4, 6, 8});
  CHECK(ran_on(dir / "two", 1) == std::vector<int>{1, 3, 5, 7});
  std::vector<std::string> lines = lines_of(slurp(dir / "two.jsonl"));
  CHECK(lines.size() == 1 + 9);  // rank 0 wrote every unit, whichever rank ran it

  // Resume under MPI after 4 units: the 5 left are split over the ranks (pending j % 2).
  const std::string head = first_lines(slurp(dir / "two.jsonl"), 1 + 4);
  std::ofstream(dir / "two.jsonl", std::ios::binary | std::ios::trunc) << head;
  std::vector<int> done;
  for (int k = 1; k <= 4; ++k)
    done.push_back(std::stoi(json::parse(lines[k]).at("key").get<std::string>().substr(1)));
  const Probe resumed = run_probe(2, 9, dir / "two.jsonl", true, dir / "resumed");
  REQUIRE(resumed.status == 0);
  CHECK(resumed.out == one.out);
  const std::vector<int> r0 = ran_on(dir / "resumed", 0), r1 = ran_on(dir / "resumed", 1);
  CHECK(r0.size() == 3);
  CHECK(r1.size() == 2);
  for (int i : done) {
    CHECK(std::count(r0.begin(), r0.end(), i) == 0);
    CHECK(std::count(r1.begin(), r1.end(), i) == 0);
  }
  CHECK(lines_of(slurp(dir / "two.jsonl")).size() == 1 + 9);
  fs::remove_all(dir);
}

TEST_CASE("mpirun -np 2 knitsim repro writes the single-process table4.csv", "[.][mpi]") {
  const fs::path dir = temp_file("mpi-repro");
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string args =
      " repro table4 --samples 1 --sets twin --runs 4 --decades 1 --countries 4 "
      "--imperialists 2 --no-pictures --quiet --out '";
  const auto run = [&](const std::string& launcher, const fs::path& out) {
    const std::string cmd = launcher + "'" + KNITSIM_EXE + "'" + args + out.string() + "' >'" +
                            (dir / "log.txt").string() + "' 2>&1 </dev/null";
    const int raw = std::system(cmd.c_str());
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  };
  REQUIRE(run("", dir / "one") == 0);
  const int two = run(std::string("'") + KNITSIM_MPIEXEC + "' -np 2 --oversubscribe" +
                          (::geteuid() == 0 ? " --allow-run-as-root " : " "),
                      dir / "two");
  INFO(slurp(dir / "log.txt"));
  REQUIRE(two == 0);
  CHECK(slurp(dir / "two" / "table4.csv") == slurp(dir / "one" / "table4.csv"));
  CHECK(lines_of(slurp(dir / "two" / "fits.jsonl")).size() == 1 + 4);
  // Again into the same folder without --resume: refused by every rank alike (rank 0 decides;
  // a per-rank check hung, rank 1 finding the checkpoint rank 0 had just begun).
  const std::string checkpoint = slurp(dir / "two" / "fits.jsonl");
  CHECK(run(std::string("'") + KNITSIM_MPIEXEC + "' -np 2 --oversubscribe" +
                (::geteuid() == 0 ? " --allow-run-as-root " : " "),
            dir / "two") == 2);
  CHECK(slurp(dir / "two" / "fits.jsonl") == checkpoint);
  fs::remove_all(dir);
}
#endif
