// Taguchi L27 (src/fit/taguchi.hpp): the array against the published table and its orthogonality,
// the additive self-check (exact main effects of additive data), the ANOVA decomposition and
// pooling, the CSV reader.
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "src/fit/taguchi.hpp"

using namespace knitsim;

namespace {

// Taguchi's printed L27(3^13), levels 1..3, runs 1..27.
const char* const kPublishedL27[kL27Runs] = {
    "1111111111111", "1111222222222", "1111333333333", "1222111222333", "1222222333111",
    "1222333111222", "1333111333222", "1333222111333", "1333333222111", "2123123123123",
    "2123231231231", "2123312312312", "2231123231312", "2231231312123", "2231312123231",
    "2312123312231", "2312231123312", "2312312231123", "3132132132132", "3132213213213",
    "3132321321321", "3213132213321", "3213213321132", "3213321132213", "3321132321213",
    "3321213132321", "3321321213132"};

// Responses whose S/N is exactly eta_run = 20 + sum_f effect[f][level], r replicates with
// alternating signs (y^2 is what counts).
std::vector<std::vector<double>> additive_responses(
    const std::vector<int>& columns, const std::vector<std::array<double, 3>>& effect,
    int replicates) {
  std::vector<std::vector<double>> y(kL27Runs);
  for (int run = 0; run < kL27Runs; ++run) {
    double eta = 20.0;
    for (std::size_t f = 0; f < columns.size(); ++f) eta += effect[f][l27_level(run, columns[f])];
    for (int k = 0; k < replicates; ++k)
      y[run].push_back((k % 2 ? -1.0 : 1.0) * std::pow(10.0, -eta / 20.0));
  }
  return y;
}

// Deterministic non-additive responses (a smooth function of the run number).
std::vector<std::vector<double>> irregular_responses() {
  std::vector<std::vector<double>> y(kL27Runs);
  for (int run = 0; run < kL27Runs; ++run)
    y[run] = {1.0 + 0.5 * std::sin(1.3 * run), 1.2 + 0.4 * std::cos(0.7 * run * run)};
  return y;
}

}  // namespace

TEST_CASE("L27 equals Taguchi's published table", "[taguchi]") {
  for (int run = 0; run < kL27Runs; ++run)
    for (int c = 1; c <= kL27Columns; ++c) {
      INFO("run " << run + 1 << ", column " << c);
      CHECK(l27_level(run, c) + 1 == kPublishedL27[run][c - 1] - '0');
    }
  CHECK_THROWS_AS(l27_level(27, 1), std::out_of_range);
  CHECK_THROWS_AS(l27_level(0, 14), std::out_of_range);
}

TEST_CASE("L27 is orthogonal: every column pair holds each level pair exactly 3 times",
          "[taguchi]") {
  for (int a = 1; a <= kL27Columns; ++a) {
    int single[3] = {0, 0, 0};
    for (int run = 0; run < kL27Runs; ++run) ++single[l27_level(run, a)];
    for (int n : single) CHECK(n == 9);
    for (int b = a + 1; b <= kL27Columns; ++b) {
      int pairs[3][3] = {};
      for (int run = 0; run < kL27Runs; ++run) ++pairs[l27_level(run, a)][l27_level(run, b)];
      for (auto& row : pairs)
        for (int n : row) {
          INFO("columns " << a << ", " << b);
          CHECK(n == 3);
        }
    }
  }
}

