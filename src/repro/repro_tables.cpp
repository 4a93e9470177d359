// The tables and report pieces of a reproduction: Table 4 and Table 6 of the fits (Table 6
// re-runs the fitted parameters on two_corner), LM against the ICA, the pictures' rows.
// Each function's contract is in repro_internal.hpp.
#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "src/base/text.hpp"
#include "src/fit/drape_fit.hpp"
#include "src/io/drape_outputs.hpp"
#include "src/paper/paper_data.hpp"
#include "src/repro/repro_internal.hpp"
#include "src/scene/scene.hpp"

namespace knitsim::repro_internal {

namespace fs = std::filesystem;
using nlohmann::json;

std::string cell(double v, int digits) { return format_number(v, digits); }

std::string fitted_topology(const std::vector<double>& x) {
  const DrapeFitBounds b;
  return std::string(
      1, static_cast<char>(
             'a' + category_of(x[kGeneTopology], b.lower[kGeneTopology], b.upper[kGeneTopology])));
}

// Names of the four continuous genes as table columns.
const std::array<const char*, 4> kParamColumns = {"stiffness", "damping", "elongation_limit",
                                                  "natural_length"};

double paper_value(const PaperSample& p, int gene) {
  switch (gene) {
    case kGeneStiffness:
      return p.stiffness;
    case kGeneDamping:
      return p.damping;
    case kGeneElongation:
      return p.elongation_limit;
    default:
      return p.natural_length;
  }
}

// The column index of `name` in t.
size_t column(const Table& t, const std::string& name) {
  return static_cast<size_t>(std::find(t.columns.begin(), t.columns.end(), name) -
                             t.columns.begin());
}

Table table4(const std::vector<SampleFits>& fits, bool cpu_column) {
  Table t;
  t.columns = {"set", "sample", "runs", "best_run"};
  for (const char* p : kParamColumns) t.columns.push_back(p);
  t.columns.insert(t.columns.end(), {"topology", "error"});
  for (const char* p : kParamColumns) {
    t.columns.push_back(std::string(p) + "_min");
    t.columns.push_back(std::string(p) + "_max");
  }
  t.columns.insert(t.columns.end(),
                   {"topologies", "error_max", "evaluations", "failed_evaluations", "status"});
  for (const char* p : kParamColumns) t.columns.push_back(std::string("paper_") + p);
  t.columns.insert(t.columns.end(),
                   {"paper_topology", "paper_error", "true_stiffness", "true_natural_length",
                    "stiffness_rel_error", "natural_length_rel_error"});
  if (cpu_column) t.columns.push_back("cpu_seconds");
  for (const SampleFits& f : fits) {
    const PaperSample& paper = paper_sample(f.sample);
    std::vector<std::string> row = {to_string(f.set), std::to_string(f.sample),
                                    std::to_string(f.runs.size())};
    const std::vector<int> good = f.by_objective();
    if (good.empty()) {
      row.resize(column(t, "paper_stiffness"));
      row[column(t, "status")] = "no fit: " + f.error;
    } else {
      const json& best = f.runs[good.front()];
      const std::vector<double> x = best["best_x"].get<std::vector<double>>();
      row.push_back(std::to_string(good.front()));
      for (int g = 0; g < 4; ++g) row.push_back(cell(x[g], 17));
      row.push_back(fitted_topology(x));
      row.push_back(cell(best["objective"].get<double>(), 17));
      std::set<std::string> topologies;
      long failed = 0;
      for (int g = 0; g < 4; ++g) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (int r : good) {
          const double v = f.runs[r]["best_x"][g].get<double>();
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
        row.push_back(cell(lo));
        row.push_back(cell(hi));
      }
      for (int r : good) {
        topologies.insert(fitted_topology(f.runs[r]["best_x"].get<std::vector<double>>()));
        failed += f.runs[r]["failed_evaluations"].get<long>();
      }
      std::string topo;
      for (const std::string& s : topologies) topo += s;
      row.push_back(topo);
      row.push_back(cell(f.runs[good.back()]["objective"].get<double>()));
      row.push_back(std::to_string(f.evaluations()));
      row.push_back(std::to_string(failed));
      row.push_back(good.size() == f.runs.size()
                        ? std::string(best["status"].get<std::string>())
                        : std::to_string(f.runs.size() - good.size()) + " runs failed: " + f.error);
    }
    for (int g = 0; g < 4; ++g) row.push_back(cell(paper_value(paper, g)));
    row.push_back(std::string(1, paper.topology));
    row.push_back(cell(paper.table4_error));
    if (f.set == SyntheticSet::Twin && !good.empty()) {
      const std::vector<double> x = f.runs[good.front()]["best_x"].get<std::vector<double>>();
      row.push_back(cell(paper.stiffness));
      row.push_back(cell(paper.natural_length));
      row.push_back(cell((x[kGeneStiffness] - paper.stiffness) / paper.stiffness));
      row.push_back(cell((x[kGeneNaturalLength] - paper.natural_length) / paper.natural_length));
    } else {
      row.insert(row.end(), 4, "");
    }
    if (cpu_column) row.push_back(good.empty() ? "" : cell(f.cpu_seconds(), 4));
    t.rows.push_back(row);
  }
  return t;
}

std::array<double, 4> mean_spread(const Table& t4, SyntheticSet set) {
  const DrapeFitBounds b;
  std::array<double, 4> sum{};
  int n = 0;
  for (const auto& row : t4.rows) {
    if (row[0] != to_string(set) || row[column(t4, "best_run")].empty()) continue;
    for (int g = 0; g < 4; ++g) {
      const double lo = std::stod(row[column(t4, std::string(kParamColumns[g]) + "_min")]);
      const double hi = std::stod(row[column(t4, std::string(kParamColumns[g]) + "_max")]);
      sum[g] += (hi - lo) / (b.upper[g] - b.lower[g]);
    }
    ++n;
  }
  for (double& s : sum) s = n > 0 ? s / n : std::nan("");
  return sum;
}

std::string table4_markdown(const Table& t4, SyntheticSet set) {
  Table m;
  m.columns = {"sample",
               "k ours (paper)",
               "c ours (paper)",
               "eps % ours (paper)",
               "L0 mm ours (paper)",
               "topology",
               "error % ours (paper)",
               "k spread",
               "c spread",
               "eps spread",
               "L0 mm spread"};
  auto f = [&](const std::vector<std::string>& row, const std::string& col, double scale,
               int digits) {
    const std::string& v = row[column(t4, col)];
    return v.empty() ? std::string("-") : format_number(std::stod(v) * scale, digits);
  };
  for (const auto& row : t4.rows) {
    if (row[0] != to_string(set)) continue;
    const std::array<double, 4> scale = {1, 1, 1, 1000};
    std::vector<std::string> r = {row[1]};
    for (int g = 0; g < 4; ++g)
      r.push_back(f(row, kParamColumns[g], scale[g], 4) + " (" +
                  f(row, std::string("paper_") + kParamColumns[g], scale[g], 4) + ")");
    r.push_back(row[column(t4, "topology")] + " (" + row[column(t4, "paper_topology")] + ")");
    r.push_back(f(row, "error", 1, 3) + " (" + f(row, "paper_error", 1, 3) + ")");
    for (int g = 0; g < 4; ++g)
      r.push_back(f(row, std::string(kParamColumns[g]) + "_min", scale[g], 3) + "-" +
                  f(row, std::string(kParamColumns[g]) + "_max", scale[g], 3));
    m.rows.push_back(r);
  }
  return m.markdown();
}

template <class T>
bool contains(const std::vector<T>& v, const T& x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

std::vector<SampleFits> table_fits(const std::vector<SampleFits>& fits, const ReproOptions& o,
                                   ReproOptimizer m) {
  std::vector<SampleFits> out;
  for (const SampleFits& f : fits)
    if (f.optimizer == m && contains(o.sets, f.set) && contains(o.samples, f.sample))
      out.push_back(f);
  return out;
}

std::string suffix(ReproOptimizer m) { return m == ReproOptimizer::Ica ? "" : "_lm"; }

Table make_table6(const std::vector<SampleFits>& fits, const ReproOptions& o,
                  const ReproTargets& targets, const fs::path& dir, ReproOptimizer m) {
  const bool cost_columns = m == ReproOptimizer::Lm;
  Table t6;
  t6.columns = {"set", "sample"};
  for (const char* p : kParamColumns) t6.columns.push_back(p);
  t6.columns.insert(t6.columns.end(), {"topology", "table4_error", "error", "drape_status",
                                       "paper_table4_error", "paper_error"});
  if (cost_columns) t6.columns.insert(t6.columns.end(), {"evaluations", "cpu_seconds"});
  for (const SampleFits& f : fits) {
    const PaperSample& paper = paper_sample(f.sample);
    std::vector<std::string> row = {to_string(f.set), std::to_string(f.sample)};
    if (f.best < 0) {
      row.insert(row.end(), 8, "");
      row[9] = "no fit: " + f.error;
    } else {
      const std::vector<double> x = f.best_x();
      const DrapeFitProblem two(sample_scene("two_corner", f.sample, o),
                                targets.get(f.set, f.sample), fit_options(o, o.ica));
      const DrapeEvaluation ev = two.evaluate(x);
      for (int g = 0; g < 4; ++g) row.push_back(cell(x[g], 17));
      row.push_back(fitted_topology(x));
      row.push_back(cell(f.runs[f.best]["objective"].get<double>(), 17));
      row.push_back(ev.failed ? "" : cell(ev.objective, 17));
      row.push_back(ev.failed ? std::string(to_string(ev.status)) + ": " + ev.message
                              : to_string(ev.status));
      if (o.pictures) {
        const Scene scene = two.scene_of(x);
        const fs::path pic = dir / "pictures" /
                             (std::string(to_string(f.set)) + "_s" + std::to_string(f.sample) +
                              "_two_corner" + suffix(m));
        fs::create_directories(pic);
        write_drape_outputs(pic, scene, run_drape(scene, two.integrator()), &two.measured());
      }
    }
    row.push_back(cell(paper.table4_error));
    row.push_back(cell(paper.table6_error));
    if (cost_columns) {
      row.push_back(f.best < 0 ? "" : std::to_string(f.evaluations()));
      row.push_back(f.best < 0 ? "" : cell(f.cpu_seconds(), 4));
    }
    t6.rows.push_back(row);
  }
  return t6;
}

// The row of (set, sample) in a table whose first columns are set, sample; null if none.
const std::vector<std::string>* find_row(const Table& t, SyntheticSet set, int sample) {
  for (const auto& row : t.rows)
    if (row[0] == to_string(set) && row[1] == std::to_string(sample)) return &row;
  return nullptr;
}

// (k / L0 fitted) / (k / L0 true) - 1.
double ratio_error(const std::vector<double>& x, const PaperSample& p) {
  return (x[kGeneStiffness] / x[kGeneNaturalLength]) / (p.stiffness / p.natural_length) - 1.0;
}

Table lm_vs_ica(const std::vector<SampleFits>& lm, const std::vector<SampleFits>& ica,
                const Table& lm_t6, const Table& ica_t6) {
  Table t;
  t.columns = {"set",
               "sample",
               "lm_error",
               "ica_error",
               "paper_error",
               "lm_two_corner_error",
               "ica_two_corner_error",
               "paper_two_corner_error",
               "lm_evaluations",
               "ica_runs",
               "ica_evaluations",
               "evaluation_ratio",
               "lm_not_worse",
               "lm_cpu_seconds",
               "ica_cpu_seconds",
               "lm_topology",
               "ica_topology",
               "paper_topology",
               "lm_k_over_L0_rel_error",
               "ica_k_over_L0_rel_error",
               "lm_stiffness_rel_error",
               "lm_natural_length_rel_error",
               "k_at_true_L0",
               "k_at_true_L0_rel_error",
               "k_at_true_L0_error",
               "k_at_true_L0_evaluations"};
  auto two_corner = [](const Table& t6, const SampleFits& f) {
    const std::vector<std::string>* row = find_row(t6, f.set, f.sample);
    return row ? (*row)[8] : std::string();
  };
  for (const SampleFits& l : lm) {
    const PaperSample& paper = paper_sample(l.sample);
    const auto i = std::find_if(ica.begin(), ica.end(), [&](const SampleFits& f) {
      return f.set == l.set && f.sample == l.sample;
    });
    const bool has_lm = l.best >= 0, has_ica = i != ica.end() && i->best >= 0;
    const bool twin = l.set == SyntheticSet::Twin;
    auto objective = [](const SampleFits& f) { return f.runs[f.best]["objective"].get<double>(); };
    std::vector<std::string> row = {to_string(l.set), std::to_string(l.sample)};
    row.push_back(has_lm ? cell(objective(l), 17) : "");
    row.push_back(has_ica ? cell(objective(*i), 17) : "");
    row.push_back(cell(paper.table4_error));
    row.push_back(two_corner(lm_t6, l));
    row.push_back(i != ica.end() ? two_corner(ica_t6, *i) : "");
    row.push_back(cell(paper.table6_error));
    row.push_back(has_lm ? std::to_string(l.evaluations()) : "");
    row.push_back(has_ica ? std::to_string(i->runs.size()) : "");
    row.push_back(has_ica ? std::to_string(i->evaluations()) : "");
    const bool both = has_lm && has_ica;
    row.push_back(both ? cell(static_cast<double>(i->evaluations()) / l.evaluations(), 4) : "");
    row.push_back(both ? (objective(l) <= objective(*i) ? "1" : "0") : "");
    row.push_back(has_lm ? cell(l.cpu_seconds(), 4) : "");
    row.push_back(has_ica ? cell(i->cpu_seconds(), 4) : "");
    row.push_back(has_lm ? fitted_topology(l.best_x()) : "");
    row.push_back(has_ica ? fitted_topology(i->best_x()) : "");
    row.push_back(std::string(1, paper.topology));
    row.push_back(twin && has_lm ? cell(ratio_error(l.best_x(), paper)) : "");
    row.push_back(twin && has_ica ? cell(ratio_error(i->best_x(), paper)) : "");
    if (twin && has_lm) {
      const std::vector<double> x = l.best_x();
      row.push_back(cell((x[kGeneStiffness] - paper.stiffness) / paper.stiffness));
      row.push_back(cell((x[kGeneNaturalLength] - paper.natural_length) / paper.natural_length));
      const json& known = l.runs[l.best]["known_length"];
      const bool known_ok = !known["stiffness"].is_null();
      const double k = known_ok ? known["stiffness"].get<double>() : 0.0;
      row.push_back(known_ok ? cell(k, 17) : "");
      row.push_back(known_ok ? cell((k - paper.stiffness) / paper.stiffness) : "");
      row.push_back(known_ok ? cell(known["objective"].get<double>(), 17) : "");
      row.push_back(std::to_string(known["evaluations"].get<long>()));
    } else {
      row.insert(row.end(), 6, "");
    }
    t.rows.push_back(row);
  }
  return t;
}

std::string lm_vs_ica_markdown(const Table& t, SyntheticSet set) {
  auto num = [&](const std::vector<std::string>& row, const std::string& c, double scale,
                 int digits) {
    const std::string& v = row[column(t, c)];
    return v.empty() ? std::string("-") : format_number(std::stod(v) * scale, digits);
  };
  const bool twin = set == SyntheticSet::Twin;
  Table m;
  m.columns = {"sample",
               "4-corner error % LM / ICA / paper",
               "2-corner error % LM / ICA / paper",
               "drapes LM / ICA (ratio)",
               "CPU s LM / ICA",
               "topology LM / ICA / paper"};
  if (twin)
    m.columns.insert(m.columns.end(),
                     {"k/L0 error % LM / ICA", "k, L0 error % LM", "k at true L0: error %"});
  int rows = 0, not_worse = 0, ratio20 = 0, ratio_ok = 0, k_ok = 0;
  double ratio_min = std::numeric_limits<double>::infinity(), ratio_max = 0.0;
  for (const auto& row : t.rows) {
    if (row[0] != to_string(set)) continue;
    std::vector<std::string> r = {
        row[1],
        num(row, "lm_error", 1, 4) + " / " + num(row, "ica_error", 1, 4) + " / " +
            num(row, "paper_error", 1, 3),
        num(row, "lm_two_corner_error", 1, 4) + " / " + num(row, "ica_two_corner_error", 1, 4) +
            " / " + num(row, "paper_two_corner_error", 1, 3),
        num(row, "lm_evaluations", 1, 6) + " / " + num(row, "ica_evaluations", 1, 6) + " (" +
            num(row, "evaluation_ratio", 1, 3) + ")",
        num(row, "lm_cpu_seconds", 1, 3) + " / " + num(row, "ica_cpu_seconds", 1, 3),
        row[column(t, "lm_topology")] + " / " + row[column(t, "ica_topology")] + " / " +
            row[column(t, "paper_topology")]};
    if (twin)
      r.insert(r.end(), {num(row, "lm_k_over_L0_rel_error", 100, 3) + " / " +
                             num(row, "ica_k_over_L0_rel_error", 100, 3),
                         num(row, "lm_stiffness_rel_error", 100, 3) + ", " +
                             num(row, "lm_natural_length_rel_error", 100, 3),
                         num(row, "k_at_true_L0_rel_error", 100, 3)});
    m.rows.push_back(r);
    ++rows;
    if (row[column(t, "lm_not_worse")] == "1") ++not_worse;
    const std::string& ratio = row[column(t, "evaluation_ratio")];
    if (!ratio.empty()) {
      ++ratio_ok;
      ratio_min = std::min(ratio_min, std::stod(ratio));
      ratio_max = std::max(ratio_max, std::stod(ratio));
      if (std::stod(ratio) >= 20.0) ++ratio20;
    }
    const std::string& k = row[column(t, "k_at_true_L0_rel_error")];
    if (!k.empty() && std::abs(std::stod(k)) <= 0.01) ++k_ok;
  }
  std::ostringstream out;
  out << m.markdown() << "\n";
  if (ratio_ok > 0)
    out << "LM error <= the ICA's best on " << not_worse << " of " << rows
        << " samples; ICA / LM drape evaluations " << format_number(ratio_min, 3) << "-"
        << format_number(ratio_max, 3) << " (>= 20 on " << ratio20 << " of " << rows << ").";
  if (twin)
    out << (ratio_ok > 0 ? " " : "") << "k at the true L0 within 1 % on " << k_ok << " of " << rows
        << ".";
  out << "\n\n";
  return out.str();
}

std::string four_corner_pictures(const std::vector<SampleFits>& fits, const ReproOptions& o,
                                 const ReproTargets& targets, const fs::path& dir, ReproOptimizer m,
                                 bool two_corner) {
  std::ostringstream rows;
  for (const SampleFits& f : fits) {
    if (f.best < 0) continue;
    const std::vector<double> x = f.best_x();
    const DrapeFitProblem four(sample_scene("four_corner", f.sample, o),
                               targets.get(f.set, f.sample), fit_options(o, o.ica));
    const Scene scene = four.scene_of(x);
    const std::string stem = std::string(to_string(f.set)) + "_s" + std::to_string(f.sample);
    const fs::path pic = dir / "pictures" / (stem + "_four_corner" + suffix(m));
    fs::create_directories(pic);
    write_drape_outputs(pic, scene, run_drape(scene, four.integrator()), &four.measured());
    rows << "| " << to_string(m) << " | " << to_string(f.set) << " | " << f.sample
         << " | ![](pictures/" << stem << "_four_corner" << suffix(m) << "/drape.png) | "
         << (two_corner ? "![](pictures/" + stem + "_two_corner" + suffix(m) + "/drape.png)"
                        : std::string("-"))
         << " |\n";
  }
  return rows.str();
}

}  // namespace knitsim::repro_internal
