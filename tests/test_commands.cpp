// The command glue, end to end on the built binary, to SUCCESS: knitsim taguchi, optimize, demo
// and repro taguchi | fig13 | all, each with the smallest budget its options allow. Each test
// checks the exit status, that the promised outputs exist and are well formed (CSV headers,
// finite numbers, the report naming each table), and at least one property that breaks if the
// glue does: a value the command prints or writes, recomputed by hand from its own inputs or
// from another output of the same run (a response from the checkpoint, an S/N from the
// response, a curve from the best run's history, a sum of squares from the level means).
//
// Cost (Release, one core, 2026-11-27): taguchi and optimize < 0.1 s, demo 3 s (its comparison
// capped at 0.5 s per integrator by demo --max-wall), repro fig13 0.2 s; repro taguchi and repro all ~10 s each (the Taguchi
// experiment's 27 ICA fits have no budget option below the quick preset's). ctest runs the two
// repro cases as test_commands_repro_taguchi and test_commands_repro_all, in parallel with the
// rest.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "models/drape_grid.hpp"
#include "solvers/integrator.hpp"
#include "src/scene/scene.hpp"
#include "tests/cli_runner.hpp"
#include "tests/test_systems.hpp"

using namespace knitsim;
using namespace knitsim::test;
using nlohmann::json;

namespace {

// A CSV without quoted cells: header and rows of cells.
struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  size_t col(const std::string& name) const {
    const auto it = std::find(header.begin(), header.end(), name);
    REQUIRE(it != header.end());
    return static_cast<size_t>(it - header.begin());
  }
  double number(size_t row, const std::string& name) const {
    return std::stod(rows.at(row).at(col(name)));
  }
};

