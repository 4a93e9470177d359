#include "src/fit/test_functions.hpp"

#include <cmath>
#include <stdexcept>

namespace knitsim {

namespace {

constexpr double kPi = 3.14159265358979323846;

double sphere(const std::vector<double>& x) {
  double f = 0.0;
  for (double xi : x) f += xi * xi;
  return f;
}

double rastrigin(const std::vector<double>& x) {
  double f = 10.0 * static_cast<double>(x.size());
  for (double xi : x) f += xi * xi - 10.0 * std::cos(2.0 * kPi * xi);
  return f;
}

double rosenbrock(const std::vector<double>& x) {
  double f = 0.0;
  for (std::size_t i = 0; i + 1 < x.size(); ++i) {
    const double a = x[i + 1] - x[i] * x[i];
    const double b = 1.0 - x[i];
    f += 100.0 * a * a + b * b;
  }
  return f;
}

double griewank(const std::vector<double>& x) {
  double sum = 0.0;
  double prod = 1.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sum += x[i] * x[i] / 4000.0;
    prod *= std::cos(x[i] / std::sqrt(static_cast<double>(i + 1)));
  }
  return 1.0 + sum - prod;
}

double ackley(const std::vector<double>& x) {
  double sq = 0.0;
  double cs = 0.0;
  for (double xi : x) {
    sq += xi * xi;
    cs += std::cos(2.0 * kPi * xi);
  }
  const double d = static_cast<double>(x.size());
  return -20.0 * std::exp(-0.2 * std::sqrt(sq / d)) - std::exp(cs / d) + 20.0 + std::exp(1.0);
}

}  // namespace

const std::vector<TestFunction>& test_function_catalog() {
  static const std::vector<TestFunction> catalog = {
      {"sphere", -5.12, 5.12, 0.0, sphere},        {"rastrigin", -5.12, 5.12, 0.0, rastrigin},
      {"rosenbrock", -5.0, 10.0, 1.0, rosenbrock}, {"griewank", -600.0, 600.0, 0.0, griewank},
      {"ackley", -32.768, 32.768, 0.0, ackley},
  };
  return catalog;
}

const TestFunction& find_test_function(const std::string& name) {
  std::string known;
  for (const auto& t : test_function_catalog()) {
    if (t.name == name) return t;
    known += (known.empty() ? "" : "|") + t.name;
  }
  throw std::invalid_argument("problem = " + name + ": must be one of " + known);
}

Problem make_test_problem(const std::string& name, int dim) {
  const TestFunction& t = find_test_function(name);
  if (dim < 1 || dim > max_test_dim)
    throw std::invalid_argument("dim = " + std::to_string(dim) + ": must be in 1.." +
                                std::to_string(max_test_dim));
  Problem p;
  p.lower.assign(dim, t.lower);
  p.upper.assign(dim, t.upper);
  p.cost = t.f;
  return p;
}

}  // namespace knitsim
