// Ctrl-C (SIGINT) and SIGTERM as a request to stop a run, not to lose it.
//
//   InterruptScope interrupt;                 // handlers installed until it goes out of scope
//   options.interrupt = interrupt.flag();     // run_to_equilibrium ends with status interrupted
//   ... write the outputs as for any other status ...
//   if (interrupt.signal()) exit with interrupt.exit_code()   // 128 + signal: 130, 143
//
// A signal only sets flags; nothing is cut short in the handler. With Reach::Everywhere (drape,
// knit, demo) it also sets the process-wide stop request (src/core/stop_request.hpp), so the run
// ends within about a second wherever it is: between any two steps of any integrator, inside
// the set-up of a large grid, inside the block LDL^T factorisation and SUNDIALS' Newton
// iterations -- only one CHOLMOD call (a supernodal factorisation, a METIS ordering) is waited
// for. The handler stays installed (no SA_RESETHAND): a second signal -- GNU `timeout` and batch
// schedulers send one to the program and one to its process group -- while the outputs are
// written changes nothing, so the folder is still written whole (docs/reliability.md).
// Reach::BetweenUnits (fit) sets only this scope's flag, read between units of work (a fit's
// decades) whose evaluations must not be cut short (a resumed fit is bit-identical); there the
// handler is one-shot (SA_RESETHAND): a second signal kills at once, and the checkpoint
// written after each decade is whole. repro installs none (a killed run resumes).
#pragma once

#include <atomic>
#include <filesystem>

namespace knitsim {

class InterruptScope {
 public:
  enum class Reach { Everywhere, BetweenUnits };
  // Installs the SIGINT and SIGTERM handlers; one scope at a time.
  explicit InterruptScope(Reach reach = Reach::Everywhere);
  ~InterruptScope();  // restores the previous handlers and clears the stop request
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

  const std::atomic<bool>* flag() const;  // true once a signal has arrived
  int signal() const;                     // the signal received, 0 if none
  int exit_code() const;                  // 128 + signal() (shell convention), 0 if none
  const char* signal_name() const;        // "SIGINT", "SIGTERM" or ""

  // A signal that arrived during a run's set-up (StopRequested, src/core/stop_request.hpp):
  // there is no state to write. Removes `dir` if `created` and still empty (a reused folder was
  // not written to, so it holds the earlier run as it was), prints one line ("knitsim drape:
  // interrupted by SIGTERM during set-up; nothing written") and throws CLI::RuntimeError with
  // exit_code().
  [[noreturn]] void end_during_setup(const char* command, const std::filesystem::path& dir,
                                     bool created) const;
};

}  // namespace knitsim
