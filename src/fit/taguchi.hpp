// Taguchi analysis of an L27 experiment (docs/commands.md, `taguchi`; paper 1, "ICA parameter
// tuning", Table 1, Fig. 10): which level of each factor gives the smallest responses, robustly.
//
// Design: the standard L27(3^13) orthogonal array. Run r = 9a + 3b + c (r = 0..26, digits
// a, b, c in 0..2 are the basic columns 1, 2, 5); column j holds (alpha_j a + beta_j b +
// gamma_j c) mod 3 with the published generators
//   col  1  2  3  4  5  6  7  8  9 10 11 12 13
//   a    1  0  1  2  0  1  2  0  1  2  0  1  2
//   b    0  1  1  1  0  0  0  1  1  1  2  2  2
//   c    0  0  0  0  1  1  1  1  1  1  1  1  1
// which reproduces Taguchi's printed table row by row (levels printed 1..3 = 0..2 + 1).
//
// Factors: k <= 13 factors, named A, B, C, ... in order, each on one column. Default for the
// paper's 7 ICA factors: columns 1, 2, 5, 9, 10, 12, 13. Why: the first three (A MaxIt,
// B countries, C imperialists, the budget factors most likely to interact) sit on the basic
// columns; their two-factor interactions fall on columns 3, 4 (AxB), 6, 7 (AxC) and 8, 11
// (BxC), which stay unassigned, so those interactions are not confounded with any main
// effect and, if negligible, form the error estimate. Main effects are the same for any
// choice of distinct columns when interactions are negligible. (Which columns the paper's
// Minitab run used is not stated.)
//
// Analysis, per run i with replicates y_i1..y_ir (any finite values; r >= 1):
//   smaller-the-better S/N  eta_i = -10 log10( mean_j y_ij^2 )   [dB]
//   main effect of factor f at level l: mean of eta over the 9 runs with f at level l
//   delta_f = max_l - min_l of those means; rank 1 = largest delta (ties: earlier factor);
//   optimal level = argmax_l (largest S/N; ties: lower level).
// ANOVA on eta (27 values, 26 dof): SS_f = 9 sum_l (mean_fl - mean)^2 with 2 dof per column;
// the 13 column sums of squares add up to SS_total exactly (orthogonality). Error = the
// unassigned columns (26 - 2k dof); if that leaves fewer than `min_error_dof` dof, the
// factors with the smallest SS are pooled into the error one at a time until it has enough
// (with 7 factors the error already has 12 dof and nothing is pooled). F = MS_f / MS_error
// (inf when MS_error = 0, e.g. exactly additive data; NaN for pooled factors); percent
// contribution = 100 SS_f / SS_total. No p-values (no F-distribution library is installed;
// F(2, 12) at 5 % is 3.89).
//
// Failure modes: a wrong run count, ragged rows, non-finite responses, a run whose responses
// are all 0 (eta = +inf), bad columns: std::invalid_argument naming the run / column.
#pragma once

#include <array>
#include <iosfwd>
#include <string>
#include <vector>

#include "src/base/table.hpp"


namespace knitsim {

constexpr int kL27Runs = 27;
constexpr int kL27Columns = 13;

// Level 0, 1 or 2 of run `run` (0..26) in column `column` (1..13, as published).
int l27_level(int run, int column);

// Columns of the paper's 7 ICA factors A..G (see the header comment).
const std::vector<int>& default_l27_columns();

// eta = -10 log10(mean(y^2)) in dB. Throws std::invalid_argument if y is empty, has a
// non-finite entry or is all zero.
double sn_smaller_the_better(const std::vector<double>& y);

struct TaguchiFactor {
  std::string name;                 // "A", "B", ...
  int column = 0;                   // L27 column 1..13
  std::array<double, 3> mean_sn{};  // mean eta at levels 1, 2, 3, dB
  double delta = 0.0;               // max - min of mean_sn, dB
  int rank = 0;                     // 1 = largest delta
  int optimal_level = 0;            // 1..3
  // ANOVA
  double ss = 0.0;  // sum of squares, dB^2
  int dof = 2;
  double ms = 0.0;       // ss / dof
  double f = 0.0;        // ms / ms_error (NaN if pooled)
  double percent = 0.0;  // 100 ss / ss_total
  bool pooled = false;   // pooled into the error
};

struct TaguchiAnalysis {
  std::vector<int> columns;
  int replicates = 0;
  std::vector<double> sn;  // eta per run, dB
  double mean_sn = 0.0;
  std::vector<TaguchiFactor> factors;
  double ss_total = 0.0;
  int dof_total = kL27Runs - 1;
  double ss_unassigned = 0.0;  // columns without a factor
  int dof_unassigned = 0;
  double ss_error = 0.0;  // unassigned + pooled factors
  int dof_error = 0;
  double ms_error = 0.0;  // NaN when dof_error = 0

  // The optimal combination, e.g. "A3 B3 C1 D2 E1 F2 G2".
  std::string optimal_levels() const;
};

// responses: 27 runs (standard order) x r replicates. columns: the factors' columns, distinct,
// in 1..13, at most 13.
TaguchiAnalysis analyze_l27(const std::vector<std::vector<double>>& responses,
                            const std::vector<int>& columns = default_l27_columns(),
                            int min_error_dof = 2);

// Reads responses as CSV: one line per run (27), comma-separated replicates, every line the
// same count. Blank lines and lines starting with '#' are skipped. The first remaining line
// is a header (skipped) iff none of its fields is a number; if the header names column 1
// "run" (any case), that column numbers the runs: it must read 1, 2, ..., 27 and is not a
// replicate (taguchi_sn_table's layout). Throws std::invalid_argument
// "line L (run R), column C: ..." on a field that is not a finite number, a ragged line, or
// a run count other than 27.
std::vector<std::vector<double>> read_responses_csv(std::istream& in);

// The results as tables (text for terminals, CSV for files; numbers to 6 significant digits):
//   sn:      run, one level column per factor (1..3), eta
//   effects: factor, column, level1, level2, level3 (mean eta, dB), delta, rank, optimal
//   anova:   source, column, ss, dof, ms, f, percent, pooled; rows: the factors, then
//            "unassigned", "error" (unassigned + pooled) and "total"
Table taguchi_sn_table(const TaguchiAnalysis& a);
Table taguchi_effects_table(const TaguchiAnalysis& a);
Table taguchi_anova_table(const TaguchiAnalysis& a);

}  // namespace knitsim