Csv read_csv(const fs::path& p) {
  REQUIRE(fs::exists(p));
  Csv csv;
  for (const std::string& line : lines(slurp(p))) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream in(line);
    while (std::getline(in, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    if (csv.header.empty())
      csv.header = cells;
    else
      csv.rows.push_back(cells);
  }
  for (const auto& r : csv.rows) REQUIRE(r.size() == csv.header.size());
  return csv;
}

// Every cell of the named columns parses as a finite number.
void check_finite(const Csv& csv, const std::vector<std::string>& columns) {
  for (size_t r = 0; r < csv.rows.size(); ++r)
    for (const std::string& c : columns) {
      INFO("row " << r + 1 << ", column " << c << ": " << csv.rows[r][csv.col(c)]);
      CHECK(std::isfinite(csv.number(r, c)));
    }
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

bool is_png(const fs::path& p) { return slurp(p).rfind("\x89PNG\r\n\x1a\n", 0) == 0; }

// The checkpoint lines after the config line: key -> result.
std::map<std::string, json> checkpoint_results(const fs::path& p) {
  std::map<std::string, json> out;
  const std::vector<std::string> all = lines(slurp(p));
  REQUIRE(all.size() >= 2);
  REQUIRE(json::parse(all[0]).contains("config"));
  for (size_t i = 1; i < all.size(); ++i) {
    const json j = json::parse(all[i]);
    out[j.at("key").get<std::string>()] = j.at("result");
  }
  return out;
}

// Taguchi's printed L27(3^13), levels 1..3, runs 1..27 (as in test_taguchi.cpp), and the
// columns of the factors A..G (src/fit/taguchi.hpp, default_l27_columns).
const char* const kPublishedL27[27] = {
    "1111111111111", "1111222222222", "1111333333333", "1222111222333", "1222222333111",
    "1222333111222", "1333111333222", "1333222111333", "1333333222111", "2123123123123",
    "2123231231231", "2123312312312", "2231123231312", "2231231312123", "2231312123231",
    "2312123312231", "2312231123312", "2312312231123", "3132132132132", "3132213213213",
    "3132321321321", "3213132213321", "3213213321132", "3213321132213", "3321132321213",
    "3321213132321", "3321321213132"};
const int kFactorColumns[7] = {1, 2, 5, 9, 10, 12, 13};
int level(int run, int column) { return kPublishedL27[run][column - 1] - '0'; }  // run 0..26

const std::vector<std::string> kFactors = {"A", "B", "C", "D", "E", "F", "G"};

// The S/N, effects and ANOVA tables of an L27 analysis with factors A..G on the default columns
// are consistent with `eta` (S/N per run, as written with 6 significant digits): each level
// mean is the mean of eta over its 9 runs, delta their spread, SS_f = 9 sum (mean_l - mean)^2.
void check_analysis(const Csv& effects, const Csv& anova, const std::vector<double>& eta) {
  REQUIRE(eta.size() == 27);
  const double mean = std::accumulate(eta.begin(), eta.end(), 0.0) / 27;
  REQUIRE(effects.rows.size() == 7);
  for (int f = 0; f < 7; ++f) {
    INFO("factor " << kFactors[f]);
    CHECK(effects.rows[f][effects.col("factor")] == kFactors[f]);
    CHECK(effects.rows[f][effects.col("column")] == std::to_string(kFactorColumns[f]));
    double m[3] = {0, 0, 0}, ss = 0.0;
    for (int r = 0; r < 27; ++r) m[level(r, kFactorColumns[f]) - 1] += eta[r] / 9;
    for (int l = 0; l < 3; ++l) {
      CHECK(effects.number(f, "level" + std::to_string(l + 1)) == Approx(m[l]).margin(1e-4));
      ss += 9 * (m[l] - mean) * (m[l] - mean);
    }
    CHECK(effects.number(f, "delta") ==
          Approx(*std::max_element(m, m + 3) - *std::min_element(m, m + 3)).margin(1e-4));
    const int best = static_cast<int>(std::max_element(m, m + 3) - m) + 1;
    CHECK(effects.rows[f][effects.col("optimal")] == kFactors[f] + std::to_string(best));
    CHECK(anova.rows[f][anova.col("source")] == kFactors[f]);
    CHECK(anova.number(f, "ss") == Approx(ss).epsilon(1e-4).margin(1e-6));
  }
  double ss_total = 0.0;
  for (double e : eta) ss_total += (e - mean) * (e - mean);
  const Csv& a = anova;
  CHECK(a.rows.back()[a.col("source")] == "total");
  CHECK(a.number(a.rows.size() - 1, "ss") == Approx(ss_total).epsilon(1e-4).margin(1e-6));
  CHECK(a.number(a.rows.size() - 1, "dof") == 26);
}

}  // namespace

TEST_CASE("knitsim taguchi: S/N, effects and ANOVA of a responses file with known answers") {
  // Two replicates +-y per run with y = 10^(-eta / 20), so eta = -10 log10(mean y^2) exactly:
  // eta = 10 (a - 1) + 5 (b - 1) + [column 3 at level 1] dB, a and b the levels of columns 1
  // and 2 (factors A and B). By hand: A's level means 5 + 1/3, 15 + 1/3, 25 + 1/3 (column 3
  // is orthogonal to column 1), B's 10 + 1/3, 15 + 1/3, 20 + 1/3; SS_A = 9 (100 + 0 + 100) =
  // 1800, SS_B = 450; the unassigned column 3 carries 9 ((2/3)^2 + 2 (1/3)^2) = 6 of error over
  // 12 dof, so F_A = 900 / 0.5 = 1800, F_B = 450; SS_total = 2256.
  TempDir tmp("commands-taguchi");
  std::vector<double> eta(27);
  {
    std::ofstream f(tmp.path / "responses.csv");
    f.precision(17);
    f << "run,y1,y2\n";
    for (int r = 0; r < 27; ++r) {
      eta[r] = 10.0 * (level(r, 1) - 1) + 5.0 * (level(r, 2) - 1) + (level(r, 3) == 1 ? 1 : 0);
      const double y = std::pow(10.0, -eta[r] / 20);
      f << r + 1 << "," << y << "," << -y << "\n";
    }
  }
  const fs::path out = tmp.path / "out";
  const Run run = run_knitsim("taguchi --responses '" + (tmp.path / "responses.csv").string() +
                                  "' --out '" + out.string() + "'",
                              tmp);
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.err.empty());
  for (const char* f : {"sn.csv", "effects.csv", "anova.csv", "manifest.json"})
    CHECK(fs::exists(out / f));

  const Csv sn = read_csv(out / "sn.csv");
  CHECK(sn.header == std::vector<std::string>{"run", "A", "B", "C", "D", "E", "F", "G", "sn"});
  REQUIRE(sn.rows.size() == 27);
  for (int r = 0; r < 27; ++r) {
    INFO("run " << r + 1);
    CHECK(sn.rows[r][0] == std::to_string(r + 1));
    for (int f = 0; f < 7; ++f)
      CHECK(sn.rows[r][1 + f] == std::to_string(level(r, kFactorColumns[f])));
    CHECK(sn.number(r, "sn") == Approx(eta[r]).margin(1e-9));
  }
  const Csv effects = read_csv(out / "effects.csv");
  const Csv anova = read_csv(out / "anova.csv");
  CHECK(effects.header == std::vector<std::string>{"factor", "column", "level1", "level2", "level3",
                                                   "delta", "rank", "optimal"});
  CHECK(anova.header ==
        std::vector<std::string>{"source", "column", "ss", "dof", "ms", "f", "percent", "pooled"});
  check_analysis(effects, anova, eta);
  // The hand-computed numbers of the header comment.
  CHECK(effects.number(0, "level1") == Approx(5 + 1.0 / 3));
  CHECK(effects.number(1, "level3") == Approx(20 + 1.0 / 3));
  CHECK(effects.rows[0][effects.col("rank")] == "1");
  CHECK(anova.number(0, "ss") == Approx(1800));
  CHECK(anova.number(1, "ss") == Approx(450));
  CHECK(anova.number(0, "f") == Approx(1800));
  CHECK(anova.number(1, "f") == Approx(450));
  CHECK(anova.number(anova.rows.size() - 1, "ss") == Approx(2256));
  const json manifest = json::parse(slurp(out / "manifest.json"));
  CHECK(manifest.at("command") == "taguchi");
  CHECK(manifest.at("options").at("replicates") == 2);
  CHECK(contains(manifest.at("options").at("optimal_levels").get<std::string>(), "A3 B3"));
  CHECK(contains(run.out, "optimal levels: A3 B3"));
}

