// Vertex-keyframe animation sources: a fixed topology plus one stored position array per frame,
// linearly interpolated at fractional frame times.
//
// - KeyframeAnimation: frames held in memory (MD2, MD3, and frame sequences loaded eagerly).
// - FrameSequence: a directory or glob of OBJ/PLY/OFF files, one per frame, in natural order of
//   the file names ("f2.obj" before "f10.obj"). The topology of every frame is checked against
//   the first one; a mismatch is an InputError naming the frame file and the first differing
//   element ("vertex count", "triangle count", "triangle 17").
//
// Time: frame time t in [0, frame_count() - 1]; t = k + a (0 <= a < 1) gives
// (1 - a) * frame[k] + a * frame[k + 1]; at integer t the stored frame is returned bit for bit.
// A time outside that range (or NaN) throws std::out_of_range: looping or clamping is the
// caller's decision (a scene's frame range), never a silent clamp here. A source with a single
// frame is static (is_static()) and returns that frame at any finite time.
// positions() is not thread-safe on one object (lazy caches, scratch space); use one source
// per thread.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "toolkit/anim/animation.h"
#include "toolkit/anim/weld.h"

namespace ptc {

/// Frames in memory, one flat array of frame_count * vertex_count positions.
class KeyframeAnimation final : public Animation {
 public:
  /// frames[k] are the positions of frame k (all of rest.vertex_count()); at least one frame.
  /// rest() is `triangles` with frame 0's positions.
  KeyframeAnimation(std::vector<Tri> triangles, std::vector<std::vector<Vec3>> frames, double fps,
                    std::string description);

  [[nodiscard]] const Mesh& rest() const override { return rest_; }
  [[nodiscard]] std::size_t frame_count() const override { return frames_; }
  [[nodiscard]] double frames_per_second() const override { return fps_; }
  void positions(double frame, std::span<Vec3> out) override;
  [[nodiscard]] std::string describe() const override { return description_; }
  [[nodiscard]] bool is_static() const override { return frames_ <= 1; }

  /// The stored positions of frame k (no interpolation).
  [[nodiscard]] std::span<const Vec3> frame(std::size_t k) const;

 private:
  Mesh rest_;
  std::vector<Vec3> data_;
  std::size_t frames_ = 0, verts_ = 0;
  double fps_ = 30.0;
  std::string description_;
};

/// Splits a frame time into (k, a) with t = k + a, checking t in [0, frame_count - 1];
/// std::out_of_range otherwise (frame_count 1: any finite t gives (0, 0)). Shared by every
/// keyframed source.
struct FrameTime {
  std::size_t k = 0;
  double a = 0.0;
};
[[nodiscard]] FrameTime split_frame_time(double t, std::size_t frame_count);

/// Linear interpolation of two frames into out, multithreaded for large meshes; a == 0 copies f0.
void lerp_frames(std::span<const Vec3> f0, std::span<const Vec3> f1, double a, std::span<Vec3> out);

/// How a frame sequence reads its files.
enum class FrameLoading {
  Lazy,   ///< frame 0 at construction, others when positions() asks (two frames cached); memory
          ///< stays at ~3 frames for any length; a bad or mismatched frame surfaces as InputError
          ///< from positions(). Reading a file allocates, so positions() is not allocation-free.
  Eager,  ///< every frame read and checked at construction (InputError there); positions() is
          ///< then allocation-free; memory = frames * vertices * 24 bytes.
};

struct FrameSequenceOptions {
  FrameLoading loading = FrameLoading::Lazy;  ///< see FrameLoading
  /// Weld vertices that coincide in every frame (for sequences written as triangle soups). All
  /// frames are read once at construction to compute the weld (streamed: one frame at a time).
  bool weld = false;
  double fps = 30.0;  ///< frames per second reported by the source (> 0)
};

/// The frame files of a directory (every .obj/.ply/.off in it) or of a glob pattern in the last
/// path component ("frames/walk_*.ply"; * ? and [...] as in fnmatch), naturally sorted.
/// InputError when the directory/pattern's folder does not exist or nothing matches.
[[nodiscard]] std::vector<std::filesystem::path> list_frame_files(const std::string& dir_or_glob);

/// Natural order of file names: digit runs compare by value ("f2" < "f10"), other characters
/// bytewise; ties broken bytewise so the order is total.
[[nodiscard]] bool natural_less(const std::string& a, const std::string& b);

/// Whether the string is a glob pattern (contains * ? or [).
[[nodiscard]] bool is_glob_pattern(const std::string& s);

class FrameSequence final : public Animation {
 public:
  /// Reads frame 0 (and all frames when Eager or weld); InputError for missing/bad/mismatched files.
  FrameSequence(std::vector<std::filesystem::path> files, const FrameSequenceOptions& opt = {});
  /// Same with list_frame_files(dir_or_glob).
  explicit FrameSequence(const std::string& dir_or_glob, const FrameSequenceOptions& opt = {});

  [[nodiscard]] const Mesh& rest() const override { return rest_; }
  [[nodiscard]] std::size_t frame_count() const override { return files_.size(); }
  [[nodiscard]] double frames_per_second() const override { return opt_.fps; }
  void positions(double frame, std::span<Vec3> out) override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool is_static() const override { return files_.size() <= 1; }

  [[nodiscard]] const std::vector<std::filesystem::path>& files() const { return files_; }
  /// Vertices merged by welding (0 without weld).
  [[nodiscard]] std::size_t merged_vertices() const { return weld_ ? weld_->merged() : 0; }

 private:
  // Reads frame k, checks its topology against frame 0, returns its (welded) positions.
  std::vector<Vec3> load(std::size_t k) const;
  const std::vector<Vec3>& cached(std::size_t k);

  std::vector<std::filesystem::path> files_;
  FrameSequenceOptions opt_;
  Mesh rest_;
  std::shared_ptr<const std::vector<Tri>> raw_tris_;  // frame 0 as in the file (before welding)
  std::size_t raw_vertices_ = 0;
  std::optional<WeldMap> weld_;
  std::unique_ptr<KeyframeAnimation> eager_;
  struct Slot {
    std::size_t k = SIZE_MAX;
    std::vector<Vec3> pos;
  };
  Slot slot_[2];
  std::size_t next_slot_ = 0;
};

}  // namespace ptc
