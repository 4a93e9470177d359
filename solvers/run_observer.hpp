// A run's observer: called by the run driver after every step and at every residual check
// (progress lines, time series, frames).
#pragma once

namespace knitsim {

// Observer of a run: on_step after every step (t after it, h = its size -- 0 for a step that did
// not advance time, e.g. a static polish attempt -- and the method order used), on_check at every
// residual check (for progress lines and time series); a check follows the step at the same t.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  virtual void on_step(double /*t*/, double /*h*/, int /*order*/) {}
  // When a run starts, before its first stop test: a driver of many runs that each conclude at
  // their start (a tensile test's warm-started steps) calls no on_step or on_check, and the
  // Python module polls its signals here too.
  virtual void on_run_start() {}
  virtual void on_check(double t, const double* x, const double* v, double residual) = 0;
};

}  // namespace knitsim
