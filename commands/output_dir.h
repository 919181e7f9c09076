// Outputs are written whole or not at all: an output directory is assembled under a temporary
// sibling name and renamed into place by commit(). An existing directory of the same name is
// replaced only at that moment (moved aside, then deleted), so an interrupted or failed run
// leaves whatever the user had intact.
//
// Only ptc's own output is ever replaced: every directory this class creates holds a marker file
// `.ptc-output` listing the files the run wrote; an existing target that is neither empty nor
// marked (a user's home, a source tree, a thesis) is refused with an InputError before any work
// is done. Files a user added to a marked directory (not listed in its marker) are kept: they
// move into the new output (as NAME.kept, NAME.kept.2, ... when the new run writes a file of that
// name), commit() says so in one line on stderr, and a commit that fails moves them back. A
// file the marker lists is ptc's and is replaced or dropped. Outputs are flat files (a
// directory among them is a programmer error: the marker would need relative paths). A
// symbolic link as the target is refused.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace ptc {

/// UsageError naming `out_flag` when writing `out` would replace `input` or a file inside it
/// (the same path, or `input` inside the directory `out`; for a glob of frame files, the
/// directory it reads): an output never overwrites an input the command was given. Paths are
/// compared after resolving symbolic links and "..". Files that a scene file refers to are not
/// followed.
void refuse_overwriting_input(const std::filesystem::path& out, const std::filesystem::path& input,
                              std::string_view out_flag = "--out");

class RunManifest;
class OutputDir;

/// `message` with ptc's temporary names (an OutputDir's ".NAME.tmp-PID-N" directory and its
/// ".old", an AtomicFile's ".NAME.tmp-PID-N") replaced by the names the user gave: an error
/// while writing names the file as it would be ("small/cl/clusters.ply: cannot write: No space
/// left on device"), not the hidden temporary that was being written.
[[nodiscard]] std::string with_user_paths(const std::string& message);

/// Whether an OutputDir for `out` was committed in this process (apps/ptc: a stdout that fails
/// after it says the output is whole).
[[nodiscard]] bool output_was_committed(const std::filesystem::path& out);

/// A byte count as a person reads it: 512 B, 1.2 MB, 3.4 GB (powers of 1000, one decimal).
[[nodiscard]] std::string readable_bytes(double bytes);

/// The last step of every command that writes a directory: lists manifest.json among the
/// outputs, writes it (RunManifest::to_json) and commits the directory. Returns the manifest.
nlohmann::json commit_with_manifest(OutputDir& dir, RunManifest& manifest);

class OutputDir {
 public:
  /// Creates the temporary sibling directory of `target` (its parent is created if missing;
  /// a trailing separator is ignored). Errors (parent not writable, target is a file, target is
  /// a non-empty directory without the marker) throw InputError naming the path.
  explicit OutputDir(std::filesystem::path target);
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;
  /// Removes the temporary directory unless committed.
  ~OutputDir();

  /// Path inside the temporary directory for a file that will end up as target/name.
  [[nodiscard]] std::filesystem::path path(std::string_view name) const;
  /// Writes `bytes` to target/name (inside the temporary directory).
  void write(std::string_view name, std::string_view bytes) const;
  /// Refuses (UsageError on `flag`) an output of at least `bytes` that the file system of the
  /// temporary directory has no room for, before any of it is written: `what` says what would be
  /// written ("frames 0:99999 (100000 frames of at least 1.2 MB)").
  void check_room(double bytes, std::string_view flag, std::string_view what) const;
  /// Moves the finished directory into place; throws Interrupted (replacing nothing) once a stop
  /// was requested.
  void commit();

  [[nodiscard]] const std::filesystem::path& target() const { return target_; }
  /// After commit(): the files of the previous output that were not ptc's and were kept.
  [[nodiscard]] const std::vector<std::string>& kept() const { return kept_; }

  /// Name of the marker file written into every output directory.
  static constexpr const char* kMarker = ".ptc-output";

 private:
  std::filesystem::path target_, tmp_;
  bool committed_ = false;
  int slot_ = -1;  // register_temporary's slot of tmp_ (toolkit/core/cancel.h)
  std::vector<std::string> kept_;
};

}  // namespace ptc
