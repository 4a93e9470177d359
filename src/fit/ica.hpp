// The Imperialist Competitive Algorithm (Atashpaz-Gargari & Lucas 2007), as used by paper 1
// (Mozafary & Payvandy 2017, Fig. 8 and Table 1) to fit the drape model (docs/fitting.md).
//
// The ICA minimises a cost over a box [lower, upper] in R^D; it knows nothing about drapes.
//
//   Problem p;                              // the box and the cost
//   p.lower = {...};  p.upper = {...};
//   p.cost = [](const std::vector<double>& x) { return ...; };
//   IcaOptions o;  o.seed = 7;  o.jobs = 2;   // defaults: paper 1's Taguchi-best settings
//   IcaResult r = run_ica(p, o);              // r.best_x, r.best_cost, r.history, ...
//
// Algorithm (one "decade" = one iteration; N = countries, N_imp = imperialists,
// N_col = N - N_imp colonies; every random number is drawn on the calling thread in the
// order written here):
//  1. N random countries x ~ U(box), evaluated; the N_imp best become imperialists.
//  2. Normalised imperialist cost C_n = c_n - max_i c_i, power p_n = |C_n / sum_i C_i|
//     (all p_n = 1/N_imp when sum_i C_i = 0); colonies per empire round(p_n N_col) for every
//     empire but the last, which takes the remainder. REPAIR (the published rule gives the
//     weakest imperialist p = 0 colonies, and the remainder can go negative, which breaks the
//     original code at the paper's small sizes, e.g. 2 imperialists): while an empire has
//     fewer than 1 colony and the empire holding the most (lowest index on ties) can spare
//     one, it gets one from it (see allocate_colonies). The colonies are dealt to the empires
//     in a random order (a random permutation, as in the original). If there are fewer
//     colonies than imperialists (Table 1's B1 C3 read swapped: 15 countries, 10
//     imperialists), each empire still without a colony gets one new random country, as the
//     original code does for an empty empire: such a run has 2 x imperialists countries.
//  Each decade, for every empire in order:
//  3. Assimilation of every colony x toward its imperialist m: d = m - x, u = d/|d|, a random
//     unit vector v perpendicular to u (isotropic: a normal vector with its u-part removed),
//     theta ~ U(-gamma, gamma), s ~ U(0, beta |d|), x += s (cos(theta) u + sin(theta) v).
//     This is the 2007 paper's x ~ U(0, beta d) along a direction deviated by theta, in D
//     dimensions (v does not exist for D = 1: the step is s u). Convention: the original
//     MATLAB code instead moves by 2 beta rand(D) .* d (per-component random factors): its
//     direction scatter does not depend on gamma (the Taguchi E factor would be pure noise)
//     and its mean step is beta d, twice ours.
//     With U(0, beta |d|) Table 1's beta levels keep distinct meanings: 0.5 never gets past
//     half-way, 1 reaches at most the imperialist, 2 (the 2007 paper's recommendation)
//     searches both sides of it with mean step |d|.
//  4. Revolution: round(revolution_rate x n_colonies) colonies of the empire, picked by a
//     random permutation, are replaced by new random countries.
//     Then every colony of every empire is evaluated (in parallel, see `jobs`).
//  5. Exchange: if the empire's best colony is better than its imperialist, they swap.
//  6. Total cost TC_n = c(imperialist_n) + xi mean(c(colonies_n)).
//  Then, once per decade:
//  7. Competition: NTC_n = TC_n - max_k TC_k, P_n = |NTC_n / sum_k NTC_k| (all 1/K when the
//     sum is 0); the weakest colony (highest cost; the original code takes a random one) of
//     the weakest empire (highest TC; lowest index on ties) goes to the empire
//     argmax_n (P_n - U_n), U_n ~ U(0,1) drawn in empire order.
//  8. Collapse: an empire left without colonies is removed; its imperialist becomes a colony
//     of the empire that won step 7.
//  9. Stop after `decades` decades, or (stop_when_one_empire) when one empire is left at the
//     end of a decade. The default runs all decades, as the original code does: with 2
//     imperialists the literal rule ends a run within a few decades, and the paper's
//     Taguchi-best levels are those found without it (docs/fitting.md, "The ICA's stop rule").
//     `--stop-one-empire` restores the literal rule.
// Evaluations: countries initially, then every colony once per decade (countries - empires,
// growing as empires collapse).
// Bounds: every new or moved position is clipped to the box. Categorical genes (e.g. the
// drape topology u in [0, 3) mapped to a/b/c by floor) are moved like any other gene; the
// problem maps them (see category_of). The ICA only keeps them inside the half-open [lower,
// upper), so floor never yields the category `upper`.
// Not implemented (not in paper 1): the original code's revolution-rate damping,
// uniting of close empires, and its 11 % gate on the competition step.
//
// Failed evaluations: a cost that is NaN or +-inf is a failed evaluation, scored as
// `failure_cost` (finite, so powers and means stay defined and failures rank last; it must
// exceed every finite cost the problem can return), counted in IcaResult::failed_evaluations.
// An exception thrown by the cost function is a bug, not a numerical failure: it is
// propagated to the caller of run_ica (after all worker threads have joined).
//
// Determinism: every random number is drawn on the calling thread in a fixed order from a
// 64-bit Mersenne twister converted to doubles by our own code (no std::*_distribution,
// whose output differs between standard libraries); only cost evaluations run in parallel,
// each writing its own slot. The same seed therefore gives bit-identical results for any
// number of jobs.
//
// Checkpoints: IcaOptions::on_decade receives the whole state (IcaState: empires, costs, the
// twister's state, history, counters) after every decade, and IcaOptions::resume_from continues
// from one; a run interrupted and resumed is bit-identical to an uninterrupted one (best_x,
// best_cost, history, counters; only wall_seconds differs).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "src/scene/fit_options.hpp"

