// The rows of `ptc trace`'s trace.csv (schema ptc-trace/5, docs/tracing.md): one row per frame
// and pass (primary, shadow, ao), the frame's BVH figures repeated on each of its rows (tidy:
// one observation per row). The frame loop and the renderer produce them; commands/trace.cpp
// writes them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/schema/table.h"
#include "bvh/trace_scene.h"
#include "render/rays.h"

namespace ptc {

struct TraceRow {
  std::string mesh;                   ///< the SCENE argument
  std::string bvh;                    ///< "triangles" or "clusters" (of the moving parts)
  std::uint64_t triangles = 0, clusters = 0;
  int width = 0, height = 0;
  unsigned threads = 0;
  std::int64_t frame = 0;
  std::string pass;                   ///< "primary", "shadow" or "ao"
  PassStats stats;                    ///< rays, hits (any hit for shadow/ao: occluded rays), counters, time
  int ao_samples = 0;                 ///< rays per pixel of the ao pass
  double setup_ms = 0;                ///< first frame: construction of the moving BVH (0 afterwards)
  double static_build_ms = 0;         ///< first frame: the static parts' BVH, built once (0 afterwards)
  double update_ms = 0, build_ms = 0; ///< the frame's update of the moving BVH (analysis/loop UpdateTimes)
  bvh::StageTimes stages;             ///< and its stages
  std::uint64_t static_triangles = 0, moving_triangles = 0;
  double rss_mb = 0, peak_rss_mb = 0;  ///< resident and peak resident memory after the frame (toolkit/core/memory.h)
};

/// trace.csv (schema ptc-trace/5).
[[nodiscard]] Table trace_table(const std::vector<TraceRow>& rows);

}  // namespace ptc
