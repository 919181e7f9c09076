// Float boxes for the BVH layer, made conservatively from the double positions of the mesh.
//
// The tracer works in single precision in a *trace frame*: positions minus a frame origin (a
// double), so that a mesh far from the world origin (offsets of 1e7) keeps its float precision.
// A box is rounded OUTWARD from the double coordinates p - origin, and the tracer's float vertex
// is p - origin rounded to NEAREST; since rounding is monotone, the float triangle always lies
// inside its float box (round_down(min) <= round_nearest(any) <= round_up(max)).
// The vertex orders of the per-frame cluster boxes (first-touch order, the fused conversion and
// box pass) are in vertex_order.h.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include <stdexcept>

#include "bvh/aligned.h"
#include "toolkit/core/types.h"

namespace ptc::bvh {

/// What trace_frame_scale and the conversion into the trace frame throw for positions beyond the
/// single-precision tracer's range (commands name the input file with it).
class FrameRangeError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
  /// The scene frame it happened in, when the frame loop knew it (analysis/loop/frame_loop.cpp).
  std::optional<std::int64_t> frame;
};


using Vec3f = std::array<float, 3>;

inline constexpr float kInf = std::numeric_limits<float>::infinity();

/// Axis-aligned float box; the empty box has lo = +inf, hi = -inf (so extend() needs no test).
struct Box3f {
  Vec3f lo{kInf, kInf, kInf};
  Vec3f hi{-kInf, -kInf, -kInf};

  void extend(const Box3f& b) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = b.lo[a] < lo[a] ? b.lo[a] : lo[a];
      hi[a] = b.hi[a] > hi[a] ? b.hi[a] : hi[a];
    }
  }
  void extend(const Vec3f& p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = p[a] < lo[a] ? p[a] : lo[a];
      hi[a] = p[a] > hi[a] ? p[a] : hi[a];
    }
  }
  [[nodiscard]] bool empty() const { return !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]); }
  /// b lies inside this box (closed); an empty b is inside every box.
  [[nodiscard]] bool contains(const Box3f& b) const {
    if (b.empty()) return true;
    for (int a = 0; a < 3; ++a)
      if (!(lo[a] <= b.lo[a] && b.hi[a] <= hi[a])) return false;
    return true;
  }
  /// Surface area 2(xy + yz + zx) in double (0 for an empty box). Double so that sums over
  /// millions of nodes (the SAH cost) do not lose digits.
  [[nodiscard]] double surface_area() const {
    if (empty()) return 0.0;
    const double x = double(hi[0]) - lo[0], y = double(hi[1]) - lo[1], z = double(hi[2]) - lo[2];
    return 2.0 * (x * y + y * z + z * x);
  }
  /// Twice the solid angle the box shows the point `eye` (BuildConfig::area_eye), roughly: with
  /// v from eye to the centre and D = max(|v|, half the diagonal),
  /// 2 ((|v_z| xy + |v_x| yz + |v_y| zx) / D + kEyeAreaIsotropic (xy + yz + zx)) / D^2;
  /// 0 for an empty box or one of no extent at the point. Not monotone: a box stretched toward
  /// the point may price below a box inside it (D is taken to the centre).
  [[nodiscard]] double area_from(const Vec3f& eye) const;
  /// The surface area with the faces across axis a weighted by w[a]: 2(w_z xy + w_x yz + w_y zx)
  /// (BuildConfig::area_weights; 0 for an empty box). With w = (1, 1, 1) the same bits as
  /// surface_area().
  [[nodiscard]] double weighted_area(const std::array<float, 3>& w) const {
    if (empty()) return 0.0;
    const double x = double(hi[0]) - lo[0], y = double(hi[1]) - lo[1], z = double(hi[2]) - lo[2];
    return 2.0 * (w[2] * (x * y) + w[0] * (y * z) + w[1] * (z * x));
  }
  [[nodiscard]] Vec3f center() const {
    return {0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), 0.5f * (lo[2] + hi[2])};
  }
  friend bool operator==(const Box3f&, const Box3f&) = default;
};

/// The share of a box's surface area (over D^2) added to its solid angle in Box3f::area_from, as
/// the floor of direction_area_weights: 1/64.
inline constexpr double kEyeAreaIsotropic = 1.0 / 64.0;

