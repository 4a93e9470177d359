#include "src/scene/fit_options.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "src/core/invalid_field.hpp"

namespace knitsim {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

void IcaOptions::validate() const {
  if (imperialists < 1) bad_field("imperialists", imperialists, "must be >= 1");
  if (countries <= imperialists)
    bad_field("countries", countries,
              "must be > imperialists (" + std::to_string(imperialists) + ")");
  if (countries > max_countries)
    bad_field("countries", countries, "must be <= " + std::to_string(max_countries));
  if (decades < 1) bad_field("decades", decades, "must be >= 1");
  if (!(beta > 0.0) || !std::isfinite(beta)) bad_field("beta", beta, "must be > 0");
  if (!(gamma >= 0.0 && gamma <= kPi)) bad_field("gamma", gamma, "must be in [0, pi] rad");
  if (!(revolution_rate >= 0.0 && revolution_rate <= 1.0))
    bad_field("revolution_rate", revolution_rate, "must be in [0, 1]");
  if (!(xi >= 0.0) || !std::isfinite(xi)) bad_field("xi", xi, "must be >= 0");
  if (jobs < 1) bad_field("jobs", jobs, "must be >= 1");
  if (!(failure_cost > 0.0) || !std::isfinite(failure_cost))
    bad_field("failure_cost", failure_cost, "must be finite and > 0");
}

void LmOptions::validate() const {
  if (max_evaluations < 1) bad_field("lm.max_evaluations", max_evaluations, "must be >= 1");
  if (!(initial_lambda > 0.0) || !std::isfinite(initial_lambda))
    bad_field("lm.initial_lambda", initial_lambda, "must be > 0");
  if (!(step_tol >= 0.0)) bad_field("lm.step_tol", step_tol, "must be >= 0");
  if (!(cost_tol >= 0.0)) bad_field("lm.cost_tol", cost_tol, "must be >= 0");
}

void LmStartOptions::validate() const {
  if (starts_per_bracket < 1)
    bad_field("lm.starts_per_bracket", starts_per_bracket, "must be >= 1");
  if (refine < 1) bad_field("lm.refine", refine, "must be >= 1");
}

void SyntheticOptions::validate() const {
  if (!std::isfinite(noise_mm) || noise_mm < 0.0)
    throw std::invalid_argument("noise_mm = " + std::to_string(noise_mm) +
                                ": must be finite and >= 0 (mm)");
  if (photos < 1 || photos > max_photos)
    throw std::invalid_argument("photos = " + std::to_string(photos) + ": must be in 1.." +
                                std::to_string(max_photos));
}

}  // namespace knitsim
