// The messages between processes that run_work_units (work_units.cpp) exchanges, behind an
// interface so that Open MPI is mapped only into a process that an MPI launcher started.
// mpi_module.cpp implements it on MPI and is built as a shared module (libknitsim_mpi.so, next
// to knitsim in the build folder) that work_units.cpp loads with dlopen when ProcessGroup sees an
// MPI launcher's environment. Linked into every binary, Open MPI and its libraries (libmpi,
// open-rte, open-pal, hwloc, libevent, ...) would add to every run's start-up
// (experiments/benchmark/README.md, "Process start").
// Internal to src/parallel.
#pragma once

#include <string>

namespace knitsim::detail {

class MessagePassing {
 public:
  virtual ~MessagePassing() = default;  // MPI_Finalize
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Rank 0's `text` on every rank. Collective.
  virtual void broadcast(std::string& text) = 0;
  // Sends `message` to rank 0 without waiting for it to be received; complete_sends() returns
  // once every message sent so far has left.
  virtual void send_to_root(std::string message) = 0;
  virtual void complete_sends() = 0;
  // Rank 0: the next message of another rank, if one has arrived (wait = false) or when it does.
  virtual bool receive(bool wait, std::string& message) = 0;
  // Ends every rank with `status` (MPI_Abort).
  [[noreturn]] virtual void abort_all(int status) = 0;
  // "Open MPI v4.1.4" (MPI_Get_library_version, up to its first comma or line break).
  virtual std::string library_version() const = 0;
};

// The module's one entry point, by this name: MPI_Init_thread (MPI_THREAD_FUNNELED: only the
// main thread calls MPI) and a MessagePassing owned by the caller.
using OpenMessagePassing = MessagePassing* (*)(int* argc, char*** argv);
inline constexpr const char* open_message_passing_symbol = "knitsim_open_message_passing";

}  // namespace knitsim::detail
