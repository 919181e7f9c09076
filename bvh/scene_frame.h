// What both scenes (triangle_scene.h, cluster_scene.h) rebuild every frame, kept from one frame
// to the next so that an update allocates nothing once the buffers have grown. Aligned vectors:
// the large ones sit on huge pages (aligned.h), as every frame rewrites them.
#pragma once

#include <vector>

#include "bvh/aligned.h"
#include "bvh/binned_sah_builder.h"
#include "bvh/scene_config.h"
#include "bvh/trace_data.h"

namespace ptc::bvh {

struct SceneFrame {
  AlignedVector<Vec3f> fpos;       ///< positions in the trace frame, then the sentinel (leaf_blocks.h)
  AlignedVector<Box3f> boxes;      ///< primitive boxes (triangles or clusters)
  AlignedVector<Vec3f> centroids;  ///< the builder's centroids
  Bvh bvh;                       ///< the binary BVH of this frame
  BuildWorkspace ws;             ///< the builder's scratch
  TraceData data;                ///< what the tracer reads
  StageTimes times;              ///< of the last update
};

}  // namespace ptc::bvh
