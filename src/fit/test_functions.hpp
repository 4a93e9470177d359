// Standard test functions for optimisers (`knitsim optimize`), with their usual
// boxes; every one has its global minimum f = 0.
//
//   sphere      f = sum x_i^2                                          box [-5.12, 5.12]^D
//   rastrigin   f = 10 D + sum (x_i^2 - 10 cos(2 pi x_i))              box [-5.12, 5.12]^D
//   rosenbrock  f = sum_{i<D} 100 (x_{i+1} - x_i^2)^2 + (1 - x_i)^2    box [-5, 10]^D, min at 1
//   griewank    f = 1 + sum x_i^2 / 4000 - prod cos(x_i / sqrt(i))     box [-600, 600]^D
//               (i = 1..D)
//   ackley      f = -20 exp(-0.2 sqrt(mean x_i^2)) - exp(mean cos(2 pi x_i)) + 20 + e
//                                                                      box [-32.768, 32.768]^D
// Minimisers are at x = 0 except rosenbrock (x = 1). Boxes as in Surjanovic & Bingham's
// Virtual Library of Simulation Experiments.
#pragma once

#include <string>
#include <vector>

#include "src/fit/ica.hpp"

namespace knitsim {

struct TestFunction {
  std::string name;
  double lower = 0.0;  // box, the same in every dimension
  double upper = 0.0;
  double argmin = 0.0;  // every coordinate of the global minimiser
  double (*f)(const std::vector<double>& x) = nullptr;
};

// All test functions, in the order listed above.
const std::vector<TestFunction>& test_function_catalog();

// The function by name; throws std::invalid_argument listing the known names.
const TestFunction& find_test_function(const std::string& name);

// Largest dimension make_test_problem accepts: the ICA holds countries x dim doubles (800 MB at
// the largest countries, IcaOptions::max_countries); the test-function literature uses D <= 100.
constexpr int max_test_dim = 10000;

// The function as an ICA problem in `dim` dimensions (1 <= dim <= max_test_dim, else
// std::invalid_argument "dim = D: must be in 1..10000").
Problem make_test_problem(const std::string& name, int dim);

}  // namespace knitsim
