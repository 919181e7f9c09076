#include "analysis/loop/frame_loop.h"

#include <algorithm>
#include <stdexcept>

#include "bvh/aligned.h"
#include "bvh/box.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/stopwatch.h"

namespace ptc::loop {

void run_frame_loop(Scene& scene, std::span<Vec3> positions, std::span<Accel* const> accels, const LoopOptions& opt,
                    const Measure& measure) {
  if (opt.rest_positions && !scene.all_static())
    throw std::invalid_argument("run_frame_loop: rest positions asked for a scene with moving parts");
  if (!opt.rest_positions && positions.size() != scene.rest().vertex_count())
    throw std::invalid_argument("run_frame_loop: the position buffer does not match the scene");
  if (opt.frames.count() < 1) throw std::invalid_argument("run_frame_loop: no frames");
  const std::span<const Vec3> frame = opt.rest_positions ? scene.rest().positions() : std::span<const Vec3>(positions);
  bvh::AlignedVector<Vec3> fresh(opt.fresh_positions ? frame.size() : 0);
  for (std::int64_t f = opt.frames.first; f <= opt.frames.last; ++f) {
    // Ctrl-C stops here (toolkit/core/cancel.h), between steps, outside every timed region.
    throw_if_cancelled();
    const int index = static_cast<int>(f - opt.frames.first);
    Stopwatch sw;
    if (!opt.rest_positions && !(index == 0 && opt.first_frame_given))
      scene.positions(double(f), positions, opt.update_static || index == 0);
    const double source_ms = sw.ms();
    for (std::size_t a = 0; a < accels.size(); ++a) {
      throw_if_cancelled();  // a frame of several large configurations can take seconds
      std::span<const Vec3> p = frame;
      if (opt.fresh_positions) {
        std::copy(frame.begin(), frame.end(), fresh.begin());
        p = fresh;
      }
      FrameRecord r;
      r.index = index;
      r.frame = f;
      r.accel = a;
      r.source_ms = source_ms;
      sw.restart();
      try {
        accels[a]->update(p);
      } catch (bvh::FrameRangeError& e) {  // (which frame: the commands name it)
        if (!e.frame) e.frame = f;
        throw;
      }
      r.update_wall_ms = sw.ms();
      r.times = accels[a]->last_update();
      measure(r, *accels[a], p);
    }
  }
}

}  // namespace ptc::loop
