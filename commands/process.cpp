// The `ptc` process's signal handling and reader notes (commands/process.h).
#include "commands/process.h"

#include <fcntl.h>
#include <malloc.h>
#include <cstdlib>
#include <filesystem>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <iostream>
#include <string>

#include "toolkit/core/cancel.h"
#include "toolkit/core/memory.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

// The first SIGINT / SIGTERM asks the run to stop at its next clean point (toolkit/core/cancel.h:
// the exception unwinds, so an uncommitted OutputDir or AtomicFile removes its temporary and a
// previous output stays as it was). A second one stops at once: the handler removes the
// registered temporaries (files and directories), says so, and ends the process by the signal's
// default action. Only async-signal-safe calls here: atomics, write, the removal's system calls,
// sigaction and raise.
std::atomic<int> g_stop_signals{0};
static_assert(std::atomic<int>::is_always_lock_free);

// StopAtOnceHeld: the signal that came while held (0: none beyond the first).
std::atomic<bool> g_at_once_held{false};
std::atomic<int> g_held_signal{0};
static_assert(std::atomic<bool>::is_always_lock_free);

void stop_at_once(int sig, bool first);

// The first signal stops at once too while the run waits in a blocking read of a FIFO or pipe
// (BlockingWaitFor, toolkit/core/cancel.h), which SA_RESTART would resume forever.
extern "C" void on_stop_signal(int sig) {
  const bool first = g_stop_signals.fetch_add(1) == 0;
  if (g_at_once_held.load()) {  // an OutputDir commit: it gives up and undoes its moves first
    request_cancel();
    if (!first) g_held_signal.store(sig);
    return;
  }
  if (first && !in_blocking_wait()) {
    request_cancel();
    return;
  }
  stop_at_once(sig, first);
}

void stop_at_once(int sig, bool first) {
  remove_temporaries_now();
  static const char again[] = "ptc: interrupted again: stopped at once (temporary files removed)\n";
  static const char waiting[] = "ptc: interrupted while waiting for input: stopped\n";
  if (first) (void)!::write(STDERR_FILENO, waiting, sizeof waiting - 1);
  else (void)!::write(STDERR_FILENO, again, sizeof again - 1);
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  sigaction(sig, &dfl, nullptr);
  raise(sig);
}

// What a reader tells about a file it read anyway (faces with fewer than 3 corners skipped,
// surplus PLY values): one line each on stderr, at most kMaxNotes over a run (a frame directory
// of such files would repeat the same note per frame).
void print_read_note(const std::string& file, const std::string& note) {
  constexpr int kMaxNotes = 4;
  static std::atomic<int> printed{0};
  const int n = printed.fetch_add(1);
  if (n < kMaxNotes)
    std::cerr << "ptc: note: " << file << ": " << note << "\n";
  else if (n == kMaxNotes)
    std::cerr << "ptc: note: further notes on the files read are not shown\n";
}

}  // namespace

void open_standard_streams() {
  for (int fd = 0; fd <= 2; ++fd)
    if (::fcntl(fd, F_GETFD) == -1 && errno == EBADF) {
      // The lowest free number is fd (those below it are open by now).
      const int got = ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
      if (got != fd && got >= 0) ::close(got);  // (cannot happen; never keep a stray descriptor)
    }
}

StopAtOnceHeld::StopAtOnceHeld() {
  held_ = !g_at_once_held.exchange(true);
}

void StopAtOnceHeld::release() {
  if (!held_) return;
  held_ = false;
  g_at_once_held.store(false);
  // A second signal came while held: act on it now (a signal during this check finds the hold
  // released and acts itself; acting twice is harmless, as the first ends the process).
  if (const int sig = g_held_signal.exchange(0)) stop_at_once(sig, false);
}

