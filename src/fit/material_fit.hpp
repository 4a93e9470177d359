// Fitting the material model (model.kind = material, docs/material_drape.md) to measured edges,
// in material units (user's view: docs/fitting.md, "The material model").
//
// Parameters (MaterialGene order, the scene's keys material.<name>): membrane stiffness along
// the wales, the courses and in shear A_w, A_c, A_s (N/m), the Poisson coupling nu_cw (1), the
// bending rigidity along the wales and the courses B_w, B_c (N m). The search box and which of
// them are fitted come from the scene's MaterialFitBox (src/scene/fit_options.hpp); the others
// keep the base scene's values. The fit works in the coordinates u = ln p (p > 0: stiffnesses
// and rigidities span decades) and u = nu for the Poisson coupling.
//
// Data: the target's four_corner edges (the base scene must hang from its corner patches,
// clamps.layout = corners). Edge names on this model: top (the row y = 0) and bottom (y = L)
// run along the courses (x), left (x = 0) and right (x = W) along the wales (y); each from its
// first vertex, top and left at (0, 0), bottom at (0, L), right at (W, 0), and normalised by
// the span rule of src/measure/measurement.hpp between the edge's two corner vertices (held:
// the clamps keep the corners at rest). Residuals r = P_measured - P_simulated, 5 coefficients
// per measured edge; objective 100 rms(r) (paper 1's Eq. 5, percent), as paper 1's model.
//
// Sensitivities (analytic, at the equilibrium x*): F(x*, p) = 0 gives K dx*/du = -dF/du with
// K = dF/dx (the model's Jacobian, rows scaled back by the mass), factored once by a sparse
// LDL^T of -K (positive definite at a stable equilibrium; a negative pivot is reported).
// The run's equilibrium is first polished by Newton steps with the same factorisation. dF/du:
// the energy is linear in the stiffness coefficients (C11, C12, C22, C66, B_c, B_w), which are
// smooth functions of p, so dF/du is the central difference of net_force over u with step
// 1e-4 (its error is O(1e-8) relative: the difference of a quadratic in the step). The edge
// coefficients' tangent along dx*/du is the central difference of the measurement (linear in
// the positions but for the polynomial fit's abscissae) with displacements of 1e-7 m.
//
// Identifiability (MaterialIdentifiability): the singular value decomposition of the relative
// Jacobian J_u (columns d r / d ln p; d r / d nu for the Poisson coupling). A combination
// sum_k v_k u_k (a right singular vector v, |v| = 1) moves the edges, when changed by 10 %
// (0.1 in u), by the Eq. 5 error 100 sigma 0.1 / sqrt(m) percent; it is "determined" when that
// is at least kDeterminedPercent = 0.1 % (the error of 0.5 mm of noise over a 0.5 m span:
// the fit cannot see less). Standard errors as paper 1's LM fit (src/fit/lm_fit.hpp): s sqrt of
// the pseudo-inverse's diagonal, s^2 = |r|^2 / (m - rank).
//
// Failure modes: set-up errors (model.kind not material, clamps.layout not corners, a target
// without four_corner, an invalid box) throw std::invalid_argument; a drape that does not reach
// equilibrium, parameters the model refuses (nu^2 A_w / A_c >= 1 in a box corner) or a singular
// stiffness make a failed evaluation (NaN objective), which the LM counts as a rejected step and
// the ICA scores as its failure cost.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <string>
#include <vector>

#include "src/fit/ica.hpp"
#include "src/fit/lm_fit.hpp"
#include "src/fit/targets.hpp"
#include "src/measure/measurement.hpp"
#include "src/scene/material_run.hpp"
#include "src/scene/scene.hpp"

