// Internal to solvers/: constructors behind the registry in integrator.cpp.
#pragma once

#include <memory>

#include "solvers/integrator.hpp"

namespace knitsim::detail {

std::unique_ptr<Integrator> make_euler();
std::unique_ptr<Integrator> make_verlet();
std::unique_ptr<Integrator> make_implicit_euler();
std::unique_ptr<Integrator> make_cvode_bdf();
std::unique_ptr<Integrator> make_cvode_bdf_dense();
std::unique_ptr<Integrator> make_cvode_bdf_gmres();
std::unique_ptr<Integrator> make_cvode_adams();
std::unique_ptr<Integrator> make_arkode_erk();
std::unique_ptr<Integrator> make_arkode_dirk();
std::unique_ptr<Integrator> make_arkode_imex();
std::unique_ptr<Integrator> make_static();
std::unique_ptr<Integrator> make_equilibrium();

}  // namespace knitsim::detail
