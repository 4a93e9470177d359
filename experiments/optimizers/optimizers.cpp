// Optimizers side by side on the drape fit: the ICA of paper 1 (src/fit/ica.hpp)
// against pagmo2's DE, SADE, CMA-ES and PSO (Debian's libpagmo-dev) and against the screened
// multi-start Levenberg-Marquardt fit (src/fit/lm_fit.hpp), on the same target and the same budget
// of drape evaluations.
//
// Problem: DrapeFitProblem (src/fit/drape_fit.hpp) of the base scene `--scene` (default
// four_corner) with the Table 2 areal density of `--sample` (as `knitsim fit --scene four_corner
// --set fabric.areal_density=<Table 2>` builds it), rtol 1e-8, the Table 3 box, fitted to
// `--target` (default: the twin target of sample 1, paper_repro/data/README.md). Cost = Eq. 5 error, percent.
// Encoding, the same for every optimizer: the 5 genes k, c, eps, L0 and the topology gene u in
// [0, 3), topology = 'a' + floor(u) (src/fit/ica.hpp category_of; pagmo may propose u = 3 exactly,
// which maps to c). LM searches the topologies x grid sizes itself (src/fit/lm_fit.hpp).
//
// Budget B drape evaluations per (optimizer, seed), enforced by one counting wrapper
// (EvaluationLog) through which every evaluation of every optimizer goes: it runs the drape,
// records the best-so-far error and CPU time, and instead of evaluation B + 1 it throws
// BudgetExhausted, which ends the optimizer (the ICA and pagmo propagate exceptions of the cost;
// LM's on_evaluation hook throws after evaluation B + 1 has run, which is then not recorded).
// The result of a run is the best country of the evaluations it was allowed, so every
// population method gets exactly B evaluations; LM stops by itself (~30-50 evaluations).
// Settings (population_plan, ica_plan): population P and generations G with P (G + 1) >= B:
//   ica    Taguchi-best A3 B3 C1 D2 E1 F2 G2 (25 countries, 2 imperialists, beta 1, gamma 0.1,
//          revolution 0.3, xi 0.15), all decades run; decades = ceil((B - N) / (N - 2)) instead
//          of 40; countries N = clamp(B / 5, 3, 25) (small budgets keep several decades);
//   de     pagmo::de, F 0.8, CR 0.9, rand/1/exp (pagmo defaults), NP = clamp(B / 5, 7, 20);
//   sade   pagmo::sade, jDE self-adaptation of F and CR (defaults), NP as de;
//   cmaes  pagmo::cmaes, lambda = clamp(B / 5, 5, 8) (Hansen's 4 + floor(3 ln 5) = 8),
//          sigma0 0.5 of the box width, force_bounds (a drape outside the box is meaningless);
//   pso    pagmo::pso, canonical constriction variant 5, lbest ring of 4 (defaults), 20 particles;
//   lm     fit_drape_lm defaults (1 start per (topology, n bracket), 2 refined), seed = run seed
//          (it only draws the k of extra starts: with the defaults LM is deterministic).
// pagmo's ftol / xtol stopping rules are set to 0 so that no run stops before its budget.
// Seeds 1..S: the ICA's IcaOptions::seed, pagmo's population and algorithm seeds.
// Each run is on one thread (--jobs N runs N of them at once); CPU seconds are that thread's
// CPU time (CLOCK_THREAD_CPUTIME_ID), so they do not depend on --jobs or the machine's load.
//
// Outputs in --out (default out/experiments/optimizers):
//   runs.csv       optimizer, seed, budget, evaluations, failed_evaluations, stop (budget |
//                  finished), final_error (%), cpu_seconds, the best country (stiffness N/m,
//                  damping N s/m, elongation_limit %, natural_length m, topology), cells
//                  n = round(W / L0);
//   trace.csv      optimizer, seed, evaluation, best_so_far (%), cpu_seconds: the first
//                  evaluation, every evaluation that lowered the best-so-far error, and the last
//                  one (best-so-far is a step function, so these rows hold all of it);
//   reference.csv  the error of the sample's Table 4 parameters (the twin's truth) on the target;
//   manifest.json  the settings of every optimizer and the study options.
// Usage:
//   knitsim_optimizers [--target FILE] [--sample S] [--scene NAME] [--budget B] [--seeds S]
//                      [--optimizers ica,de,sade,cmaes,pso,lm] [--jobs N] [--out DIR]
//                      [--resume]   (keeps the runs already in DIR/runs.csv with this budget)
// Cost: about B x S x 5 four_corner drapes (~73 ms CPU each at rtol 1e-8) plus S LM fits.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <pagmo/algorithm.hpp>
#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/algorithms/de.hpp>
#include <pagmo/algorithms/pso.hpp>
#include <pagmo/algorithms/sade.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "src/base/command_line.hpp"
#include "src/base/files.hpp"
#include "src/base/table.hpp"
#include "src/base/text.hpp"
#include "src/io/json.hpp"
#include "src/io/manifest.hpp"
#include "src/fit/lm_fit.hpp"
#include "src/measure/measurement.hpp"
#include "src/paper/paper_data.hpp"
#include "src/scene/scene.hpp"

