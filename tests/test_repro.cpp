// knitsim repro (src/repro/repro.hpp) and its plot (src/render/plot.hpp): the tick rules, the seed
// and budget helpers, and a tiny-budget Table 4 + 6 run whose CSVs are checked against paper_data
// and against objective() recomputed from the fitted parameters, and for independence of the thread
// count. Matching the paper's numbers is NOT tested.
#include <cairo.h>
#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "src/base/text.hpp"
#include "src/fit/drape_fit.hpp"
#include "src/fit/test_functions.hpp"
#include "src/measure/measurement.hpp"
#include "src/paper/paper_data.hpp"
#include "src/render/plot.hpp"
#include "src/repro/repro.hpp"
#include "src/scene/scene.hpp"
#include "tests/cli_runner.hpp"

using namespace knitsim;
using knitsim::test::TempDir;
namespace fs = std::filesystem;

namespace {

// CSV without quoted cells (repro's tables quote nothing numeric) as rows of cells.
std::vector<std::vector<std::string>> read_csv(const fs::path& p) {
  std::vector<std::vector<std::string>> rows;
  for (const std::string& line : knitsim::test::lines(knitsim::test::slurp(p))) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream in(line);
    while (std::getline(in, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    rows.push_back(cells);
  }
  return rows;
}

size_t col(const std::vector<std::string>& header, const std::string& name) {
  const auto it = std::find(header.begin(), header.end(), name);
  REQUIRE(it != header.end());
  return static_cast<size_t>(it - header.begin());
}

ReproOptions tiny_options(int jobs) {
  ReproOptions o = repro_preset("quick");
  o.task = ReproTask::Table6;  // Table 6 needs (and writes) Table 4's fits
  o.samples = {1};
  o.sets = {SyntheticSet::Twin};
  o.runs = 2;
  o.ica.countries = 4;
  o.ica.imperialists = 2;
  o.ica.decades = 1;
  o.jobs = jobs;
  o.pictures = false;
  o.progress = false;
  const fs::path committed = fs::path(KNITSIM_PAPER_DATA) / "targets";
  if (fs::is_directory(committed)) o.targets_dir = committed.string();
  return o;
}

// The country of a table row: the 4 genes as written (17 digits) and a topology gene inside the
// written topology's unit interval.
std::vector<double> country(const std::vector<std::string>& header,
                            const std::vector<std::string>& row) {
  std::vector<double> x;
  for (const char* p : {"stiffness", "damping", "elongation_limit", "natural_length"})
    x.push_back(std::stod(row[col(header, p)]));
  x.push_back(row[col(header, "topology")].at(0) - 'a' + 0.5);
  return x;
}

// The scene run_repro evaluates: the sample's fabric; four_corner on the repro's default
// symmetry reduction.
Scene sample_scene(const std::string& name, int sample) {
  std::vector<std::string> sets = {"fabric.areal_density=" +
                                   format_number(paper_sample(sample).areal_density, 17)};
  if (name == "four_corner")
    sets.push_back(std::string("model.symmetry=") +
                   to_string(repro_preset("quick").four_corner_symmetry));
  Scene s = load_scene(name, sets);
  s.options.rtol = 1e-8;
  return s;
}

// The fit options run_repro evaluates with: its default integrator, one thread.
DrapeFitOptions repro_fit_options() {
  DrapeFitOptions fo;
  fo.ica.jobs = 1;
  fo.integrator = repro_integrator(repro_preset("quick"));
  return fo;
}

}  // namespace

TEST_CASE("nice_ticks: 1-2-5 steps covering the range, at most max_ticks", "[plot]") {
  CHECK(nice_ticks(0.0, 9.3) == std::vector<double>{0, 2, 4, 6, 8, 10});
  for (auto [lo, hi] : std::vector<std::pair<double, double>>{
           {0.0, 9.3}, {-3.7, 141.0}, {0.013, 0.0171}, {5.0, 5.0}, {-1e6, 3e5}}) {
    const std::vector<double> t = nice_ticks(lo, hi, 8);
    REQUIRE(t.size() >= 2);
    CHECK(t.size() <= 8);
    CHECK(t.front() <= lo + 1e-12 * std::abs(lo));  // a tick may be an ulp off lo or hi
    CHECK(t.back() >= hi - 1e-12 * std::abs(hi));
    const double step = t[1] - t[0];
    const double mantissa = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    CHECK((std::abs(mantissa - 1) < 1e-6 || std::abs(mantissa - 2) < 1e-6 ||
           std::abs(mantissa - 5) < 1e-6));
  }
}

TEST_CASE("log_ticks: powers of ten, with 2 and 5 over at most two decades", "[plot]") {
  CHECK(log_ticks(0.3, 40.0) == std::vector<double>{0.1, 1.0, 10.0, 100.0});
  const std::vector<double> t = log_ticks(1.2, 3.0);
  REQUIRE(t.size() == 4);
  CHECK(t[0] == 1.0);
  CHECK(t[1] == 2.0);
  CHECK(t[2] == 5.0);
  CHECK(t[3] == 10.0);
  CHECK_THROWS_AS(log_ticks(0.0, 1.0), std::invalid_argument);
}

TEST_CASE("render_line_plot_png: a PNG of the requested size; bad plots are rejected", "[plot]") {
  TempDir tmp("plot");
  LinePlot p;
  p.width = 640;
  p.height = 400;
  p.log_y = true;
  PlotSeries s;
  s.x = {0, 1, 2, 3};
  s.y = {10, 3, 1, -1};  // the last point is not drawable on a log axis and is skipped
  p.series.push_back(s);
  const std::string file = (tmp.path / "p.png").string();
  render_line_plot_png(file, p);
  cairo_surface_t* img = cairo_image_surface_create_from_png(file.c_str());
  REQUIRE(cairo_surface_status(img) == CAIRO_STATUS_SUCCESS);
  CHECK(cairo_image_surface_get_width(img) == 640);
  CHECK(cairo_image_surface_get_height(img) == 400);
  cairo_surface_destroy(img);
  p.series[0].y.pop_back();
  CHECK_THROWS_AS(render_line_plot_png(file, p), std::invalid_argument);  // x, y lengths
  p.series[0].x.pop_back();
  p.series[0].y = {-1, -2, -3};
  CHECK_THROWS_AS(render_line_plot_png(file, p), std::invalid_argument);  // nothing drawable
}

TEST_CASE("unit_seed depends on the key and the base seed only", "[repro]") {
  CHECK(unit_seed(2017, "fit/twin/s1/run00") == unit_seed(2017, "fit/twin/s1/run00"));
  CHECK(unit_seed(2017, "fit/twin/s1/run00") != unit_seed(2017, "fit/twin/s1/run01"));
  CHECK(unit_seed(2017, "fit/twin/s1/run00") != unit_seed(2017, "fit/cross/s1/run00"));
  CHECK(unit_seed(2017, "fit/twin/s1/run00") != unit_seed(2018, "fit/twin/s1/run00"));
}

TEST_CASE("ica_evaluation_estimate equals the ICA's count when no empire can collapse", "[repro]") {
  IcaOptions o;
  o.countries = 10;
  o.imperialists = 1;  // one empire: nothing collapses
  o.decades = 5;
  const IcaResult r = run_ica(make_test_problem("sphere", 3), o);
  CHECK(r.evaluations == ica_evaluation_estimate(o));
  CHECK(ica_evaluation_estimate(o) == 10 + 5 * 9);
  o.countries = 15;  // Table 1's B1 C3: fewer colonies than imperialists -> 2 x 10 countries
  o.imperialists = 10;
  CHECK(ica_evaluation_estimate(o) == 20 + 5 * 10);
}

TEST_CASE("the paper preset is the paper's protocol; a bad option is refused by its name",
          "[repro]") {
  const ReproOptions paper = repro_preset("paper");
  CHECK(paper.runs == 10);
  CHECK(paper.ica.countries == 25);
  CHECK(paper.ica.imperialists == 2);
  CHECK(paper.ica.decades == 40);
  CHECK(paper.taguchi_decades == std::array<int, 3>{10, 20, 40});
  CHECK_NOTHROW(repro_preset("quick").validate());
  CHECK_THROWS_WITH(repro_preset("fast"), Catch::Contains("preset = fast"));
  ReproOptions o = repro_preset("quick");
  o.samples = {1, 10};
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("samples = 10"));
  o.samples = {2, 2};
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("samples = 2"));
  o = repro_preset("quick");
  o.runs = 0;
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("runs = 0"));
  CHECK_THROWS_WITH(repro_task_from_name("table5"), Catch::Contains("task = table5"));
  o = repro_preset("quick");
  CHECK(o.optimizers == std::vector<ReproOptimizer>{ReproOptimizer::Ica});  // the paper's
  o.optimizers = {ReproOptimizer::Lm, ReproOptimizer::Lm};
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("optimizers = 2 optimizers"));
  o.optimizers = {ReproOptimizer::Lm};
  o.task = ReproTask::Taguchi;  // a study of the ICA
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("optimizers = lm"));
  o.task = ReproTask::All;
  CHECK_NOTHROW(o.validate());
  CHECK_THROWS_WITH(repro_optimizer_from_name("pso"), Catch::Contains("optimizers = pso"));
  CHECK(four_corner_symmetry_from_name("eighth") == DrapeSymmetry::Eighth);
  CHECK(repro_preset("quick").four_corner_symmetry == DrapeSymmetry::Eighth);  // the default
  CHECK(repro_preset("paper").four_corner_symmetry == DrapeSymmetry::Eighth);
  CHECK_THROWS_WITH(four_corner_symmetry_from_name("half"),
                    Catch::Contains("four_corner_symmetry = half: accepted none|quarter|eighth"));
  o = repro_preset("quick");
  o.four_corner_symmetry = DrapeSymmetry::Half;  // four_corner has no half reduction of its own
  CHECK_THROWS_WITH(o.validate(), Catch::Contains("four_corner_symmetry = half"));
}

