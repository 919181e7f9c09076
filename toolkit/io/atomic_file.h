// Replace a file atomically: write to a temporary file in the same directory, then rename it over
// the target. A reader never sees a half-written file, and a write that fails or is interrupted
// (exception, crash, full disk) leaves the previous file untouched.
//
//   AtomicFile f(path);   // creates ".<name>.tmp-<pid>-<counter>" next to path
//   f.write(bytes);       // any number of times
//   f.commit();           // flush, fsync, close, rename over path
//   // destroyed without commit(): the temporary is removed, path is unchanged
//
// Interrupts (toolkit/core/cancel.h): write() and commit() throw Interrupted, after removing the
// temporary, once a stop was requested, so an interrupted run never replaces the target; the
// temporary is registered for removal by a second signal that ends the process at once.
//
// Durability: commit() fsyncs the file before the rename, so the new content is on disk before it
// becomes visible; the directory itself is not fsynced (after a power loss the rename may be
// lost, in which case the old file is still there, whole).
#pragma once

#include <filesystem>
#include <cstdint>
#include <string>
#include <string_view>

namespace ptc {

/// The start of the hidden name of a temporary beside an output named `name`: "." + its first
/// 200 bytes + ".tmp-", followed by "PID-N" (and ".old" for a directory moved aside). A name of
/// up to NAME_MAX (255) bytes is legal; the first 200 keep its temporaries legal too. AtomicFile
/// and commands/output_dir.h's OutputDir name theirs so, and look for them by it.
[[nodiscard]] std::string temporary_prefix(std::string_view name);

class AtomicFile {
 public:
  /// Creates the temporary file (mode 0666 & ~umask, or the target's mode when it exists).
  /// Throws InputError naming `target` and strerror when it cannot.
  explicit AtomicFile(std::filesystem::path target);
  /// Removes the temporary file unless commit() succeeded. Never throws.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Appends bytes (unbuffered: pass large chunks). Throws InputError on failure. A large file
  /// is written behind: every 8 MiB the kernel is told to write the bytes out, and the chunk
  /// before, once on disk, leaves the page cache. The file's pages are then reused instead of
  /// new memory taken for each (at 13.3M triangles `ptc cluster` writes 670 MB; commit() fsyncs
  /// the file anyway).
  void write(std::string_view bytes);
  /// fsync + close + rename over the target. Throws InputError (naming the target and strerror) on
  /// failure, after which the temporary is removed and the target is unchanged. Call once.
  void commit();

  [[nodiscard]] const std::filesystem::path& target() const { return target_; }
  [[nodiscard]] const std::filesystem::path& temp_path() const { return temp_; }
  [[nodiscard]] bool committed() const { return committed_; }

 private:
  [[noreturn]] void fail(const char* what, int err);
  void discard() noexcept;
  void stop_if_cancelled();

  std::filesystem::path target_, temp_;
  int fd_ = -1;
  int slot_ = -1;  // register_temporary's slot
  std::uint64_t written_ = 0, flushing_ = 0, dropped_ = 0;  // write behind: bytes written, sent, dropped
  bool committed_ = false;
};

}  // namespace ptc
