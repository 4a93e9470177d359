// The Schur-complement LDL^T Newton solver (solvers/schur_ldl_solver.hpp) against a dense LU
// of the full 2n x 2n matrix A = I - gamma J, and cvode-bdf with either Newton solver.
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <random>

#include "models/drape_grid.hpp"
#include "solvers/integrator.hpp"
#include "solvers/schur_ldl_solver.hpp"
#include "src/first_order.hpp"

using namespace knitsim;

TEST_CASE("Schur LDL^T solve equals a dense LU solve of I - gamma J") {
  DrapeParams p;
  p.natural_length = 0.1;  // 6 x 6 grid, 2n = 192
  const DrapeGrid g = build_drape_grid(p);
  const FirstOrderSystem fo(g.network);
  const int N = fo.size(), n = N / 2;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> y(N);
  g.network.initial_state(y.data(), y.data() + n);
  for (int i = 0; i < n; ++i) y[i] += 0.01 * u(rng);  // stretched and compressed springs
  for (int i = n; i < N; ++i) y[i] = 1e-3 * u(rng);

  SUNContext ctx;
  REQUIRE(SUNContext_Create(nullptr, &ctx) == 0);
  const CscPattern& P = fo.jacobian_pattern();
  SUNMatrix A = SUNSparseMatrix(N, N, P.nnz(), CSC_MAT, ctx);
  std::copy(P.colptr.begin(), P.colptr.end(), SUNSparseMatrix_IndexPointers(A));
  std::copy(P.rowind.begin(), P.rowind.end(), SUNSparseMatrix_IndexValues(A));
  SUNLinearSolver LS = detail::make_schur_ldl_solver(ctx, fo);
  REQUIRE(LS != nullptr);
  N_Vector b = N_VNew_Serial(N, ctx), x = N_VNew_Serial(N, ctx);

  for (double gamma : {1e-6, 1e-3, 1.0, 100.0}) {
    std::vector<double> jv(P.nnz());
    fo.jacobian_values(0.0, y.data(), jv.data());
    double* a = SUNSparseMatrix_Data(A);
    Eigen::MatrixXd dense = Eigen::MatrixXd::Identity(N, N);
    for (int j = 0; j < N; ++j)
      for (int k = P.colptr[j]; k < P.colptr[j + 1]; ++k) {
        a[k] = (P.rowind[k] == j ? 1.0 : 0.0) - gamma * jv[k];
        dense(P.rowind[k], j) -= gamma * jv[k];
      }
    REQUIRE(SUNLinSolSetup(LS, A) == 0);
    Eigen::VectorXd rhs(N);
    for (int i = 0; i < N; ++i) rhs[i] = NV_Ith_S(b, i) = u(rng);
    REQUIRE(SUNLinSolSolve(LS, A, x, b, 0.0) == 0);
    const Eigen::VectorXd ref = dense.partialPivLu().solve(rhs);
    double err = 0.0;
    for (int i = 0; i < N; ++i) err = std::max(err, std::abs(NV_Ith_S(x, i) - ref[i]));
    INFO("gamma " << gamma << " max error " << err << " vs |ref| " << ref.cwiseAbs().maxCoeff());
    CHECK(err <= 1e-9 * std::max(1.0, ref.cwiseAbs().maxCoeff()));
  }
  N_VDestroy(b);
  N_VDestroy(x);
  SUNLinSolFree(LS);
  SUNMatDestroy(A);
  SUNContext_Free(&ctx);
}

TEST_CASE("cvode-bdf takes the same steps to the same equilibrium with KLU and Schur LDL^T") {
  const DrapeGrid g = build_drape_grid(DrapeParams{});
  RunStats s[2];
  std::vector<double> x[2];
  const IntegratorOptions::NewtonSolver which[2] = {IntegratorOptions::NewtonSolver::Klu,
                                                    IntegratorOptions::NewtonSolver::SchurLdl};
  for (int k = 0; k < 2; ++k) {
    IntegratorOptions opt;
    opt.newton_solver = which[k];
    std::vector<double> v;
    s[k] = run_to_equilibrium(g.network, "cvode-bdf", opt, x[k], v);
    REQUIRE(s[k].status == RunStatus::Equilibrium);
  }
  CHECK(s[0].steps == s[1].steps);
  CHECK(s[0].lin_setups == s[1].lin_setups);
  double diff = 0.0;
  for (size_t i = 0; i < x[0].size(); ++i) diff = std::max(diff, std::abs(x[0][i] - x[1][i]));
  CHECK(diff < 1e-12);
}