namespace {
bool g_stop_blocked_by_exec = false;  // this image was executed with SIGINT and SIGTERM blocked
sigset_t stop_signals() {              // the requests to stop: Ctrl-C and SIGTERM
  sigset_t s;
  sigemptyset(&s);
  sigaddset(&s, SIGINT);
  sigaddset(&s, SIGTERM);
  return s;
}
}  // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaddset(&sa.sa_mask, SIGINT);  // one handler at a time
  sigaddset(&sa.sa_mask, SIGTERM);
  // SA_RESTART: a write or fsync interrupted by the signal resumes instead of failing with EINTR,
  // which would report an I/O error (exit 1) instead of the interrupt.
  sa.sa_flags = SA_RESTART;
  for (int sig : {SIGINT, SIGTERM}) {
    struct sigaction old {};
    // A signal ignored on entry (a background job of a non-interactive shell, nohup) stays
    // ignored, as the shell meant.
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
    sigaction(sig, &sa, nullptr);
  }
  // Blocked across use_huge_page_malloc's exec: a signal that came meanwhile is delivered now.
  if (!g_stop_blocked_by_exec) return;
  const sigset_t stop = stop_signals();
  ::sigprocmask(SIG_UNBLOCK, &stop, nullptr);
}

namespace {
bool names_huge_pages(const std::string& tunables) {
  return tunables.find("glibc.malloc.hugetlb=1") != std::string::npos ||
         tunables.find("glibc.malloc.hugetlb=2") != std::string::npos;
}
}  // namespace

void use_huge_page_malloc(char** argv) {
  // The one exec happened: give the user's GLIBC_TUNABLES back (child programs such as ffmpeg,
  // Xvfb and jupyter see the environment ptc was started with), and never exec again. The
  // marker holds "-" for "was unset", else "=" and the user's value.
  if (const char* marker = std::getenv("PTC_HUGEPAGES_EXECUTED")) {
    g_stop_blocked_by_exec = true;  // (see the exec below)
    const std::string was = marker;
    if (was.size() > 1 && was[0] == '=') ::setenv("GLIBC_TUNABLES", was.c_str() + 1, 1);
    else ::unsetenv("GLIBC_TUNABLES");
    ::unsetenv("PTC_HUGEPAGES_EXECUTED");
    set_malloc_huge_pages(true);
    return;
  }
  const char* t = std::getenv("GLIBC_TUNABLES");
  const std::string current = t ? t : "";
  set_malloc_huge_pages(names_huge_pages(current));
  if (const char* off = std::getenv("PTC_HUGEPAGES"); off && std::string(off) == "0") return;
  if (current.find("glibc.malloc.hugetlb") != std::string::npos) return;  // the user's choice stands
  // Not under valgrind (the new image would run outside it) or an explicit loader invocation
  // (/proc/self/exe is then ld.so itself).
  if (const char* pre = std::getenv("LD_PRELOAD"); pre && std::string(pre).find("vgpreload") != std::string::npos) return;
  {
    std::error_code ec;
    const std::string exe = std::filesystem::read_symlink("/proc/self/exe", ec).filename().string();
    if (ec || exe.rfind("ld-", 0) == 0 || exe.rfind("ld.so", 0) == 0) return;
  }
  if (const std::string mode = transparent_huge_page_mode(); mode.empty() || mode == "never") return;
  const std::string value = current.empty() ? "glibc.malloc.hugetlb=1" : current + ":glibc.malloc.hugetlb=1";
  const std::string marker = t ? "=" + current : std::string("-");
  if (::setenv("PTC_HUGEPAGES_EXECUTED", marker.c_str(), 1) != 0 || ::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) {
    ::unsetenv("PTC_HUGEPAGES_EXECUTED");
    if (t) ::setenv("GLIBC_TUNABLES", current.c_str(), 1);
    return;
  }
  // Ctrl-C and SIGTERM are blocked across the exec (the mask and pending signals survive it):
  // one that arrives while the new image loads stays pending until install_stop_handlers
  // unblocks it, and is then a stop request like any other (exit 130 and its line), instead of
  // killing the process silently by the default action.
  const sigset_t stop = stop_signals();
  sigset_t before;
  ::sigprocmask(SIG_BLOCK, &stop, &before);
  ::execv("/proc/self/exe", argv);
  // Still here: the exec failed; carry on as we were.
  ::sigprocmask(SIG_SETMASK, &before, nullptr);
  ::unsetenv("PTC_HUGEPAGES_EXECUTED");
  if (t) ::setenv("GLIBC_TUNABLES", current.c_str(), 1);
  else ::unsetenv("GLIBC_TUNABLES");
}

void set_memory_policy() {
  // Setting the thresholds turns glibc's dynamic adjustment off (mallopt(3)).
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  mallopt(M_TRIM_THRESHOLD, 4 * 1024 * 1024);
}

void print_read_notes_on_stderr() { set_read_note_handler(print_read_note); }

}  // namespace ptc