namespace knitsim {

// State at the end of one decade (decade 0 = the initial empires). Costs as the original
// code's convergence plot (paper 1 Fig. 13): over the imperialists, failures at failure_cost.
struct IcaDecade {
  int decade = 0;
  double best_cost = 0.0;  // min over imperialists (= best of the current population)
  double mean_cost = 0.0;  // mean over imperialists
  int empires = 0;
  long evaluations = 0;  // cumulative
};

// The complete state of a run at the end of a decade: with the same problem and options, a
// run continued from it (IcaOptions::resume_from) is bit-identical to the uninterrupted run.
// Points are D-vectors (Problem::dimension()); costs as scored (failures at failure_cost).
struct IcaEmpireState {
  std::vector<double> imperialist;
  double imperialist_cost = 0.0;
  std::vector<std::vector<double>> colonies;
  std::vector<double> colony_costs;  // one per colony
  double total_cost = 0.0;           // step 6's TC
};
struct IcaState {
  int decade = 0;  // decades completed (0: the initial empires)
  std::vector<IcaEmpireState> empires;
  std::string random;              // the Mersenne twister's state, as its operator<< writes it
  std::vector<IcaDecade> history;  // decade + 1 entries
  long evaluations = 0;
  long failed_evaluations = 0;
  bool found = false;          // some evaluation succeeded
  double best_cost = 0.0;      // best successful cost so far (meaningful when found)
  std::vector<double> best_x;  // its point (the first failed point while !found)
  double wall_seconds = 0.0;   // wall time spent so far, over every process of a resumed run
};

// Paper 1 Table 1: the options of one level combination, levels 1..3 for the
// factors A..G in order (B = countries, C = imperialists, read swapped). Other fields default.
IcaOptions ica_table1_options(const std::array<int, 7>& levels);
// The three values of each Table 1 factor A..G (B = countries, C = imperialists).
const std::array<std::array<double, 3>, 7>& ica_table1_levels();

// A minimisation problem over a box. Exactly one of `cost` and `batch_cost` must be set.
struct Problem {
  using PointCost = std::function<double(const std::vector<double>& x)>;
  using BatchCost =
      std::function<void(const std::vector<std::vector<double>>& xs, std::vector<double>& costs)>;

