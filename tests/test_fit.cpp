// Drape fitting (src/fit/drape_fit.hpp) on twin targets, failed evaluations, determinism across
// thread counts, and the paper's tables (paper_repro/data) against the code's defaults.
//
// Speed: the base scene is a 30 cm sheet (fabric.width = 0.3), so L0 ~ 5 cm gives a 7 x 7 grid
// and one evaluation costs a few ms.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "src/base/table.hpp"
#include "src/cli/commands.hpp"
#include "src/fit/drape_fit.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/scene.hpp"

using namespace knitsim;

namespace {

// The twin's true parameters: sample 1 of Table 4, but L0 = 5 cm on a 30 cm sheet.
const std::vector<double> kTrue = {852.0, 12.0, 5.0, 0.05, 0.5};

Scene small_base(const std::vector<std::string>& extra = {}) {
  std::vector<std::string> sets = {"fabric.width=0.3"};
  sets.insert(sets.end(), extra.begin(), extra.end());
  return load_scene("four_corner", sets);
}

// A noise-free twin target: the model's own edges at kTrue, written as a target CSV.
void write_twin_target(const std::string& path) {
  // Built from scene keys, independently of DrapeFitProblem::params_of.
  const Scene twin =
      small_base({"model.stiffness=852", "model.damping=12", "model.elongation_limit=5",
                  "model.natural_length=0.05", "model.topology=a"});
  const DrapeResult run = run_drape(twin, default_integrator());
  REQUIRE(run.stats.status == RunStatus::Equilibrium);
  TargetScene scene{"four_corner", {}, {}};
  for (const EdgeFit& e : measure_edges(run.grid, run.positions)) {
    TargetEdge t;
    t.name = e.name;
    t.kind = TargetKind::Points;
    t.points = e.points;
    scene.edges.push_back(t);
  }
  write_target_csv(Target{{scene}}, path, {"twin of kTrue on a 30 cm sheet, no noise"});
}

Target twin_target() {
  const std::string path = std::filesystem::temp_directory_path() /
                           ("knitsim_test_fit_" + std::to_string(::getpid()) + ".csv");
  write_twin_target(path);
  Target read = read_target_csv(path);
  std::filesystem::remove(path);
  return read;
}

// Runs `knitsim fit ARGS` in process (the command as main() registers it).
void run_fit_command(std::vector<std::string> args) {
  CLI::App app;
  register_fit_command(app);
  args.insert(args.begin(), {"knitsim", "fit"});
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  app.parse(static_cast<int>(argv.size()), argv.data());
}

// Box around the twin: L0 narrow (k and L0 are nearly confounded in normalised edges: the
// strain scales with rho g L0 / k), everything else as Table 3.
DrapeFitOptions twin_options(int decades, int countries) {
  DrapeFitOptions o;
  o.bounds.lower[kGeneNaturalLength] = 0.0495;
  o.bounds.upper[kGeneNaturalLength] = 0.0505;
  o.ica.decades = decades;
  o.ica.countries = countries;
  o.ica.imperialists = 2;
  o.ica.seed = 3;
  return o;
}

// RFC 4180 rows of a small CSV (quoted fields may hold commas); no embedded newlines.
std::vector<std::map<std::string, std::string>> read_csv(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in);
  auto split = [](const std::string& line) {
    std::vector<std::string> f(1);
    bool quoted = false;
    for (char c : line) {
      if (c == '"')
        quoted = !quoted;
      else if (c == ',' && !quoted)
        f.emplace_back();
      else
        f.back() += c;
    }
    return f;
  };
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> f = split(line);
    REQUIRE(f.size() == header.size());
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < f.size(); ++i) row[header[i]] = f[i];
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

