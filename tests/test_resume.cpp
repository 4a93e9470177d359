// Resumable ICA runs (src/fit/ica.hpp checkpoints, knitsim fit --resume): the twister's state round
// trip, a run continued from any decade's saved state (through JSON) is bit-identical to the
// uninterrupted run, states that do not fit are refused, and `knitsim fit` killed with SIGKILL
// after a decade, or stopped by SIGTERM at a decade's end, then resumed writes the same best
// country, objective and history as a run never interrupted.
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "src/fit/ica.hpp"
#include "src/fit/test_functions.hpp"
#include "src/io/json.hpp"
#include "src/io/run_state.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"
#include "tests/cli_runner.hpp"

using namespace knitsim;

namespace {

// stderr's lines without knit's yarn-overlap warning (a tuck chart's yarns overlap until the
// model has contact; that warning is not the status line these tests count).
std::vector<std::string> lines_but_yarn_warning(const std::string& err) {
  std::vector<std::string> out;
  for (const std::string& l : knitsim::test::lines(err))
    if (l.find("warning: yarns overlap") == std::string::npos) out.push_back(l);
  return out;
}

// Rastrigin in D = 6, failing (NaN) where x0 > 4: exercises the failure counters too.
Problem failing_rastrigin() {
  Problem p = make_test_problem("rastrigin", 6);
  p.cost = [f = p.cost](const std::vector<double>& x) {
    return x[0] > 4.0 ? std::numeric_limits<double>::quiet_NaN() : f(x);
  };
  return p;
}

IcaOptions small_options() {
  IcaOptions o;
  o.decades = 20;
  o.countries = 20;
  o.imperialists = 4;
  o.seed = 5;
  return o;
}

// Runs the ICA collecting every saved state.
IcaResult run_saving(const Problem& p, IcaOptions o, std::vector<IcaState>& states) {
  states.clear();
  o.on_decade = [&states](const IcaState& s) { states.push_back(s); };
  return run_ica(p, o);
}

// A state as the checkpoint file carries it: to JSON text and back.
std::shared_ptr<const IcaState> through_json(const IcaState& s) {
  return std::make_shared<const IcaState>(
      ica_state_from_json(nlohmann::json::parse(to_json(s).dump())));
}

// Everything of a state but the wall time.
nlohmann::json without_wall(const IcaState& s) {
  nlohmann::json j = to_json(s);
  j.erase("wall_seconds");
  return j;
}

void check_same_run(const IcaResult& r, const IcaResult& ref) {
  CHECK(r.status == ref.status);
  CHECK(r.best_x == ref.best_x);  // exact comparison of doubles, on purpose
  CHECK(r.best_cost == ref.best_cost);
  CHECK(r.evaluations == ref.evaluations);
  CHECK(r.failed_evaluations == ref.failed_evaluations);
  CHECK(r.decades == ref.decades);
  REQUIRE(r.history.size() == ref.history.size());
  for (std::size_t d = 0; d < r.history.size(); ++d) {
    CHECK(r.history[d].best_cost == ref.history[d].best_cost);
    CHECK(r.history[d].mean_cost == ref.history[d].mean_cost);
    CHECK(r.history[d].empires == ref.history[d].empires);
    CHECK(r.history[d].evaluations == ref.history[d].evaluations);
  }
}

// Starts `knitsim <args>` in the background, sends it `signal` once `ready(pid)` holds (checked
// with the run stopped: cli_runner.hpp, signal_when) and waits for it to end; returns its wait
// status, or -1 if it ended before ready() held or had not ended 600 s after the start.
int interrupted_run(const std::string& args, int signal, const std::function<bool(pid_t)>& ready,
                    const knitsim::test::TempDir& tmp) {
  const pid_t pid = knitsim::test::start_knitsim(args, tmp);
  if (pid <= 0) return -1;
  const knitsim::test::SignalledRun r =
      knitsim::test::signal_when(pid, signal, [&] { return ready(pid); });
  return r.signalled ? r.status : -1;
}

// The arguments of a small, fast fit on a 30 cm four_corner sheet (add --decades, --seed,
// --out): its target, given by coefficients, is written into tmp (any valid target serves: the
// tests compare two fits of it): d(s) = 0.3 s - 0.3 s^2 on every edge.
std::string small_fit_args(const knitsim::test::TempDir& tmp) {
  std::ofstream t(tmp.path / "target.csv");
  t << "scene,edge,kind,a,b\n";
  for (const char* edge : {"top", "bottom", "left", "right"})
    for (int i = 0; i <= 4; ++i)
      t << "four_corner," << edge << ",coeff," << i << ","
        << (i == 1   ? "0.3"
            : i == 2 ? "-0.3"
                     : "0")
        << "\n";
  return "fit --scene four_corner --set fabric.width=0.3 --target '" +
         (tmp.path / "target.csv").string() + "' --countries 6 --imperialists 2 --quiet";
}

// Starts the fit `args` writing into `out`, sends it `signal` once its checkpoint holds decade 1
// or later (checked with the fit stopped, so it cannot run on to its end in between:
// cli_runner.hpp, signal_when) and waits for it to end; returns its wait status (-1 if it ended
// first), and in `decade` the checkpoint's decade when the signal was sent (-1 if none).
int fit_signalled_after_decade_one(const std::string& args, const std::filesystem::path& out,
                                   int signal, const knitsim::test::TempDir& tmp, int& decade) {
  const pid_t pid = knitsim::test::start_knitsim(args + " --out '" + out.string() + "'", tmp);
  if (pid <= 0) return -1;
  const std::filesystem::path checkpoint = out / "ica_checkpoint.json";
  decade = -1;
  const knitsim::test::SignalledRun r = knitsim::test::signal_when(pid, signal, [&] {
    if (std::filesystem::exists(checkpoint))  // written atomically: always whole
      decade = nlohmann::json::parse(knitsim::test::slurp(checkpoint))
                   .at("state")
                   .at("decade")
                   .get<int>();
    return decade >= 1;
  });
  return r.signalled ? r.status : -1;
}

// The fit resumed in `cut` wrote what the uninterrupted fit in `whole` did, bit for bit.
void check_same_fit(const std::filesystem::path& whole, const std::filesystem::path& cut) {
  using knitsim::test::slurp;
  const nlohmann::json a = nlohmann::json::parse(slurp(whole / "summary.json"));
  const nlohmann::json b = nlohmann::json::parse(slurp(cut / "summary.json"));
  for (const char* key : {"best_country", "objective", "params", "history", "evaluations",
                          "failed_evaluations", "status", "fitted_drape_status"}) {
    INFO(key);
    CHECK(b.at(key) == a.at(key));
  }
  CHECK(slurp(cut / "history.csv") == slurp(whole / "history.csv"));
  CHECK(slurp(cut / "drape" / "nodes.csv") == slurp(whole / "drape" / "nodes.csv"));
}

// The run in dir/second (continued with --continue from dir/first) ended where dir/whole (one
// uninterrupted run) did, bit for bit -- state.json and `file` (nodes.csv, points.csv) -- and
// says it started at first's t_final.
void check_continued_equals_whole(const std::filesystem::path& dir, const char* file) {
  using knitsim::test::slurp;
  auto json = [&](const char* run, const char* name) {
    return nlohmann::json::parse(slurp(dir / run / name));
  };
  const nlohmann::json second = json("second", "state.json"), whole = json("whole", "state.json");
  CHECK(second.at("t") == whole.at("t"));
  CHECK(second.at("x") == whole.at("x"));
  CHECK(second.at("v") == whole.at("v"));
  CHECK(slurp(dir / "second" / file) == slurp(dir / "whole" / file));
  CHECK(json("second", "summary.json").at("t_start") ==
        json("first", "summary.json").at("t_final"));
}

// A refused command line: exit 2, one line on stderr containing `says`, nothing written at `out`.
void check_refused(const knitsim::test::Run& r, const std::string& says,
                   const std::filesystem::path& out) {
  CHECK(r.status == 2);
  CHECK(knitsim::test::lines(r.err).size() == 1);
  CHECK(r.err.find(says) != std::string::npos);
  CHECK(!std::filesystem::exists(out));
}

}  // namespace

