// The element energies of the discrete elastic rod, shared by the models that hold yarns:
// YarnRods (open yarns, models/yarn_rods.hpp, where the equations and their sources are) and
// YarnCell (a periodic cell of yarns, models/yarn_cell.hpp). Each is a function of the positions
// of its own vertices only; the models map their derivatives onto their unknowns. Defined in
// models/yarn_rods.cpp.
#pragma once

#include "src/core/vec3.hpp"

namespace knitsim {

// The shifted IPC barrier psi(D) = kappa (d - d0)^2 phi(g), g = (D - d0) / (d - d0),
// phi(g) = -(g - 1)^2 ln g, and its first two derivatives in D (J, N, N/m), for d0 < D < d
// (the caller keeps D in that range: psi = 0 for D >= d, +inf for D <= d0).
struct ContactBarrier {
  double e, de, dde;
};
ContactBarrier contact_barrier(double D, double d, double d0, double kappa);

// Bending at one interior vertex x1 between x0 and x2: E = K (kappa - kappa0)^2 with
// kappa = 2 tan(phi / 2) (phi the turning angle; K = B / (2 lbar), J), and, by `order`
// (0: energy, 1: and the gradient, 2: and the Hessian), its gradient (9: dE/dx0, dE/dx1, dE/dx2)
// and Hessian (9 x 9, row-major over (x0, x1, x2)). False where the energy is not defined (the
// vertex folded back, a zero edge, or, for order >= 1, a bent-at-rest vertex exactly straight).
struct BendElement {
  double energy = 0.0;
  double grad[9];
  double hess[81];
};
bool bend_element(const Vec3& x0, const Vec3& x1, const Vec3& x2, double K, double kappa0,
                  int order, BendElement& out);

}  // namespace knitsim