TEST_CASE("country -> drape parameters: box of Table 3 and the topology encoding") {
  const Target target = twin_target();
  DrapeFitOptions o;
  const DrapeFitProblem p(small_base(), target, o);
  CHECK(p.target_scene() == "four_corner");
  const DrapeParams a = p.params_of({900, 15, 10, 0.045, 0.999});
  CHECK(a.stiffness == 900);
  CHECK(a.damping == 15);
  CHECK(a.elongation_limit == 10);
  CHECK(a.natural_length == 0.045);
  CHECK(a.topology == 'a');
  CHECK(a.width == 0.3);  // from the base scene
  CHECK(p.params_of({900, 15, 10, 0.045, 1.0}).topology == 'b');
  CHECK(p.params_of({900, 15, 10, 0.045, 2.999}).topology == 'c');

  DrapeFitOptions bc = o;  // topology restricted to b, c: u in [1, 3)
  bc.bounds.lower[kGeneTopology] = 1;
  const DrapeFitProblem q(small_base(), target, bc);
  CHECK(q.params_of({900, 15, 10, 0.045, 1.5}).topology == 'b');
  CHECK(q.params_of({900, 15, 10, 0.045, 2.5}).topology == 'c');

  DrapeFitOptions bad = o;
  bad.bounds.upper[kGeneTopology] = 2.5;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("bounds.topology"));
  bad = o;
  bad.bounds.lower[kGeneStiffness] = 1300;
  CHECK_THROWS_WITH(bad.validate(), Catch::Contains("bounds.stiffness = [1300, 1200]"));
  bad = o;
  bad.integrator = "no-such";
  CHECK_THROWS_AS(bad.validate(), std::invalid_argument);
  // The target must hold the matching scene, with edges.
  CHECK_THROWS_WITH(DrapeFitProblem(load_scene("two_corner"), target, o),
                    Catch::Contains("two_corner"));
  CHECK_THROWS_WITH(DrapeFitProblem(small_base(), Target{{{"four_corner", {}, {}}}}, o),
                    Catch::Contains("no edges"));
}

TEST_CASE("twin target: zero error at the true parameters, and the ICA moves toward them") {
  const Target target = twin_target();
  const DrapeFitProblem p(small_base(), target, twin_options(2, 6));
  const DrapeEvaluation at_truth = p.evaluate(kTrue);
  REQUIRE(!at_truth.failed);
  CHECK(at_truth.objective < 1e-6);  // the same run: only the CSV round trip (17 digits)
  const DrapeEvaluation soft = p.evaluate({600, 12, 5, 0.05, 0.5});
  REQUIRE(!soft.failed);
  CHECK(soft.objective > 0.05);  // a 30 % softer sheet sags visibly more

  const DrapeFitResult r = fit_drape(p);
  INFO("initial best " << r.history.front().best_cost << ", final " << r.objective);
  long expected = 6;  // header of src/fit/ica.hpp: countries, then countries - empires per decade
  for (size_t d = 1; d < r.history.size(); ++d) expected += 6 - r.history[d - 1].empires;
  CHECK(r.evaluations == expected);
  CHECK(r.failed_evaluations == 0);
  CHECK(r.objective < r.history.front().best_cost);
  CHECK(r.objective == p.evaluate(r.best_x).objective);  // deterministic re-run
}

TEST_CASE("twin target: a larger budget recovers k / L0, the combination the edges determine") {
  // At a fixed mesh (n = 6 for every L0 of the box) the normalised edges depend on k and L0
  // only through the strain scale rho g L0 / k: k alone is not identifiable (the box holds L0
  // to +-1 %, so k may be off by that much with a perfect fit), k / L0 is.
  const Target target = twin_target();
  const DrapeFitProblem p(small_base(), target, twin_options(8, 12));
  auto objective_at = [&](double k_factor, double L0_factor) {
    std::vector<double> x = kTrue;
    x[kGeneStiffness] *= k_factor;
    x[kGeneNaturalLength] *= L0_factor;
    return p.evaluate(x).objective;
  };
  // k and L0 scaled together leave the objective at the runs' stop noise (measured 1.5e-8);
  // k alone moves it linearly: slope S = objective per relative change of k / L0 (0.90).
  CHECK(objective_at(1.01, 1.01) < 1e-5);
  const double delta = 0.01;
  const double slope = std::min(objective_at(1 + delta, 1), objective_at(1 - delta, 1)) / delta;
  REQUIRE(slope > 0.5);

  const DrapeFitResult r = fit_drape(p);
  const double ratio = (r.params.stiffness / r.params.natural_length) / (852.0 / 0.05);
  INFO("k " << r.params.stiffness << ", L0 " << r.params.natural_length << ", k / L0 off by "
            << ratio - 1 << ", objective " << r.objective << ", slope " << slope);
  CHECK(r.params.topology == 'a');
  // Measured 1.1e-3 (seed 3; seeds 4-7: 4.2e-4 to 4.6e-3): this budget gets k / L0 within 1 %.
  CHECK(r.objective < 0.01);
  // The objective is a function of k / L0 alone and linear in its error, so the fit's k / L0
  // is off by objective / S. Measured: objective / |k / L0 error| = 0.888 to 0.925 over errors
  // up to 3 %; 1.2 / S covers that. Measured 0.118 % against a bound of 0.142 %.
  CHECK(std::abs(ratio - 1) <= 1.2 * r.objective / slope);
}

