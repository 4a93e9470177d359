#include "src/core/stop_request.hpp"

namespace knitsim {

static_assert(std::atomic<bool>::is_always_lock_free, "a signal handler sets it");

std::atomic<bool> g_stop_requested{false};

}  // namespace knitsim
