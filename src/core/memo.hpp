// PatternMemo<T>: a process-wide store of immutable results that are pure functions of an
// integer pattern (a sparsity pattern, a list of spring ends), so that set-up work repeated for
// every drape of a fit -- the same mesh, other parameters -- is done once. A hit returns the
// entry itself (shared, never copied), identical to a fresh computation on any thread.
//
//   static PatternMemo<Analysis> memo(size_t{1} << 23);  // at most 8 M integers held
//   auto a = memo.find([&](const Analysis& e) { return e.key == key; });
//   if (!a) a = memo.insert(std::make_shared<const Analysis>(compute(key)), footprint);
//
// Bounded by the integers its entries hold (the caller's footprint); the oldest go first, and an
// entry larger than the bound is returned but not kept. Thread-safe.
#pragma once

#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <utility>

namespace knitsim {

template <class T>
class PatternMemo {
 public:
  explicit PatternMemo(std::size_t max_integers) : max_(max_integers) {}
  PatternMemo(const PatternMemo&) = delete;
  PatternMemo& operator=(const PatternMemo&) = delete;

  // The first entry for which same(entry) holds, or null.
  template <class Same>
  std::shared_ptr<const T> find(const Same& same) {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (const Entry& e : entries_)
      if (same(*e.value)) return e.value;
    return nullptr;
  }

  // Keeps `value` (footprint: the integers it holds) and returns it.
  std::shared_ptr<const T> insert(std::shared_ptr<const T> value, std::size_t footprint) {
    if (footprint > max_) return value;
    const std::lock_guard<std::mutex> lock(mutex_);
    while (!entries_.empty() && held_ + footprint > max_) {
      held_ -= entries_.front().footprint;
      entries_.pop_front();
    }
    held_ += footprint;
    entries_.push_back({value, footprint});
    return value;
  }

  void clear() {
    const std::lock_guard<std::mutex> lock(mutex_);
    entries_.clear();
    held_ = 0;
  }

 private:
  struct Entry {
    std::shared_ptr<const T> value;
    std::size_t footprint;
  };
  std::size_t max_;
  std::mutex mutex_;
  std::deque<Entry> entries_;
  std::size_t held_ = 0;
};

}  // namespace knitsim