TEST_CASE("repro on the eighth: the same fits and Tables 4 and 6 as on the whole sheet",
          "[repro]") {
  TempDir tmp("repro-eighth");
  const fs::path whole = tmp.path / "whole", eighth = tmp.path / "eighth";
  fs::create_directories(whole);
  fs::create_directories(eighth);
  ReproOptions o = tiny_options(1);
  o.four_corner_symmetry = DrapeSymmetry::None;
  ReproTargets targets(o);
  run_repro(o, targets, whole, false);
  o.four_corner_symmetry = DrapeSymmetry::Eighth;
  run_repro(o, targets, eighth, false);
  for (const char* table : {"table4.csv", "table6.csv"}) {
    const auto a = read_csv(whole / table), b = read_csv(eighth / table);
    REQUIRE(a.size() == b.size());
    REQUIRE(a.size() == 2);  // header + twin sample 1
    const std::vector<std::string>& h = a[0];
    INFO(table);
    // The same ICA path: the same country (to the restriction's round-off), the same topology
    // and evaluation count, the same error to 1e-6 relative.
    for (const char* p : {"stiffness", "damping", "elongation_limit", "natural_length", "error"}) {
      const std::string& x = a[1][col(h, p)];
      const std::string& y = b[1][col(h, p)];
      INFO(p << ": " << x << " vs " << y);
      // Table 6's error is empty where its two_corner drape did not settle (drape_status says
      // why); that drape does not depend on four_corner's symmetry, so both tables agree.
      REQUIRE(x.empty() == y.empty());
      if (!x.empty())
        CHECK(std::stod(y) ==
              Approx(std::stod(x)).epsilon(std::string(p) == "error" ? 1e-6 : 1e-9));
    }
    CHECK(b[1][col(h, "topology")] == a[1][col(h, "topology")]);
    if (std::string(table) == "table6.csv")
      CHECK(b[1][col(h, "drape_status")] == a[1][col(h, "drape_status")]);
    if (std::string(table) == "table4.csv")
      CHECK(b[1][col(h, "evaluations")] == a[1][col(h, "evaluations")]);
  }
  const std::string report = knitsim::test::slurp(eighth / "report.md");
  CHECK(report.find("four_corner integrated on the eighth") != std::string::npos);
}