using namespace knitsim;

namespace {

// CPU seconds of the calling thread (each run is on one thread, see --jobs).
double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

const std::vector<std::string> kOptimizers = {"ica", "de", "sade", "cmaes", "pso", "lm"};

struct StudyOptions {
  std::string target = "paper_repro/data/targets/twin_sample1.csv";
  int sample = 1;                     // paper sample: Table 2 areal density, Table 4 reference
  std::string scene = "four_corner";  // base scene
  double rtol = 1e-8;                 // of every drape (as knitsim fit)
  long budget = 300;                  // drape evaluations per (optimizer, seed), >= 10
  int seeds = 10;                     // seeds 1..seeds, >= 1
  int jobs = 1;                       // threads, each running whole (optimizer, seed) runs
  bool resume = false;                // keep the runs already in out/runs.csv (same budget)
  std::vector<std::string> optimizers = kOptimizers;
  std::string out = "out/experiments/optimizers";

  // std::invalid_argument "<field> = <value>: accepted range".
  void validate() const {
    if (budget < 10)
      throw std::invalid_argument("budget = " + std::to_string(budget) + ": must be >= 10");
    if (seeds < 1)
      throw std::invalid_argument("seeds = " + std::to_string(seeds) + ": must be >= 1");
    if (jobs < 1) throw std::invalid_argument("jobs = " + std::to_string(jobs) + ": must be >= 1");
    if (!(rtol > 0.0 && rtol <= 0.1))
      throw std::invalid_argument("rtol = " + format_number(rtol) + ": accepted (0, 0.1]");
    for (const std::string& o : optimizers)
      if (std::find(kOptimizers.begin(), kOptimizers.end(), o) == kOptimizers.end())
        throw std::invalid_argument("optimizers = " + o + ": accepted ica|de|sade|cmaes|pso|lm");
    paper_sample(sample);  // throws for a sample outside 1..9
  }
};

// Thrown by EvaluationLog instead of running evaluation budget + 1.
struct BudgetExhausted : std::runtime_error {
  BudgetExhausted() : std::runtime_error("evaluation budget exhausted") {}
};

// The one counting wrapper (see the header comment). Single-threaded.
class EvaluationLog {
 public:
  struct Point {
    long evaluation;
    double best_so_far;  // percent; +inf while every evaluation failed
    double cpu_seconds;  // since the log was made
  };

  EvaluationLog(const DrapeFitProblem& problem, long budget)
      : problem_(problem), budget_(budget), cpu0_(cpu_now()) {}

  // One drape evaluation of country x: its Eq. 5 error, NaN if it failed.
  double cost(const std::vector<double>& x) {
    if (evaluations_ >= budget_) throw BudgetExhausted();
    const DrapeEvaluation e = problem_.evaluate(x);
    return record(x, e.failed, e.objective);
  }
  // Records an evaluation made elsewhere (LM's); returns its error, NaN if it failed.
  double record(const std::vector<double>& x, bool failed, double objective) {
    if (evaluations_ >= budget_) throw BudgetExhausted();
    ++evaluations_;
    if (failed) ++failed_;
    const double cpu = cpu_now() - cpu0_;
    const bool improved = !failed && objective < best_;
    if (improved) {
      best_ = objective;
      best_x_ = x;
    }
    if (improved || trace_.empty()) trace_.push_back({evaluations_, best_, cpu});
    last_ = {evaluations_, best_, cpu};
    return failed ? std::numeric_limits<double>::quiet_NaN() : objective;
  }

  long evaluations() const { return evaluations_; }
  long failed() const { return failed_; }
  bool exhausted() const { return evaluations_ >= budget_; }
  double best() const { return best_; }
  const std::vector<double>& best_x() const { return best_x_; }
  double cpu_seconds() const { return cpu_now() - cpu0_; }
  // The improvement points plus the last evaluation.
  std::vector<Point> trace() const {
    std::vector<Point> t = trace_;
    if (!t.empty() && t.back().evaluation != last_.evaluation) t.push_back(last_);
    return t;
  }

