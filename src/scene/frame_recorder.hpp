// The frames of a knit run (knitsim knit --frames, docs/knit.md "Outputs"): the start and states
// at the run's residual checks, `frames` of them evenly spaced in log time -- the first is the
// start, then from the first check to the last. The equilibrium solver's flow leaves t where it
// started, so its checks are spaced in log of their count instead.
//
// Memory is bounded whatever the number of checks: a check's state is kept when log t has
// advanced by `spacing` since the last kept one; past 2 x frames kept states every other one is
// dropped and `spacing` doubles.
#pragma once

#include <vector>

#include "solvers/integrator.hpp"

namespace knitsim {

class FrameRecorder final : public RunObserver {
 public:
  struct Frame {
    double t = 0.0;         // s
    double residual = 0.0;  // the static residual at t
    std::vector<double> x;  // free dofs, as the integrator holds them
    long check = 0;         // 0: the start; k: the k-th residual check
    double clock = 0.0;     // t, or the check where t stands still (the equilibrium solver)
  };

  // frames >= 1; `next` (may be null) receives every step and check after this one.
  FrameRecorder(int frames, int dof, RunObserver* next) : frames_(frames), n_(dof), next_(next) {}

  // Offers the state (t, x) with its residual: the start, then each check.
  void record(double t, const double* x, double residual);
  void on_run_start() override {
    if (next_) next_->on_run_start();
  }
  void on_step(double t, double h, int order) override;
  void on_check(double t, const double* x, const double* v, double residual) override;

  // `frames` states evenly spaced over the recorded checks, the last check included.
  std::vector<Frame> frames() const;

 private:
  int frames_;
  int n_;
  RunObserver* next_;
  double spacing_ = 1e-3;  // in log t
  std::vector<Frame> kept_;
  Frame last_;
};

}  // namespace knitsim