TEST_CASE("the random state round trip continues the same stream", "[resume]") {
  IcaRandom a(11);
  for (int k = 0; k < 1000; ++k) a.uniform();
  const std::string saved = a.state();
  std::vector<double> next;
  for (int k = 0; k < 20; ++k) next.push_back(a.normal());
  IcaRandom b(99);
  b.set_state(saved);
  for (int k = 0; k < 20; ++k) CHECK(b.normal() == next[k]);
  CHECK_THROWS_AS(b.set_state("1 2 3"), std::invalid_argument);
  CHECK_THROWS_AS(b.set_state(saved + " 7"), std::invalid_argument);
}

TEST_CASE("a run resumed from any decade's state is bit-identical to the uninterrupted one",
          "[resume]") {
  const Problem p = failing_rastrigin();
  const IcaOptions o = small_options();
  std::vector<IcaState> states;
  const IcaResult ref = run_saving(p, o, states);
  REQUIRE(ref.failed_evaluations > 0);
  REQUIRE(states.size() == 21);
  for (int d = 0; d <= 20; ++d) CHECK(states[d].decade == d);
  CHECK(states.back().evaluations == ref.evaluations);

  for (int d : {0, 1, 9, 19, 20}) {
    INFO("resumed from decade " << d);
    IcaOptions again = o;
    again.jobs = 3;  // threads do not change the run, resumed or not
    again.resume_from = through_json(states[d]);
    std::vector<IcaState> later;
    check_same_run(run_saving(p, again, later), ref);
    // The states after the resume are the uninterrupted run's, field by field.
    REQUIRE(later.size() == states.size() - d - 1);
    for (std::size_t k = 0; k < later.size(); ++k)
      CHECK(without_wall(later[k]) == without_wall(states[d + 1 + k]));
  }
  SECTION("the test can fail: one decade's state with another decade's random state") {
    IcaState mixed = states[9];
    mixed.random = states[8].random;
    IcaOptions again = o;
    again.resume_from = std::make_shared<const IcaState>(mixed);
    CHECK(run_ica(p, again).history.back().mean_cost != ref.history.back().mean_cost);
  }
}

