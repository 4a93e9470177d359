// Internal to solvers/: constructors behind the registry in integrator.cpp.
#pragma once

#include <memory>

#include "solvers/integrator.hpp"

namespace knitsim::detail {

std::unique_ptr<Integrator> make_euler();
std::unique_ptr<Integrator> make_verlet();
std::unique_ptr<Integrator> make_implicit_euler();

}  // namespace knitsim::detail