TEST_CASE("knitsim optimize: the ICA reaches the sphere's minimum; the report is its own run's") {
  TempDir tmp("commands-optimize");
  const Run run = run_knitsim("optimize --problem sphere --dim 2 --seed 1", tmp);
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  const std::vector<std::string> out = lines(run.out);
  REQUIRE(out.size() >= 4);
  // Ends with exactly `best: <cost>` and `evaluations: <n>` (src/cli/cmd_optimize.cpp).
  const std::string best_line = out[out.size() - 2], evaluations_line = out.back();
  REQUIRE(best_line.rfind("best: ", 0) == 0);
  REQUIRE(evaluations_line.rfind("evaluations: ", 0) == 0);
  const double best = std::stod(best_line.substr(6));
  const long evaluations = std::stol(evaluations_line.substr(13));
  // The sphere's minimum is 0 at the origin; 40 decades of 25 countries reach ~1e-6
  // (measured 2.5e-7 to 8.6e-7 for seeds 1-3) from a box of half-width 100.
  CHECK(std::isfinite(best));
  CHECK(best >= 0.0);
  CHECK(best < 1e-4);
  // The printed point is the best one: its cost (x printed with 8 digits) is `best`.
  const auto x_line = std::find_if(out.begin(), out.end(),
                                   [](const std::string& l) { return l.rfind("x:", 0) == 0; });
  REQUIRE(x_line != out.end());
  std::istringstream xs(x_line->substr(2));
  double x0 = NAN, x1 = NAN;
  xs >> x0 >> x1;
  CHECK(x0 * x0 + x1 * x1 == Approx(best).epsilon(1e-6));
  // The decade table: decades 0..40, cumulative evaluations ending at the total, the best
  // never worse than the decade before (the best imperialist is kept).
  std::vector<std::vector<std::string>> table;
  for (const std::string& l : out) {
    std::istringstream in(l);
    std::vector<std::string> cells;
    for (std::string c; in >> c;) cells.push_back(c);
    if (cells.size() == 5 && std::all_of(cells[0].begin(), cells[0].end(), ::isdigit))
      table.push_back(cells);
  }
  REQUIRE(table.size() == 41);
  for (size_t d = 0; d < table.size(); ++d) {
    CHECK(table[d][0] == std::to_string(d));
    if (d > 0) CHECK(std::stod(table[d][1]) <= std::stod(table[d - 1][1]));
  }
  CHECK(std::stol(table.back()[4]) == evaluations);
  CHECK(std::stod(table.back()[1]) == Approx(best).epsilon(1e-7));
}