TEST_CASE("resume with the step-9 rule: a run that stopped at one empire stays stopped",
          "[resume]") {
  const Problem p = make_test_problem("sphere", 4);
  IcaOptions o = small_options();
  o.imperialists = 2;
  o.stop_when_one_empire = true;
  std::vector<IcaState> states;
  const IcaResult ref = run_saving(p, o, states);
  REQUIRE(ref.status == IcaStatus::OneEmpire);
  REQUIRE(states.back().empires.size() == 1);
  for (std::size_t d : {std::size_t{0}, states.size() - 1}) {
    IcaOptions again = o;
    again.resume_from = through_json(states[d]);
    check_same_run(run_ica(p, again), ref);
  }
}

TEST_CASE("stop_requested ends a run at the end of a decade, and resuming it finishes the run",
          "[resume]") {
  const Problem p = failing_rastrigin();
  const IcaOptions o = small_options();
  std::vector<IcaState> states;
  const IcaResult ref = run_saving(p, o, states);
  for (int asked_after : {0, 7, 19, 20}) {
    INFO("stop asked once decade " << asked_after << " was saved");
    IcaOptions cut = o;
    int saved = -1;
    cut.on_decade = [&saved](const IcaState& s) { saved = s.decade; };
    cut.stop_requested = [&saved, asked_after] { return saved >= asked_after; };
    const IcaResult r = run_ica(p, cut);
    if (asked_after == o.decades) {  // asked after the last decade: the run is complete
      check_same_run(r, ref);
      continue;
    }
    CHECK(r.status == IcaStatus::Interrupted);
    CHECK(r.decades == asked_after);
    CHECK(saved == asked_after);
    CHECK(r.history.size() == static_cast<std::size_t>(asked_after) + 1);
    CHECK(r.evaluations == states[asked_after].evaluations);
    CHECK(r.best_x == states[asked_after].best_x);
    IcaOptions again = o;
    again.resume_from = through_json(states[asked_after]);
    check_same_run(run_ica(p, again), ref);
  }
}