TEST_CASE(
    "repro table6, one sample, tiny budget: columns, paper values, errors recomputed, "
    "independent of --jobs",
    "[repro]") {
  TempDir tmp("repro");
  const fs::path d1 = tmp.path / "jobs1", d2 = tmp.path / "jobs2";
  fs::create_directories(d1);
  fs::create_directories(d2);
  const ReproOptions o1 = tiny_options(1);
  ReproTargets targets(o1);
  run_repro(o1, targets, d1, false);
  run_repro(tiny_options(2), targets, d2, false);

  // Determinism: the tables do not depend on the number of threads.
  for (const char* f : {"table4.csv", "table6.csv"})
    CHECK(knitsim::test::slurp(d1 / f) == knitsim::test::slurp(d2 / f));

  const Target& target = targets.get(SyntheticSet::Twin, 1);
  const PaperSample& paper = paper_sample(1);
  const auto t4 = read_csv(d1 / "table4.csv");
  REQUIRE(t4.size() == 2);  // header + twin sample 1
  const std::vector<std::string>& h = t4[0];
  const std::vector<std::string> expected = {"set",
                                             "sample",
                                             "runs",
                                             "best_run",
                                             "stiffness",
                                             "damping",
                                             "elongation_limit",
                                             "natural_length",
                                             "topology",
                                             "error",
                                             "stiffness_min",
                                             "stiffness_max",
                                             "damping_min",
                                             "damping_max",
                                             "elongation_limit_min",
                                             "elongation_limit_max",
                                             "natural_length_min",
                                             "natural_length_max",
                                             "topologies",
                                             "error_max",
                                             "evaluations",
                                             "failed_evaluations",
                                             "status",
                                             "paper_stiffness",
                                             "paper_damping",
                                             "paper_elongation_limit",
                                             "paper_natural_length",
                                             "paper_topology",
                                             "paper_error",
                                             "true_stiffness",
                                             "true_natural_length",
                                             "stiffness_rel_error",
                                             "natural_length_rel_error"};
  CHECK(h == expected);
  const std::vector<std::string>& r = t4[1];
  REQUIRE(r.size() == h.size());
  CHECK(r[col(h, "set")] == "twin");
  CHECK(r[col(h, "runs")] == "2");
  CHECK(std::stod(r[col(h, "paper_stiffness")]) == paper.stiffness);
  CHECK(std::stod(r[col(h, "paper_damping")]) == paper.damping);
  CHECK(std::stod(r[col(h, "paper_elongation_limit")]) == paper.elongation_limit);
  CHECK(std::stod(r[col(h, "paper_natural_length")]) == paper.natural_length);
  CHECK(r[col(h, "paper_topology")] == std::string(1, paper.topology));
  CHECK(std::stod(r[col(h, "paper_error")]) == paper.table4_error);
  CHECK(std::stod(r[col(h, "true_stiffness")]) == paper.stiffness);
  // 2 runs x (4 countries + 1 decade x 2 colonies), unless an empire collapsed.
  CHECK(std::stol(r[col(h, "evaluations")]) >= 2 * 6);
  // The best run's parameters lie within the runs' spread.
  for (const char* p : {"stiffness", "damping", "elongation_limit", "natural_length"}) {
    const double v = std::stod(r[col(h, p)]);
    CHECK(v >= std::stod(r[col(h, std::string(p) + "_min")]) * (1 - 1e-5));
    CHECK(v <= std::stod(r[col(h, std::string(p) + "_max")]) * (1 + 1e-5));
  }
  const std::vector<double> x = country(h, r);
  CHECK(std::stod(r[col(h, "stiffness_rel_error")]) ==
        Approx((x[0] - paper.stiffness) / paper.stiffness).epsilon(1e-5));

  // Our Table 4 error is objective() of the written parameters, recomputed.
  const DrapeFitOptions fo = repro_fit_options();
  const DrapeFitProblem four(sample_scene("four_corner", 1), target, fo);
  const DrapeEvaluation e4 = four.evaluate(x);
  REQUIRE_FALSE(e4.failed);
  CHECK(std::stod(r[col(h, "error")]) == Approx(e4.objective).epsilon(1e-12));

  // Table 6: the same parameters, the two_corner error recomputed, the paper's column.
  const auto t6 = read_csv(d1 / "table6.csv");
  REQUIRE(t6.size() == 2);
  const std::vector<std::string>& h6 = t6[0];
  CHECK(h6 == std::vector<std::string>{"set", "sample", "stiffness", "damping", "elongation_limit",
                                       "natural_length", "topology", "table4_error", "error",
                                       "drape_status", "paper_table4_error", "paper_error"});
  const std::vector<std::string>& r6 = t6[1];
  REQUIRE(r6.size() == h6.size());
  CHECK(country(h6, r6) == x);
  CHECK(r6[col(h6, "table4_error")] == r[col(h, "error")]);
  CHECK(std::stod(r6[col(h6, "paper_error")]) == paper.table6_error);
  const DrapeFitProblem two(sample_scene("two_corner", 1), target, fo);
  const DrapeEvaluation e6 = two.evaluate(x);
  // The row records the re-run as it ended (the repro default, `equilibrium`, settles it).
  INFO("two_corner re-run: " << to_string(e6.status) << ", " << e6.message);
  REQUIRE_FALSE(e6.failed);
  CHECK(r6[col(h6, "drape_status")] == "equilibrium");
  CHECK(std::stod(r6[col(h6, "error")]) == Approx(e6.objective).epsilon(1e-12));

  // The report and the manifest are there, naming the integrator.
  CHECK(fs::exists(d1 / "report.md"));
  CHECK(knitsim::test::slurp(d1 / "report.md").find("; integrator equilibrium,") != std::string::npos);
  CHECK(knitsim::test::slurp(d1 / "manifest.json").find("\"integrator\": \"equilibrium\"") !=
        std::string::npos);
}