TEST_CASE("S/N smaller-the-better is -10 log10 mean(y^2); zero, NaN and no response are refused",
          "[taguchi]") {
  CHECK(sn_smaller_the_better({1.0}) == 0.0);
  CHECK(sn_smaller_the_better({0.1, -0.1}) == Approx(20.0));
  CHECK(sn_smaller_the_better({1.0, 3.0}) == Approx(-10.0 * std::log10(5.0)));
  CHECK_THROWS_AS(sn_smaller_the_better({0.0, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(sn_smaller_the_better({1.0, NAN}), std::invalid_argument);
  CHECK_THROWS_AS(sn_smaller_the_better({}), std::invalid_argument);
}

TEST_CASE("additive self-check: main effects return 20 + each level effect exactly", "[taguchi]") {
  // Zero-sum effects per factor (dB), chosen so the best levels are the paper's
  // A3 B3 C1 D2 E1 F2 G2.
  const std::vector<std::array<double, 3>> effect = {
      {-2.0, 0.5, 1.5},    {-0.3, -0.2, 0.5}, {3.0, -1.0, -2.0}, {-0.4, 0.7, -0.3},
      {0.25, -0.05, -0.2}, {-1.0, 1.1, -0.1}, {0.05, 0.1, -0.15}};
  const auto& columns = default_l27_columns();
  const TaguchiAnalysis a = analyze_l27(additive_responses(columns, effect, 3), columns);
  REQUIRE(a.factors.size() == 7);
  CHECK(a.replicates == 3);
  CHECK(a.mean_sn == Approx(20.0).margin(1e-10));
  for (std::size_t f = 0; f < 7; ++f)
    for (int l = 0; l < 3; ++l)
      CHECK(a.factors[f].mean_sn[l] == Approx(20.0 + effect[f][l]).margin(1e-10));
  CHECK(a.optimal_levels() == "A3 B3 C1 D2 E1 F2 G2");
  // Deltas A..G: 3.5, 0.8, 5, 1.1, 0.45, 2.1, 0.25.
  const int ranks[7] = {2, 5, 1, 4, 6, 3, 7};
  for (std::size_t f = 0; f < 7; ++f) CHECK(a.factors[f].rank == ranks[f]);
  CHECK(a.factors[0].delta == Approx(3.5).margin(1e-10));
  // Nothing but the factors: the unassigned columns carry no variance.
  CHECK(a.ss_unassigned == Approx(0.0).margin(1e-18));
  CHECK(a.dof_unassigned == 12);
  // SS_f = 9 sum_l effect^2.
  CHECK(a.factors[2].ss == Approx(9 * (9.0 + 1.0 + 4.0)).epsilon(1e-12));
}

TEST_CASE("ANOVA: the column sums of squares add up to the total", "[taguchi]") {
  const auto y = irregular_responses();
  const TaguchiAnalysis a = analyze_l27(y);
  double sum = a.ss_unassigned;
  for (const auto& f : a.factors) sum += f.ss;
  CHECK(sum == Approx(a.ss_total).epsilon(1e-12));
  CHECK(a.ss_total > 0.0);
  // Direct total: sum of squared deviations of the 27 S/N ratios.
  double direct = 0.0;
  for (int run = 0; run < kL27Runs; ++run) {
    const double eta = sn_smaller_the_better(y[run]);
    CHECK(a.sn[run] == Approx(eta));
    direct += (eta - a.mean_sn) * (eta - a.mean_sn);
  }
  CHECK(a.ss_total == Approx(direct).epsilon(1e-12));
  // 7 factors: 12 error dof already, nothing pooled; F = MS / MS_error.
  CHECK(a.dof_error == 12);
  CHECK(a.ss_error == a.ss_unassigned);
  for (const auto& f : a.factors) {
    CHECK_FALSE(f.pooled);
    CHECK(f.f == Approx(f.ss / 2 / (a.ss_error / 12)));
  }
  double percent = 0.0;
  for (const auto& f : a.factors) percent += f.percent;
  CHECK(percent + 100 * a.ss_unassigned / a.ss_total == Approx(100.0));
}

TEST_CASE("ANOVA pools the smallest factors when the error has < 2 dof", "[taguchi]") {
  std::vector<int> all(kL27Columns);
  for (int c = 1; c <= kL27Columns; ++c) all[c - 1] = c;
  const TaguchiAnalysis a = analyze_l27(irregular_responses(), all);
  CHECK(a.dof_unassigned == 0);
  CHECK(a.dof_error == 2);
  int pooled = -1;
  double smallest = INFINITY;
  double sum = 0.0;
  for (std::size_t k = 0; k < a.factors.size(); ++k) {
    sum += a.factors[k].ss;
    if (a.factors[k].ss < smallest) {
      smallest = a.factors[k].ss;
      pooled = static_cast<int>(k);
    }
  }
  CHECK(sum == Approx(a.ss_total).epsilon(1e-12));  // 13 columns = the whole variation
  for (std::size_t k = 0; k < a.factors.size(); ++k)
    CHECK(a.factors[k].pooled == (static_cast<int>(k) == pooled));
  CHECK(a.ss_error == Approx(smallest));
  CHECK(std::isnan(a.factors[pooled].f));
}

TEST_CASE("an interaction lands on its interaction columns, not on the main effects", "[taguchi]") {
  // eta = 20 + g((a + b) mod 3): an AxB interaction, which lives on column 3 only.
  std::vector<std::vector<double>> y(kL27Runs);
  const double g[3] = {-1.0, 0.0, 1.0};
  for (int run = 0; run < kL27Runs; ++run)
    y[run] = {std::pow(10.0, -(20.0 + g[l27_level(run, 3)]) / 20.0)};
  const TaguchiAnalysis a = analyze_l27(y);
  for (const auto& f : a.factors) CHECK(f.ss == Approx(0.0).margin(1e-18));
  CHECK(a.ss_unassigned == Approx(18.0));  // 9 x (1 + 0 + 1)
  CHECK(a.ss_total == Approx(18.0));
}

TEST_CASE("bad designs and responses are named", "[taguchi]") {
  auto y = irregular_responses();
  CHECK_THROWS_WITH(analyze_l27(y, {1, 2, 2}), Catch::StartsWith("columns: 2 listed twice"));
  CHECK_THROWS_WITH(analyze_l27(y, {0}), Catch::StartsWith("columns: 0"));
  CHECK_THROWS_WITH(analyze_l27(y, {}), Catch::StartsWith("columns"));
  y[4] = {0.0, 0.0};
  CHECK_THROWS_WITH(analyze_l27(y), Catch::StartsWith("run 5: all responses are 0"));
  y[4] = {1.0};
  CHECK_THROWS_WITH(analyze_l27(y), Catch::StartsWith("run 5: 1 replicates"));
  y.pop_back();
  CHECK_THROWS_WITH(analyze_l27(y), Catch::StartsWith("responses: 26 runs"));
}

TEST_CASE("response CSV: optional header, comments, errors with line and column", "[taguchi]") {
  std::ostringstream good;
  good << "# ICA final costs\nrep1, rep2\n";
  for (int run = 0; run < kL27Runs; ++run) good << run + 1 << ", " << 0.5 * run + 1 << "\n\n";
  std::istringstream in(good.str());
  const auto rows = read_responses_csv(in);
  REQUIRE(rows.size() == 27);
  CHECK(rows[26] == std::vector<double>{27.0, 14.0});

  auto error = [](const std::string& text) {
    std::istringstream s(text);
    try {
      read_responses_csv(s);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string body;
  for (int run = 0; run < kL27Runs; ++run) body += "1,2\n";
  CHECK(error(body).empty());  // no header
  CHECK(error("a,b\n" + body).empty());
  // A header naming column 1 "run": that column numbers the runs and is not a replicate.
  std::ostringstream numbered;
  numbered << "Run,r1,r2\n";
  for (int run = 0; run < kL27Runs; ++run) numbered << run + 1 << "," << run << ",2\n";
  std::istringstream numbered_in(numbered.str());
  const auto numbered_rows = read_responses_csv(numbered_in);
  REQUIRE(numbered_rows.size() == 27);
  CHECK(numbered_rows[26] == std::vector<double>{26.0, 2.0});
  std::string misnumbered = numbered.str();
  misnumbered.replace(misnumbered.find("\n3,"), 3, "\n4,");  // run 3 numbered 4
  CHECK(error(misnumbered) ==
        "line 4 (run 3), column 1 (run): 4, expected 3 followed by the replicates (runs in L27 "
        "order)");
  CHECK(error(body + "1,2\n") == "28 runs (data lines) read, an L27 experiment has 27");
  std::string bad = body;
  bad.replace(bad.find("1,2\n", 4 * 4), 4, "1,x\n");  // run 5
  CHECK(error(bad) == "line 5 (run 5), column 2: 'x' is not a finite number");
  bad = body;
  bad.replace(0, 4, "1,nan\n");
  CHECK(error(bad) == "line 1 (run 1), column 2: 'nan' is not a finite number");
  bad = body;
  bad.replace(4 * 2, 4, "1,2,3\n");  // run 3
  CHECK(error(bad) == "line 3 (run 3): 3 values, run 1 has 2");
  CHECK(error("1,\n" + body) == "line 1 (run 1), column 2: '' is not a finite number");
}
