#include "src/cli/interrupt.hpp"

#include <csignal>
#include <stdexcept>

namespace knitsim {

namespace {

// Lock-free atomics are async-signal-safe; the handler touches nothing else.
std::atomic<bool> g_requested{false};
std::atomic<int> g_signal{0};
std::atomic<bool> g_active{false};
struct sigaction g_previous_int, g_previous_term;

static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

extern "C" void on_signal(int sig) {
  g_signal.store(sig, std::memory_order_relaxed);
  g_requested.store(true, std::memory_order_relaxed);
}

}  // namespace

InterruptScope::InterruptScope() {
  if (g_active.exchange(true)) throw std::logic_error("InterruptScope: one scope at a time");
  g_requested = false;
  g_signal = 0;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND | SA_RESTART;  // one-shot; file I/O is not cut short
  sigaction(SIGINT, &action, &g_previous_int);
  sigaction(SIGTERM, &action, &g_previous_term);
}

InterruptScope::~InterruptScope() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
  g_active = false;
}

const std::atomic<bool>* InterruptScope::flag() const { return &g_requested; }

int InterruptScope::signal() const { return g_signal.load(std::memory_order_relaxed); }

int InterruptScope::exit_code() const { return signal() ? 128 + signal() : 0; }

const char* InterruptScope::signal_name() const {
  switch (signal()) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "";
  }
}

}  // namespace knitsim
