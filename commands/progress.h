// A progress bar on stderr, shown only when stderr is a terminal and the work has already taken
// more than a second (architecture.md: "the ptc command"); otherwise it prints nothing, so logs
// and pipes stay clean.
#pragma once

#include <chrono>
#include <string>

namespace ptc {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  ~ProgressBar();  ///< clears the bar if one was drawn
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// fraction in [0, 1]; redraws at most ~10 times a second. Safe to call often. Throws
  /// ptc::Interrupted when cancel was requested (toolkit/core/cancel.h): call it only from the
  /// thread that runs the command, never from a TBB task.
  void update(double fraction);

 private:
  std::string label_;
  bool tty_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace ptc
