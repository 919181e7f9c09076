#include "bvh/triangle_scene.h"

#include "bvh/leaf_blocks.h"
#include "bvh/sah_cost.h"
#include "bvh/stage_clock.h"
#include "bvh/sweep_sah_builder.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace ptc::bvh {

namespace {
constexpr std::size_t kWideNodesPerTask = 4096;  // wide nodes per task of the leaf data's fill

// New boxes for a tree whose leaf children are direct block ranges (child = first block,
// count = triangles): a leaf slot gets the union of its blocks' exact boxes, widened one unit in
// the last place as the build's triangle boxes are (widening is monotone: the widened union is
// the union of the widened boxes), an inner slot the union of its node's slots (one reverse sweep:
// children come after their parents). So a tree refitted to the positions it was built with
// holds the build's boxes. Returns the root's box.
template <class Nodes>
Box3f refit_block_tree(Nodes& nodes, std::span<const Box3f> block_boxes) {
  for (std::size_t i = nodes.size(); i-- > 0;) {
    auto& n = nodes[i];
    for (int k = 0; k < n.kWidth; ++k) {
      if (n.is_empty(k)) continue;
      Box3f b;
      if (n.is_leaf(k)) {
        const std::uint32_t first = n.child[k], nb = blocks_for(n.count[k]);
        for (std::uint32_t j = first; j < first + nb; ++j) b.extend(block_boxes[j]);
        for (int a = 0; a < 3; ++a) b.lo[a] = next_below(b.lo[a]), b.hi[a] = next_above(b.hi[a]);
      } else {
        if (n.child[k] <= i)  // (the sweep needs children after parents, as every walk lays them out)
          throw std::logic_error("TriangleScene refit: node " + std::to_string(i) + " has child " +
                                 std::to_string(n.child[k]) + " before it");
        const auto& c = nodes[n.child[k]];
        for (int j = 0; j < c.kWidth; ++j) b.extend(c.child_box(j));
      }
      n.set_child_box(k, b);
    }
  }
  Box3f root;
  if (!nodes.empty())
    for (int j = 0; j < nodes[0].kWidth; ++j) root.extend(nodes[0].child_box(j));
  return root;
}
}  // namespace

TriangleScene::TriangleScene(const Mesh& mesh, const SceneConfig& cfg) : tris_(mesh.shared_triangles()), cfg_(cfg) {
  const FrameMap frame = trace_frame(mesh, cfg);
  f_.data.origin = frame.origin, f_.data.scale = frame.scale;
  update(mesh.positions());
}

void TriangleScene::update(std::span<const Vec3> positions) {
  const std::span<const Tri> tris = tris_ ? std::span<const Tri>(*tris_) : std::span<const Tri>();
  StageTimes& times = f_.times;
  const double t0 = clock_ms(cfg_.clock);
  frame_positions(positions, f_.data.frame(), f_.fpos);
  check_finite(positions, f_.fpos, f_.data.frame());  // (a NaN box would break the build)
  add_sentinel(f_.fpos);
  const std::span<const Vec3f> fp(f_.fpos.data(), f_.fpos.size() - 2);  // (less the sentinel and its pad)
  times = {};
  times.vertices_ms = clock_ms(cfg_.clock) - t0;
  const bool attempt = cfg_.refit_growth > 0.0 && !f_.data.wide8.nodes.empty() && refit_due_;
  refit_tried_ = attempt;
  refitted_ = attempt && try_refit(fp, tris);
  if (attempt && !refitted_ && age_ == 0) {
    // Even one frame of refit passed the limit: leave out the next attempts after the rebuilds
    // of 1, 2, 4, then 8 frames (retrying, as the motion may slow down), so that a scene whose
    // tree cannot be kept pays the wasted refit on one frame in nine at most.
    skip_ = backoff_, backoff_ = std::min<std::uint32_t>(2 * backoff_, 8);
  }
  if (!refitted_) rebuild(fp, tris);
}

// The blocks refilled from their lanes' triangle ids (the layout kept), each block's box taken
// as it is written, and both wide trees' boxes recomputed from those; kept when the 8-wide
// tree's cost stays within the growth allowed over its cost at the build.
bool TriangleScene::try_refit(std::span<const Vec3f> fp, std::span<const Tri> tris) {
  TraceData& data = f_.data;
  StageTimes& times = f_.times;
  double t0 = clock_ms(cfg_.clock);
  block_boxes_.resize(data.blocks.size());
  fill_blocks_from_lanes(data.triangle_ids, tris, f_.fpos[0].data(), static_cast<std::uint32_t>(fp.size()), data.blocks,
                         block_boxes_.data());
  times.leaf_data_ms = clock_ms(cfg_.clock) - t0;
  t0 = clock_ms(cfg_.clock);
  data.wide.bounds = refit_block_tree(data.wide.nodes, block_boxes_);
  const Box3f root = refit_block_tree(data.wide8.nodes, block_boxes_);
  wide_cost_ = wide_sah_cost(data.wide8.nodes, root, cfg_.build.cost);
  times.refit_ms = clock_ms(cfg_.clock) - t0;
  if (!(wide_cost_ <= (1.0 + cfg_.refit_growth) * built_wide_cost_)) return false;
  // The next frame's growth, extrapolated as the square of the tree's age (boxes that spread
  // apart linearly grow in area quadratically): when it would pass the limit, the next frame
  // rebuilds without trying the refit first.
  ++age_, backoff_ = 1;
  const double next = (wide_cost_ / built_wide_cost_ - 1.0) * double(age_ + 1) * double(age_ + 1) / (double(age_) * double(age_));
  refit_due_ = next <= cfg_.refit_growth;
  return true;
}

void TriangleScene::rebuild(std::span<const Vec3f> fp, std::span<const Tri> tris) {
  TraceData& data = f_.data;
  StageTimes& times = f_.times;
  const auto V = static_cast<std::uint32_t>(fp.size());  // (the sentinel's index)
  double t0 = clock_ms(cfg_.clock);
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
  times.leaf_data_ms += clock_ms(cfg_.clock) - t0;
  t0 = clock_ms(cfg_.clock);
  regroup_to_8(data.wide, data.wide8, wide_ws_);
  times.collapse_ms += clock_ms(cfg_.clock) - t0;
  if (cfg_.refit_growth > 0.0) {
    t0 = clock_ms(cfg_.clock);
    built_wide_cost_ = wide_cost_ = wide_sah_cost(data.wide8.nodes, data.wide.bounds, cfg_.build.cost);
    age_ = 0, refit_due_ = skip_ == 0;
    if (skip_ > 0) --skip_;
    times.refit_ms += clock_ms(cfg_.clock) - t0;
  }
}

}  // namespace ptc::bvh
