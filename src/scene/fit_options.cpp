#include "src/scene/fit_options.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "src/base/text.hpp"
#include "src/core/invalid_field.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

void IcaOptions::validate() const {
  if (imperialists < 1) bad_field("imperialists", imperialists, "must be >= 1");
  if (countries <= imperialists || countries > max_countries)
    bad_field("countries", countries,
              "must be > imperialists (" + std::to_string(imperialists) +
                  ") and <= " + std::to_string(max_countries));
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
    bad_field("noise_mm", noise_mm, "must be finite and >= 0 mm");
  if (photos < 1 || photos > max_photos)
    bad_field("photos", photos, "must be in 1.." + std::to_string(max_photos));
}

namespace {

constexpr const char* kMaterialParameterNames[MaterialFitBox::kParameters] = {
    "membrane_wale", "membrane_course", "membrane_shear",
    "poisson",       "bending_wale",    "bending_course"};

// The fitted names of `list` (comma-separated, spaces ignored), in the order given.
std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> names(1);
  for (char c : list) {
    if (c == ',')
      names.emplace_back();
    else if (c != ' ')
      names.back() += c;
  }
  return names;
}

}  // namespace

double MaterialFitBox::lower(int parameter) const {
  const double v[kParameters] = {membrane_wale_min, membrane_course_min, membrane_shear_min,
                                 poisson_min,       bending_wale_min,    bending_course_min};
  return v[parameter];
}

double MaterialFitBox::upper(int parameter) const {
  const double v[kParameters] = {membrane_wale_max, membrane_course_max, membrane_shear_max,
                                 poisson_max,       bending_wale_max,    bending_course_max};
  return v[parameter];
}

bool MaterialFitBox::fitted(int parameter) const {
  for (const std::string& name : split_names(parameters))
    if (name == kMaterialParameterNames[parameter]) return true;
  return false;
}

void MaterialFitBox::validate() const {
  for (int g = 0; g < kParameters; ++g) {
    const std::string name = std::string("fit.") + kMaterialParameterNames[g];
    const double lo = lower(g), hi = upper(g);
    const bool poisson = g == 3;
    const std::string range = poisson ? "must be in [0, 0.99]" : "must be finite and > 0";
    if (!(poisson ? lo >= 0.0 && lo <= 0.99 : lo > 0.0 && std::isfinite(lo)))
      bad_field(name + "_min", lo, range);
    if (!(poisson ? hi >= 0.0 && hi <= 0.99 : hi > 0.0 && std::isfinite(hi)))
      bad_field(name + "_max", hi, range);
    if (!(lo <= hi))
      bad_field(name + "_max", hi, "must be >= " + name + "_min (" + format_number(lo, 6) + ")");
  }
  const std::vector<std::string> names = split_names(parameters);
  std::string known;
  for (const char* n : kMaterialParameterNames) known += (known.empty() ? "" : ", ") + std::string(n);
  for (size_t i = 0; i < names.size(); ++i) {
    bool ok = false;
    for (const char* n : kMaterialParameterNames) ok = ok || names[i] == n;
    for (size_t j = 0; j < i; ++j) ok = ok && names[j] != names[i];
    if (!ok) bad_field("fit.parameters", parameters, "must be distinct names of " + known);
  }
  for (int g = 0; g < kParameters; ++g)
    if (fitted(g) && !(lower(g) < upper(g)))
      bad_field(std::string("fit.") + kMaterialParameterNames[g] + "_max", upper(g),
                std::string("must be > fit.") + kMaterialParameterNames[g] + "_min (" +
                    format_number(lower(g), 6) + "): the parameter is fitted");
}

namespace {

// A row of a fitting command's flag, bound to `member` of its options struct S (the value the
// struct's validate() names `field`), of `unit` ("1" for counts and ratios, "" for a flag that
// takes no value), with its --help text.
template <class S, class T>
Key fit_row(const char* flag, const char* field, T S::*member, const char* unit,
            const char* meaning) {
  Key row;
  row.flag = flag;
  row.field = field;
  row.model = KeyModel::Fit;
  row.kind = std::is_floating_point_v<T> ? Key::Kind::Number
             : std::is_same_v<T, bool>   ? Key::Kind::Text
                                         : Key::Kind::Integer;
  row.unit = unit;
  row.meaning = meaning;
  row.member = member;
  row.default_value = [member]() -> std::string {
    const T value = S{}.*member;
    if constexpr (std::is_same_v<T, bool>)
      return value ? "on" : "off";
    else if constexpr (std::is_floating_point_v<T>)
      return format_number(value, 6);
    else
      return std::to_string(value);
  };
  if constexpr (std::is_same_v<T, bool>) {
    row.accepted = "a flag: on when given";
  } else {
    row.probe_range = [member] {
      S probe;
      if constexpr (std::is_floating_point_v<T>)
        probe.*member = std::numeric_limits<T>::quiet_NaN();
      else
        probe.*member = -1;
      probe.validate();
    };
  }
  return row;
}

}  // namespace

void append_fit_option_rows(std::vector<Key>& rows) {
  using I = IcaOptions;
  rows.push_back(fit_row("--jobs", "jobs", &I::jobs, "1",
                         "threads evaluating costs; the same result for any value"));
  rows.push_back(fit_row("--decades", "decades", &I::decades, "1", "MaxIt, number of decades"));
  rows.push_back(fit_row("--countries", "countries", &I::countries, "1", "number of countries"));
  rows.push_back(
      fit_row("--imperialists", "imperialists", &I::imperialists, "1", "number of imperialists"));
  rows.push_back(fit_row("--beta", "beta", &I::beta, "1", "assimilation coefficient"));
  rows.push_back(fit_row("--gamma", "gamma", &I::gamma, "rad", "assimilation angle bound"));
  rows.push_back(
      fit_row("--revolution", "revolution_rate", &I::revolution_rate, "1", "revolution rate"));
  rows.push_back(fit_row("--xi", "xi", &I::xi, "1", "colonies' share of the empire cost"));
  rows.push_back(fit_row("--stop-one-empire", "stop_when_one_empire", &I::stop_when_one_empire, "",
                         "stop as soon as one empire is left (paper's literal step 9; default: "
                         "run all decades)"));
  rows.push_back(fit_row("--lm-starts", "lm.starts_per_bracket",
                         &LmStartOptions::starts_per_bracket, "1",
                         "lm: screened starts per topology and grid-size bracket (k at the box "
                         "centre, then seeded random k)"));
  rows.push_back(fit_row("--lm-refine", "lm.refine", &LmStartOptions::refine, "1",
                         "lm: best screened starts refined by LM"));
  rows.push_back(fit_row("--lm-evaluations", "lm.max_evaluations", &LmOptions::max_evaluations, "1",
                         "lm: drape evaluations per refined start at most"));
  rows.push_back(fit_row("--noise-mm", "noise_mm", &SyntheticOptions::noise_mm, "mm",
                         "Noise sigma per camera coordinate and photo"));
  rows.push_back(
      fit_row("--photos", "photos", &SyntheticOptions::photos, "1", "Photos averaged per point"));
}

}  // namespace knitsim
