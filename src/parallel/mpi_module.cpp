// MessagePassing on MPI (message_passing.hpp); built as the shared module libknitsim_mpi.so, the
// only code of knitsim that links MPI.
#include <mpi.h>

#include <deque>
#include <string>
#include <vector>

#include "src/parallel/message_passing.hpp"

namespace knitsim::detail {

namespace {

constexpr int kResultTag = 7301;

class MpiMessagePassing final : public MessagePassing {
 public:
  MpiMessagePassing(int* argc, char*** argv) {
    int provided = 0;
    MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  }
  ~MpiMessagePassing() override {
    complete_sends();
    MPI_Finalize();
  }

  int rank() const override {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
  }
  int size() const override {
    int size = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    return size;
  }

  void broadcast(std::string& text) override {
    long long size = static_cast<long long>(text.size());
    MPI_Bcast(&size, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
    text.resize(static_cast<std::size_t>(size));
    MPI_Bcast(text.data(), static_cast<int>(size), MPI_CHAR, 0, MPI_COMM_WORLD);
  }

  void send_to_root(std::string message) override {
    buffers_.push_back(std::move(message));
    requests_.emplace_back();
    MPI_Isend(buffers_.back().data(), static_cast<int>(buffers_.back().size()), MPI_CHAR, 0,
              kResultTag, MPI_COMM_WORLD, &requests_.back());
  }
  void complete_sends() override {
    if (!requests_.empty())
      MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
    requests_.clear();
    buffers_.clear();
  }

  bool receive(bool wait, std::string& message) override {
    MPI_Status status;
    int arrived = 1;
    if (wait)
      MPI_Probe(MPI_ANY_SOURCE, kResultTag, MPI_COMM_WORLD, &status);
    else
      MPI_Iprobe(MPI_ANY_SOURCE, kResultTag, MPI_COMM_WORLD, &arrived, &status);
    if (!arrived) return false;
    int size = 0;
    MPI_Get_count(&status, MPI_CHAR, &size);
    message.resize(static_cast<std::size_t>(size));
    MPI_Recv(message.data(), size, MPI_CHAR, status.MPI_SOURCE, kResultTag, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    return true;
  }

  [[noreturn]] void abort_all(int status) override {
    MPI_Abort(MPI_COMM_WORLD, status);
    __builtin_unreachable();
  }

  std::string library_version() const override {
    char text[MPI_MAX_LIBRARY_VERSION_STRING];
    int length = 0;
    MPI_Get_library_version(text, &length);
    const std::string version(text, static_cast<std::size_t>(length));
    return version.substr(0, version.find_first_of(",\n"));  // "Open MPI v4.1.4, package: ..."
  }

 private:
  std::deque<std::string> buffers_;  // stable addresses while the sends are under way
  std::vector<MPI_Request> requests_;
};

}  // namespace

}  // namespace knitsim::detail

extern "C" __attribute__((visibility("default"))) knitsim::detail::MessagePassing*
knitsim_open_message_passing(int* argc, char*** argv) {
  return new knitsim::detail::MpiMessagePassing(argc, argv);
}