TEST_CASE("knitsim repro: bad input is one line, exit 2, nothing written", "[repro][cli]") {
  TempDir tmp("repro-cli");
  for (const std::string& args :
       {std::string("table5"), std::string("table4 --samples 0"),
        std::string("table4 --samples 3-1"), std::string("table4 --preset fast"),
        std::string("table4 --jobs 0"), std::string("all --sets twin,wool"),
        std::string("table4 --targets /nonexistent"), std::string("table4 --optimizer xyz"),
        std::string("fig13 --optimizer lm"), std::string("table4 --optimizer lm,lm"),
        std::string("table4 --four-corner-symmetry half"),
        std::string("table4 --integrator rk4")}) {
    const fs::path out = tmp.path / "out";
    const knitsim::test::Run run =
        knitsim::test::run_knitsim("repro " + args + " --out '" + out.string() + "'", tmp);
    INFO(args << " -> " << run.err);
    CHECK(run.status == 2);
    CHECK(knitsim::test::lines(run.err).size() == 1);
    CHECK_FALSE(fs::exists(out));
  }
  // --samples takes the comma lists its help shows: a list is read as a whole (the error
  // names the list and the range), and a valid list passes on to the next check.
  const fs::path out = tmp.path / "out";
  const auto err_of = [&](const std::string& args) {
    const knitsim::test::Run run =
        knitsim::test::run_knitsim("repro " + args + " --out '" + out.string() + "'", tmp);
    CHECK(run.status == 2);
    CHECK_FALSE(fs::exists(out));
    return run.err;
  };
  CHECK(err_of("table4 --samples 1,10").find("--samples = 1,10: accepted") != std::string::npos);
  CHECK(err_of("table4 --samples 2,5-7 --jobs 0").find("--jobs") != std::string::npos);
  // A target file under another sample's name: its first line says which it is. Sample 2's
  // target copied as twin_sample1.csv would have fitted sample 1's fabric to sample 2's edges.
  const fs::path targets = tmp.path / "targets";
  fs::create_directories(targets);
  fs::copy_file(fs::path(KNITSIM_PAPER_DATA) / "targets" / "twin_sample2.csv",
                targets / "twin_sample1.csv");
  const std::string swapped =
      err_of("table4 --samples 1 --sets twin --targets '" + targets.string() + "'");
  CHECK(knitsim::test::lines(swapped).size() == 1);
  CHECK(swapped.find("twin_sample1.csv is not the target of twin sample 1: its first line says "
                     "\"Synthetic target (SPEC 2.8, src/synthetic_targets.hpp): twin, sample 2") !=
        std::string::npos);
}