TEST_CASE("a state that does not fit the options or is incomplete is refused", "[resume]") {
  const Problem p = failing_rastrigin();
  IcaOptions o = small_options();
  std::vector<IcaState> states;
  run_saving(p, o, states);
  IcaOptions again = o;
  again.resume_from = std::make_shared<const IcaState>(states[9]);
  SECTION("fewer decades than the state has run") {
    again.decades = 8;
    CHECK_THROWS_WITH(run_ica(p, again), Catch::Contains("decade 9 does not fit"));
  }
  SECTION("another dimension") {
    CHECK_THROWS_WITH(run_ica(make_test_problem("rastrigin", 5), again),
                      Catch::Contains("dimension 6 does not fit"));
  }
  SECTION("more empires than imperialists") {
    REQUIRE(states[0].empires.size() == 4);
    again.resume_from = std::make_shared<const IcaState>(states[0]);
    again.imperialists = 1;
    again.countries = 20;
    CHECK_THROWS_WITH(run_ica(p, again), Catch::Contains("empires does not fit"));
  }
  nlohmann::json j = to_json(states[9]);
  j.erase("random");
  CHECK_THROWS_WITH(ica_state_from_json(j), Catch::Contains("field random"));
  j = to_json(states[9]);
  j["history"] = 3;
  CHECK_THROWS_WITH(ica_state_from_json(j), Catch::Contains("field history"));
}

TEST_CASE("knitsim fit killed after a decade and resumed equals an uninterrupted fit",
          "[resume][cli]") {
  using namespace knitsim::test;
  TempDir tmp("resume");
  const std::string args = small_fit_args(tmp) + " --decades 5";
  const fs::path whole = tmp.path / "whole", cut = tmp.path / "cut";
  const Run reference = run_knitsim(args + " --seed 3 --out '" + whole.string() + "'", tmp);
  REQUIRE(reference.status == 0);

  // The same fit, killed once its checkpoint holds decade 1 or later.
  int decade = -1;
  const int status = fit_signalled_after_decade_one(args + " --seed 3", cut, SIGKILL, tmp, decade);
  INFO("checkpoint decade " << decade << "; " << slurp(tmp.path / "background-stderr.txt"));
  REQUIRE(WIFSIGNALED(status));  // killed before it finished
  REQUIRE(decade >= 1);
  REQUIRE(decade < 5);
  CHECK(!fs::exists(cut / "summary.json"));

  // Other settings are refused with one line; --resume needs --out.
  const Run other = run_knitsim(args + " --seed 4 --out '" + cut.string() + "' --resume", tmp);
  CHECK(other.status == 2);
  CHECK(lines(other.err).size() == 1);
  CHECK(other.err.find("first difference: /ica/seed") != std::string::npos);
  const Run no_out = run_knitsim(args + " --seed 3 --resume", tmp);
  CHECK(no_out.status == 2);
  CHECK(no_out.err.find("--resume: needs --out") != std::string::npos);

  // Resumed with 2 threads: the same fit, bit for bit.
  const Run resumed =
      run_knitsim(args + " --seed 3 --jobs 2 --out '" + cut.string() + "' --resume", tmp);
  REQUIRE(resumed.status == 0);
  check_same_fit(whole, cut);
  CHECK(nlohmann::json::parse(slurp(cut / "summary.json")).at("resumed_from_decade").get<int>() >=
        decade);
}

