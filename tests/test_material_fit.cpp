// Fitting the material model in material units (src/fit/material_fit.hpp, docs/fitting.md "The
// material model"): the analytic sensitivities against finite differences of whole drapes, the
// identifiability at a four-corner drape, the fit recovering known parameters on another mesh,
// and the fitted parameters predicting another specimen size.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <vector>

#include "src/fit/material_fit.hpp"
#include "src/scene/scene.hpp"

using namespace knitsim;

namespace {

// four_corner_material at `cells`, every parameter of the box fitted that `fitted` names.
Scene base_scene(int cells, const std::string& fitted) {
  Scene s = load_scene("four_corner_material", {"mesh.cells=" + std::to_string(cells),
                                                "fit.parameters=" + fitted});
  return s;
}

}  // namespace

TEST_CASE("material fit: sensitivities and singular values at four_corner_material",
          "[material_fit][explore]") {
  const std::string all =
      "membrane_wale,membrane_course,membrane_shear,poisson,bending_wale,bending_course";
  Scene s = base_scene(20, all);
  const Target target = material_target(s);
  const MaterialFitProblem problem(s, target, "");
  const std::vector<double> u0 = problem.u_of(material_parameters(s));
  const MaterialResiduals at = problem.evaluate(u0);
  REQUIRE_FALSE(at.failed);
  printf("objective at truth %g, residual %g, negative pivots %d\n", at.objective, at.residual,
         at.negative_pivots);
  for (size_t a = 0; a < u0.size(); ++a) {
    const double h = 1e-3;
    std::vector<double> up = u0, um = u0;
    up[a] += h;
    um[a] -= h;
    const MaterialResiduals ep = problem.evaluate(up, false), em = problem.evaluate(um, false);
    const Eigen::VectorXd fd = (ep.r - em.r) / (2 * h);
    printf("%s: |J| %.4g |fd| %.4g |J-fd| %.3g\n", material_gene_names()[problem.fitted()[a]],
           at.J.col(a).norm(), fd.norm(), (at.J.col(a) - fd).norm());
  }
  MaterialFitResult fit;
  fit.ok = true;
  fit.u = u0;
  fit.parameters = material_parameters(s);
  fit.identifiability = problem.identifiability(at, u0);
  printf("%s", identifiability_text(problem, fit).c_str());
}
