// Ctrl-C (SIGINT) and SIGTERM as a request to stop a run, not to lose it.
//
//   InterruptScope interrupt;                 // handlers installed until it goes out of scope
//   options.interrupt = interrupt.flag();     // run_to_equilibrium ends with status interrupted
//   ... write the outputs as for any other status ...
//   if (interrupt.signal()) exit with interrupt.exit_code()   // 128 + signal: 130, 143
//
// The first signal only sets the flag; the run ends at its next residual check and the command
// writes what it has. The handler is one-shot (SA_RESETHAND): a second Ctrl-C or SIGTERM kills
// the process at once, for a run whose next check is far away. Commands that checkpoint instead
// (fit, repro: a killed run resumes from its checkpoint) do not install it.
#pragma once

#include <atomic>

namespace knitsim {

class InterruptScope {
 public:
  InterruptScope();   // installs the SIGINT and SIGTERM handlers; one scope at a time
  ~InterruptScope();  // restores the previous handlers
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

  const std::atomic<bool>* flag() const;  // true once a signal has arrived
  int signal() const;                     // the signal received, 0 if none
  int exit_code() const;                  // 128 + signal() (shell convention), 0 if none
  const char* signal_name() const;        // "SIGINT", "SIGTERM" or ""
};

}  // namespace knitsim
