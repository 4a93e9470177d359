// Validation at the boundary (docs/reliability.md: non-zero with one clear line naming the bad
// input; never a crash or a hang on bad input): oversized and endless input files, NaN/inf and
// unknown keys where knit --set and the target reader missed them, and an unwritable --out for
// every command that writes. Each case states the message it expects; each failed before its fix
// (noted per case) or pins down behaviour the fuzzers and the CLI rely on.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "src/base/files.hpp"
#include "src/fit/targets.hpp"
#include "src/scene/scene.hpp"
#include "tests/cli_runner.hpp"

using namespace knitsim;
using namespace knitsim::test;

namespace {

int count_lines(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

// Runs knitsim and expects the bad-input contract: exit 2, one stderr line containing `names`,
// nothing on stdout.
void expect_bad_input(const std::string& args, const std::string& names, const TempDir& tmp) {
  CAPTURE(args);
  const Run r = run_knitsim(args, tmp);
  CHECK(r.status == 2);
  CHECK(count_lines(r.err) == 1);
  CHECK(r.err.find(names) != std::string::npos);
  CHECK(r.out.empty());
}

}  // namespace

TEST_CASE("input files over their size cap are refused unread, endless ones too") {
  TempDir tmp("validation-size");
  // A scene file one byte over the cap, all of it a valid TOML comment: was accepted.
  const fs::path big = tmp.path / "big.toml";
  {
    std::ofstream out(big);
    out << "#" << std::string(kMaxSceneFileBytes, 'x');
  }
  CHECK(error_of([&] { load_scene(big.string()); }) ==
        "scene: cannot read " + big.string() + ": larger than " +
            std::to_string(kMaxSceneFileBytes) + " bytes, the limit for this input");
  // /dev/zero never ends: before the cap the reader filled memory until killed.
  expect_bad_input("drape --scene /dev/zero --out '" + (tmp.path / "o1").string() + "'",
                   "scene: cannot read /dev/zero: larger than", tmp);
  expect_bad_input("knit --chart /dev/zero --out '" + (tmp.path / "o2").string() + "'",
                   "--chart /dev/zero: cannot read the file: larger than", tmp);
  expect_bad_input("drape --target /dev/zero --out '" + (tmp.path / "o3").string() + "'",
                   "/dev/zero: cannot open target file: larger than", tmp);
  for (const char* o : {"o1", "o2", "o3"}) CHECK(!fs::exists(tmp.path / o));
}

TEST_CASE("a drape grid over the particle cap is refused before allocating") {
  // 1e4 x 1e4 particles would need ~10 GB: the message comes at once, naming the key.
  CHECK(error_of([] { load_scene("four_corner", {"model.natural_length=5e-5"}); }) ==
        "model.natural_length = 5e-05: gives a 10001 x 10001 grid, over the cap of 4000000 "
        "particles");
}

TEST_CASE("knit --set: messages name the keys the user types, nearest key suggested") {
  TempDir tmp("validation-knit");
  const fs::path chart = tmp.path / "c.chart";
  std::ofstream(chart) << "KKK\nKTK\nKKK\n";
  const std::string base =
      "knit --chart '" + chart.string() + "' --out '" + (tmp.path / "out").string() + "' ";
  // Before: "--set knit.dampng=1: unknown key; accepted keys: ..." (no suggestion).
  expect_bad_input(base + "--set knit.dampng=1",
                   "knit.dampng: unknown key; did you mean knit.damping?", tmp);
  // Before: "model.loop_radius = nan: ..." although the user typed knit.loop_radius.
  expect_bad_input(base + "--set knit.loop_radius=nan",
                   "knit.loop_radius = nan: must be a number > 0 m", tmp);
  expect_bad_input(base + "--set knit.stabiliser=inf",
                   "knit.stabiliser = inf: must be a number in [0, 1]", tmp);
  expect_bad_input(base + "--set knit.areal_density=-1",
                   "knit.areal_density = -1: must be > 0 g/m^2", tmp);
  // Before: "t_max = inf: must be > 0 s" and "rtol = nan: ..." (struct field names).
  expect_bad_input(base + "--set run.t_max=inf",
                   "run.t_max = inf: must be a number in [1e-9, 1e15] s", tmp);
  expect_bad_input(base + "--set run.position_tol=1",
                   "run.position_tol = 1: must be in (0, 1e-2] m", tmp);
  expect_bad_input(base + "--rtol nan", "--rtol = nan: must be in (0, 1)", tmp);
  expect_bad_input(base + "--eps-lin 1.00000001", "--eps-lin = 1.00000001: must be in (0, 1]", tmp);
  // Values as typed (printed as a double, 100.0000001 was "100", which looks in range); a key
  // given twice by --set is refused; an empty key says so.
  expect_bad_input(base + "--set knit.contact=100.0000001",
                   "knit.contact = 100.0000001: must be in [0, 100]", tmp);
  expect_bad_input(base + "--set knit.contact=-1 --set knit.contact=5",
                   "--set knit.contact: given twice (-1, then 5); give each key once", tmp);
  expect_bad_input(base + "--set =5",
                   "--set =5: the key is empty; expected key=value, e.g. knit.contact=0", tmp);
  CHECK(!fs::exists(tmp.path / "out"));
}

TEST_CASE("drape: NaN and inf in --set, scene files and flags name the key and the range") {
  TempDir tmp("validation-drape");
  const std::string out = " --out '" + (tmp.path / "out").string() + "'";
  expect_bad_input("drape --set fabric.width=inf" + out,
                   "fabric.width = inf: must be a number > 0 m", tmp);
  expect_bad_input("drape --set pins.span=nan" + out, "pins.span = nan: must be a number in (0, 1]",
                   tmp);
  expect_bad_input("drape --rtol inf" + out, "--rtol = inf: must be in (0, 1)", tmp);
  // A flag's value as typed too (printed as a double, 1.0000001 was "1").
  expect_bad_input("drape --rtol 1.0000001" + out, "--rtol = 1.0000001: must be in (0, 1)", tmp);
  expect_bad_input("drape --set model.stiffness=-1 --set model.stiffness=900" + out,
                   "--set model.stiffness: given twice (-1, then 900); give each key once", tmp);
  // An infinite wall-clock cap would be no cap at all (0 is the way to say so).
  expect_bad_input("drape --max-wall inf" + out,
                   "--max-wall = inf: must be >= 0 s and finite (0 = no cap)", tmp);
  const fs::path scene = tmp.path / "s.toml";
  std::ofstream(scene) << "[model]\nstiffness = inf\n";
  expect_bad_input("drape --scene '" + scene.string() + "'" + out,
                   "model.stiffness = inf: must be a number > 0 N/m", tmp);
  // Masses would overflow (a sheet of 2 L0 per side): refused by the grid rule, not later by
  // the spring network's "particle masses must be > 0 kg".
  expect_bad_input("drape --set model.natural_length=1e300" + out,
                   "model.natural_length = 1e300: must be <= fabric.width / 1.5", tmp);
  // The block-Jacobi preconditioner needs x, y, z of every particle: refused on reductions
  // (the quarter's 93 unknowns are a multiple of 3 and used to pass, misaligned).
  expect_bad_input(
      "drape --integrator cvode-bdf-gmres --gmres-preconditioner block-jacobi --set "
      "model.symmetry=quarter" +
          out,
      "--gmres-preconditioner block-jacobi: needs every particle's x, y, z", tmp);
  // fit's LM options are named by their flags.
  const fs::path target = fs::path(KNITSIM_FUZZ_CORPUS) / "target" / "points_four_corner.csv";
  expect_bad_input("fit --scene four_corner --optimizer lm --lm-starts 0 --target '" +
                       target.string() + "'" + out,
                   "--lm-starts = 0: must be >= 1", tmp);
  CHECK(!fs::exists(tmp.path / "out"));
}

TEST_CASE("seeds, dimensions, countries and photos: refused outside their ranges, not wrapped") {
  // Before: CLI11 read --seed -1 as 2^64 - 1 and 2^64 as 2^64 - 1, silently (a run that could
  // not be repeated from what the user typed); --dim 2000000000 ended in std::bad_alloc after
  // trying to allocate, and --countries and --photos had no upper bound.
  TempDir tmp("validation-ranges");
  const std::string out = " --out '" + (tmp.path / "out").string() + "'";
  const std::string opt = "optimize --problem sphere --dim 2 --decades 1";
  expect_bad_input(opt + " --seed -1",
                   "--seed: must be a decimal integer in 0..18446744073709551615", tmp);
  expect_bad_input(opt + " --seed 18446744073709551616", "--seed: must be a decimal integer", tmp);
  expect_bad_input(opt + " --seed 0x10", "--seed: must be a decimal integer", tmp);
  expect_bad_input("targets --seed 4294967296" + out,
                   "--seed: must be a decimal integer in 0..4294967295", tmp);
  expect_bad_input("repro table4 --seed -5" + out, "--seed: must be a decimal integer", tmp);
  expect_bad_input("optimize --problem sphere --dim 2000000000",
                   "--dim = 2000000000: must be in 1..10000", tmp);
  expect_bad_input("optimize --problem sphere --dim 2 --countries 20000",
                   "--countries = 20000: must be > imperialists (2) and <= 10000", tmp);
  expect_bad_input("targets --photos 100000" + out, "--photos = 100000: must be in 1..10000", tmp);
  CHECK(!fs::exists(tmp.path / "out"));
  // The largest values are accepted, and the seed is the one typed.
  const Run r = run_knitsim(opt + " --seed 18446744073709551615", tmp);
  CHECK(r.status == 0);
  CHECK(r.out.find("seed 18446744073709551615,") != std::string::npos);
}

TEST_CASE("every flag of the fitting commands' rows is refused under its flag, with its range") {
  // The ICA, LM and synthetic-target flags are rows of the parameter table: a value out of range
  // is one line naming the flag (not the struct's field: revolution_rate, lm.starts_per_bracket,
  // noise_mm) with the range `knitsim list keys` shows, exit 2, nothing written.
  TempDir tmp("validation-fit-rows");
  const std::string out = " --out '" + (tmp.path / "out").string() + "'";
  const fs::path target = fs::path(KNITSIM_FUZZ_CORPUS) / "target" / "points_four_corner.csv";
  const Table keys = scene_key_table();
  int checked = 0;
  for (const Key& key : key_table()) {
    if (key.model != KeyModel::Fit || !key.probe_range) continue;
    std::string range;
    for (const auto& row : keys.rows)
      if (row[0] == key.flag) range = row[4];
    REQUIRE(!range.empty());
    const std::string command =
        key.flag.rfind("--lm-", 0) == 0
            ? "fit --scene four_corner --optimizer lm --target '" + target.string() + "'" + out
        : key.flag == "--noise-mm" || key.flag == "--photos" ? "targets" + out
                                                              : "optimize --problem sphere --dim 2";
    const Run r = run_knitsim(command + " " + key.flag + "=-1", tmp);
    CAPTURE(key.flag);
    CHECK(r.status == 2);
    CHECK(r.err == "knitsim: error: " + key.flag + " = -1: must be " + range + "\n");
    CHECK(r.out.empty());
    ++checked;
  }
  CHECK(checked == 13);  // 8 ICA flags, 3 LM, 2 of the targets
  CHECK(!fs::exists(tmp.path / "out"));
}

TEST_CASE("target CSV: a number with trailing bytes after a NUL is not a number") {
  // Before: strtod stopped at the NUL and the row was read as 0.04.
  const std::string csv =
      std::string("scene,edge,kind,a,b\nfour_corner,top,point,0.5,0.04") + '\0' + "junk\n";
  CHECK(error_of([&] { parse_target_csv(csv, "t.csv"); }).rfind("t.csv:2: field b = '0.04", 0) ==
        0);
}

TEST_CASE("an unwritable --out fails before any work, for every command that writes") {
  TempDir tmp("validation-out");
  const fs::path file = tmp.path / "a-file";
  std::ofstream(file) << "not a folder\n";
  const fs::path target = fs::path(KNITSIM_FUZZ_CORPUS) / "target" / "points_four_corner.csv";
  const fs::path chart = tmp.path / "c.chart";
  std::ofstream(chart) << "KKK\nKTK\nKKK\n";
  const fs::path responses = tmp.path / "r.csv";
  {
    std::ofstream out(responses);
    for (int run = 1; run <= 27; ++run) out << run << "," << run + 0.5 << "\n";
  }
  const std::vector<std::string> commands = {
      "drape --set model.natural_length=0.1",
      "knit --chart '" + chart.string() + "'",
      "fit --scene four_corner --set model.natural_length=0.1 --target '" + target.string() +
          "' --decades 1 --countries 4 --imperialists 1",
      "taguchi --responses '" + responses.string() + "'",
      "demo",
  };
  // No run started: expect_bad_input requires an empty stdout, and the runs print as they go
  // (fit its settings line before the first drape, demo a line per run). (A wall-clock bound
  // stood here; it proved less and could break under a sanitizer on a loaded machine.)
  for (const fs::path& bad : {fs::path("/proc/knitsim-out"), file / "sub"})
    for (const std::string& c : commands) {
      expect_bad_input(c + " --out '" + bad.string() + "'", "--out " + bad.string(), tmp);
      CHECK(!fs::exists(bad));
    }
}

TEST_CASE("a reused --out: another command's results and checkpoints are kept, stale files go") {
  TempDir tmp("validation-reuse");
  const fs::path target = fs::path(KNITSIM_FUZZ_CORPUS) / "target" / "points_four_corner.csv";
  const std::string small = " --set model.natural_length=0.1";
  const std::string fit = "fit --scene four_corner" + small + " --target '" + target.string() +
                          "' --decades 1 --countries 4 --imperialists 1 --quiet";
  // A fit's folder given to drape: refused, the fit's files untouched (drape used to replace
  // its summary.json and manifest.json).
  const fs::path fitted = tmp.path / "fitted";
  REQUIRE(run_knitsim(fit + " --out '" + fitted.string() + "'", tmp).status == 0);
  const std::string summary = slurp(fitted / "summary.json"),
                    manifest = slurp(fitted / "manifest.json");
  CHECK(manifest.find("\"command\": \"fit\"") != std::string::npos);
  expect_bad_input("drape" + small + " --out '" + fitted.string() + "'",
                   "--out " + fitted.string() + ": holds the results of `knitsim fit`", tmp);
  CHECK(slurp(fitted / "summary.json") == summary);
  CHECK(slurp(fitted / "manifest.json") == manifest);

  // The same fit again without --resume: refused, the checkpoint kept (it used to be
  // replaced); with --resume it goes on.
  const std::string checkpoint = slurp(fitted / "ica_checkpoint.json");
  expect_bad_input(fit + " --out '" + fitted.string() + "'",
                   "holds the checkpoint ica_checkpoint.json of an earlier run; add --resume", tmp);
  CHECK(slurp(fitted / "ica_checkpoint.json") == checkpoint);
  CHECK(run_knitsim(fit + " --resume --out '" + fitted.string() + "'", tmp).status == 0);

  // repro: its checkpoint of fits, likewise (checked before any target is made or fit run).
  const fs::path repro = tmp.path / "repro";
  fs::create_directories(repro);
  std::ofstream(repro / "fits.jsonl") << "{\"config\": {}}\n";
  expect_bad_input("repro table4 --samples 1 --out '" + repro.string() + "'",
                   "holds the checkpoint fits.jsonl of an earlier run", tmp);
  CHECK(slurp(repro / "fits.jsonl") == "{\"config\": {}}\n");

  // A drape folder reused by drape: the optional outputs this run does not write go (a
  // two_corner run used to leave the four_corner picture and steps.csv beside its summary).
  const fs::path drape = tmp.path / "drape";
  REQUIRE(
      run_knitsim("drape" + small + " --step-history --quiet --out '" + drape.string() + "'", tmp)
          .status == 0);
  REQUIRE(fs::exists(drape / "drape.png"));
  REQUIRE(fs::exists(drape / "steps.csv"));
  REQUIRE(
      run_knitsim("drape" + small + " --no-pictures --quiet --out '" + drape.string() + "'", tmp)
          .status == 0);
  CHECK(!fs::exists(drape / "drape.png"));
  CHECK(!fs::exists(drape / "steps.csv"));
  CHECK(fs::exists(drape / "summary.json"));
}

TEST_CASE("option values: integers decimal, 64-bit overflow refused, text not empty") {
  TempDir tmp("validation-integers");
  const std::string out = " --out '" + (tmp.path / "o").string() + "'";
  // --max-steps (a long): 1e20 was read as 2^63 - 1, silently; 0x10 as 16 and 010 as 8.
  expect_bad_input("drape --max-steps 99999999999999999999" + out,
                   "--max-steps: out of range: 99999999999999999999", tmp);
  expect_bad_input("drape --max-steps 0x10" + out, "--max-steps: must be a decimal integer", tmp);
  expect_bad_input("drape --max-restarts 1.5" + out, "--max-restarts: must be a decimal integer",
                   tmp);
  expect_bad_input("knit --frames +3" + out, "--frames: must be a decimal integer", tmp);
  // An empty text value: `--integrator ''` ran the default integrator.
  expect_bad_input("drape --integrator ''" + out, "--integrator: must not be empty", tmp);
  CHECK(!fs::exists(tmp.path / "o"));
  const Run r =
      run_knitsim("drape --integrator cvode-bdf --max-steps 010 --no-pictures --quiet" + out, tmp);
  CHECK(r.status == 3);  // stopped by the step cap of ten, not eight
  CHECK(slurp(tmp.path / "o" / "summary.json").find("\"steps\": 10,") != std::string::npos);
}

TEST_CASE("an integrator option refused at run start names its flag and leaves no folder") {
  TempDir tmp("validation-run-start");
  const fs::path chart = tmp.path / "c.chart";
  std::ofstream(chart) << "KKK\nKTK\nKKK\n";
  for (const std::string& cmd : {std::string("drape --integrator cvode-bdf"),
                                 "knit --integrator cvode-bdf --chart '" + chart.string() + "'"}) {
    expect_bad_input(cmd + " --max-order 9 --out '" + (tmp.path / "o").string() + "'",
                     "--max-order = 9: must be in 0..5 for cvode-bdf", tmp);
    CHECK(!fs::exists(tmp.path / "o"));
  }
}

TEST_CASE("valid but misleading input: one warning line, the run goes on") {
  TempDir tmp("validation-warnings");
  const auto run = [&](const std::string& args) {
    return run_knitsim("drape --set model.natural_length=0.1 --no-pictures --quiet --out '" +
                           (tmp.path / "o").string() + "' " + args,
                       tmp);
  };
  // No damping: the dynamics used to run for hours without a word (capped here at 0.2 s of wall
  // time); the equilibrium solver (the default) needs no damping and says nothing.
  const Run undamped = run("--integrator cvode-bdf --set model.damping=0 --max-wall 0.2");
  CHECK(undamped.status == 3);
  CHECK(undamped.err.find("knitsim drape: warning: model.damping = 0: with no damping nothing "
                          "comes to rest") != std::string::npos);
  const Run undamped_default = run("--set model.damping=0");
  CHECK(undamped_default.status == 0);
  CHECK(undamped_default.err.empty());
  // --dt with an adaptive integrator is ignored: said so, and the result is the plain run's.
  const Run plain = run("--integrator cvode-bdf");
  REQUIRE(plain.status == 0);
  CHECK(plain.err.empty());
  const std::string nodes = slurp(tmp.path / "o" / "nodes.csv");
  const Run with_dt = run("--integrator cvode-bdf --dt 5");
  CHECK(with_dt.status == 0);
  CHECK(count_lines(with_dt.err) == 1);
  CHECK(with_dt.err.find("warning: --dt is for the fixed-step integrators; cvode-bdf chooses "
                         "its own steps and ignores it") != std::string::npos);
  CHECK(slurp(tmp.path / "o" / "nodes.csv") == nodes);
  // Where it applies: no warning.
  CHECK(run("--integrator implicit-euler --dt 100").err.empty());
  // Its numerical damping settles an undamped sheet at its default step (1 s; at 10 s and more
  // the first undamped steps run away: status diverged).
  const Run numerically_damped = run("--integrator implicit-euler --set model.damping=0");
  CHECK(numerically_damped.status == 0);
  CHECK(numerically_damped.err.empty());

  // fit --optimizer lm with ICA flags: they were ignored without a word.
  const fs::path target = fs::path(KNITSIM_FUZZ_CORPUS) / "target" / "points_four_corner.csv";
  const Run lm = run_knitsim(
      "fit --scene four_corner --set model.natural_length=0.1 --target '" + target.string() +
          "' --optimizer lm --lm-starts 1 --lm-refine 1 --lm-evaluations 2 --countries 7 "
          "--stop-one-empire --quiet --out '" +
          (tmp.path / "lm").string() + "'",
      tmp);
  CHECK(lm.err.find("knitsim fit: warning: --countries, --stop-one-empire are not read by "
                    "--optimizer lm") != std::string::npos);
  CHECK(count_lines(lm.err) == 1);
}

TEST_CASE("an unknown command is named; --version answers") {
  TempDir tmp("validation-command");
  // It used to say "A subcommand is required".
  expect_bad_input("frob --out x", "unknown command 'frob': one of drape, knit, list", tmp);
  // Another command's flag names this command and the flag with its value, in order (CLI11
  // listed them last-first and pointed at the top-level help).
  expect_bad_input("drape --scene four_corner --optimizer lm --out x",
                   "knitsim drape does not take '--optimizer lm' (its flags: knitsim drape --help)",
                   tmp);
  CHECK(!fs::exists(tmp.path / "x"));
  const Run version = run_knitsim("--version", tmp);
  CHECK(version.status == 0);
  CHECK(version.out.rfind("knitsim ", 0) == 0);
  CHECK(version.out.find("(commit ") != std::string::npos);
}

TEST_CASE("a write that fails mid-run (a full disk): exit 4, one line naming the file") {
  TempDir tmp("validation-write-fails");
  // A file size limit of 2 KiB (SIGXFSZ ignored, so a write past it fails with EFBIG, as on a
  // full disk): --out is made and probed, the run settles, the first larger output fails.
  const fs::path out = tmp.path / "o";
  const std::string cmd = "sh -c \"trap '' XFSZ; ulimit -f 2; exec '" + std::string(KNITSIM_EXE) +
                          "' drape --no-pictures --quiet --out '" + out.string() + "'\" 2>'" +
                          (tmp.path / "err.txt").string() + "'";
  const int raw = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(raw));
  CHECK(WEXITSTATUS(raw) == 4);
  const std::string err = slurp(tmp.path / "err.txt");
  CHECK(count_lines(err) == 1);
  CHECK(err.rfind("knitsim: error: cannot write " + out.string() + "/", 0) == 0);
  CHECK(err.find("File too large") != std::string::npos);
  for (const auto& e : fs::directory_iterator(out)) CHECK(e.path().extension() != ".tmp");
}