inline double Box3f::area_from(const Vec3f& eye) const {
  if (empty()) return 0.0;
  const double x = double(hi[0]) - lo[0], y = double(hi[1]) - lo[1], z = double(hi[2]) - lo[2];
  double v[3], d2 = 0.0;
  for (int a = 0; a < 3; ++a) v[a] = 0.5 * (double(lo[a]) + hi[a]) - eye[a], d2 += v[a] * v[a];
  const double r2 = 0.25 * (x * x + y * y + z * z), D2 = d2 > r2 ? d2 : r2;
  if (!(D2 > 0.0)) return 0.0;
  const double D = std::sqrt(D2);
  return 2.0 * ((std::abs(v[2]) * (x * y) + std::abs(v[0]) * (y * z) + std::abs(v[1]) * (z * x)) / D +
                kEyeAreaIsotropic * (x * y + y * z + z * x)) /
         D2;
}

/// Largest float <= x (x finite or infinite). Branch-free (boxes are made per frame, and the
/// rounding direction is a coin flip the branch predictor cannot learn): when the nearest float
/// f overshoots, step one unit in the last place towards -inf on the bit pattern (f > 0: bits - 1;
/// f < 0: bits + 1; f = +0 cannot overshoot since a negative x rounds to -0).
[[nodiscard]] inline float round_down(double x) {
  const float f = static_cast<float>(x);
  const auto b = std::bit_cast<std::int32_t>(f);
  const std::int32_t step = ((b >> 31) * 2) + 1;  // +1 for f >= +0, -1 for f <= -0
  const std::int32_t adj = -static_cast<std::int32_t>(static_cast<double>(f) > x);
  return std::bit_cast<float>(b - (step & adj));
}
/// Smallest float >= x (mirror of round_down; -0 cannot undershoot since a positive x rounds to +0).
[[nodiscard]] inline float round_up(double x) {
  const float f = static_cast<float>(x);
  const auto b = std::bit_cast<std::int32_t>(f);
  const std::int32_t step = ((b >> 31) * 2) + 1;
  const std::int32_t adj = -static_cast<std::int32_t>(static_cast<double>(f) < x);
  return std::bit_cast<float>(b + (step & adj));
}

/// The trace frame: a point p of the world is (p - origin) * scale there, rounded to float; a
/// ray's origin likewise and its direction times scale, so the parameter t of a ray is the same
/// in both. `scale` is a power of two (trace_frame_scale, scene_config.h): multiplying by it is
/// exact, so the frame's floats, and every hit's t, u and v, are those of the unscaled frame
/// wherever that one neither overflows nor underflows (scale 1 for every mesh of ordinary size).
/// Implicit from an origin alone (scale 1).
struct FrameMap {
  Vec3 origin = Vec3::Zero();
  double scale = 1.0;
  FrameMap() = default;
  FrameMap(const Vec3& o, double s = 1.0) : origin(o), scale(s) {}  // NOLINT: implicit on purpose
  template <class D>  // (an Eigen expression such as Vec3::Zero())
  FrameMap(const Eigen::MatrixBase<D>& o, double s = 1.0) : origin(o), scale(s) {}  // NOLINT
};

/// (p - origin) * scale rounded to the nearest float: the tracer's vertex in the trace frame.
[[nodiscard]] inline Vec3f to_frame(const Vec3& p, const FrameMap& f) {
  return {static_cast<float>((p.x() - f.origin.x()) * f.scale), static_cast<float>((p.y() - f.origin.y()) * f.scale),
          static_cast<float>((p.z() - f.origin.z()) * f.scale)};
}

/// A double box in the frame `f`: its corners through to_frame (nearest floats; for
/// metrics on boxes, not for traversal, which needs the outward-rounded boxes below).
[[nodiscard]] inline Box3f to_frame(const Box3& b, const FrameMap& origin) {
  Box3f f;
  f.extend(to_frame(b.lo, origin));
  f.extend(to_frame(b.hi, origin));
  return f;
}

/// One box per triangle in the frame at `origin`, rounded outward (contains the float triangle
/// to_frame(corners)). Precondition: indices < positions.size() (asserted by the Mesh class).
[[nodiscard]] std::vector<Box3f> triangle_boxes(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                                const FrameMap& origin = {});


/// The centre of every box (the builders' centroids when none better is known).
[[nodiscard]] std::vector<Vec3f> box_centers(std::span<const Box3f> boxes);