TEST_CASE("knitsim repro killed after a unit and resumed writes the uninterrupted tables",
          "[repro][resume][cli]") {
  using namespace knitsim::test;
  TempDir tmp("repro-resume");
  const std::string args =
      "repro table4 --samples 1 --sets twin --runs 4 --decades 2 --countries 4 "
      "--imperialists 2 --no-pictures --quiet --out '";
  const fs::path whole = tmp.path / "whole", cut = tmp.path / "cut";
  REQUIRE(run_knitsim(args + whole.string() + "'", tmp).status == 0);

  // The same run, killed once its checkpoint holds the config line and at least one unit
  // (checked with the run stopped, so it cannot finish in between: cli_runner.hpp).
  const pid_t pid = start_knitsim(args + cut.string() + "'", tmp);
  REQUIRE(pid > 0);
  const fs::path checkpoint = cut / "fits.jsonl";
  long done = 0;
  const SignalledRun killed = signal_when(pid, SIGKILL, [&] {
    done = fs::exists(checkpoint) ? complete_lines(checkpoint) : 0;
    return done >= 2;
  });
  REQUIRE(killed.signalled);
  REQUIRE(WIFSIGNALED(killed.status));  // killed before it finished
  REQUIRE(done >= 2);
  REQUIRE(done < 1 + 4);
  CHECK(!fs::exists(cut / "table4.csv"));
  // The complete lines before the kill (a last line may have been cut short mid-write).
  std::vector<std::string> before = lines(slurp(checkpoint));
  if (!before.empty() && slurp(checkpoint).back() != '\n') before.pop_back();

  const Run resumed = run_knitsim(args + cut.string() + "' --resume", tmp);
  INFO(resumed.err);
  REQUIRE(resumed.status == 0);
  CHECK(slurp(cut / "table4.csv") == slurp(whole / "table4.csv"));
  // The units done before the kill were kept, not re-run: the checkpoint starts with them and
  // holds each of the 4 units once.
  const std::vector<std::string> after = lines(slurp(checkpoint));
  CHECK(after.size() == 1 + 4);
  REQUIRE(after.size() >= before.size());
  CHECK(std::equal(before.begin(), before.end(), after.begin()));

  // The integrator is part of the settings: resuming with another one is refused.
  const Run other = run_knitsim(args + cut.string() + "' --resume --integrator cvode-bdf", tmp);
  CHECK(other.status == 2);
  CHECK(lines(other.err).size() == 1);
  CHECK(other.err.find("integrator") != std::string::npos);
}

