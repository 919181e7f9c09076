// The files the toolkit's readers open, for the commands' manifests (commands/inputs.h records
// and hashes them): a scene names its data files, a scene file its meshes, a frame sequence its
// frames, none of which the command sees by name. While an InputLog lives on a thread, every
// note_input_file() on that thread adds to it; without one it is a no-op.
#pragma once

#include <filesystem>
#include <string>
#include <unordered_set>
#include <vector>

namespace ptc {

class InputLog {
 public:
  InputLog();
  ~InputLog();
  InputLog(const InputLog&) = delete;
  InputLog& operator=(const InputLog&) = delete;
  /// The files noted while it lived, in the order first noted, each once (by absolute path).
  [[nodiscard]] const std::vector<std::filesystem::path>& files() const { return files_; }

 private:
  friend void note_input_file(const std::filesystem::path& path);
  std::vector<std::filesystem::path> files_;
  std::unordered_set<std::string> seen_;  // files_ as strings: each file once without a linear search
  InputLog* outer_;  // a nested log also passes its files to the one around it
};

/// A reader opened `path` (its contents shape what the command computes).
void note_input_file(const std::filesystem::path& path);

}  // namespace ptc