  std::vector<double> lower;  // box lower bounds, one per dimension
  std::vector<double> upper;  // box upper bounds, upper[i] > lower[i]
  // Optional, empty or one flag per dimension: genes the problem maps to a category by floor;
  // the ICA keeps them in [lower, upper) (see the header comment).
  std::vector<bool> categorical;
  // Cost of one point. Called from `jobs` threads at once: must be reentrant when jobs > 1.
  // Report a failed evaluation by returning NaN or +-inf.
  PointCost cost;
  // Alternative: costs of a batch of points (costs is resized to xs.size() by the caller); the
  // problem parallelises as it likes, and the ICA's `jobs` is unused.
  BatchCost batch_cost;

  int dimension() const { return static_cast<int>(lower.size()); }
  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

// The category index of a categorical gene u in [lower, upper): floor(u - lower), clamped to
// 0 .. ceil(upper - lower) - 1 (e.g. topology u in [0, 3) -> 0, 1, 2 = a, b, c).
int category_of(double u, double lower, double upper);

// Random numbers of the ICA: std::mt19937_64 (bit-exact on every platform) with our own
// conversions, so that a seed means the same run everywhere.
class IcaRandom {
 public:
  explicit IcaRandom(std::uint64_t seed) : engine_(seed) {}
  double uniform();                    // U[0, 1), 53 random bits
  double uniform(double a, double b);  // a + (b - a) U[0, 1)
  int index(int n);                    // uniform integer in [0, n), n >= 1, unbiased
  double normal();                     // N(0, 1), Box-Muller from two uniform() draws
  // The engine's state as text (operator<<, classic locale), and back (std::invalid_argument
  // if `state` is not one).
  std::string state() const;
  void set_state(const std::string& state);

 private:
  std::mt19937_64 engine_;
};

// Step 3 on one colony, before clipping: x += s (cos(theta) u + sin(theta) v) with
// d = imperialist - x, s ~ U(0, beta |d|), theta ~ U(-gamma, gamma); nothing moves (and no
// random number is drawn) when x equals the imperialist. Draw order: s, theta, then D normals
// for v (D > 1 only).
void assimilate(std::vector<double>& x, const std::vector<double>& imperialist, double beta,
                double gamma, IcaRandom& rng);

enum class IcaStatus {
  DecadeLimit,  // ran all `decades` decades
  OneEmpire,    // stopped early: one empire left (stop_when_one_empire)
  AllFailed,    // finished, but every evaluation failed: best_x is not a valid point
  Interrupted,  // stopped early at the end of a decade by `stop_requested` (checkpoint saved)
};
const char* to_string(IcaStatus s);

struct IcaResult {
  IcaStatus status = IcaStatus::DecadeLimit;
  std::string message;
  std::vector<double> best_x;  // best point ever evaluated (ICA itself is not elitist)
  double best_cost = 0.0;      // its cost (failure_cost if status == AllFailed)
  long evaluations = 0;
  long failed_evaluations = 0;
  int decades = 0;                 // decades run
  std::vector<IcaDecade> history;  // decades + 1 entries
  double wall_seconds = 0.0;
};

// Step 2's colony counts for imperialists of the given costs (any order) and `colonies` >= 1
// colonies, with the repair: counts are >= 1, or >= 0 when colonies < imperialists.
std::vector<int> allocate_colonies(const std::vector<double>& imperialist_costs, int colonies);

// Runs the ICA. Validates options and problem (std::invalid_argument).
IcaResult run_ica(const Problem& problem, const IcaOptions& options);

// The options that determine an ICA run's result, as JSON: every field but seed, jobs and the
// checkpoint hooks (callers add the seed where it identifies the run).
nlohmann::json to_json(const IcaOptions& options);

// IcaState as JSON (doubles written with max_digits10 digits, so they read back bit for bit)
// and back; ica_state_from_json throws std::invalid_argument naming a missing or mistyped field.
nlohmann::json to_json(const IcaState& state);
IcaState ica_state_from_json(const nlohmann::json& j);

}  // namespace knitsim
