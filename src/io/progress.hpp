// The progress line of a long run on a terminal.
#pragma once

#include <chrono>
#include <string>

#include "solvers/integrator.hpp"

namespace knitsim {

// One self-overwriting status line on stderr -- only when stderr is a terminal, and at most 10
// times a second: label, t, static residual against the tolerance, elapsed wall time and a
// rough ETA (extrapolating log(residual) linearly in wall time). Cleared on destruction.
class ProgressLine final : public RunObserver {
 public:
  ProgressLine(std::string label, double equilibrium_tol, bool enabled = true);
  ~ProgressLine() override;
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  void on_check(double t, const double* x, const double* v, double residual) override;

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  double tol_;
  bool active_;
  bool shown_ = false;
  double first_residual_ = -1.0;
  Clock::time_point start_, last_;
};

}  // namespace knitsim