 private:
  const DrapeFitProblem& problem_;
  long budget_;
  double cpu0_;
  long evaluations_ = 0, failed_ = 0;
  double best_ = std::numeric_limits<double>::infinity();
  std::vector<double> best_x_;
  std::vector<Point> trace_;
  Point last_{0, 0.0, 0.0};
};

// Population P = clamp(B / 5, minimum, nominal) and generations G = ceil((B - P) / P), so that
// P (G + 1) >= B: the budget, not the generation count, ends the run.
struct PopulationPlan {
  int population = 0;
  int generations = 0;
};
PopulationPlan population_plan(long budget, int minimum, int nominal) {
  const int p = static_cast<int>(std::clamp<long>(budget / 5, minimum, nominal));
  return {p, static_cast<int>((budget - 1) / p)};  // ceil((B - P) / P)
}

// The Taguchi-best ICA with N = clamp(B / 5, 3, 25) countries and decades = ceil((B - N) /
// (N - imperialists)): at least B evaluations (colonies only grow as empires collapse).
IcaOptions ica_plan(long budget, std::uint64_t seed) {
  IcaOptions o;  // A3 B3 C1 D2 E1 F2 G2
  o.countries = static_cast<int>(std::clamp<long>(budget / 5, 3, o.countries));
  const long colonies = o.countries - o.imperialists;
  o.decades = static_cast<int>((budget - o.countries + colonies - 1) / colonies);
  o.seed = seed;
  o.jobs = 1;
  return o;
}

constexpr double kFailureCost = 1e10;  // pagmo's score of a failed drape (as IcaOptions)

// The drape fit as a pagmo user-defined problem; every fitness call goes through the log.
struct PagmoDrape {
  EvaluationLog* log = nullptr;
  pagmo::vector_double lower, upper;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    const double e = log->cost(x);
    return {std::isnan(e) ? kFailureCost : e};
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    return {lower, upper};
  }
};

// The pagmo algorithm `name` planned for the budget, seeded; plan receives its sizes.
pagmo::algorithm pagmo_algorithm(const std::string& name, long budget, unsigned seed,
                                 PopulationPlan& plan) {
  if (name == "de") {
    plan = population_plan(budget, 7, 20);
    return pagmo::algorithm(pagmo::de(plan.generations, 0.8, 0.9, 2u, 0.0, 0.0, seed));
  }
  if (name == "sade") {
    plan = population_plan(budget, 7, 20);
    return pagmo::algorithm(pagmo::sade(plan.generations, 2u, 1u, 0.0, 0.0, false, seed));
  }
  if (name == "cmaes") {
    plan = population_plan(budget, 5, 8);
    return pagmo::algorithm(
        pagmo::cmaes(plan.generations, -1, -1, -1, -1, 0.5, 0.0, 0.0, false, true, seed));
  }
  plan = population_plan(budget, 7, 20);  // pso
  return pagmo::algorithm(
      pagmo::pso(plan.generations, 0.7298, 2.05, 2.05, 0.5, 5u, 2u, 4u, false, seed));
}

// The settings of optimizer `name` for this budget (for the manifest).
nlohmann::json optimizer_settings(const std::string& name, long budget) {
  if (name == "ica") return to_json(ica_plan(budget, 1));
  if (name == "lm") return to_json(DrapeLmOptions{});
  PopulationPlan plan;
  const pagmo::algorithm algo = pagmo_algorithm(name, budget, 1, plan);
  return {{"population", plan.population},
          {"generations", plan.generations},
          {"algorithm", algo.get_name()}};
}

// Runs optimizer `name` with this seed until it finishes or the log's budget ends it; returns
// the stop reason ("budget" | "finished").
std::string run_optimizer(const std::string& name, const DrapeFitProblem& problem, long budget,
                          int seed, EvaluationLog& log) {
  try {
    if (name == "ica") {
      const IcaOptions o = ica_plan(budget, static_cast<std::uint64_t>(seed));
      Problem p = problem.ica_problem();  // the box and the categorical topology gene
      p.cost = [&log](const std::vector<double>& x) { return log.cost(x); };
      run_ica(p, o);
    } else if (name == "lm") {
      DrapeLmOptions o;
      o.seed = static_cast<std::uint64_t>(seed);
      o.on_evaluation = [&log](const std::vector<double>& x, const DrapeResiduals& e) {
        log.record(x, e.failed, e.objective);
      };
      fit_drape_lm(problem, o);
    } else {
      PopulationPlan plan;
      pagmo::algorithm algo = pagmo_algorithm(name, budget, static_cast<unsigned>(seed), plan);
      const DrapeFitBounds& box = problem.options().bounds;
      PagmoDrape udp{
          &log, {box.lower.begin(), box.lower.end()}, {box.upper.begin(), box.upper.end()}};
      pagmo::population pop(pagmo::problem(udp),
                            static_cast<pagmo::population::size_type>(plan.population),
                            static_cast<unsigned>(seed));
      algo.evolve(pop);
    }
  } catch (const BudgetExhausted&) {
    return "budget";
  }
  return "finished";
}

