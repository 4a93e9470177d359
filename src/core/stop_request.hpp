// A process-wide request to stop, for the long loops that have no run options at hand.
//
// The command line's signal handler (src/cli/interrupt.hpp) sets it on SIGINT or SIGTERM. The
// driver (run_to_equilibrium) reads it through IntegratorOptions::interrupt after every step;
// the loops that can run for seconds without a step read it here directly: a drape grid's and
// a reduction's set-up (throw StopRequested), the block LDL^T factorisation's column loop and
// the SUNDIALS callbacks (they fail the step, and the driver then reports `interrupted` with the
// last accepted state). One call to CHOLMOD (the supernodal factorisation and its METIS
// ordering) cannot be cut short: a request waits for it to return (docs/reliability.md).
#pragma once

#include <atomic>
#include <stdexcept>

namespace knitsim {

// Set from a signal handler (a lock-free atomic store is async-signal-safe); never cleared
// by the loops that read it.
extern std::atomic<bool> g_stop_requested;

inline bool stop_requested() { return g_stop_requested.load(std::memory_order_relaxed); }

// Thrown by a set-up loop that saw the request: there is no state yet to report, so the command
// ends without outputs (src/cli: status interrupted, nothing written).
struct StopRequested : std::runtime_error {
  StopRequested() : std::runtime_error("stopped on request during set-up") {}
};

// Throws StopRequested if a stop was requested; for set-up loops, every few thousand items.
inline void throw_if_stop_requested() {
  if (stop_requested()) throw StopRequested();
}

}  // namespace knitsim
