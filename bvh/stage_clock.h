// The clock of the per-frame stage timers. Wall: steady_clock, the default and what a user
// waits for. ThreadCpu: CPU time of the calling thread (CLOCK_THREAD_CPUTIME_ID): on a machine
// shared with other jobs it leaves out the time the thread was descheduled, so single-threaded
// comparisons stay meaningful under load (cache interference remains). Only meaningful for work
// done on the calling thread (one thread; Embree with threads = 1 under a oneTBB
// global_control of 1 runs its commit there).
#pragma once

#include <chrono>
#include <ctime>

namespace ptc::bvh {

enum class StageClock { Wall, ThreadCpu };

/// Milliseconds on the chosen clock (an arbitrary origin: only differences mean something).
[[nodiscard]] inline double clock_ms(StageClock c) {
  if (c == StageClock::ThreadCpu) {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
  }
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace ptc::bvh
