#include "toolkit/anim/load_animation.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "toolkit/anim/static_source.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {

namespace fs = std::filesystem;

AnimationFileKind classify_animation_path(const std::string& path) {
  std::error_code ec;
  if (is_glob_pattern(path) && !fs::exists(path, ec)) return AnimationFileKind::FrameSequence;
  if (fs::is_directory(path, ec)) return AnimationFileKind::FrameSequence;
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".md2") return AnimationFileKind::Md2;
  if (ext == ".md3") return AnimationFileKind::Md3;
  if (format_from_extension(path)) return AnimationFileKind::MeshFile;
  return AnimationFileKind::AssimpAsset;
}

const char* to_string(AnimationFileKind k) {
  switch (k) {
    case AnimationFileKind::FrameSequence: return "frame-sequence";
    case AnimationFileKind::Md2: return "md2";
    case AnimationFileKind::Md3: return "md3";
    case AnimationFileKind::MeshFile: return "mesh";
    case AnimationFileKind::AssimpAsset: return "assimp";
  }
  return "?";
}

AnimationPtr load_animation(const std::string& path, const LoadAnimationOptions& opt) {
  if (path.empty()) throw InputError("", "", "", "empty path");
  switch (classify_animation_path(path)) {
    case AnimationFileKind::FrameSequence:
      return std::make_unique<FrameSequence>(path, opt.sequence);
    case AnimationFileKind::Md2:
      return load_md2(path, opt.md2);
    case AnimationFileKind::Md3:
      return load_md3(path, opt.md3);
    case AnimationFileKind::MeshFile:
      return std::make_unique<StaticSource>(read_mesh(path).mesh, path);
    case AnimationFileKind::AssimpAsset:
      return load_assimp_animation(path, opt.assimp);
  }
  throw std::logic_error("load_animation: unhandled kind");
}

}  // namespace ptc