TEST_CASE("knitsim demo: scenes, the comparison of every integrator, report, exit 0") {
  TempDir tmp("commands-demo");
  const fs::path out = tmp.path / "demo";
  const Run run =
      run_knitsim("demo --max-wall 0.5 --out '" + out.string() + "'", tmp);
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(contains(run.out, "report: " + (out / "report.md").string()));
  for (const char* scene : {"four_corner", "two_corner"})
    for (const char* f : {"summary.json", "nodes.csv", "drape.vtk", "drape.png", "manifest.json"})
      CHECK(fs::exists(out / scene / f));
  CHECK(is_png(out / "four_corner" / "drape.png"));
  // The scenes ran the built-in sample-1 fabric: four_corner's sag is the independent
  // implementation's 1.288 cm (test_drape_answers.cpp).
  const json four = json::parse(slurp(out / "four_corner" / "summary.json"));
  CHECK(four.at("status") == "equilibrium");
  CHECK(four.at("centre_sag_m").get<double>() == Approx(0.01288).margin(5e-6));
  CHECK(json::parse(slurp(out / "two_corner" / "summary.json")).at("status") == "equilibrium");

  // comparison.csv: one row per registered integrator, in the registry's order.
  const Csv c = read_csv(out / "comparison.csv");
  CHECK(c.header == std::vector<std::string>{"integrator", "status", "t_final", "steps",
                                             "rhs_evals", "jac_evals", "lin_setups", "residual",
                                             "wall_ms", "max_dx_m"});
  const std::vector<IntegratorInfo>& catalog = integrator_catalog();
  REQUIRE(c.rows.size() == catalog.size());
  check_finite(c, {"t_final", "steps", "rhs_evals", "jac_evals", "lin_setups", "residual",
                   "wall_ms", "max_dx_m"});
  // A run stops at equilibrium, then within the stop criterion's bound of every other settled
  // run (tests/test_systems.hpp; 6.4e-10 m, measured up to 5e-11 m), or at the cap.
  Scene scene = load_scene("four_corner");
  scene.params.symmetry = DrapeSymmetry::None;
  const DrapeGrid grid = build_drape_grid(scene.params);
  std::vector<double> x, v;
  const RunStats ref = run_to_equilibrium(grid.network, "cvode-bdf", scene.options, x, v);
  REQUIRE(ref.status == RunStatus::Equilibrium);
  const double bound = settled_distance_bound(grid.network, ref.t_final, x, ref.t_final, x,
                                              scene.options.equilibrium_tol);
  bool reference_settled = false;
  for (size_t k = 0; k < c.rows.size(); ++k) {
    const std::string status = c.rows[k][c.col("status")];
    INFO(c.rows[k][0] << ": " << status);
    CHECK(c.rows[k][0] == catalog[k].name);
    CHECK((status == "equilibrium" || status == "wall_limit"));
    if (c.rows[k][0] == "cvode-bdf") {
      CHECK(c.number(k, "max_dx_m") == 0.0);  // the reference
      reference_settled = status == "equilibrium";
    }
  }
  if (reference_settled)
    for (size_t k = 0; k < c.rows.size(); ++k)
      if (c.rows[k][c.col("status")] == "equilibrium") {
        INFO(c.rows[k][0]);
        CHECK(c.number(k, "max_dx_m") <= bound);
      }

  const std::string report = slurp(out / "report.md");
  CHECK(contains(report, "# knitsim demo"));
  CHECK(contains(report, "## Integrator comparison on four_corner"));
  CHECK(contains(report, "each capped at 0.5 s of wall time"));
  CHECK(contains(report, "](four_corner/drape.png)"));
  CHECK(contains(report, "](two_corner/drape.png)"));
  for (const IntegratorInfo& info : catalog) CHECK(contains(report, "| " + info.name + " |"));
  CHECK_FALSE(contains(report, "Interrupted"));
  const json manifest = json::parse(slurp(out / "manifest.json"));
  CHECK(manifest.at("options").at("comparison_wall_cap_s") == 0.5);
  CHECK(manifest.at("options").at("comparison_integrators").size() == catalog.size());
}