namespace knitsim {

enum MaterialGene {
  kMembraneWale,
  kMembraneCourse,
  kMembraneShear,
  kPoisson,
  kBendingWale,
  kBendingCourse,
  kMaterialGenes
};
// membrane_wale, membrane_course, membrane_shear, poisson, bending_wale, bending_course
const std::array<const char*, kMaterialGenes>& material_gene_names();
// N/m, N/m, N/m, 1, N m, N m
const std::array<const char*, kMaterialGenes>& material_gene_units();

// The six parameters of a scene's material model, in MaterialGene order.
std::array<double, kMaterialGenes> material_parameters(const Scene& scene);
// The scene with those parameters set.
Scene with_material_parameters(Scene scene, const std::array<double, kMaterialGenes>& p);

// The material model's four edges, measured (names and order: top, bottom, left, right; see
// above). Throws std::invalid_argument for clamps.layout = edge or non-finite positions.
std::vector<EdgeFit> measure_material_edges(const MaterialSheet& sheet,
                                            const std::vector<Vec3>& positions);

// A target made by the model itself: its four_corner edges as coefficient rows (no noise).
// Throws std::runtime_error if the drape does not reach equilibrium.
Target material_target(const Scene& scene, const std::string& integrator = "");

struct MaterialResiduals {
  bool failed = true;
  std::string message;
  double objective = 0.0;   // 100 rms(r), percent
  Eigen::VectorXd r;        // measured - simulated coefficients
  Eigen::MatrixXd J;        // dr/du over the fitted parameters (columns in MaterialGene order)
  int negative_pivots = 0;  // of -K (0: a stable equilibrium)
  double residual = 0.0;    // static residual after the polish
  double centre_sag = 0.0;  // m
};

struct MaterialDetermined {
  double singular_value = 0.0;       // of the relative Jacobian
  std::vector<double> combination;   // right singular vector over the fitted parameters
  double edge_change_percent = 0.0;  // Eq. 5 change for a 10 % change of the combination
  bool determined = false;           // edge_change_percent >= kDeterminedPercent
};

struct MaterialParameterError {
  double value = 0.0;
  double relative_standard_error = 0.0;     // of ln p (nu: absolute); +inf when not determined
  double conditional_relative_error = 0.0;  // the same with the others known
  bool on_bound = false;                    // within 1e-3 (in u, relative to the box) of a bound
};

struct MaterialIdentifiability {
  static constexpr double kDeterminedPercent = 0.1;
  std::vector<int> fitted;                         // MaterialGene of each column
  std::vector<MaterialDetermined> combinations;    // by decreasing singular value
  std::vector<MaterialParameterError> parameters;  // per fitted parameter
  double sigma = 0.0;                              // residual standard deviation s
  int residuals = 0, determined = 0;
};

class MaterialFitProblem {
 public:
  // Checks the scene (material kind, corners), the box (base.fit_box) and reads the target's
  // four_corner scene (std::invalid_argument).
  MaterialFitProblem(Scene base, const Target& target, std::string integrator);

  const std::vector<int>& fitted() const { return fitted_; }  // MaterialGene per coordinate
  std::vector<double> lower() const;                          // box in u (ln p, or nu)
  std::vector<double> upper() const;
  std::vector<double> u_of(const std::array<double, kMaterialGenes>& p) const;
  std::array<double, kMaterialGenes> parameters_of(const std::vector<double>& u) const;
  Scene scene_of(const std::vector<double>& u) const;

  // One drape; with `jacobian` also the sensitivities. Reentrant.
  MaterialResiduals evaluate(const std::vector<double>& u, bool jacobian = true) const;
  // The ICA problem over u: cost = evaluate(u, false).objective.
  Problem ica_problem() const;

  MaterialIdentifiability identifiability(const MaterialResiduals& at,
                                          const std::vector<double>& u) const;

  const Scene& base() const { return base_; }
  const std::vector<EdgeFit>& measured() const { return measured_; }
  const std::string& integrator() const { return integrator_; }

 private:
  Scene base_;
  std::string integrator_;
  std::vector<int> fitted_;
  std::vector<EdgeFit> measured_;
};

struct MaterialFitResult {
  bool ok = false;
  std::string optimizer;  // lm | ica
  std::string message;
  std::vector<double> u;  // best point
  std::array<double, kMaterialGenes> parameters{};
  double objective = 0.0;  // percent
  long evaluations = 0, failed_evaluations = 0;
  MaterialIdentifiability identifiability;
  std::vector<std::string> warnings;  // a parameter on a bound
  double wall_seconds = 0.0;
};

// Multi-start LM: the box centre then starts - 1 seeded uniform points in u, each evaluated;
// the best `refine` refined by run_lm (analytic Jacobian), the best result kept.
MaterialFitResult fit_material_lm(const MaterialFitProblem& problem, const LmStartOptions& starts,
                                  const LmOptions& lm, std::uint64_t seed);
// The ICA over u (options as paper 1's fit), then the identifiability at its best point.
MaterialFitResult fit_material_ica(const MaterialFitProblem& problem, const IcaOptions& options);

// The console's lines on identifiability (the same for both optimisers): the combinations the
// edges determine and those they do not, and a `warning:` per parameter on a bound.
std::string identifiability_text(const MaterialFitProblem& problem, const MaterialFitResult& fit);

}  // namespace knitsim