TEST_CASE(
    "knitsim fit stopped by SIGTERM: ends at the decade's end with the best so far, exit 143; "
    "--resume finishes it",
    "[resume][cli]") {
  using namespace knitsim::test;
  TempDir tmp("fit-interrupt");
  // 10 decades: the signal is sent at decade 1 with the fit stopped (signal_when), so the run
  // cannot reach its end first; 60 decades used to buy that margin against a timed poll.
  const std::string args = small_fit_args(tmp) + " --decades 10 --seed 3";
  const fs::path whole = tmp.path / "whole", cut = tmp.path / "cut";
  const Run reference = run_knitsim(args + " --out '" + whole.string() + "'", tmp);
  REQUIRE(reference.status == 0);

  int seen = -1;
  const int status = fit_signalled_after_decade_one(args, cut, SIGTERM, tmp, seen);
  REQUIRE(seen >= 1);
  const std::string err = slurp(tmp.path / "background-stderr.txt");
  INFO(err);
  REQUIRE(WIFEXITED(status));  // the handler ran: not killed by the signal
  CHECK(WEXITSTATUS(status) == 128 + SIGTERM);
  CHECK(lines(err).size() == 1);
  CHECK(err.find("knitsim fit: interrupted by SIGTERM after decade ") != std::string::npos);
  CHECK(err.find("with --resume") != std::string::npos);
  const nlohmann::json summary = nlohmann::json::parse(slurp(cut / "summary.json"));
  const nlohmann::json state =
      nlohmann::json::parse(slurp(cut / "ica_checkpoint.json")).at("state");
  CHECK(summary.at("status") == "interrupted");
  CHECK(summary.at("fitted_drape_status") == "not_run");
  CHECK(!fs::exists(cut / "drape"));
  // The summary is the checkpoint's decade: the one the run stopped after, written whole.
  const int decade = state.at("decade").get<int>();
  CHECK(decade < 10);
  CHECK(summary.at("history").back().at("decade") == decade);
  CHECK(summary.at("evaluations") == state.at("evaluations"));
  CHECK(summary.at("best_country") == state.at("best_x"));
  CHECK(fs::exists(cut / "manifest.json"));

  // --resume finishes it: the uninterrupted fit, bit for bit.
  const Run resumed = run_knitsim(args + " --out '" + cut.string() + "' --resume", tmp);
  REQUIRE(resumed.status == 0);
  check_same_fit(whole, cut);
  CHECK(nlohmann::json::parse(slurp(cut / "summary.json")).at("resumed_from_decade") == decade);
}

TEST_CASE(
    "knitsim drape and knit stopped by SIGINT or SIGTERM: outputs written, status "
    "interrupted, exit 128 + signal") {
  using namespace knitsim::test;
  TempDir tmp("interrupt");
  // Two runs that take minutes (explicit Euler to equilibrium), signalled once their handler is
  // installed and their set-up is past (a signal there writes nothing): the run ends after the
  // step it is in (not at its first residual check, 1000 Euler steps later:
  // docs/reliability.md, "Signals").
  std::string chart;
  for (int r = 0; r < 20; ++r, chart += '\n')
    for (int c = 0; c < 20; ++c) chart += (r % 4 == 1 && c % 5 == 2) ? 'T' : 'K';
  std::ofstream(tmp.path / "tucks.chart") << chart;
  struct Case {
    std::string args;
    int signal;
    std::vector<std::string> files;
    double past_set_up;  // s of CPU: the set-up takes ms (Release) to ~0.5 s (ASan); the knit's
                         // Euler run settles in ~1.4 s (Release)
  };
  const std::vector<Case> cases = {
      {"drape --integrator euler", SIGINT, {"summary.json", "nodes.csv", "drape.png"}, 2.0},
      {"knit --integrator euler --set knit.contact=0 --chart '" +
           (tmp.path / "tucks.chart").string() + "'",
       SIGTERM,
       {"summary.json", "points.csv", "after.png"},
#ifdef KNITSIM_SANITIZED
       1.0}};  // the chart's set-up under AddressSanitizer: a stop asked during it ends the
               // run at its start, no step taken, and this case is about a run stopped mid-way
#else
       0.2}};
