#include "bvh/triangle_scene.h"

#include "bvh/leaf_blocks.h"
#include "bvh/stage_clock.h"
#include "bvh/sweep_sah_builder.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace ptc::bvh {

namespace {
constexpr std::size_t kWideNodesPerTask = 4096;  // wide nodes per task of the leaf data's fill
}  // namespace

TriangleScene::TriangleScene(const Mesh& mesh, const SceneConfig& cfg) : tris_(mesh.shared_triangles()), cfg_(cfg) {
  const FrameMap frame = trace_frame(mesh, cfg);
  f_.data.origin = frame.origin, f_.data.scale = frame.scale;
  update(mesh.positions());
}

void TriangleScene::update(std::span<const Vec3> positions) {
  const std::span<const Tri> tris = tris_ ? std::span<const Tri>(*tris_) : std::span<const Tri>();
  TraceData& data = f_.data;
  StageTimes& times = f_.times;
  double t0 = clock_ms(cfg_.clock);
  frame_positions(positions, data.frame(), f_.fpos);
  check_finite(positions, f_.fpos, data.frame());  // (a NaN box would break the build)
  const auto V = static_cast<std::uint32_t>(f_.fpos.size());
  add_sentinel(f_.fpos);
  const std::span<const Vec3f> fp(f_.fpos.data(), V);
  times.vertices_ms = clock_ms(cfg_.clock) - t0;

  t0 = clock_ms(cfg_.clock);
  f_.boxes.resize(tris.size());  // (kept from frame to frame)
  f_.centroids.resize(tris.size());
  triangle_boxes_and_centroids(fp, tris, f_.boxes, f_.centroids);
  times.boxes_ms = clock_ms(cfg_.clock) - t0;

  t0 = clock_ms(cfg_.clock);
  if (cfg_.builder == SahBuilder::Sweep) f_.bvh = build_sweep_sah({f_.boxes, f_.centroids, {}}, cfg_.build);
  else build_binned_sah({f_.boxes, f_.centroids, {}}, cfg_.build, f_.bvh, f_.ws);
  times.build_ms = clock_ms(cfg_.clock) - t0;

  t0 = clock_ms(cfg_.clock);
  collapse_to_wide(f_.bvh, data.wide, wide_ws_);
  times.collapse_ms = clock_ms(cfg_.clock) - t0;

  // Leaf data: blocks in the order the leaves appear in the wide nodes; leaves become direct.
  // The nodes' first blocks (a prefix sum), then the nodes in chunks on the caller's threads
  // (each chunk fences its own streaming stores): the same bytes at any count.
  t0 = clock_ms(cfg_.clock);
  const std::size_t W = data.wide.nodes.size();
  first_block_.resize(W + 1);
  first_block_[0] = 0;
  for (std::size_t i = 0; i < W; ++i) {
    const WideNode& n = data.wide.nodes[i];
    std::uint32_t nb = 0;
    for (int k = 0; k < 4; ++k)
      if (n.is_leaf(k)) nb += blocks_for(n.count[k]);
    first_block_[i + 1] = first_block_[i] + nb;
  }
  const std::uint32_t nblocks = first_block_[W];
  data.blocks.resize(nblocks);
  data.triangle_ids.resize(4 * static_cast<std::size_t>(nblocks));
  data.ranges.clear();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, W, kWideNodesPerTask), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      WideNode& n = data.wide.nodes[i];
      std::uint32_t next = first_block_[i];
      for (int k = 0; k < 4; ++k) {
        if (!n.is_leaf(k)) continue;
        const std::uint32_t nb = blocks_for(n.count[k]);
        fill_leaf_blocks(std::span<const std::uint32_t>(f_.bvh.prim_order.data() + n.child[k], n.count[k]), tris,
                         f_.fpos[0].data(), V, data.triangle_ids.data() + 4 * std::size_t(next),
                         std::span<TriBlock>(data.blocks.data() + next, nb));
        n.child[k] = next;  // direct leaf: count stays the triangle count
        next += nb;
      }
    }
    fence_blocks();
  });
  times.leaf_data_ms = clock_ms(cfg_.clock) - t0;
  times.refit_ms = 0.0;
  t0 = clock_ms(cfg_.clock);
  regroup_to_8(data.wide, data.wide8, wide_ws_);
  times.collapse_ms += clock_ms(cfg_.clock) - t0;
}

}  // namespace ptc::bvh
