#include "commands/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "toolkit/core/cancel.h"

namespace ptc {

ProgressBar::ProgressBar(std::string label)
    : label_(std::move(label)), tty_(::isatty(STDERR_FILENO) == 1), start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() {
  if (drawn_) std::fprintf(stderr, "\r\033[K");
}

void ProgressBar::update(double fraction) {
  // A step of the work is a clean point to stop at, with or without a terminal.
  throw_if_cancelled();
  if (!tty_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < std::chrono::seconds(1)) return;
  if (drawn_ && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  drawn_ = true;
  fraction = std::clamp(fraction, 0.0, 1.0);
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth);
  const double secs = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, "\r%s [%.*s%*s] %3.0f%% %.0fs", label_.c_str(), filled, "==============================",
               kWidth - filled, "", 100.0 * fraction, secs);
  std::fflush(stderr);
}

}  // namespace ptc