TEST_CASE("knitsim repro fig13: the convergence curve is the best run's history", "[repro]") {
  TempDir tmp("commands-fig13");
  const fs::path out = tmp.path / "fig13";
  const Run run = run_knitsim(
      "repro fig13 --runs 3 --decades 2 --countries 4 --imperialists 2 "
      "--quiet --out '" +
          out.string() + "'",
      tmp);
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(is_png(out / "fig13.png"));
  CHECK(contains(slurp(out / "report.md"), "## Fig. 13: convergence"));
  CHECK(fs::exists(out / "manifest.json"));
  for (const char* other : {"table4.csv", "table6.csv", "taguchi_sn.csv"})  // fig13 only
    CHECK_FALSE(fs::exists(out / other));

  const Csv fig = read_csv(out / "fig13.csv");
  CHECK(fig.header == std::vector<std::string>{"curve", "run", "decade", "best", "mean"});
  check_finite(fig, {"run", "decade", "best", "mean"});
  // The runs in the checkpoint: the curve marked best is the history of the lowest final cost.
  const std::map<std::string, json> units = checkpoint_results(out / "fits.jsonl");
  REQUIRE(units.size() == 3);
  int best_run = -1;
  double best_cost = INFINITY;
  for (int r = 0; r < 3; ++r) {
    const json& u = units.at("fit/cross/s1/run0" + std::to_string(r));
    if (u.at("objective").get<double>() < best_cost) {
      best_cost = u.at("objective").get<double>();
      best_run = r;
    }
  }
  const json& history = units.at("fit/cross/s1/run0" + std::to_string(best_run)).at("history");
  REQUIRE(history.size() == 3);  // decades 0, 1, 2
  size_t rows = 0;
  for (size_t i = 0; i < fig.rows.size(); ++i) {
    if (fig.rows[i][0] != "best") continue;
    const size_t d = static_cast<size_t>(fig.number(i, "decade"));
    INFO("decade " << d);
    CHECK(d == rows++);
    CHECK(fig.number(i, "run") == best_run);
    CHECK(fig.number(i, "best") == history.at(d).at(0).get<double>());  // 17 digits: exact
    CHECK(fig.number(i, "mean") == history.at(d).at(1).get<double>());
    CHECK(fig.number(i, "best") <= fig.number(i, "mean"));
  }
  CHECK(rows == 3);
  CHECK(history.back().at(0).get<double>() == best_cost);
}

namespace {

// The checks of a repro Taguchi experiment (quick preset: cross sample 1, 1 replicate, factor
// A's decades 1 / 2 / 4) written into `out`.
void check_repro_taguchi(const fs::path& out) {
  const Csv y = read_csv(out / "taguchi_responses.csv");
  CHECK(y.header == std::vector<std::string>{"run", "A", "B", "C", "D", "E", "F", "G", "y1"});
  REQUIRE(y.rows.size() == 27);
  check_finite(y, {"y1"});
  const std::map<std::string, json> units = checkpoint_results(out / "taguchi.jsonl");
  CHECK(units.size() == 27);
  const int decades[3] = {1, 2, 4};
  std::vector<double> eta(27);
  const Csv sn = read_csv(out / "taguchi_sn.csv");
  REQUIRE(sn.rows.size() == 27);
  for (int r = 0; r < 27; ++r) {
    INFO("run " << r + 1);
    CHECK(y.rows[r][0] == std::to_string(r + 1));
    for (int f = 0; f < 7; ++f)  // the published L27 on the factors' columns
      CHECK(y.rows[r][1 + f] == std::to_string(level(r, kFactorColumns[f])));
    // The response is the final cost of the run's ICA fit, which had factor A's decades.
    char key[64];
    std::snprintf(key, sizeof key, "taguchi/cross/s1/e%02d/r0", r + 1);
    REQUIRE(units.count(key) == 1);
    const json& u = units.at(key);
    CHECK(y.number(r, "y1") == u.at("objective").get<double>());  // 17 digits: exact
    CHECK(u.at("history").size() == static_cast<size_t>(decades[level(r, 1) - 1] + 1));
    // Smaller-the-better S/N of one replicate: -20 log10 |y| (written with 6 digits).
    CHECK(sn.number(r, "sn") ==
          Approx(-20 * std::log10(std::abs(y.number(r, "y1")))).epsilon(1e-5));
    eta[r] = sn.number(r, "sn");
  }
  check_analysis(read_csv(out / "taguchi_effects.csv"), read_csv(out / "taguchi_anova.csv"), eta);
  CHECK(contains(slurp(out / "report.md"), "## Taguchi L27"));
}

}  // namespace