TEST_CASE("failed evaluations are scored, and the fit completes") {
  // The dynamics (cvode-bdf) make drapes that stop at t_max; the equilibrium solver's t stays
  // where the pins stop, so it never meets t_max.
  const Target target = twin_target();
  const auto dynamics_options = [](int decades, int countries) {
    DrapeFitOptions o = twin_options(decades, countries);
    o.integrator = "cvode-bdf";
    return o;
  };
  SECTION("every run stops at t_max: all evaluations fail") {
    const DrapeFitProblem p(small_base({"run.t_max=1"}), target, dynamics_options(2, 6));
    const DrapeEvaluation e = p.evaluate(kTrue);
    CHECK(e.failed);
    CHECK(e.status == RunStatus::TimeLimit);
    CHECK(std::isnan(e.objective));
    const DrapeFitResult r = fit_drape(p);
    CHECK(r.status == IcaStatus::AllFailed);
    CHECK(r.failed_evaluations == r.evaluations);
    CHECK(r.objective == p.options().ica.failure_cost);
  }
  SECTION("a t_max between settling times: some fail, the fit ranks them last") {
    // Settling times over the box spread from ~1e3 s to ~1e6 s (measured; not monotone in
    // k or c): t_max = 3000 s keeps the twin (settles at ~2.1e3 s) and fails a share of the
    // countries.
    const DrapeFitOptions o = dynamics_options(2, 6);
    const DrapeFitProblem p(small_base({"run.t_max=3000"}), target, o);
    CHECK(!p.evaluate(kTrue).failed);
    const DrapeFitResult r = fit_drape(p);
    INFO("failed " << r.failed_evaluations << " of " << r.evaluations);
    CHECK(r.failed_evaluations > 0);
    CHECK(r.failed_evaluations < r.evaluations);
    CHECK(r.objective < o.ica.failure_cost);
  }
}

TEST_CASE("the same seed gives the same fit with 1 and 2 threads") {
  const Target target = twin_target();
  DrapeFitOptions one = twin_options(2, 6), two = one;
  two.ica.jobs = 2;
  const DrapeFitResult a = fit_drape(DrapeFitProblem(small_base(), target, one));
  const DrapeFitResult b = fit_drape(DrapeFitProblem(small_base(), target, two));
  CHECK(a.best_x == b.best_x);
  CHECK(a.objective == b.objective);
  CHECK(a.evaluations == b.evaluations);
}

