#include "toolkit/core/cancel.h"

#include <atomic>

namespace ptc {
namespace {
// A signal handler may touch only lock-free atomics (or volatile sig_atomic_t); checked here so
// that a platform where bool is not lock-free fails to compile instead of deadlocking.
std::atomic<bool> g_cancel{false};
static_assert(std::atomic<bool>::is_always_lock_free, "request_cancel must be async-signal-safe");
}  // namespace

void request_cancel() noexcept { g_cancel.store(true, std::memory_order_relaxed); }

bool cancel_requested() noexcept { return g_cancel.load(std::memory_order_relaxed); }

void reset_cancel() noexcept { g_cancel.store(false, std::memory_order_relaxed); }

void throw_if_cancelled() {
  if (cancel_requested()) throw Interrupted();
}

}  // namespace ptc
