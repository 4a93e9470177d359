// The progress line of a long run on a terminal.
#pragma once

#include <chrono>
#include <string>

#include "solvers/integrator.hpp"

namespace knitsim {

// The status of a run on stderr: label, t, static residual against the tolerance, elapsed wall
// time and a rough ETA (extrapolating log(residual) linearly in wall time). On a terminal one
// self-overwriting line, at most 10 times a second, cleared on destruction; otherwise (stderr
// to a file or a pipe: a batch job's log) one plain line every kLogInterval seconds of a long
// run, so that a run that goes nowhere says so while it runs.
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
  static constexpr double kLogInterval = 30.0;  // s between log lines (stderr not a terminal)
  bool active_;
  bool terminal_;
  bool shown_ = false;
  double first_residual_ = -1.0;
  Clock::time_point start_, last_;
};

}  // namespace knitsim