TEST_CASE("repro table6 --optimizer ica,lm: LM tables, errors recomputed, the comparison",
          "[repro][lm]") {
  TempDir tmp("repro-lm");
  ReproOptions o = tiny_options(1);
  o.runs = 1;
  o.optimizers = {ReproOptimizer::Ica, ReproOptimizer::Lm};
  ReproTargets targets(o);
  run_repro(o, targets, tmp.path, false);
  const Target& target = targets.get(SyntheticSet::Twin, 1);
  const PaperSample& paper = paper_sample(1);

  // table4_lm.csv: Table 4's columns, then cpu_seconds; one run.
  const auto ica = read_csv(tmp.path / "table4.csv");
  const auto t4 = read_csv(tmp.path / "table4_lm.csv");
  REQUIRE(t4.size() == 2);
  const std::vector<std::string>& h = t4[0];
  std::vector<std::string> expected = ica[0];
  expected.push_back("cpu_seconds");
  CHECK(h == expected);
  const std::vector<std::string>& r = t4[1];
  REQUIRE(r.size() == h.size());
  CHECK(r[col(h, "runs")] == "1");
  CHECK(std::stod(r[col(h, "cpu_seconds")]) > 0.0);
  // The error is objective() of the written parameters (LM scores the Newton-polished
  // equilibrium, objective() the integrator's, settled to equilibrium_tol: ~1e-9 apart).
  const std::vector<double> x = country(h, r);
  const DrapeFitProblem four(sample_scene("four_corner", 1), target, repro_fit_options());
  CHECK(std::stod(r[col(h, "error")]) == Approx(four.evaluate(x).objective).epsilon(1e-7));

  // table6_lm.csv: Table 6's columns plus evaluations and cpu_seconds of the fit.
  const auto t6 = read_csv(tmp.path / "table6_lm.csv");
  const auto ica6 = read_csv(tmp.path / "table6.csv");
  REQUIRE(t6.size() == 2);
  expected = ica6[0];
  expected.insert(expected.end(), {"evaluations", "cpu_seconds"});
  CHECK(t6[0] == expected);
  CHECK(country(t6[0], t6[1]) == x);
  CHECK(t6[1][col(t6[0], "evaluations")] == r[col(h, "evaluations")]);

  // lm_vs_ica.csv: the two tables side by side, ratios and recovery errors consistent.
  const auto c = read_csv(tmp.path / "lm_vs_ica.csv");
  REQUIRE(c.size() == 2);
  const std::vector<std::string>& hc = c[0];
  const std::vector<std::string>& rc = c[1];
  REQUIRE(rc.size() == hc.size());
  CHECK(rc[col(hc, "lm_error")] == r[col(h, "error")]);
  CHECK(rc[col(hc, "ica_error")] == ica[1][col(ica[0], "error")]);
  CHECK(rc[col(hc, "lm_two_corner_error")] == t6[1][col(t6[0], "error")]);
  const double lm_evals = std::stod(rc[col(hc, "lm_evaluations")]);
  const double ica_evals = std::stod(rc[col(hc, "ica_evaluations")]);
  CHECK(ica_evals == std::stod(ica[1][col(ica[0], "evaluations")]));
  CHECK(std::stod(rc[col(hc, "evaluation_ratio")]) == Approx(ica_evals / lm_evals).epsilon(1e-3));
  CHECK(rc[col(hc, "lm_not_worse")] ==
        (std::stod(rc[col(hc, "lm_error")]) <= std::stod(rc[col(hc, "ica_error")]) ? "1" : "0"));
  CHECK(std::stod(rc[col(hc, "lm_k_over_L0_rel_error")]) ==
        Approx((x[0] / x[3]) / (paper.stiffness / paper.natural_length) - 1.0).margin(1e-5));

  // k at the true L0: a minimum of the objective along k (with L0, topology at the truth and
  // the blind damping and elongation limit at the box centre), its error recomputed.
  const double k = std::stod(rc[col(hc, "k_at_true_L0")]);
  CHECK(std::stod(rc[col(hc, "k_at_true_L0_rel_error")]) ==
        Approx((k - paper.stiffness) / paper.stiffness).margin(1e-5));
  const DrapeFitBounds box;
  auto at = [&](double stiffness) {
    return four
        .evaluate({stiffness, 0.5 * (box.lower[1] + box.upper[1]),
                   0.5 * (box.lower[2] + box.upper[2]), paper.natural_length,
                   paper.topology - 'a' + 0.5})
        .objective;
  };
  const double e = at(k);
  CHECK(std::stod(rc[col(hc, "k_at_true_L0_error")]) == Approx(e).epsilon(1e-7));
  if (k > box.lower[0] * 1.01) CHECK(at(k * 0.99) >= e - 1e-9);
  if (k < box.upper[0] * 0.99) CHECK(at(k * 1.01) >= e - 1e-9);
  // The checkpoint holds the ICA run and the LM unit under their keys.
  const std::string checkpoint = knitsim::test::slurp(tmp.path / "fits.jsonl");
  CHECK(checkpoint.find("\"fit/twin/s1/run00\"") != std::string::npos);
  CHECK(checkpoint.find("\"lm/twin/s1\"") != std::string::npos);
}