const std::vector<std::string> kRunsColumns = {
    "optimizer",          "seed",    "budget",           "evaluations",
    "failed_evaluations", "stop",    "final_error",      "cpu_seconds",
    "stiffness",          "damping", "elongation_limit", "natural_length",
    "topology",           "cells"};
const std::vector<std::string> kTraceColumns = {"optimizer", "seed", "evaluation", "best_so_far",
                                                "cpu_seconds"};

// The data rows of a CSV file this program wrote (cells never hold commas or quotes);
// std::invalid_argument if its header is not `columns`.
std::vector<std::vector<std::string>> read_rows(const std::filesystem::path& path,
                                                const std::vector<std::string>& columns) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  for (bool header = true; std::getline(in, line); header = false) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    if (header && cells != columns)
      throw std::invalid_argument("--resume: " + path.string() + " is not this program's");
    if (!header) rows.push_back(cells);
  }
  return rows;
}

// One (optimizer, seed) run: its runs.csv row and trace.csv rows.
struct RunRecord {
  bool done = false;
  std::vector<std::string> row;
  std::vector<std::vector<std::string>> trace;
};

RunRecord run_unit(const std::string& name, int seed, const DrapeFitProblem& problem, long budget) {
  EvaluationLog log(problem, budget);
  RunRecord rec;
  rec.done = true;
  const std::string stop = run_optimizer(name, problem, budget, seed, log);
  rec.row = {name,
             std::to_string(seed),
             std::to_string(budget),
             std::to_string(log.evaluations()),
             std::to_string(log.failed()),
             stop,
             format_number(log.best(), 8),
             format_number(log.cpu_seconds(), 4)};
  if (log.best_x().empty()) {
    rec.row.insert(rec.row.end(), 6, "");
  } else {
    const DrapeParams p = problem.params_of(log.best_x());
    rec.row.insert(rec.row.end(), {format_number(p.stiffness, 6), format_number(p.damping, 6),
                                   format_number(p.elongation_limit, 6),
                                   format_number(p.natural_length, 6), std::string(1, p.topology),
                                   std::to_string(std::lround(p.width / p.natural_length))});
  }
  for (const EvaluationLog::Point& pt : log.trace())
    rec.trace.push_back({name, std::to_string(seed), std::to_string(pt.evaluation),
                         format_number(pt.best_so_far, 8), format_number(pt.cpu_seconds, 4)});
  return rec;
}

}  // namespace

