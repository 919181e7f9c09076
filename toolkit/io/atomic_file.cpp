#include "toolkit/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>

#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"

namespace ptc {
namespace {
std::atomic<unsigned> g_counter{0};

std::string errno_text(int err) { return std::strerror(err); }
}  // namespace

std::string temporary_prefix(std::string_view name) {
  std::string p = ".";
  p.append(name.substr(0, 200));
  p += ".tmp-";
  return p;
}

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  const std::filesystem::path dir = target_.parent_path();
  const std::string base = target_.filename().string();
  if (base.empty() || base == "." || base == "..") throw InputError(target_.string(), "", "", "not a file name");
  struct stat st {};
  const bool exists = ::stat(target_.c_str(), &st) == 0;
  if (exists && S_ISDIR(st.st_mode)) throw InputError(target_.string(), "", "", "is a directory");
  // O_EXCL: never reuse a name another writer (thread or process) holds; retry with the next counter.
  for (int attempt = 0;; ++attempt) {
    const std::string name =
        temporary_prefix(base) + std::to_string(::getpid()) + "-" + std::to_string(g_counter.fetch_add(1));
    temp_ = dir.empty() ? std::filesystem::path(name) : dir / name;
    fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ >= 0) break;
    const int err = errno;
    if ((err == EEXIST || err == EINTR) && attempt < 100) continue;
    // In the user's words: the file they asked for, and why (the hidden temporary's name is ours).
    const std::filesystem::path where = dir.empty() ? std::filesystem::path(".") : dir;
    std::error_code dir_ec;
    if (err == ENOENT)  // no such directory, or one that takes no new files (/dev/fd, /proc)
      throw InputError(target_.string(), "", "",
                       "cannot write it: the directory '" + where.string() + "' " +
                           (std::filesystem::exists(where, dir_ec) ? "takes no new files" : "does not exist"));
    throw InputError(target_.string(), "", "", "cannot write it: " + errno_text(err));
  }
  slot_ = register_temporary(temp_, false);
  if (exists) (void)::fchmod(fd_, st.st_mode & 07777);  // keep the replaced file's permissions
}

AtomicFile::~AtomicFile() { discard(); }

void AtomicFile::discard() noexcept {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  if (!committed_ && !temp_.empty()) {
    ::unlink(temp_.c_str());
    temp_.clear();
  }
  unregister_temporary(slot_);
  slot_ = -1;
}

void AtomicFile::stop_if_cancelled() {
  if (!cancel_requested()) return;
  discard();
  throw Interrupted();
}

void AtomicFile::fail(const char* what, int err) {
  discard();
  throw InputError(target_.string(), "", "", std::string(what) + ": " + errno_text(err));
}

void AtomicFile::write(std::string_view bytes) {
  if (fd_ < 0) throw InputError(target_.string(), "", "", "write after commit or failure");
  stop_if_cancelled();
  constexpr std::uint64_t kChunk = std::uint64_t{8} << 20;
  const char* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    if (written_ % kChunk == 0 && p != bytes.data()) stop_if_cancelled();  // Ctrl-C between chunks of a large write
    // At most to the next chunk boundary, so that a large write is written behind too.
    const std::size_t step = static_cast<std::size_t>(std::min<std::uint64_t>(left, kChunk - written_ % kChunk));
    const ssize_t n = ::write(fd_, p, step);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("cannot write", errno);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
    written_ += static_cast<std::uint64_t>(n);
    if (written_ - flushing_ >= kChunk) {
      // Best effort (errors show in commit()'s fsync): start writing the new chunk out; wait for
      // the one before and drop its pages.
      (void)::sync_file_range(fd_, static_cast<off_t>(flushing_), static_cast<off_t>(written_ - flushing_),
                              SYNC_FILE_RANGE_WRITE);
      if (flushing_ > dropped_) {
        (void)::sync_file_range(fd_, static_cast<off_t>(dropped_), static_cast<off_t>(flushing_ - dropped_),
                                SYNC_FILE_RANGE_WAIT_BEFORE | SYNC_FILE_RANGE_WRITE | SYNC_FILE_RANGE_WAIT_AFTER);
        (void)::posix_fadvise(fd_, static_cast<off_t>(dropped_), static_cast<off_t>(flushing_ - dropped_),
                              POSIX_FADV_DONTNEED);
        dropped_ = flushing_;
      }
      flushing_ = written_;
    }
  }
}

void AtomicFile::commit() {
  if (fd_ < 0) throw InputError(target_.string(), "", "", "commit after commit or failure");
  stop_if_cancelled();  // an interrupted run replaces nothing
  if (::fsync(fd_) != 0 && errno != EINVAL) fail("cannot flush", errno);  // EINVAL: fs without fsync
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail("cannot close", errno);
  if (::rename(temp_.c_str(), target_.c_str()) != 0) fail("cannot rename temporary file over it", errno);
  committed_ = true;
  unregister_temporary(slot_);
  slot_ = -1;
}

}  // namespace ptc
