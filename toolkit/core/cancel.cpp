#include "toolkit/core/cancel.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <climits>
#include <cstring>

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

namespace {
std::atomic<int> g_blocking{0};
static_assert(std::atomic<int>::is_always_lock_free, "in_blocking_wait must be async-signal-safe");
}  // namespace

bool in_blocking_wait() noexcept { return g_blocking.load() > 0; }

BlockingWaitFor::BlockingWaitFor(const std::filesystem::path& path) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  held_ = ec || !std::filesystem::is_regular_file(st);
  if (held_) g_blocking.fetch_add(1);
}
BlockingWaitFor::~BlockingWaitFor() {
  if (held_) g_blocking.fetch_sub(1);
}

namespace {

// A slot is Free, Filling (a thread is copying a path in), File or Dir; `gen` changes with every
// registration, so that the handler, which copies a path and then checks that neither state nor
// generation moved meanwhile, never acts on a path that was half rewritten for a new temporary.
enum SlotState : int { kFree = 0, kFilling = 1, kFile = 2, kDir = 3 };
struct Slot {
  std::atomic<int> state{kFree};
  std::atomic<unsigned> gen{0};
  char path[PATH_MAX];
};
Slot g_slots[kMaxTemporaries];
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<unsigned>::is_always_lock_free,
              "the temporaries' registry must be async-signal-safe");

struct Dirent64 {  // the record of getdents64(2)
  unsigned long long d_ino;
  long long d_off;
  unsigned short d_reclen;
  unsigned char d_type;
  char d_name[1];
};

// Removes `name` (relative to the open directory `parent`): a file, or a directory and everything
// in it. Only system calls: unlinkat, openat, getdents64, lseek, close. `depth` bounds the
// recursion (outputs are flat; a deeper tree is left for the normal unwinding). A pass over the
// directory that removes nothing ends the loop (an entry that cannot be removed stays).
void remove_tree_at(int parent, const char* name, int depth) noexcept {
  if (::unlinkat(parent, name, 0) == 0 || depth <= 0) {
    if (depth <= 0) ::unlinkat(parent, name, AT_REMOVEDIR);
    return;
  }
  const int fd = ::openat(parent, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return;
  for (bool removed = true; removed;) {
    removed = false;
    alignas(8) char buf[4096];
    for (long n; (n = ::syscall(SYS_getdents64, fd, buf, sizeof buf)) > 0;)
      for (long off = 0; off < n;) {
        const auto* d = reinterpret_cast<const Dirent64*>(buf + off);
        off += d->d_reclen;
        const char* e = d->d_name;
        if (e[0] == '.' && (e[1] == 0 || (e[1] == '.' && e[2] == 0))) continue;
        if (d->d_type == DT_DIR) {
          remove_tree_at(fd, e, depth - 1);
          removed = true;
        } else if (::unlinkat(fd, e, 0) == 0) {
          removed = true;
        }
      }
    ::lseek(fd, 0, SEEK_SET);
  }
  ::close(fd);
  ::unlinkat(parent, name, AT_REMOVEDIR);
}

}  // namespace

int register_temporary(const std::filesystem::path& path, bool directory) noexcept {
  const std::string& s = path.native();
  if (s.empty() || s.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kMaxTemporaries; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kFilling, std::memory_order_acq_rel)) continue;
    g_slots[i].gen.fetch_add(1, std::memory_order_acq_rel);
    std::memcpy(g_slots[i].path, s.c_str(), s.size() + 1);
    g_slots[i].state.store(directory ? kDir : kFile, std::memory_order_release);
    return i;
  }
  return -1;
}

void unregister_temporary(int slot) noexcept {
  if (slot >= 0 && slot < kMaxTemporaries) g_slots[slot].state.store(kFree, std::memory_order_release);
}

void remove_temporaries_now() noexcept {
  for (Slot& slot : g_slots) {
    const int st = slot.state.load(std::memory_order_acquire);
    if (st != kFile && st != kDir) continue;
    const unsigned gen = slot.gen.load(std::memory_order_acquire);
    char path[PATH_MAX];
    std::size_t i = 0;
    for (const volatile char* p = slot.path; i + 1 < sizeof path && p[i] != 0; ++i) path[i] = p[i];
    path[i] = 0;
    std::atomic_thread_fence(std::memory_order_acquire);
    if (slot.state.load(std::memory_order_acquire) != st || slot.gen.load(std::memory_order_acquire) != gen) continue;
    if (st == kFile)
      ::unlink(path);
    else
      remove_tree_at(AT_FDCWD, path, 8);
  }
}

int registered_temporaries() noexcept {
  int n = 0;
  for (const Slot& slot : g_slots) {
    const int st = slot.state.load(std::memory_order_acquire);
    n += st == kFile || st == kDir;
  }
  return n;
}

}  // namespace ptc