TEST_CASE("paper 1's tables (paper_repro/data) parse and agree with the code's defaults") {
  const std::string dir = KNITSIM_PAPER_DATA;
  const auto t1 = read_csv(dir + "/table1_ica_levels.csv");
  REQUIRE(t1.size() == 7);
  for (int f = 0; f < 7; ++f)
    for (int l = 0; l < 3; ++l)
      CHECK(std::stod(t1[f].at("level" + std::to_string(l + 1))) == ica_table1_levels()[f][l]);
  CHECK(t1[1].at("name") == "countries");  // the B/C swap reading
  CHECK(t1[2].at("name") == "imperialists");

  const auto t2 = read_csv(dir + "/table2_samples.csv");
  REQUIRE(t2.size() == 9);
  CHECK(std::stod(t2[0].at("weight_g_m2")) == DrapeParams{}.areal_density);
  for (const auto& row : t2)  // loop density = wale x course density (per cm^2)
    CHECK(std::stod(row.at("loop_density_per_cm2")) ==
          std::stod(row.at("wale_density_per_cm")) * std::stod(row.at("course_density_per_cm")));

  const auto t3 = read_csv(dir + "/table3_bounds.csv");
  REQUIRE(t3.size() == 4);
  const DrapeFitBounds box;
  for (int g = 0; g < 4; ++g) {
    CHECK(t3[g].at("parameter") == drape_gene_names()[g]);
    CHECK(std::stod(t3[g].at("lower")) == box.lower[g]);
    CHECK(std::stod(t3[g].at("upper")) == box.upper[g]);
  }

  for (const char* name : {"/table4_four_corner.csv", "/table6_two_corner.csv"}) {
    const auto t = read_csv(dir + name);
    REQUIRE(t.size() == 9);
    for (const auto& row : t) {  // natural length printed in mm (paper_repro/data/README.md)
      const double mm = std::stod(row.at("natural_length_printed"));
      CHECK(std::stod(row.at("natural_length_m")) == Approx(mm / 1000).epsilon(1e-15));
      CHECK(std::stod(row.at("natural_length_m")) >= box.lower[kGeneNaturalLength]);
      CHECK(std::stod(row.at("natural_length_m")) <= box.upper[kGeneNaturalLength]);
    }
    const DrapeParams d;  // built-in defaults are sample 1
    CHECK(std::stod(t[0].at("stiffness_N_m")) == d.stiffness);
    CHECK(std::stod(t[0].at("natural_length_m")) == d.natural_length);
    CHECK(std::stod(t[0].at("damping_N_s_m")) == d.damping);
  }
  const auto t6 = read_csv(dir + "/table6_two_corner.csv");
  CHECK(t6[8].at("error_printed") == "2,6");
  CHECK(std::stod(t6[8].at("error_percent")) == 2.6);
}

TEST_CASE(
    "knitsim fit: bad input writes nothing; a run writes the summary docs/summary_json.md names") {
  namespace fs = std::filesystem;
  const fs::path tmp =
      fs::temp_directory_path() / ("knitsim_test_fit_cli_" + std::to_string(::getpid()));
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  const std::string target = (tmp / "twin.csv").string();
  write_twin_target(target);
  const std::string out = (tmp / "out").string();
  const std::vector<std::string> base = {"--scene", "four_corner", "--set",  "fabric.width=0.3",
                                         "--out",   out,           "--quiet"};
  auto with = [&](std::vector<std::string> extra) {
    extra.insert(extra.end(), base.begin(), base.end());
    return extra;
  };
  CHECK_THROWS_WITH(run_fit_command(with({"--target", (tmp / "missing.csv").string()})),
                    Catch::Contains("cannot open target file"));
  CHECK_THROWS_WITH(run_fit_command(with({"--target", target, "--countries", "1"})),
                    Catch::StartsWith("--countries = 1"));
  CHECK_THROWS_WITH(run_fit_command(with({"--target", target, "--integrator", "nope"})),
                    Catch::StartsWith("--integrator = nope"));
  CHECK_THROWS_WITH(run_fit_command(with({"--target", target, "--optimizer", "pso"})),
                    Catch::StartsWith("--optimizer = pso"));
  CHECK_THROWS_WITH(
      run_fit_command({"--scene", "two_corner", "--target", target, "--out", out, "--quiet"}),
      Catch::Contains("two_corner"));
  CHECK(!fs::exists(out));

  run_fit_command(with({"--target", target, "--decades", "2", "--countries", "6", "--jobs", "2"}));
  std::ifstream in(fs::path(out) / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  for (const char* key : {"stiffness", "damping", "elongation_limit", "natural_length"})
    CHECK(s.at("params").at(key).is_number());
  CHECK(s.at("params").at("topology").get<std::string>().size() == 1);
  CHECK(s.at("objective").get<double>() < 1.0);
  CHECK(s.at("evaluations").get<long>() >= 6 + 2 * 4);
  CHECK(s.at("history").size() == 3);
  std::ifstream history(fs::path(out) / "history.csv");
  std::string line;
  int lines = 0;
  while (std::getline(history, line)) ++lines;
  CHECK(lines == 1 + 3);
  for (const char* f : {"manifest.json", "drape/nodes.csv", "drape/drape.png", "drape/edges.csv",
                        "drape/target_edges.csv", "drape/summary.json"})
    CHECK(fs::exists(fs::path(out) / f));
  fs::remove_all(tmp);
}