TEST_CASE("knitsim repro taguchi: 27 fits, responses from the checkpoint, S/N and effects",
          "[.repro_taguchi]") {
  TempDir tmp("commands-repro-taguchi");
  const fs::path out = tmp.path / "taguchi";
  const Run run = run_knitsim("repro taguchi --quiet --out '" + out.string() + "'", tmp);
  INFO(run.err);
  REQUIRE(run.status == 0);
  CHECK(run.out.empty());  // --quiet
  check_repro_taguchi(out);
  for (const char* other : {"table4.csv", "fig13.csv"}) CHECK_FALSE(fs::exists(out / other));
  CHECK(json::parse(slurp(out / "manifest.json")).at("options").at("task") == "taguchi");
}

TEST_CASE("knitsim repro all: Tables 4 and 6, Taguchi and Fig. 13 in one report", "[.repro_all]") {
  TempDir tmp("commands-repro-all");
  const fs::path out = tmp.path / "all";
  const Run run = run_knitsim(
      "repro all --samples 1 --sets twin --runs 2 --decades 1 --countries 4 --imperialists 2 "
      "--no-pictures --quiet --out '" +
          out.string() + "'",
      tmp);
  INFO(run.err);
  REQUIRE(run.status == 0);
  const std::string report = slurp(out / "report.md");
  for (const char* section : {"## Table 4", "## Table 6", "## Fig. 13", "## Taguchi L27"})
    CHECK(contains(report, section));
  CHECK(is_png(out / "fig13.png"));

  // Table 4: the best of the 2 runs of twin sample 1, its error the lowest final cost in the
  // checkpoint; Table 6 applies the same parameters.
  const Csv t4 = read_csv(out / "table4.csv");
  REQUIRE(t4.rows.size() == 1);
  CHECK(t4.rows[0][t4.col("set")] == "twin");
  check_finite(t4, {"stiffness", "damping", "elongation_limit", "natural_length", "error",
                    "evaluations", "paper_error", "stiffness_rel_error"});
  const std::map<std::string, json> units = checkpoint_results(out / "fits.jsonl");
  const double e0 = units.at("fit/twin/s1/run00").at("objective").get<double>();
  const double e1 = units.at("fit/twin/s1/run01").at("objective").get<double>();
  CHECK(t4.number(0, "error") == std::min(e0, e1));
  CHECK(t4.number(0, "best_run") == (e1 < e0 ? 1 : 0));
  const Csv t6 = read_csv(out / "table6.csv");
  REQUIRE(t6.rows.size() == 1);
  check_finite(t6, {"error", "table4_error"});
  for (const char* p : {"stiffness", "damping", "elongation_limit", "natural_length", "topology"})
    CHECK(t6.rows[0][t6.col(p)] == t4.rows[0][t4.col(p)]);
  CHECK(t6.rows[0][t6.col("table4_error")] == t4.rows[0][t4.col("error")]);
  // Fig. 13 and the Taguchi experiment as the single tasks write them.
  const Csv fig = read_csv(out / "fig13.csv");
  CHECK(!fig.rows.empty());
  check_finite(fig, {"best", "mean"});
  check_repro_taguchi(out);
}