#endif
  for (const Case& c : cases) {
    INFO(c.args);
    const fs::path out = tmp.path / ("out-" + std::to_string(c.signal));
    const int status = interrupted_run(
        c.args + " --quiet --out '" + out.string() + "'", c.signal,
        [&](pid_t pid) {
          return knitsim::test::knitsim_handles(pid, c.signal) &&
                 knitsim::test::cpu_seconds_of(pid) >= c.past_set_up;
        },
        tmp);
    const std::string err = slurp(tmp.path / "background-stderr.txt");
    INFO("stderr: " << err);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 128 + c.signal);
    CHECK(lines_but_yarn_warning(err).size() == 1);
    CHECK(err.find(std::string("interrupted by ") + (c.signal == SIGINT ? "SIGINT" : "SIGTERM")) !=
          std::string::npos);
    CHECK(err.find(out.string()) != std::string::npos);
    for (const std::string& f : c.files) CHECK(fs::exists(out / f));
    const nlohmann::json summary = nlohmann::json::parse(slurp(out / "summary.json"));
    CHECK(summary.at("status") == "interrupted");
    const nlohmann::json& stats = summary.contains("stats") ? summary.at("stats") : summary;
    CHECK(stats.at("steps").get<long>() >= 1);
    CHECK(stats.at("t_final").get<double>() > 0.0);
    // Nothing lost: cvode-bdf continues from the interrupted state to equilibrium.
    const std::string args = c.args.substr(0, c.args.find(" --integrator")) +
                             c.args.substr(c.args.find(" --integrator euler") + 19);
    const fs::path continued = tmp.path / ("continued-" + std::to_string(c.signal));
    const Run more = run_knitsim(args + " --continue '" + out.string() +
                                     "' --no-pictures --quiet --out '" + continued.string() + "'",
                                 tmp);
    INFO(more.err);
    CHECK(more.status == 0);
    const nlohmann::json end = nlohmann::json::parse(slurp(continued / "summary.json"));
    CHECK(end.at("t_start") == stats.at("t_final"));
    CHECK(end.at("status") == "equilibrium");
    // The drape's sag: a regression pin of this program's own value for the built-in
    // four_corner (the independent check against 1.288 cm is test_drape_answers.cpp).
    if (c.signal == SIGINT)
      CHECK(end.at("centre_sag_m").get<double>() == Approx(0.012882511).epsilon(1e-6));
  }
}

TEST_CASE("knitsim drape --continue: a run continued where it stopped is the uninterrupted run") {
  using namespace knitsim::test;
  TempDir tmp("continue");
  auto drape = [&](const std::string& args, const std::string& out) {
    return run_knitsim("drape " + args + " --quiet --out '" + (tmp.path / out).string() + "'", tmp);
  };
  auto json = [&](const std::string& out, const char* file) {
    return nlohmann::json::parse(slurp(tmp.path / out / file));
  };
  // Euler (automatic step): 3000 + 2000 steps equal 5000 steps bit for bit, state and nodes.
  REQUIRE(drape("--integrator euler --max-steps 3000", "first").status == 3);
  REQUIRE(drape("--integrator euler --max-steps 2000 --continue '" + (tmp.path / "first").string() +
                    "'",
                "second")
              .status == 3);
  REQUIRE(drape("--integrator euler --max-steps 5000", "whole").status == 3);
  check_continued_equals_whole(tmp.path, "nodes.csv");
  CHECK(json("second", "summary.json").at("dt") == json("whole", "summary.json").at("dt"));

  // Another integrator may take over: cvode-bdf from the Euler state reaches the same equilibrium.
  REQUIRE(drape("--continue '" + (tmp.path / "first").string() + "'", "bdf").status == 0);
  REQUIRE(drape("", "reference").status == 0);
  CHECK(json("bdf", "summary.json").at("centre_sag_m").get<double>() ==
        Approx(json("reference", "summary.json").at("centre_sag_m").get<double>()).epsilon(1e-8));

  // Refused with one line and nothing written: no drape folder, another model, t_max passed,
  // a state file that is not JSON (said without the JSON library's exception tag).
  fs::create_directories(tmp.path / "garbled");
  std::ofstream(tmp.path / "garbled" / "state.json") << "{\"t\": 1e400}\n";
  struct Bad {
    std::string args, says;
  };
  for (const Bad& b :
       {Bad{"--continue '" + tmp.path.string() + "'", "not the output folder of a knitsim drape"},
        Bad{"--continue '" + (tmp.path / "garbled").string() + "'",
            "state.json: not a valid state file: number overflow parsing '1e400'"},
        Bad{"--continue '" + (tmp.path / "first").string() + "' --set model.stiffness=900",
            "model.stiffness = 900"},
        // named by the keys --set knows (they used to read model.layout, model.width)
        Bad{"--continue '" + (tmp.path / "first").string() + "' --scene two_corner",
            "pins.layout = \"two_corner\" here, \"four_corner\" in the run being continued"},
        Bad{"--continue '" + (tmp.path / "first").string() + "' --set fabric.width=0.4",
            "fabric.width = 0.4 here"},
        Bad{"--continue '" + (tmp.path / "first").string() + "' --set run.t_max=1e-3",
            "raise run.t_max"}}) {
    INFO(b.args);
    check_refused(drape(b.args, "refused"), b.says, tmp.path / "refused");
  }

  // A state file of an earlier version, whose keys read model.width, model.layout, ...:
  // continued as before (the Euler pieces, bit for bit).
  const nlohmann::json state = json("first", "state.json");
  nlohmann::json old_state = state;
  old_state["model"] = nlohmann::json::object();
  for (const auto& [key, value] : state.at("model").items()) {
    const std::string field = key.substr(key.find('.') + 1);
    old_state["model"][key.rfind("model.", 0) == 0 ? key
                       : field == "span"           ? "model.pin_span"
                       : field == "move_time"      ? "model.pin_move_time"
                                                   : "model." + field] = value;
  }
  REQUIRE(old_state.at("model").contains("model.layout"));
  fs::create_directories(tmp.path / "old");
  std::ofstream(tmp.path / "old" / "state.json") << old_state.dump();
  fs::copy_file(tmp.path / "first" / "manifest.json", tmp.path / "old" / "manifest.json");
  REQUIRE(
      drape("--integrator euler --max-steps 2000 --continue '" + (tmp.path / "old").string() + "'",
            "second-from-old")
          .status == 3);
  CHECK(slurp(tmp.path / "second-from-old" / "nodes.csv") ==
        slurp(tmp.path / "whole" / "nodes.csv"));
}

