#include "toolkit/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

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
        "." + base + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(g_counter.fetch_add(1));
    temp_ = dir.empty() ? std::filesystem::path(name) : dir / name;
    fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ >= 0) break;
    const int err = errno;
    if ((err == EEXIST || err == EINTR) && attempt < 100) continue;
    // In the user's words: the file they asked for, and why (the hidden temporary's name is ours).
    if (err == ENOENT)
      throw InputError(target_.string(), "", "", "cannot write it: the directory '" + (dir.empty() ? std::string(".") : dir.string()) +
                                                     "' does not exist");
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
  const char* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("cannot write", errno);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
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
