// The plain option structs of the fitting commands (fit, optimize, repro, targets), each with
// its validate(): the ICA's (src/fit/ica.hpp), the Levenberg-Marquardt fit's (src/fit/lm_fit.hpp)
// and the synthetic targets' (src/fit/synthetic_targets.hpp). Their algorithms live in src/fit;
// the structs sit here, one level below, beside the parameter table that has a row for each of
// their flags (key_table(), src/scene/scene.hpp; docs/architecture.md, "Where a file sits").
// validate() throws InvalidField (src/core/invalid_field.hpp) naming the field.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace knitsim {

struct IcaState;  // the ICA's whole state at the end of a decade (src/fit/ica.hpp)
struct Key;       // a row of the parameter table (src/scene/scene.hpp)

struct IcaOptions {
  // Most countries validate() accepts (the paper's levels are 15..25): each holds a point of
  // the problem's dimension.
  static constexpr int max_countries = 10000;
  // Defaults: paper 1's Taguchi-best combination A3 B3 C1 D2 E1 F2 G2 of Table 1, with B and C
  // read swapped (B = number of countries, C = number of imperialists; paper_repro/data/README.md).
  int decades = 40;              // MaxIt, Table 1 factor A (levels 10 / 20 / 40)
  int countries = 25;            // N_country, factor B (15 / 20 / 25); > imperialists, <= max
  int imperialists = 2;          // N_imp, factor C (2 / 5 / 10); >= 1
  double beta = 1.0;             // assimilation coefficient, factor D (0.5 / 1 / 2); > 0
  double gamma = 0.1;            // assimilation angle bound, rad, factor E (0.1/0.3/0.5); [0, pi]
  double revolution_rate = 0.3;  // fraction of colonies revolved per decade, factor F; [0, 1]
  double xi = 0.15;              // colonies' share of the empire total cost, factor G; >= 0
  std::uint64_t seed = 1;        // random seed
  int jobs = 1;                  // threads evaluating costs (the result does not depend on it)
  double failure_cost = 1e10;    // cost given to failed (non-finite) evaluations; finite, > 0
  // Step 9's literal rule (paper 1: "When only one empire exists, the algorithm is
  // terminated"). Off by default: with the Taguchi-best settings it ends a run after ~2
  // decades, contradicting the ~950 evaluations per run of the paper's protocol
  // (src/fit/ica.hpp, step 9).
  bool stop_when_one_empire = false;

  // Checkpointing (knitsim fit --resume; not part of validate()). `on_decade`, when set, is
  // called on the calling thread with the complete state after the initial empires (decade 0)
  // and after every decade; an exception it throws ends the run and propagates. `resume_from`,
  // when set, continues that state (from a run with the same problem and options but any
  // `jobs`) instead of starting afresh: std::invalid_argument if it does not fit the options
  // (dimension, decade, counts).
  std::function<void(const IcaState&)> on_decade;
  std::shared_ptr<const IcaState> resume_from;
  // Asked after every decade's on_decade (never in the middle of one, so the saved state is
  // whole): true ends the run there with status Interrupted, unless that was the last decade
  // or the step-9 rule stops it anyway. knitsim fit sets it to "SIGINT or SIGTERM received".
  std::function<bool()> stop_requested;

  // Throws InvalidField naming the bad field and its accepted range.
  void validate() const;
};

// The Levenberg-Marquardt budget of one start (src/fit/lm_fit.hpp, run_lm).
struct LmOptions {
  int max_evaluations = 15;      // residual + Jacobian evaluations per start (>= 1)
  double initial_lambda = 1e-3;  // lambda_0 = initial_lambda x max diag(J_u^T J_u) (> 0)
  double step_tol = 1e-6;        // stop when |delta|_inf (unit box) <= step_tol (>= 0)
  double cost_tol = 1e-6;        // stop when an accepted step lowers |r|^2 by <= cost_tol
                                 // relative (>= 0)
  void validate() const;         // InvalidField "lm.<field> = value: range"
};

// The drape LM fit's starts (src/fit/lm_fit.hpp, DrapeLmOptions): how many are screened and how
// many of them are refined.
struct LmStartOptions {
  int starts_per_bracket = 1;  // >= 1: k at the box centre, then seeded uniform k
  int refine = 2;              // >= 1: screened starts refined by LM
  void validate() const;       // InvalidField "lm.<field> = value: range"
};

// The noise of the synthetic targets (src/fit/synthetic_targets.hpp).
struct SyntheticOptions {
  // Most photos per point: 2 x photos normal draws per point, ~1e7 per sample at the most.
  static constexpr int max_photos = 10000;
  double noise_mm = 0.5;  // sigma of the Gaussian noise per point and photo, mm (>= 0)
  int photos = 5;         // photos averaged per point (1..max_photos)
  unsigned seed = 2017;   // base seed; each (sample, set, scene) draws from its own stream
  // Throws InvalidField "noise_mm = X: must be finite and >= 0 mm" or
  // "photos = P: must be in 1..10000".
  void validate() const;
};

// The material model's fit (model.kind = material; src/fit/material_fit.hpp): the search box of
// its six material parameters, in material units, and which of them are fitted. A parameter not
// fitted keeps the base scene's value. Rows of the key table: scene keys fit.<parameter>_min and
// fit.<parameter>_max (e.g. fit.membrane_wale_min), the flags --<parameter>-min/-max
// (--membrane-wale-min), and fit.parameters / --fit-parameters.
// Parameter order (MaterialGene, src/fit/material_fit.hpp): membrane_wale, membrane_course,
// membrane_shear (N/m), poisson (1), bending_wale, bending_course (N m).
struct MaterialFitBox {
  static constexpr int kParameters = 6;
  // Defaults: knitted and woven fabrics' ranges (docs/fitting.md, "The material model"):
  // membrane 5..5000 N/m, shear 1..2000 N/m, Poisson 0..0.9, bending 1e-7..1e-3 N m.
  double membrane_wale_min = 5.0, membrane_wale_max = 5000.0;
  double membrane_course_min = 5.0, membrane_course_max = 5000.0;
  double membrane_shear_min = 1.0, membrane_shear_max = 2000.0;
  double poisson_min = 0.0, poisson_max = 0.9;
  double bending_wale_min = 1e-7, bending_wale_max = 1e-3;
  double bending_course_min = 1e-7, bending_course_max = 1e-3;
  // The fitted parameters, comma-separated names (a non-empty subset of the six); the default
  // is what a hanging four-corner drape's edges determine (docs/fitting.md).
  std::string parameters = "membrane_wale,membrane_course";

  // The bounds of parameter g (the order above).
  double lower(int parameter) const;
  double upper(int parameter) const;
  bool fitted(int parameter) const;  // named in `parameters`
  // Throws InvalidField naming the bound (fit.membrane_wale_min, ...): finite, min <= max,
  // membrane and bending min > 0, poisson in [0, 0.99]; `parameters` known names, no repeat,
  // at least one; a fitted parameter's min < max.
  void validate() const;
};

// The rows of the fitting commands' flags, appended to key_table() (src/scene/scene.hpp) in
// `knitsim list keys` order: the ICA's (--jobs, --decades, ... --stop-one-empire), the LM fit's
// (--lm-starts, --lm-refine, --lm-evaluations) and the synthetic targets' (--noise-mm,
// --photos). Each row's validator field is the struct's, so a bad value is refused under the flag
// (rethrow_as_typed), and its meaning is the flag's --help text.
void append_fit_option_rows(std::vector<Key>& rows);

}  // namespace knitsim
