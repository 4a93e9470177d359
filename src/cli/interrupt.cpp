#include "src/cli/interrupt.hpp"

#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <stdexcept>

#include "src/base/files.hpp"
#include "src/core/stop_request.hpp"

namespace knitsim {

namespace {

// Lock-free atomics are async-signal-safe; the handler touches nothing else.
std::atomic<bool> g_requested{false};
std::atomic<int> g_signal{0};
std::atomic<bool> g_active{false};
std::atomic<bool> g_everywhere{false};  // set g_stop_requested too (Reach::Everywhere)
struct sigaction g_previous_int, g_previous_term;

static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

extern "C" void on_signal(int sig) {
  g_signal.store(sig, std::memory_order_relaxed);
  g_requested.store(true, std::memory_order_relaxed);
  if (g_everywhere.load(std::memory_order_relaxed))
    g_stop_requested.store(true, std::memory_order_relaxed);
}

}  // namespace

InterruptScope::InterruptScope(Reach reach) {
  if (g_active.exchange(true)) throw std::logic_error("InterruptScope: one scope at a time");
  g_requested = false;
  g_signal = 0;
  g_stop_requested = false;
  g_everywhere = reach == Reach::Everywhere;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  // SA_RESTART: file I/O is not cut short. Persistent where the run stops within a second
  // (a second signal must not kill it while it writes); one-shot between units of work.
  action.sa_flags = SA_RESTART | (reach == Reach::Everywhere ? 0 : SA_RESETHAND);
  sigaction(SIGINT, &action, &g_previous_int);
  sigaction(SIGTERM, &action, &g_previous_term);
}

InterruptScope::~InterruptScope() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
  g_stop_requested = false;
  g_everywhere = false;
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

void InterruptScope::end_during_setup(const char* command, const std::filesystem::path& dir,
                                      bool created) const {
  remove_if_unused(dir, created);
  std::cerr << "knitsim " << command << ": interrupted by " << signal_name()
            << " during set-up, before the run started; nothing written" << std::endl;
  throw CLI::RuntimeError(exit_code());
}

}  // namespace knitsim