/// Next float towards -inf / +inf of a finite f (one unit in the last place).
[[nodiscard]] inline float next_below(float f) {
  const auto b = std::bit_cast<std::int32_t>(f);
  if (f == 0.0f) return -std::numeric_limits<float>::denorm_min();
  return std::bit_cast<float>(b >= 0 ? b - 1 : b + 1);
}
[[nodiscard]] inline float next_above(float f) {
  const auto b = std::bit_cast<std::int32_t>(f);
  if (f == 0.0f) return std::numeric_limits<float>::denorm_min();
  return std::bit_cast<float>(b >= 0 ? b + 1 : b - 1);
}

/// The positions in the trace frame, rounded to nearest (the tracer's vertices): out[v] =
/// to_frame(positions[v], origin). One pass, done once per frame (in chunks on the caller's
/// threads); everything else gathers from it.
/// `out` gets capacity for two more entries (add_sentinel's, leaf_blocks.h): appending them does
/// not move the array (at 13.3M vertices that was 160 MB of new memory on the first frame).
void frame_positions(std::span<const Vec3> positions, const FrameMap& origin, AlignedVector<Vec3f>& out);

/// Boxes from frame positions (floats rounded to nearest), widened by one unit in the last
/// place on every side. Since a double p lies within half a unit of its float, the box contains
/// the double triangle (or point group) as well as the float one: rounded outward like the
/// double versions above, at most one unit looser, and about twice as fast (half the memory).
[[nodiscard]] std::vector<Box3f> triangle_boxes(std::span<const Vec3f> frame_pos, std::span<const Tri> triangles);
/// The same into out[0 .. triangles.size()) (sized by the caller: a scene's kept storage).
void triangle_boxes(std::span<const Vec3f> frame_pos, std::span<const Tri> triangles, std::span<Box3f> out);
void point_group_boxes(std::span<const Vec3f> frame_pos, std::span<const std::uint32_t> offsets,
                       std::span<const std::uint32_t> indices, AlignedVector<Box3f>& out);
/// The same boxes, and their centres (Box3f::center(), bit for bit) in one pass, reusing the
/// storage of `out` and `centers` (the per-frame cluster box update).
void point_group_boxes(std::span<const Vec3f> frame_pos, std::span<const std::uint32_t> offsets,
                       std::span<const std::uint32_t> indices, AlignedVector<Box3f>& out, AlignedVector<Vec3f>& centers);
/// The boxes and centres of the overload above over frame_positions(positions, frame), bit for
/// bit, without the frame positions: each point converted where it is read (a cluster scene's
/// rest boxes, made once). Groups in chunks on the caller's threads (the same values at any
/// count). Positions must be finite in the frame (check_finite).
void point_group_boxes(std::span<const Vec3> positions, const FrameMap& frame, std::span<const std::uint32_t> offsets,
                       std::span<const std::uint32_t> indices, AlignedVector<Box3f>& out, AlignedVector<Vec3f>& centers);

/// Throws std::invalid_argument naming the first vertex whose position is not finite in the
/// trace frame (NaN, infinite, or a float overflow of p - origin) when frame_pos (the converted
/// positions) holds such a value; otherwise returns. One pass over frame_pos.
void check_finite(std::span<const Vec3> positions, std::span<const Vec3f> frame_pos, const FrameMap& origin);
/// The message of check_finite for positions known to hold such a vertex.
[[noreturn]] void throw_not_finite(std::span<const Vec3> positions, const FrameMap& origin);

/// Centroids of float triangles (v0 + v1 + v2) / 3, inside the boxes above.
[[nodiscard]] std::vector<Vec3f> triangle_centroids(std::span<const Vec3f> frame_pos, std::span<const Tri> triangles);
/// The same into out[0 .. triangles.size()) (sized by the caller).
void triangle_centroids(std::span<const Vec3f> frame_pos, std::span<const Tri> triangles, std::span<Vec3f> out);

/// triangle_boxes and triangle_centroids (the same bits) in one pass over the triangles' corners,
/// in chunks on the caller's threads (the per-frame pass of a triangle scene).
void triangle_boxes_and_centroids(std::span<const Vec3f> frame_pos, std::span<const Tri> triangles,
                                  std::span<Box3f> boxes, std::span<Vec3f> centroids);

/// Centroids (v0 + v1 + v2) / 3 of the triangles in the frame at `origin`.
[[nodiscard]] std::vector<Vec3f> triangle_centroids(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                                    const FrameMap& origin = {});

/// Union of boxes.
[[nodiscard]] Box3f union_of(std::span<const Box3f> boxes);

}  // namespace ptc::bvh