int main(int argc, char** argv) {
  set_command_line(argc, argv);
  StudyOptions o;
  std::string optimizers;
  CLI::App app{"Optimizers side by side on the drape fit (experiments/optimizers/README.md)"};
  app.add_option("--target", o.target, "Target CSV (src/fit/targets.hpp)");
  app.add_option("--sample", o.sample, "Paper sample: Table 2 areal density, Table 4 reference");
  app.add_option("--scene", o.scene, "Base scene (built-in name or TOML file)");
  app.add_option("--rtol", o.rtol, "Relative tolerance of every drape");
  app.add_option("--budget", o.budget, "Drape evaluations per optimizer and seed (>= 10)");
  app.add_option("--seeds", o.seeds, "Seeds 1..S per optimizer");
  app.add_option("--jobs", o.jobs, "Threads, each running whole (optimizer, seed) runs");
  app.add_option("--optimizers", optimizers, "Comma list of ica,de,sade,cmaes,pso,lm");
  app.add_option("--out", o.out, "Output folder");
  app.add_flag("--resume", o.resume, "Keep the runs of an interrupted study in --out");
  CLI11_PARSE(app, argc, argv);
  try {
    if (!optimizers.empty()) {
      o.optimizers.clear();
      std::stringstream ss(optimizers);
      for (std::string item; std::getline(ss, item, ',');) o.optimizers.push_back(item);
    }
    o.validate();
    const PaperSample& sample = paper_sample(o.sample);
    Scene base =
        load_scene(o.scene, {"fabric.areal_density=" + format_number(sample.areal_density, 17)});
    base.options.rtol = o.rtol;
    const DrapeFitProblem problem(base, read_target_csv(o.target), DrapeFitOptions{});
    std::filesystem::create_directories(o.out);
    const std::filesystem::path out(o.out);

    // Reference: the sample's Table 4 parameters (for a twin target, the truth).
    const std::vector<double> table4 = {sample.stiffness, sample.damping, sample.elongation_limit,
                                        sample.natural_length, sample.topology - 'a' + 0.5};
    const DrapeEvaluation at_table4 = problem.evaluate(table4);
    Table reference;
    reference.columns = {"reference", "error"};
    reference.rows.push_back({"table4_parameters", format_number(at_table4.objective, 8)});
    write_file_atomic(out / "reference.csv", reference.csv());
    std::cout << "error at the Table 4 parameters of sample " << o.sample << ": "
              << format_number(at_table4.objective, 6) << " %\n";

    // The runs, seed by seed (an interrupted study has every optimizer on its first seeds);
    // --jobs threads take them in turn.
    std::vector<std::pair<std::string, int>> units;
    for (int seed = 1; seed <= o.seeds; ++seed)
      for (const std::string& name : o.optimizers) units.emplace_back(name, seed);
    std::vector<RunRecord> records(units.size());
    if (o.resume && std::filesystem::exists(out / "runs.csv")) {  // keep the finished runs
      const auto trace_rows = read_rows(out / "trace.csv", kTraceColumns);
      for (const std::vector<std::string>& row : read_rows(out / "runs.csv", kRunsColumns))
        for (size_t i = 0; i < units.size(); ++i)
          if (row[0] == units[i].first && row[1] == std::to_string(units[i].second) &&
              row[2] == std::to_string(o.budget)) {
            records[i] = {true, row, {}};
            for (const std::vector<std::string>& t : trace_rows)
              if (t[0] == row[0] && t[1] == row[1]) records[i].trace.push_back(t);
          }
    }
    std::mutex mutex;
    std::atomic<size_t> next{0};
    bool failed = false;       // some run threw (guarded by mutex)
    auto write_tables = [&] {  // the finished runs, in seed order (after every run)
      Table runs, trace;
      runs.columns = kRunsColumns;
      trace.columns = kTraceColumns;
      for (const RunRecord& r : records)
        if (r.done) {
          runs.rows.push_back(r.row);
          trace.rows.insert(trace.rows.end(), r.trace.begin(), r.trace.end());
        }
      write_file_atomic(out / "runs.csv", runs.csv());
      write_file_atomic(out / "trace.csv", trace.csv());
    };
    auto worker = [&] {
      for (size_t i = next++; i < units.size(); i = next++) {
        if (records[i].done) continue;  // resumed
        RunRecord rec;
        try {
          rec = run_unit(units[i].first, units[i].second, problem, o.budget);
        } catch (const std::exception& e) {  // a bug: report it, finish the other runs
          std::lock_guard<std::mutex> lock(mutex);
          std::cerr << units[i].first << " seed " << units[i].second << ": " << e.what() << "\n";
          failed = true;
          continue;
        }
        std::lock_guard<std::mutex> lock(mutex);
        std::cout << units[i].first << " seed " << units[i].second << ": " << rec.row[6]
                  << " % after " << rec.row[3] << " evaluations (" << rec.row[5] << "), "
                  << rec.row[7] << " s CPU\n"
                  << std::flush;
        records[i] = std::move(rec);
        write_tables();
      }
    };
    std::vector<std::thread> threads;
    for (int t = 1; t < o.jobs; ++t) threads.emplace_back(worker);
    worker();
    for (std::thread& t : threads) t.join();

    nlohmann::json settings = nlohmann::json::object();
    for (const std::string& name : o.optimizers)
      settings[name] = optimizer_settings(name, o.budget);
    write_json_atomic(
        out / "manifest.json",
        manifest({{"target", o.target},
                  {"sample", o.sample},
                  {"scene", o.scene},
                  {"areal_density", sample.areal_density},
                  {"rtol", o.rtol},
                  {"integrator", problem.integrator()},
                  {"budget", o.budget},
                  {"seeds", o.seeds},
                  {"jobs", o.jobs},
                  {"optimizers", o.optimizers},
                  {"settings", settings},
                  {"topology_encoding", "gene u in [0, 3), topology = 'a' + floor(u)"},
                  {"error_at_table4_parameters", at_table4.objective}}));
    if (failed) return 1;
  } catch (const std::invalid_argument& e) {
    std::cerr << "knitsim_optimizers: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
