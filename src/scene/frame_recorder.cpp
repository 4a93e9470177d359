#include "src/scene/frame_recorder.hpp"

#include <cmath>
#include <utility>

namespace knitsim {

void FrameRecorder::record(double t, const double* x, double residual) {
  const long check = kept_.empty() ? 0 : last_.check + 1;
  const double clock = kept_.empty() || t != kept_.front().t ? t : static_cast<double>(check);
  last_ = {t, residual, std::vector<double>(x, x + n_), check, clock};
  if (kept_.size() < 2 || std::log(clock / kept_.back().clock) >= spacing_) kept_.push_back(last_);
  if (static_cast<int>(kept_.size()) > 2 * frames_ + 1) {
    std::vector<Frame> half{std::move(kept_[0])};  // the start, then every other check
    for (size_t k = 1; k < kept_.size(); k += 2) half.push_back(std::move(kept_[k]));
    kept_ = std::move(half);
    spacing_ *= 2.0;
  }
}

void FrameRecorder::on_step(double t, double h, int order) {
  if (next_) next_->on_step(t, h, order);
}

void FrameRecorder::on_check(double t, const double* x, const double* v, double residual) {
  record(t, x, residual);
  if (next_) next_->on_check(t, x, v, residual);
}

std::vector<FrameRecorder::Frame> FrameRecorder::frames() const {
  std::vector<Frame> all = kept_;
  if (all.back().check != last_.check) all.push_back(last_);
  if (static_cast<int>(all.size()) <= frames_) return all;
  std::vector<Frame> out;
  for (int k = 0; k < frames_; ++k) {
    const double at = frames_ == 1 ? all.size() - 1.0 : k * (all.size() - 1.0) / (frames_ - 1);
    out.push_back(all[static_cast<size_t>(std::lround(at))]);
  }
  return out;
}

}  // namespace knitsim
