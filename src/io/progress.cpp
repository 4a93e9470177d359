#include "src/io/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "src/base/text.hpp"

namespace knitsim {

ProgressLine::ProgressLine(std::string label, double equilibrium_tol, bool enabled)
    : label_(std::move(label)),
      tol_(equilibrium_tol),
      active_(enabled),
      terminal_(::isatty(STDERR_FILENO) == 1),
      start_(Clock::now()),
      last_(start_) {}

ProgressLine::~ProgressLine() {
  if (shown_) std::fprintf(stderr, "\r\033[K");
}

void ProgressLine::on_check(double t, const double*, const double*, double residual) {
  if (!active_) return;
  if (first_residual_ < 0.0) first_residual_ = residual;
  const Clock::time_point now = Clock::now();
  if (now - last_ < (terminal_ ? std::chrono::duration<double>(0.1)
                               : std::chrono::duration<double>(kLogInterval)))
    return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::string eta;
  // Fraction of the way from the first residual to the tolerance, on a log scale.
  if (residual > tol_ && first_residual_ > residual && tol_ > 0.0) {
    const double f = std::log(first_residual_ / residual) / std::log(first_residual_ / tol_);
    if (f > 0.02) eta = "  eta ~" + format_number(elapsed * (1.0 - f) / f, 2) + " s";
  }
  std::fprintf(stderr, "%s%s  t = %.3g s  residual %.2e (tol %.0e)  elapsed %.1f s%s%s",
               terminal_ ? "\r\033[K" : "progress: ", label_.c_str(), t, residual, tol_, elapsed,
               eta.c_str(), terminal_ ? "" : "\n");
  std::fflush(stderr);
  shown_ = terminal_;
}


}  // namespace knitsim
