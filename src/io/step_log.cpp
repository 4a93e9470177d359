#include "src/io/step_log.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace knitsim {

namespace {
constexpr double kUnchecked = std::numeric_limits<double>::quiet_NaN();
}

StepLog::StepLog(RunObserver* next, std::size_t max_rows) : next_(next), max_rows_(max_rows) {
  if (max_rows < 1) throw std::invalid_argument("StepLog max_rows = 0: must be >= 1");
  last_.residual = kUnchecked;
}

void StepLog::on_step(double t, double h, int order) {
  last_ = Row{last_.step + 1, t, h, order, kUnchecked};
  last_kept_ = last_.step % stride_ == 0;
  if (last_kept_) {
    rows_.push_back(last_);
    if (rows_.size() >= 2 * max_rows_) {  // keep every other row: multiples of 2 stride
      stride_ *= 2;
      std::size_t kept = 0;
      for (const Row& r : rows_)
        if (r.step % stride_ == 0) rows_[kept++] = r;
      rows_.resize(kept);
      last_kept_ = last_.step % stride_ == 0;
    }
  }
  if (next_) next_->on_step(t, h, order);
}

void StepLog::on_check(double t, const double* x, const double* v, double residual) {
  if (last_.step > 0 && t == last_.t) {
    last_.residual = residual;
    if (last_kept_) rows_.back().residual = residual;
  }
  if (next_) next_->on_check(t, x, v, residual);
}

std::vector<StepLog::Row> StepLog::rows() const {
  std::vector<Row> out = rows_;
  if (last_.step > 0 && !last_kept_) out.push_back(last_);
  return out;
}

std::string StepLog::csv() const {
  std::ostringstream os;
  os.precision(17);
  os << "step,t,h,order,residual\n";
  for (const Row& r : rows()) {
    os << r.step << ',' << r.t << ',' << r.h << ',' << r.order << ',';
    if (!std::isnan(r.residual)) os << r.residual;
    os << '\n';
  }
  return os.str();
}

}  // namespace knitsim
