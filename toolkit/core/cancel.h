// Stopping a long run at the user's request (Ctrl-C, SIGTERM): one process-wide flag. A signal
// handler only sets it (request_cancel: a lock-free atomic store, async-signal-safe); the long
// loops poll it at points where stopping is clean (throw_if_cancelled: before each frame and
// each configuration's update in analysis/loop/frame_loop.cpp, at each progress-bar step in
// commands/). The exception then unwinds like any failure, so an OutputDir that was not
// committed removes its temporary directory and a previous output stays as it was; apps/ptc
// maps Interrupted to exit code 130 (128 + SIGINT, what a shell reports for a Ctrl-C).
//
// Poll only on the thread that runs the command: never inside a TBB task (a worker's exception
// would cancel the task group at an arbitrary point) nor in a destructor.
#pragma once

#include <filesystem>
#include <stdexcept>

namespace ptc {

/// The run was stopped by request_cancel(); what() is "interrupted".
class Interrupted : public std::runtime_error {
 public:
  Interrupted() : std::runtime_error("interrupted") {}
};

/// Sets the flag. Async-signal-safe: callable from a signal handler.
void request_cancel() noexcept;
/// Whether request_cancel() was called since the start or the last reset_cancel().
[[nodiscard]] bool cancel_requested() noexcept;
/// Clears the flag (tests; a process that runs several commands in turn).
void reset_cancel() noexcept;
/// Throws Interrupted when cancel_requested(). One relaxed atomic load otherwise: cheap enough to
/// call once per frame and configuration.
void throw_if_cancelled();

/// While one lives for a file that is not a regular file (a FIFO, a pipe; or a path that cannot
/// be examined), a request to stop cannot wait for the next clean point: the thread may be
/// blocked in a system call that the handlers resume after the signal (SA_RESTART), such as
/// opening a FIFO that nobody writes to. apps/ptc's handler then stops at once, as for a second
/// Ctrl-C. Readers hold one around the open and the reading of their input file.
class BlockingWaitFor {
 public:
  explicit BlockingWaitFor(const std::filesystem::path& path);
  ~BlockingWaitFor();
  BlockingWaitFor(const BlockingWaitFor&) = delete;
  BlockingWaitFor& operator=(const BlockingWaitFor&) = delete;

 private:
  bool held_ = false;
};
/// Whether a BlockingWaitFor of a file that is not a regular file lives (on any thread).
/// Async-signal-safe.
[[nodiscard]] bool in_blocking_wait() noexcept;

/// Temporaries that must not outlive a run stopped at once: a second Ctrl-C (or SIGTERM) does not
/// wait for the unwinding, so the signal handler removes what is registered here before the
/// process ends (AtomicFile registers its temporary file, OutputDir its temporary directory).
/// At most kMaxTemporaries at a time; registering more returns -1 (that one is then only
/// removed by the normal unwinding).
inline constexpr int kMaxTemporaries = 64;
/// Registers `path` (a file, or a directory removed with everything in it); returns its slot.
[[nodiscard]] int register_temporary(const std::filesystem::path& path, bool directory) noexcept;
/// The temporary of `slot` is gone or became an output: forget it. -1 is ignored.
void unregister_temporary(int slot) noexcept;
/// Removes every registered temporary (directories with their contents, up to 8 levels deep).
/// Async-signal-safe: only atomics and the open/getdents/unlink/rmdir system calls.
void remove_temporaries_now() noexcept;
/// How many temporaries are registered (tests).
[[nodiscard]] int registered_temporaries() noexcept;

}  // namespace ptc
