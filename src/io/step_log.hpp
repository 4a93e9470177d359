// StepLog: the step history of a run (`knitsim drape|knit --step-history` -> steps.csv), the
// diagnostic behind "why does this integrator take N steps here": for every step, the time
// reached t (s), the step size h (s; 0 for a step that did not advance time, e.g. a static
// polish attempt), the method order used and the static residual (docs/equilibrium.md) where the
// driver checked it (every step for adaptive methods; every check_every steps for fixed-step ones).
//
// Memory is bounded: every step is kept until there are 2 max_rows rows; then every other row
// is dropped and from then on only steps whose number is a multiple of the doubled stride are
// kept, so a run of any length keeps between max_rows and 2 max_rows rows spread evenly over its
// steps (the `step` column numbers them from 1). The last step is always written.
//
// It forwards every call to `next` (e.g. the progress line) when given.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "solvers/integrator.hpp"

namespace knitsim {

class StepLog final : public RunObserver {
 public:
  struct Row {
    long step = 0;    // 1-based step number
    double t = 0.0;   // s, after the step
    double h = 0.0;   // s
    int order = 0;    // method order used
    double residual;  // static residual at t; NaN if not checked at this step
  };

  // max_rows >= 1 (throws std::invalid_argument otherwise).
  explicit StepLog(RunObserver* next = nullptr, std::size_t max_rows = 100000);

  void on_run_start() override {
    if (next_) next_->on_run_start();
  }
  void on_step(double t, double h, int order) override;
  void on_check(double t, const double* x, const double* v, double residual) override;

  // The kept rows, then the last step if it was not kept.
  std::vector<Row> rows() const;
  // "step,t,h,order,residual" and one line per row (residual empty where not checked).
  std::string csv() const;

 private:
  RunObserver* next_;
  std::size_t max_rows_;
  long stride_ = 1;  // keep steps whose number is a multiple of this
  std::vector<Row> rows_;
  Row last_;
  bool last_kept_ = false;
};

}  // namespace knitsim
