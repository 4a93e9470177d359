#include "src/fit/ica.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <locale>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "src/core/invalid_field.hpp"

namespace knitsim {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

// ---------------------------------------------------------------------------------------
// Options, Table 1, problem

const std::array<std::array<double, 3>, 7>& ica_table1_levels() {
  static const std::array<std::array<double, 3>, 7> levels = {{
      {10, 20, 40},      // A MaxIt (decades)
      {15, 20, 25},      // B number of countries (printed as "imperials")
      {2, 5, 10},        // C number of imperialists (printed as "countries")
      {0.5, 1, 2},       // D beta
      {0.1, 0.3, 0.5},   // E gamma, rad
      {0.2, 0.3, 0.4},   // F revolution rate
      {0.1, 0.15, 0.2},  // G xi
  }};
  return levels;
}

IcaOptions ica_table1_options(const std::array<int, 7>& levels) {
  for (int f = 0; f < 7; ++f)
    if (levels[f] < 1 || levels[f] > 3)
      bad_field(std::string("level of factor ") + static_cast<char>('A' + f), levels[f],
                "must be 1, 2 or 3");
  const auto& t = ica_table1_levels();
  auto value = [&](int f) { return t[f][levels[f] - 1]; };
  IcaOptions o;
  o.decades = static_cast<int>(value(0));
  o.countries = static_cast<int>(value(1));
  o.imperialists = static_cast<int>(value(2));
  o.beta = value(3);
  o.gamma = value(4);
  o.revolution_rate = value(5);
  o.xi = value(6);
  return o;
}

void Problem::validate() const {
  if (lower.empty()) throw std::invalid_argument("problem dimension = 0: must be >= 1");
  if (upper.size() != lower.size())
    bad_field("problem upper bounds", upper.size(),
              "must have one entry per dimension (" + std::to_string(lower.size()) + ")");
  for (std::size_t i = 0; i < lower.size(); ++i)
    if (!(std::isfinite(lower[i]) && std::isfinite(upper[i]) && upper[i] > lower[i]))
      bad_field("problem bounds [" + std::to_string(i) + "]", upper[i] - lower[i],
                "upper - lower must be finite and > 0");
  if (!categorical.empty() && categorical.size() != lower.size())
    bad_field("problem categorical flags", categorical.size(),
              "must be empty or one per dimension (" + std::to_string(lower.size()) + ")");
  if (static_cast<bool>(cost) == static_cast<bool>(batch_cost))
    throw std::invalid_argument("problem cost: set exactly one of cost and batch_cost");
}

int category_of(double u, double lower, double upper) {
  const int count = static_cast<int>(std::ceil(upper - lower));
  const int k = static_cast<int>(std::floor(u - lower));
  return std::clamp(k, 0, std::max(0, count - 1));
}

// ---------------------------------------------------------------------------------------
// Random numbers

double IcaRandom::uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

double IcaRandom::uniform(double a, double b) { return a + (b - a) * uniform(); }

int IcaRandom::index(int n) {
  const std::uint64_t range = static_cast<std::uint64_t>(n);
  const std::uint64_t threshold = (0 - range) % range;  // 2^64 mod n: reject below it
  for (;;) {
    const std::uint64_t r = engine_();
    if (r >= threshold) return static_cast<int>(r % range);
  }
}

double IcaRandom::normal() {
  const double u1 = 1.0 - uniform();  // (0, 1]
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

std::string IcaRandom::state() const {
  std::ostringstream os;
  os.imbue(std::locale::classic());
  os << engine_;
  return os.str();
}

void IcaRandom::set_state(const std::string& state) {
  std::istringstream is(state);
  is.imbue(std::locale::classic());
  std::mt19937_64 engine;
  is >> engine;
  if (!is || !(is >> std::ws).eof())
    throw std::invalid_argument("ICA random state: not a std::mt19937_64 state");
  engine_ = engine;
}

// ---------------------------------------------------------------------------------------
// Steps 2 and 3

std::vector<int> allocate_colonies(const std::vector<double>& imperialist_costs, int colonies) {
  const int k = static_cast<int>(imperialist_costs.size());
  if (k < 1 || colonies < 1) bad_field("colonies", colonies, "must be >= 1, with >= 1 imperialist");
  const double worst = *std::max_element(imperialist_costs.begin(), imperialist_costs.end());
  double sum = 0.0;
  for (double c : imperialist_costs) sum += c - worst;
  std::vector<int> count(k);
  int dealt = 0;
  for (int n = 0; n + 1 < k; ++n) {
    const double power = sum != 0.0 ? std::abs((imperialist_costs[n] - worst) / sum) : 1.0 / k;
    count[n] = static_cast<int>(std::lround(power * colonies));
    dealt += count[n];
  }
  count[k - 1] = colonies - dealt;
  for (;;) {  // the repair: the richest empire gives to the poorest while it can spare one
    const auto poorest = std::min_element(count.begin(), count.end());
    const auto richest = std::max_element(count.begin(), count.end());
    if (*poorest >= 1 || (*poorest == 0 && *richest < 2)) break;
    --*richest;
    ++*poorest;
  }
  return count;
}

void assimilate(std::vector<double>& x, const std::vector<double>& imperialist, double beta,
                double gamma, IcaRandom& rng) {
  const std::size_t dim = x.size();
  std::vector<double> u(dim);
  double norm = 0.0;
  for (std::size_t i = 0; i < dim; ++i) {
    u[i] = imperialist[i] - x[i];
    norm += u[i] * u[i];
  }
  norm = std::sqrt(norm);
  if (norm == 0.0) return;
  const double s = rng.uniform(0.0, beta * norm);
  const double theta = rng.uniform(-gamma, gamma);
  for (double& ui : u) ui /= norm;
  if (dim == 1) {
    x[0] += s * u[0];
    return;
  }
  std::vector<double> v(dim);
  double vu = 0.0;
  for (std::size_t i = 0; i < dim; ++i) {
    v[i] = rng.normal();
    vu += v[i] * u[i];
  }
  double vnorm = 0.0;
  for (std::size_t i = 0; i < dim; ++i) {
    v[i] -= vu * u[i];
    vnorm += v[i] * v[i];
  }
  vnorm = std::sqrt(vnorm);
  const double along = s * std::cos(theta);
  const double across = vnorm > 0.0 ? s * std::sin(theta) / vnorm : 0.0;
  for (std::size_t i = 0; i < dim; ++i) x[i] += along * u[i] + across * v[i];
}

const char* to_string(IcaStatus s) {
  switch (s) {
    case IcaStatus::DecadeLimit:
      return "decade_limit";
    case IcaStatus::OneEmpire:
      return "one_empire";
    case IcaStatus::AllFailed:
      return "all_failed";
    case IcaStatus::Interrupted:
      return "interrupted";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------------------
// The algorithm

namespace {

using Point = std::vector<double>;

struct Empire {
  Point imperialist;
  double imperialist_cost = 0.0;
  std::vector<Point> colonies;
  std::vector<double> colony_costs;
  double total_cost = 0.0;
};

// Point costs of xs on `jobs` threads; each result goes to its own slot. An exception thrown
// by the cost function stops the batch and is rethrown here after every thread has joined.
void evaluate_points(const Problem::PointCost& cost, const std::vector<Point>& xs,
                     std::vector<double>& costs, int jobs) {
  const int n = static_cast<int>(xs.size());
  const int threads = std::min(jobs, n);
  if (threads <= 1) {
    for (int i = 0; i < n; ++i) costs[i] = cost(xs[i]);
    return;
  }
  std::atomic<int> next{0};
  std::vector<std::exception_ptr> errors(threads);
  auto work = [&](int t) {
    try {
      for (int i = next++; i < n; i = next++) costs[i] = cost(xs[i]);
    } catch (...) {
      errors[t] = std::current_exception();
      next = n;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
  for (auto& th : pool) th.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

// Evaluates batches, scores failures, counts, and keeps the best point ever evaluated.
class Evaluator {
 public:
  Evaluator(const Problem& p, const IcaOptions& o) : problem_(p), options_(o) {}

  void operator()(const std::vector<Point>& xs, std::vector<double>& costs) {
    costs.assign(xs.size(), 0.0);
    if (problem_.batch_cost) {
      problem_.batch_cost(xs, costs);
      if (costs.size() != xs.size())
        throw std::logic_error("Problem::batch_cost resized the cost vector");
    } else {
      evaluate_points(problem_.cost, xs, costs, options_.jobs);
    }
    for (std::size_t i = 0; i < xs.size(); ++i) {
      ++evaluations;
      if (!std::isfinite(costs[i])) {
        costs[i] = options_.failure_cost;
        ++failed;
        if (best_x.empty()) best_x = xs[i];
        continue;
      }
      if (!found || costs[i] < best_cost) {
        found = true;
        best_cost = costs[i];
        best_x = xs[i];
      }
    }
  }

  long evaluations = 0;
  long failed = 0;
  bool found = false;  // some evaluation succeeded
  double best_cost = 0.0;
  Point best_x;

 private:
  const Problem& problem_;
  const IcaOptions& options_;
};

class Ica {
 public:
  Ica(const Problem& p, const IcaOptions& o)
      : problem_(p), options_(o), rng_(o.seed), evaluate_(p, o), upper_(p.upper) {
    for (std::size_t i = 0; i < p.categorical.size(); ++i)
      if (p.categorical[i]) upper_[i] = std::nextafter(p.upper[i], p.lower[i]);
  }

  IcaResult run();

 private:
  // The initial empires (steps 1-2), or the state of options_.resume_from; returns the number
  // of decades completed.
  int start();
  int restore(const IcaState& state);
  void save(int decade) const;
  double wall_seconds() const {  // of this run, over every process of a resumed run
    return earlier_wall_seconds_ +
           std::chrono::duration<double>(std::chrono::steady_clock::now() - session_start_).count();
  }
  Point random_country() {
    Point x(problem_.lower.size());
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = std::min(rng_.uniform(problem_.lower[i], problem_.upper[i]), upper_[i]);
    return x;
  }
  void clip(Point& x) const {
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = std::clamp(x[i], problem_.lower[i], upper_[i]);
  }
  // The first `count` entries of a uniformly random permutation of 0 .. n-1.
  std::vector<int> random_subset(int n, int count) {
    std::vector<int> idx(n);
    std::iota(idx.begin(), idx.end(), 0);
    for (int k = 0; k < count; ++k) std::swap(idx[k], idx[k + rng_.index(n - k)]);
    idx.resize(count);
    return idx;
  }

  void create_empires();
  void move_colonies();
  void evaluate_colonies();
  void exchange_and_total_cost(Empire& e) const;
  void compete();
  void record(int decade);

  const Problem& problem_;
  const IcaOptions& options_;
  IcaRandom rng_;
  Evaluator evaluate_;
  Point upper_;  // upper bounds as clipped: nextafter(upper, lower) for categorical genes
  std::vector<Empire> empires_;
  std::vector<IcaDecade> history_;
  std::chrono::steady_clock::time_point session_start_ = std::chrono::steady_clock::now();
  double earlier_wall_seconds_ = 0.0;  // of the processes before a resume
};

void Ica::create_empires() {
  const int n = options_.countries;
  const int n_imp = options_.imperialists;
  std::vector<Point> countries(n);
  for (auto& c : countries) c = random_country();
  std::vector<double> costs;
  evaluate_(countries, costs);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return costs[a] < costs[b]; });

  empires_.assign(n_imp, Empire{});
  std::vector<double> imperialist_costs(n_imp);
  for (int k = 0; k < n_imp; ++k) {
    empires_[k].imperialist = countries[order[k]];
    empires_[k].imperialist_cost = imperialist_costs[k] = costs[order[k]];
  }
  const std::vector<int> count = allocate_colonies(imperialist_costs, n - n_imp);
  const std::vector<int> deal = random_subset(n - n_imp, n - n_imp);
  int next = 0;
  std::vector<Point> extra;  // one new country per empire left without a colony
  for (int k = 0; k < n_imp; ++k) {
    for (int c = 0; c < count[k]; ++c, ++next) {
      const int country = order[n_imp + deal[next]];
      empires_[k].colonies.push_back(countries[country]);
      empires_[k].colony_costs.push_back(costs[country]);
    }
    if (count[k] == 0) extra.push_back(random_country());
  }
  if (!extra.empty()) {
    std::vector<double> extra_costs;
    evaluate_(extra, extra_costs);
    std::size_t e = 0;
    for (int k = 0; k < n_imp; ++k)
      if (count[k] == 0) {
        empires_[k].colonies.push_back(extra[e]);
        empires_[k].colony_costs.push_back(extra_costs[e++]);
      }
  }
  for (auto& e : empires_) exchange_and_total_cost(e);
}

void Ica::move_colonies() {
  for (auto& e : empires_) {
    for (auto& x : e.colonies) {
      assimilate(x, e.imperialist, options_.beta, options_.gamma, rng_);
      clip(x);
    }
    const int n_col = static_cast<int>(e.colonies.size());
    const int n_rev = static_cast<int>(std::lround(options_.revolution_rate * n_col));
    for (int c : random_subset(n_col, n_rev)) e.colonies[c] = random_country();
  }
}

void Ica::evaluate_colonies() {
  std::vector<Point> xs;
  for (const auto& e : empires_) xs.insert(xs.end(), e.colonies.begin(), e.colonies.end());
  std::vector<double> costs;
  evaluate_(xs, costs);
  std::size_t next = 0;
  for (auto& e : empires_)
    for (double& c : e.colony_costs) c = costs[next++];
}

void Ica::exchange_and_total_cost(Empire& e) const {
  const auto best = std::min_element(e.colony_costs.begin(), e.colony_costs.end());
  if (*best < e.imperialist_cost) {
    const auto c = best - e.colony_costs.begin();
    std::swap(e.imperialist, e.colonies[c]);
    std::swap(e.imperialist_cost, e.colony_costs[c]);
  }
  const double mean = std::accumulate(e.colony_costs.begin(), e.colony_costs.end(), 0.0) /
                      static_cast<double>(e.colony_costs.size());
  e.total_cost = e.imperialist_cost + options_.xi * mean;
}

void Ica::compete() {
  const int k = static_cast<int>(empires_.size());
  if (k <= 1) return;
  int weakest = 0;
  for (int n = 1; n < k; ++n)
    if (empires_[n].total_cost > empires_[weakest].total_cost) weakest = n;
  const double max_tc = empires_[weakest].total_cost;
  double sum = 0.0;
  for (const auto& e : empires_) sum += e.total_cost - max_tc;
  int winner = 0;
  double winner_score = -std::numeric_limits<double>::infinity();
  for (int n = 0; n < k; ++n) {
    const double p = sum != 0.0 ? std::abs((empires_[n].total_cost - max_tc) / sum) : 1.0 / k;
    const double score = p - rng_.uniform();
    if (score > winner_score) {
      winner_score = score;
      winner = n;
    }
  }
  if (winner == weakest) return;
  Empire& loser = empires_[weakest];
  Empire& gainer = empires_[winner];
  const auto c = std::max_element(loser.colony_costs.begin(), loser.colony_costs.end()) -
                 loser.colony_costs.begin();
  gainer.colonies.push_back(std::move(loser.colonies[c]));
  gainer.colony_costs.push_back(loser.colony_costs[c]);
  loser.colonies.erase(loser.colonies.begin() + c);
  loser.colony_costs.erase(loser.colony_costs.begin() + c);
  if (loser.colonies.empty()) {  // step 8: collapse
    gainer.colonies.push_back(std::move(loser.imperialist));
    gainer.colony_costs.push_back(loser.imperialist_cost);
    empires_.erase(empires_.begin() + weakest);
  }
}

void Ica::record(int decade) {
  IcaDecade d;
  d.decade = decade;
  d.empires = static_cast<int>(empires_.size());
  d.evaluations = evaluate_.evaluations;
  d.best_cost = empires_[0].imperialist_cost;
  double sum = 0.0;
  for (const auto& e : empires_) {
    d.best_cost = std::min(d.best_cost, e.imperialist_cost);
    sum += e.imperialist_cost;
  }
  d.mean_cost = sum / static_cast<double>(empires_.size());
  history_.push_back(d);
}

int Ica::start() {
  if (options_.resume_from) return restore(*options_.resume_from);
  create_empires();
  record(0);
  save(0);
  return 0;
}

int Ica::restore(const IcaState& s) {
  auto reject = [](const std::string& what) {
    throw std::invalid_argument("ICA resume state: " + what + " does not fit these options");
  };
  const std::size_t dim = problem_.lower.size();
  auto check_point = [&](const Point& x) {
    if (x.size() != dim) reject("a point of dimension " + std::to_string(x.size()));
  };
  if (s.decade < 0 || s.decade > options_.decades) reject("decade " + std::to_string(s.decade));
  if (s.empires.empty() || s.empires.size() > static_cast<std::size_t>(options_.imperialists))
    reject(std::to_string(s.empires.size()) + " empires");
  if (s.history.size() != static_cast<std::size_t>(s.decade) + 1)
    reject(std::to_string(s.history.size()) + " history entries");
  empires_.clear();
  for (const IcaEmpireState& e : s.empires) {
    check_point(e.imperialist);
    for (const Point& x : e.colonies) check_point(x);
    if (e.colonies.empty() || e.colony_costs.size() != e.colonies.size())
      reject("an empire of " + std::to_string(e.colonies.size()) + " colonies and " +
             std::to_string(e.colony_costs.size()) + " colony costs");
    empires_.push_back(
        {e.imperialist, e.imperialist_cost, e.colonies, e.colony_costs, e.total_cost});
  }
  if (!s.best_x.empty()) check_point(s.best_x);
  rng_.set_state(s.random);
  history_ = s.history;
  evaluate_.evaluations = s.evaluations;
  evaluate_.failed = s.failed_evaluations;
  evaluate_.found = s.found;
  evaluate_.best_cost = s.best_cost;
  evaluate_.best_x = s.best_x;
  earlier_wall_seconds_ = s.wall_seconds;
  return s.decade;
}

void Ica::save(int decade) const {
  if (!options_.on_decade) return;
  IcaState s;
  s.decade = decade;
  for (const Empire& e : empires_)
    s.empires.push_back(
        {e.imperialist, e.imperialist_cost, e.colonies, e.colony_costs, e.total_cost});
  s.random = rng_.state();
  s.history = history_;
  s.evaluations = evaluate_.evaluations;
  s.failed_evaluations = evaluate_.failed;
  s.found = evaluate_.found;
  s.best_cost = evaluate_.best_cost;
  s.best_x = evaluate_.best_x;
  s.wall_seconds = wall_seconds();
  options_.on_decade(s);
}

IcaResult Ica::run() {
  IcaResult r;
  int decade = start();
  // Step 9's rule is checked at the end of a decade, never after the initial empires.
  auto one_empire_left = [&] {
    return decade > 0 && options_.stop_when_one_empire && empires_.size() == 1;
  };
  auto asked_to_stop = [&] { return options_.stop_requested && options_.stop_requested(); };
  bool stopped = one_empire_left();
  bool interrupted = !stopped && decade < options_.decades && asked_to_stop();
  while (!stopped && !interrupted && decade < options_.decades) {
    ++decade;
    move_colonies();
    evaluate_colonies();
    for (auto& e : empires_) exchange_and_total_cost(e);
    compete();
    record(decade);
    save(decade);
    stopped = one_empire_left();
    interrupted = !stopped && decade < options_.decades && asked_to_stop();
  }
  r.decades = decade;
  r.status = stopped ? IcaStatus::OneEmpire : IcaStatus::DecadeLimit;
  if (!evaluate_.found) r.status = IcaStatus::AllFailed;
  if (interrupted) r.status = IcaStatus::Interrupted;
  r.best_x = evaluate_.best_x;
  r.best_cost = evaluate_.found ? evaluate_.best_cost : options_.failure_cost;
  r.evaluations = evaluate_.evaluations;
  r.failed_evaluations = evaluate_.failed;
  r.history = std::move(history_);
  std::ostringstream msg;
  msg << to_string(r.status) << " after " << r.decades << " decades, " << r.evaluations
      << " evaluations (" << r.failed_evaluations << " failed)";
  r.message = msg.str();
  r.wall_seconds = wall_seconds();
  return r;
}

}  // namespace

IcaResult run_ica(const Problem& problem, const IcaOptions& options) {
  options.validate();
  problem.validate();
  return Ica(problem, options).run();
}

// ---------------------------------------------------------------------------------------
// Checkpoint state as JSON

nlohmann::json to_json(const IcaOptions& o) {
  return {{"decades", o.decades},
          {"countries", o.countries},
          {"imperialists", o.imperialists},
          {"beta", o.beta},
          {"gamma", o.gamma},
          {"revolution_rate", o.revolution_rate},
          {"xi", o.xi},
          {"failure_cost", o.failure_cost},
          {"stop_when_one_empire", o.stop_when_one_empire}};
}

nlohmann::json to_json(const IcaState& s) {
  nlohmann::json empires = nlohmann::json::array();
  for (const IcaEmpireState& e : s.empires)
    empires.push_back({{"imperialist", e.imperialist},
                       {"imperialist_cost", e.imperialist_cost},
                       {"colonies", e.colonies},
                       {"colony_costs", e.colony_costs},
                       {"total_cost", e.total_cost}});
  nlohmann::json history = nlohmann::json::array();
  for (const IcaDecade& d : s.history)
    history.push_back({{"decade", d.decade},
                       {"best_cost", d.best_cost},
                       {"mean_cost", d.mean_cost},
                       {"empires", d.empires},
                       {"evaluations", d.evaluations}});
  return {{"decade", s.decade},
          {"empires", empires},
          {"random", s.random},
          {"history", history},
          {"evaluations", s.evaluations},
          {"failed_evaluations", s.failed_evaluations},
          {"found", s.found},
          {"best_cost", s.best_cost},
          {"best_x", s.best_x},
          {"wall_seconds", s.wall_seconds}};
}

IcaState ica_state_from_json(const nlohmann::json& j) {
  auto field = [](const nlohmann::json& object, const char* name, auto& value) {
    try {
      object.at(name).get_to(value);
    } catch (const nlohmann::json::exception&) {
      throw std::invalid_argument(std::string("ICA state field ") + name +
                                  ": missing or of the wrong type");
    }
  };
  IcaState s;
  field(j, "decade", s.decade);
  field(j, "random", s.random);
  field(j, "evaluations", s.evaluations);
  field(j, "failed_evaluations", s.failed_evaluations);
  field(j, "found", s.found);
  field(j, "best_cost", s.best_cost);
  field(j, "best_x", s.best_x);
  field(j, "wall_seconds", s.wall_seconds);
  auto array = [](const nlohmann::json& object, const char* name) -> const nlohmann::json& {
    if (!object.contains(name) || !object.at(name).is_array())
      throw std::invalid_argument(std::string("ICA state field ") + name +
                                  ": missing or not a list");
    return object.at(name);
  };
  for (const nlohmann::json& e : array(j, "empires")) {
    IcaEmpireState& es = s.empires.emplace_back();
    field(e, "imperialist", es.imperialist);
    field(e, "imperialist_cost", es.imperialist_cost);
    field(e, "colonies", es.colonies);
    field(e, "colony_costs", es.colony_costs);
    field(e, "total_cost", es.total_cost);
  }
  for (const nlohmann::json& h : array(j, "history")) {
    IcaDecade& d = s.history.emplace_back();
    field(h, "decade", d.decade);
    field(h, "best_cost", d.best_cost);
    field(h, "mean_cost", d.mean_cost);
    field(h, "empires", d.empires);
    field(h, "evaluations", d.evaluations);
  }
  return s;
}

}  // namespace knitsim
