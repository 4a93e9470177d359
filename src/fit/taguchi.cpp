#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/fit/taguchi.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <istream>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace knitsim {

namespace {

// Generators (a, b, c coefficients) of the 13 columns, see the header.
constexpr int kGenerator[kL27Columns][3] = {{1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {2, 1, 0}, {0, 0, 1},
                                            {1, 0, 1}, {2, 0, 1}, {0, 1, 1}, {1, 1, 1}, {2, 1, 1},
                                            {0, 2, 1}, {1, 2, 1}, {2, 2, 1}};

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Mean S/N at each level of one column.
std::array<double, 3> level_means(const std::vector<double>& sn, int column) {
  std::array<double, 3> sum{};
  for (int run = 0; run < kL27Runs; ++run) sum[l27_level(run, column)] += sn[run];
  for (double& s : sum) s /= kL27Runs / 3;
  return sum;
}

// ANOVA sum of squares of one column: 9 sum_l (mean_l - mean)^2.
double column_ss(const std::array<double, 3>& means, double mean) {
  double ss = 0.0;
  for (double m : means) ss += (kL27Runs / 3) * (m - mean) * (m - mean);
  return ss;
}

void check_columns(const std::vector<int>& columns) {
  if (columns.empty() || columns.size() > static_cast<std::size_t>(kL27Columns))
    throw std::invalid_argument("columns: " + std::to_string(columns.size()) +
                                " given, must list 1 to 13 L27 columns");
  std::vector<bool> used(kL27Columns + 1, false);
  for (int c : columns) {
    if (c < 1 || c > kL27Columns)
      throw std::invalid_argument("columns: " + std::to_string(c) + " must be in 1..13");
    if (used[c]) throw std::invalid_argument("columns: " + std::to_string(c) + " listed twice");
    used[c] = true;
  }
}

// A finite number filling the whole (trimmed) field, or false.
bool parse_number(const std::string& field, double& value) {
  if (field.empty()) return false;
  char* end = nullptr;
  value = std::strtod(field.c_str(), &end);
  return end == field.c_str() + field.size() && std::isfinite(value);
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, ',')) fields.push_back(trim(f));
  if (!line.empty() && line.back() == ',') fields.push_back("");
  return fields;
}

}  // namespace

int l27_level(int run, int column) {
  if (run < 0 || run >= kL27Runs || column < 1 || column > kL27Columns)
    throw std::out_of_range("l27_level: run " + std::to_string(run) + ", column " +
                            std::to_string(column));
  const int digit[3] = {run / 9, (run / 3) % 3, run % 3};
  const int* g = kGenerator[column - 1];
  return (g[0] * digit[0] + g[1] * digit[1] + g[2] * digit[2]) % 3;
}

const std::vector<int>& default_l27_columns() {
  static const std::vector<int> columns = {1, 2, 5, 9, 10, 12, 13};
  return columns;
}

double sn_smaller_the_better(const std::vector<double>& y) {
  if (y.empty()) throw std::invalid_argument("no responses: S/N needs at least one");
  double sum = 0.0;
  for (double v : y) {
    if (!std::isfinite(v)) throw std::invalid_argument("response is not finite");
    sum += v * v;
  }
  if (!(sum > 0.0))
    throw std::invalid_argument("all responses are 0: S/N = -10 log10(0) is infinite");
  return -10.0 * std::log10(sum / static_cast<double>(y.size()));
}

std::string TaguchiAnalysis::optimal_levels() const {
  std::string s;
  for (const auto& f : factors)
    s += (s.empty() ? "" : " ") + f.name + std::to_string(f.optimal_level);
  return s;
}

