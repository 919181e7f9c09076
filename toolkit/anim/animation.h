// An animation source: a fixed topology whose vertex positions change per frame (method.md:
// "meshes keep their connectivity while vertices move"). Every producer of frames - frame-file
// sequences, keyframed and skinned assets (assimp, MD3), simulations, procedural deformers, and
// subdivided versions of any of these - implements this one interface, so the per-frame loop
// (analysis: animate -> update boxes -> build -> trace) never knows where positions come from.
//
// Per-frame state is positions only: rest() holds the shared immutable triangle array (and the
// rest positions); positions() writes into caller-owned storage and must not allocate in the
// steady state (sources keep their scratch space from construction on).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "toolkit/core/types.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

class Animation {
 public:
  virtual ~Animation() = default;

  /// Topology (shared with every frame) and rest positions.
  [[nodiscard]] virtual const Mesh& rest() const = 0;

  /// Number of distinct frames the source holds (0 = unbounded: simulations and procedural
  /// deformers produce any frame index). Valid frame times are [0, frame_count() - 1].
  [[nodiscard]] virtual std::size_t frame_count() const = 0;

  /// Frames per second of the source's time base (for keyframed assets: the asset's rate).
  [[nodiscard]] virtual double frames_per_second() const { return 30.0; }

  /// Positions at (possibly fractional) frame time `frame` into out (size = rest().vertex_count();
  /// otherwise std::invalid_argument). Keyframed sources interpolate between stored frames;
  /// simulations advance their state (call in increasing order; an earlier time restarts).
  /// Throws InputError for data that turns out to be bad only when read (lazy frame files).
  virtual void positions(double frame, std::span<Vec3> out) = 0;

  /// One line for listings and manifests (kind, source file, sizes).
  [[nodiscard]] virtual std::string describe() const = 0;

  /// Whether positions never change (static meshes of a scene keep their BVH across frames).
  [[nodiscard]] virtual bool is_static() const { return false; }

  /// Renumbers the vertices once, in place, when the source can do so at no cost per frame:
  /// afterwards rest() and positions() use new index i for old vertex to_old[i] (to_old a
  /// permutation of 0 .. vertex_count-1, else std::invalid_argument) and the triangle order is
  /// unchanged. Returns false, changing nothing, when the source cannot (use
  /// renumber_vertices(AnimationPtr, ...) below, which then gathers per frame). Used to hand
  /// the per-frame loop positions in the clusters' vertex order (bvh::cluster_vertex_order).
  virtual bool renumber_vertices_in_place(std::span<const std::uint32_t> /*to_old*/) { return false; }
};

using AnimationPtr = std::unique_ptr<Animation>;

/// `source` with its vertices renumbered (see Animation::renumber_vertices_in_place): the source
/// itself when it renumbers in place, else a wrapper that produces the source's positions into
/// its own buffer and gathers them per frame (describe() says which). Throws
/// std::invalid_argument unless to_old is a permutation of the source's vertices.
[[nodiscard]] AnimationPtr renumber_vertices(AnimationPtr source, std::span<const std::uint32_t> to_old);

}  // namespace ptc