TEST_CASE("one run per --out: a second run into a busy folder exits 5; no stale lock") {
  TempDir tmp("validation-busy");
  const fs::path out = tmp.path / "o";
  // Whether some process holds the folder's lock (tried from here, released at once).
  const auto held = [&out] {
    const int fd = ::open(out.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return false;
    const bool busy = ::flock(fd, LOCK_EX | LOCK_NB) != 0;
    ::close(fd);
    return busy;
  };
  const std::string slow = "drape --integrator euler --max-wall 300 --no-pictures --quiet --out '" +
                           out.string() + "'";
  // The second run is made while the first is stopped holding the lock (signal_when), so the
  // outcome does not depend on timing; then the first is interrupted and writes its outputs.
  Run second;
  const pid_t first_pid = start_knitsim(slow, tmp);
  const SignalledRun first = signal_when(first_pid, SIGINT, [&] {
    // Past its set-up (a signal there writes nothing; ms in Release, ~0.5 s under ASan).
    if (!held() || cpu_seconds_of(first_pid) < 2.0) return false;
    second = run_knitsim("drape --no-pictures --quiet --out '" + out.string() + "'", tmp);
    return true;
  });
  REQUIRE(first.signalled);
  CHECK_FALSE(WIFSIGNALED(first.status));  // the handler is installed before the folder's lock
  CHECK(WEXITSTATUS(first.status) == 130);
  CHECK(second.status == 5);
  CHECK(count_lines(second.err) == 1);
  CHECK(second.err.find("knitsim: error: --out " + out.string() +
                        ": in use by another knitsim run") != std::string::npos);
  CHECK(fs::exists(out / "summary.json"));  // the first run's, written after the refusal
  CHECK(nlohmann::json::parse(slurp(out / "summary.json"))["integrator"] == "euler");
  // The lock ends with its process, however it ends: after a SIGKILL the folder is free.
  const SignalledRun killed = signal_when(start_knitsim(slow, tmp), SIGKILL, held);
  REQUIRE(killed.signalled);
  CHECK(WIFSIGNALED(killed.status));
  CHECK_FALSE(held());
  CHECK(run_knitsim("drape --no-pictures --quiet --out '" + out.string() + "'", tmp).status == 0);
}
