// The one frame loop of every experiment (architecture.md, "analysis/loop"):
//
//   for each frame f of the range:
//     positions <- the scene at f                       (timed once: source_ms)
//     for each configuration a:
//       (untimed) copy the positions, so that a reads freshly written memory, not what the
//                 configuration before it left in the caches (LoopOptions::fresh_positions)
//       a.update(positions)                             (timed: update_wall_ms, and a's stages)
//       measure(record, a, positions)                   (what the experiment measures: rays,
//                                                        images, metrics)
//
// What differs between experiments is only `measure`: bench traces primary rays and compares
// hits; trace renders the view and writes images; the analysis experiments compute metrics.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "analysis/loop/accel.h"
#include "toolkit/anim/scene.h"

namespace ptc::loop {

/// What the loop knows about one configuration's frame.
struct FrameRecord {
  int index = 0;               ///< 0 .. frames - 1 (position in the loop)
  std::int64_t frame = 0;      ///< the scene frame
  std::size_t accel = 0;       ///< index of the configuration
  double source_ms = 0;        ///< producing the frame's positions, once per frame, outside every configuration
  double update_wall_ms = 0;   ///< wall time of the configuration's whole update() call
  UpdateTimes times;           ///< the configuration's own stage times of that update
};

struct LoopOptions {
  FrameRange frames;
  /// Copy the positions before each configuration's update (untimed; see the file comment).
  bool fresh_positions = true;
  /// Scene::positions(update_static): false leaves the static parts' ranges as the caller filled
  /// them (the first frame always fills everything).
  bool update_static = true;
  /// The buffer already holds the first frame (the caller needed it before the loop, e.g. to
  /// frame the camera): the loop does not make it again (its source_ms is 0).
  bool first_frame_given = false;
  /// Every part is static (Scene::all_static()): each frame is the rest pose, so the loop makes
  /// no frame and hands every configuration the scene's rest positions (source_ms 0; the
  /// `positions` buffer is not used and may be empty). A caller saves the vertex-sized copy
  /// (160 MB at 13.3M triangles). std::invalid_argument when a part moves.
  bool rest_positions = false;
};

/// measure(record, configuration, positions it was updated with).
using Measure = std::function<void(const FrameRecord&, Accel&, std::span<const Vec3>)>;

/// Runs the loop. `positions` (the scene's vertex count) is the frame buffer: on return it
/// holds the last frame (with LoopOptions::rest_positions it is left as it is). std::invalid_argument for a wrong buffer size or an empty range;
/// ptc::Interrupted (toolkit/core/cancel.h) when cancel was requested, checked before each frame
/// and before each configuration's update.
void run_frame_loop(Scene& scene, std::span<Vec3> positions, std::span<Accel* const> accels, const LoopOptions& opt,
                    const Measure& measure);

}  // namespace ptc::loop
