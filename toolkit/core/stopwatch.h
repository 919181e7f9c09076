// The one stopwatch: wall time on std::chrono::steady_clock, in milliseconds (what a user waits
// for). Per-frame stage timers that may also run on the thread's CPU clock are bvh/stage_clock.h.
#pragma once

#include <chrono>

namespace ptc {

class Stopwatch {
 public:
  Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
  /// Milliseconds since construction or the last restart()/lap_ms().
  [[nodiscard]] double ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
  }
  /// ms(), then restarts: the time of one step of a sequence.
  double lap_ms() {
    const auto now = std::chrono::steady_clock::now();
    const double d = std::chrono::duration<double, std::milli>(now - t0_).count();
    t0_ = now;
    return d;
  }
  void restart() { t0_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace ptc