TEST_CASE("a state that is not finite leaves no state.json, not even an earlier run's") {
  namespace fs = std::filesystem;
  knitsim::test::TempDir tmp("state");
  SavedRun saved{"drape", {1.0, {0.0, 1.0}, {0.0, 0.0}}, "euler", 1e-3, nlohmann::json::object()};
  write_run_state(tmp.path, saved);
  REQUIRE(fs::exists(tmp.path / "state.json"));
  CHECK(read_run_state(tmp.path, "drape").state.x == saved.state.x);
  for (double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    SavedRun diverged = saved;
    diverged.state.x[1] = bad;
    write_run_state(tmp.path, saved);
    write_run_state(tmp.path, diverged);
    CHECK_FALSE(fs::exists(tmp.path / "state.json"));
  }
}

TEST_CASE("a drape state's model keys are the keys --set takes") {
  const std::vector<std::string> known = knitsim::scene_keys();
  const nlohmann::json keys = knitsim::drape_model_keys(knitsim::DrapeParams{});
  REQUIRE(keys.size() == knitsim::to_json(knitsim::DrapeParams{}).size());  // one per field
  for (const auto& [key, value] : keys.items()) {
    INFO(key);
    CHECK(std::find(known.begin(), known.end(), key) != known.end());
  }
}