TaguchiAnalysis analyze_l27(const std::vector<std::vector<double>>& responses,
                            const std::vector<int>& columns, int min_error_dof) {
  check_columns(columns);
  if (responses.size() != static_cast<std::size_t>(kL27Runs))
    throw std::invalid_argument("responses: " + std::to_string(responses.size()) +
                                " runs, an L27 experiment has 27");
  TaguchiAnalysis a;
  a.columns = columns;
  a.replicates = static_cast<int>(responses[0].size());
  for (int run = 0; run < kL27Runs; ++run) {
    const std::string where = "run " + std::to_string(run + 1);
    if (responses[run].size() != responses[0].size())
      throw std::invalid_argument(where + ": " + std::to_string(responses[run].size()) +
                                  " replicates, run 1 has " + std::to_string(a.replicates));
    try {
      a.sn.push_back(sn_smaller_the_better(responses[run]));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ": " + e.what());
    }
  }
  a.mean_sn = std::accumulate(a.sn.begin(), a.sn.end(), 0.0) / kL27Runs;
  for (double eta : a.sn) a.ss_total += (eta - a.mean_sn) * (eta - a.mean_sn);

  std::vector<bool> assigned(kL27Columns + 1, false);
  for (std::size_t k = 0; k < columns.size(); ++k) {
    TaguchiFactor f;
    f.name = std::string(1, static_cast<char>('A' + k));
    f.column = columns[k];
    f.mean_sn = level_means(a.sn, f.column);
    const auto hi = std::max_element(f.mean_sn.begin(), f.mean_sn.end());  // first: lower level
    f.delta = *hi - *std::min_element(f.mean_sn.begin(), f.mean_sn.end());
    f.optimal_level = static_cast<int>(hi - f.mean_sn.begin()) + 1;
    f.ss = column_ss(f.mean_sn, a.mean_sn);
    f.ms = f.ss / f.dof;
    f.percent = a.ss_total > 0.0 ? 100.0 * f.ss / a.ss_total : 0.0;
    assigned[f.column] = true;
    a.factors.push_back(f);
  }
  std::vector<int> by_delta(a.factors.size());
  std::iota(by_delta.begin(), by_delta.end(), 0);
  std::stable_sort(by_delta.begin(), by_delta.end(),
                   [&](int x, int y) { return a.factors[x].delta > a.factors[y].delta; });
  for (std::size_t r = 0; r < by_delta.size(); ++r) a.factors[by_delta[r]].rank = r + 1;

  for (int c = 1; c <= kL27Columns; ++c)
    if (!assigned[c]) {
      a.ss_unassigned += column_ss(level_means(a.sn, c), a.mean_sn);
      a.dof_unassigned += 2;
    }
  a.ss_error = a.ss_unassigned;
  a.dof_error = a.dof_unassigned;
  std::vector<int> by_ss(a.factors.size());
  std::iota(by_ss.begin(), by_ss.end(), 0);
  std::stable_sort(by_ss.begin(), by_ss.end(),
                   [&](int x, int y) { return a.factors[x].ss < a.factors[y].ss; });
  for (int k : by_ss) {
    if (a.dof_error >= min_error_dof) break;
    a.factors[k].pooled = true;
    a.ss_error += a.factors[k].ss;
    a.dof_error += a.factors[k].dof;
  }
  a.ms_error = a.dof_error > 0 ? a.ss_error / a.dof_error : kNaN;
  for (auto& f : a.factors) {
    if (f.pooled)
      f.f = kNaN;
    else if (a.ms_error > 0.0)
      f.f = f.ms / a.ms_error;
    else
      f.f = std::isnan(a.ms_error) ? kNaN : std::numeric_limits<double>::infinity();
  }
  return a;
}