TEST_CASE("knitsim knit --continue: a run continued where it stopped is the uninterrupted run") {
  using namespace knitsim::test;
  TempDir tmp("knit-continue");
  std::ofstream(tmp.path / "tuck.chart") << "KKKKKK\nKKKTKK\nKKKKKK\nKKKKKK\n";
  std::ofstream(tmp.path / "other.chart") << "KKKKKK\nKKTKKK\nKKKKKK\nKKKKKK\n";
  std::ofstream(tmp.path / "wide.chart") << "KKKKKKKKKKKK\nKKKKKTKKKKKK\nKKKKKKKKKKKK\n";
  auto knit = [&](const std::string& args, const std::string& out,
                  const std::string& chart = "tuck.chart") {
    return run_knitsim("knit --chart '" + (tmp.path / chart).string() + "' " + args +
                           " --set knit.contact=0 --no-pictures --quiet --out '" +
                           (tmp.path / out).string() + "'",
                       tmp);
  };
  auto json = [&](const std::string& out, const char* file) {
    return nlohmann::json::parse(slurp(tmp.path / out / file));
  };
  // Euler (automatic step) on the network without contact (the contact's renewed points are not
  // part of the saved state): 1500 + 1000 steps equal 2500 steps bit for bit (none settles).
  const Run capped = knit("--integrator euler --max-steps 1500", "first");
  REQUIRE(capped.status == 3);
  CHECK(lines_but_yarn_warning(capped.err).size() == 1);  // says how to go on
  CHECK(capped.err.find("stopped by --max-steps") != std::string::npos);
  CHECK(capped.err.find("--continue " + (tmp.path / "first").string()) != std::string::npos);
  REQUIRE(
      knit("--integrator euler --max-steps 1000 --continue '" + (tmp.path / "first").string() + "'",
           "second")
          .status == 3);
  REQUIRE(knit("--integrator euler --max-steps 2500", "whole").status == 3);
  check_continued_equals_whole(tmp.path, "points.csv");
  CHECK(json("second", "summary.json").at("stats").at("steps") == 1000);

  // With contact (the default): the continued run re-linearises the contact points about the
  // saved state and settles in about the steps the whole run has left (at rest-made points it
  // crawled: 10 minutes on several_tucks against 1.5 s).
  const fs::path chart = fs::path(KNITSIM_CHARTS) / "several_tucks.chart";
  auto contact = [&](const std::string& args, const std::string& out) {
    return run_knitsim("knit --chart '" + chart.string() + "' " + args +
                           " --max-wall 60 --no-pictures --quiet --out '" +
                           (tmp.path / out).string() + "'",
                       tmp);
  };
  REQUIRE(contact("--max-steps 10", "contact-first").status == 3);
  const Run went_on =
      contact("--max-steps 60 --continue '" + (tmp.path / "contact-first").string() + "'",
              "contact-second");
  INFO(went_on.err);
  CHECK(went_on.status == 0);
  const nlohmann::json s = json("contact-second", "summary.json");
  CHECK(s.at("status") == "equilibrium");
  CHECK(s.at("stats").at("steps").get<int>() <= 30);
  CHECK(s.at("yarn").at("clearance_min_over_r").get<double>() >= 0.9);

  // Refused with one line and nothing written: another chart, other parameters (a key given
  // there and not here too), a drape's state.
  REQUIRE(knit("--integrator euler --max-steps 10 --set knit.pins=bottom", "pinned").status == 3);
  REQUIRE(run_knitsim("drape --integrator cvode-bdf --max-steps 10 --quiet --out '" +
                          (tmp.path / "drape").string() + "'",
                      tmp)
              .status == 3);
  struct Bad {
    std::string args, chart, says;
  };
  const std::string first = " --continue '" + (tmp.path / "first").string() + "'";
  for (const Bad& b : {Bad{first, "other.chart", "chart = [\"KKKKKK\",\"KKKKKK\",\"KKTKKK\""},
                       Bad{first, "wide.chart", "chart differs from the run being continued"},
                       Bad{first + " --set knit.damping=0.001", "tuck.chart",
                           "knit.damping = 0.001 here, 0.0005 in the run being continued"},
                       Bad{" --continue '" + (tmp.path / "pinned").string() + "'", "tuck.chart",
                           "knit.pins = \"bottom\" in the run being continued, the default here"},
                       Bad{" --continue '" + (tmp.path / "drape").string() + "'", "tuck.chart",
                           "the state of a knitsim drape run; this is knitsim knit"}}) {
    INFO(b.args);
    check_refused(knit(b.args, "refused", b.chart), b.says, tmp.path / "refused");
  }
}

TEST_CASE("knitsim demo stopped by SIGINT: the report of the runs so far, exit 130") {
  using namespace knitsim::test;
  TempDir tmp("demo-interrupt");
  const fs::path out = tmp.path / "demo";
  // Signalled once the last scene's summary is written: the scenes are done, and the
  // integrator comparison (a minute) is cut short at its first run or before it starts.
  const int status = interrupted_run(
      "demo --out '" + out.string() + "'", SIGINT,
      [&](pid_t) { return fs::exists(out / "two_corner" / "summary.json"); }, tmp);
  const std::string err = slurp(tmp.path / "background-stderr.txt");
  INFO("stderr: " << err);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 130);
  CHECK(lines(err).size() == 1);
  CHECK(err.find("interrupted by SIGINT") != std::string::npos);
  for (const char* f : {"report.md", "comparison.csv", "manifest.json", "four_corner/drape.png",
                        "two_corner/summary.json"})
    CHECK(fs::exists(out / f));
  const std::string report = slurp(out / "report.md");
  // (a run marked interrupted in its table too, unless the signal fell between two runs)
  CHECK(report.find("**Interrupted** by SIGINT") != std::string::npos);
}