std::vector<std::vector<double>> read_responses_csv(std::istream& in) {
  std::vector<std::vector<double>> rows;
  std::string line;
  int line_no = 0;
  bool first = true;
  bool run_column = false;  // the header names column 1 "run": it numbers the runs
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const std::vector<std::string> fields = split_fields(t);
    std::vector<double> values(fields.size());
    std::vector<bool> ok(fields.size());
    for (std::size_t c = 0; c < fields.size(); ++c) ok[c] = parse_number(fields[c], values[c]);
    const bool is_header = first && std::none_of(ok.begin(), ok.end(), [](bool b) { return b; });
    first = false;
    if (is_header) {
      std::string name = fields[0];
      std::transform(name.begin(), name.end(), name.begin(),
                     [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
      run_column = name == "run";
      continue;
    }
    const std::string where =
        "line " + std::to_string(line_no) + " (run " + std::to_string(rows.size() + 1) + ")";
    for (std::size_t c = 0; c < fields.size(); ++c)
      if (!ok[c])
        throw std::invalid_argument(where + ", column " + std::to_string(c + 1) + ": '" +
                                    fields[c] + "' is not a finite number");
    if (run_column) {
      if (values.size() < 2 || values[0] != static_cast<double>(rows.size() + 1))
        throw std::invalid_argument(
            where + ", column 1 (run): " + (values.empty() ? std::string("missing") : fields[0]) +
            ", expected " + std::to_string(rows.size() + 1) +
            " followed by the replicates (runs in L27 order)");
      values.erase(values.begin());
    }
    if (!rows.empty() && values.size() != rows[0].size())
      throw std::invalid_argument(where + ": " + std::to_string(values.size()) +
                                  " values, run 1 has " + std::to_string(rows[0].size()));
    rows.push_back(values);
  }
  if (rows.size() != static_cast<std::size_t>(kL27Runs))
    throw std::invalid_argument(std::to_string(rows.size()) +
                                " runs (data lines) read, an L27 experiment has 27");
  return rows;
}

Table taguchi_sn_table(const TaguchiAnalysis& a) {
  Table t;
  t.columns = {"run"};
  for (const auto& f : a.factors) t.columns.push_back(f.name);
  t.columns.push_back("sn");
  for (int run = 0; run < kL27Runs; ++run) {
    std::vector<std::string> row = {std::to_string(run + 1)};
    for (const auto& f : a.factors) row.push_back(std::to_string(l27_level(run, f.column) + 1));
    row.push_back(format_number(a.sn[run], 6));
    t.rows.push_back(row);
  }
  return t;
}

Table taguchi_effects_table(const TaguchiAnalysis& a) {
  Table t;
  t.columns = {"factor", "column", "level1", "level2", "level3", "delta", "rank", "optimal"};
  for (const auto& f : a.factors)
    t.rows.push_back({f.name, std::to_string(f.column), format_number(f.mean_sn[0], 6),
                      format_number(f.mean_sn[1], 6), format_number(f.mean_sn[2], 6),
                      format_number(f.delta, 6), std::to_string(f.rank),
                      f.name + std::to_string(f.optimal_level)});
  return t;
}

Table taguchi_anova_table(const TaguchiAnalysis& a) {
  Table t;
  t.columns = {"source", "column", "ss", "dof", "ms", "f", "percent", "pooled"};
  for (const auto& f : a.factors)
    t.rows.push_back({f.name, std::to_string(f.column), format_number(f.ss, 6),
                      std::to_string(f.dof), format_number(f.ms, 6),
                      f.pooled ? "" : format_number(f.f, 6), format_number(f.percent, 4),
                      f.pooled ? "yes" : "no"});
  const double pct = a.ss_total > 0.0 ? 100.0 / a.ss_total : 0.0;
  t.rows.push_back({"unassigned", "", format_number(a.ss_unassigned, 6),
                    std::to_string(a.dof_unassigned), "", "",
                    format_number(pct * a.ss_unassigned, 4), ""});
  t.rows.push_back({"error", "", format_number(a.ss_error, 6), std::to_string(a.dof_error),
                    format_number(a.ms_error, 6), "", format_number(pct * a.ss_error, 4), ""});
  t.rows.push_back({"total", "", format_number(a.ss_total, 6), std::to_string(a.dof_total), "", "",
                    a.ss_total > 0.0 ? "100" : "0", ""});
  return t;
}

}  // namespace knitsim
