#include "bvh/cluster_scene.h"

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include "bvh/box_simd.h"
#include "bvh/leaf_blocks.h"
#include "bvh/leaf_tables.h"
#include "bvh/refit.h"
#include "bvh/stage_clock.h"
#include "bvh/threads.h"
#include "bvh/top_down_builder.h"
#include "bvh/sweep_sah_builder.h"
#include "toolkit/geometry/morton.h"
#include "toolkit/geometry/triangle.h"

namespace ptc::bvh {

namespace {

// The sum of the triangles' areas of `mesh` at its positions (triangle_area, toolkit/geometry/
// triangle.h), in the trace frame of `scale`: per fixed chunk of triangles on the threads, the
// chunks' sums added in order (the same bits at any thread count).
double mesh_area_in_frame(const Mesh& mesh, double scale) {
  const std::span<const Vec3> p = mesh.positions();
  const std::span<const Tri> t = mesh.triangles();
  constexpr std::size_t kChunk = 16384;
  std::vector<double> part((t.size() + kChunk - 1) / kChunk, 0.0);
  tbb::parallel_for(std::size_t{0}, part.size(), [&](std::size_t k) {
    double acc = 0;
    for (std::size_t i = k * kChunk; i < std::min(t.size(), (k + 1) * kChunk); ++i)
      acc += triangle_area(p[t[i][0]], p[t[i][1]], p[t[i][2]]);
    part[k] = acc;
  });
  double sum = 0;
  for (const double x : part) sum += x;
  return sum * scale * scale;
}

// The sum of the boxes' half surface areas (xy + yz + zx; Box3f::surface_area / 2), empty boxes
// counting 0. SSE2: a box's lo and hi by two unaligned loads (lo x y z hi.x, hi x y z and the next box's
// lo.x; the last box alone), its extents clamped at 0, times their rotation (ey ez ex) summed in
// float per 1024 boxes, the runs added in double in order. For the twist's 52k clusters 0.044 ms
// on warm boxes (a throwaway stand-alone loop), against 0.09-0.12 ms for the scalar form (double
// products, a branch per box, as surface_area): about 2% of the one-thread update, which pays it
// only with the fallback on.
double box_half_areas(std::span<const Box3f> boxes) {
  static_assert(sizeof(Box3f) == 6 * sizeof(float));
  double sum = 0;
  const std::size_t n = boxes.size();
  const float* f = n ? &boxes[0].lo[0] : nullptr;
  const __m128 keep = _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1)), zero = _mm_setzero_ps();
  std::size_t i = 0;
  while (i + 1 < n) {
    __m128 acc = zero;
    for (const std::size_t end = std::min(n - 1, i + 1024); i < end; ++i) {
      const __m128 e = _mm_max_ps(_mm_sub_ps(_mm_loadu_ps(f + 6 * i + 3), _mm_loadu_ps(f + 6 * i)), zero);
      acc = _mm_add_ps(acc, _mm_and_ps(_mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1))), keep));
    }
    alignas(16) float a[4];
    _mm_store_ps(a, acc);
    sum += double(a[0]) + double(a[1]) + double(a[2]);
  }
  if (n) {  // (the last box: its hi's load would read past the array)
    const Box3f& b = boxes[n - 1];
    const float ex = std::max(b.hi[0] - b.lo[0], 0.0f), ey = std::max(b.hi[1] - b.lo[1], 0.0f),
                ez = std::max(b.hi[2] - b.lo[2], 0.0f);
    sum += double(ex * ey) + double(ey * ez) + double(ez * ex);
  }
  return sum;
}

// The set-up's per-cluster and per-block passes run in chunks on the caller's threads (oneTBB,
// `--threads N`); each chunk writes only its own clusters' or blocks' entries.
constexpr std::size_t kSetupClustersPerTask = 1024;
constexpr std::size_t kSetupBlocksPerTask = 8192;
constexpr std::size_t kSetupGroupsPerChunk = 512;  // groups' trees built before they are appended
constexpr std::uint32_t kSrcIndexLimit = 1u << 30;  // a fixed slot's box record: (kind << 30) | index

// Frees a vector's storage (`v = {}` would pick the initializer-list assignment and keep it).
template <class V>
void release(V& v) {
  V().swap(v);
}

// The clustering's consistency (what ClusterScene relies on): offsets from 0 to T, no empty
// cluster, triangle_order a permutation of the mesh's triangles, vertex offsets matching.
void check_view(const Mesh& mesh, const ClusterView& cv) {
  const std::size_t T = mesh.triangle_count();
  const auto& offs = cv.triangle_offsets;
  if (offs.empty() || offs.front() != 0 || offs.back() != cv.triangle_order.size() || cv.triangle_order.size() != T)
    throw std::invalid_argument("ClusterScene: the clustering's offsets/order do not cover the " + std::to_string(T) +
                                " triangles");
  std::vector<std::uint8_t> seen(T, 0);
  for (std::uint32_t t : cv.triangle_order)
    if (t >= T || seen[t]++) throw std::invalid_argument("ClusterScene: triangle_order is not a permutation");
  const std::size_t C = offs.size() - 1;
  if (!cv.vertex_offsets.empty() &&
      (cv.vertex_offsets.size() != C + 1 || cv.vertex_offsets.front() != 0 || cv.vertex_offsets.back() != cv.vertices.size()))
    throw std::invalid_argument("ClusterScene: vertex_offsets do not match the clusters");
  for (std::size_t c = 0; c < C; ++c) {
    if (offs[c + 1] <= offs[c]) throw std::invalid_argument("ClusterScene: empty or decreasing cluster " + std::to_string(c));
    if (!cv.vertex_offsets.empty() && cv.vertex_offsets[c + 1] < cv.vertex_offsets[c])
      throw std::invalid_argument("ClusterScene: decreasing vertex offsets at cluster " + std::to_string(c));
  }
}

// The rest-pose BVH over the clusters (boxes over their vertex lists, or their triangles'
// corners, in the scene's frame; the scene's build settings, plain build): its primitive order
// is the order in which the scene keeps the clusters, and its subtrees of at most
// cluster_group_size clusters are the groups of the two-level build. Its boxes and centres (in
// the view's cluster order) are those the per-frame pass makes at the rest pose (point_group_boxes
// in the frame: each vertex rounded to its nearest float, the box widened by one unit in the last
// place), bit for bit, so the tree is the plain build's tree of that frame. A checked view.
struct RestTree {
  Bvh bvh;
  AlignedVector<Box3f> boxes;
  AlignedVector<Vec3f> centres;
};
RestTree rest_tree(const Mesh& mesh, const ClusterView& cv, const SceneConfig& cfg, const FrameMap& frame) {
  const std::size_t C = cv.triangle_offsets.size() - 1;
  std::vector<std::uint32_t> offs, idx;
  std::span<const std::uint32_t> o = cv.vertex_offsets, v = cv.vertices;
  if (cv.vertex_offsets.empty()) {
    const auto tris = mesh.triangles();
    offs.assign(1, 0);
    idx.reserve(3 * cv.triangle_order.size());
    for (std::size_t c = 0; c < C; ++c) {
      for (std::uint32_t i = cv.triangle_offsets[c]; i < cv.triangle_offsets[c + 1]; ++i)
        for (std::uint32_t x : tris[cv.triangle_order[i]]) idx.push_back(x);
      offs.push_back(static_cast<std::uint32_t>(idx.size()));
    }
    o = offs, v = idx;
  }
  for (std::uint32_t x : v)
    if (x >= mesh.vertex_count())
      throw std::invalid_argument("ClusterScene: vertex " + std::to_string(x) + " of a cluster's list is not in the mesh");
  RestTree r;
  point_group_boxes(mesh.positions(), frame, o, v, r.boxes, r.centres);
  std::vector<std::uint32_t> weights(C);
  for (std::size_t c = 0; c < C; ++c) weights[c] = cv.triangle_offsets[c + 1] - cv.triangle_offsets[c];
  BuildConfig b = cfg.build;
  b.max_leaf_size = 1;
  r.bvh = build_binned_sah({r.boxes, r.centres, weights}, b);
  return r;
}

// Group offsets (in prim_order positions) of a tree over single-primitive leaves: the maximal
// subtrees of at most `size` primitives, left to right.
std::vector<std::uint32_t> subtree_groups(const Bvh& t, std::uint32_t size) {
  const std::size_t N = t.nodes.size();
  std::vector<std::uint32_t> first(N), count(N);
  for (std::size_t i = N; i-- > 0;) {  // children have larger indices
    const BvhNode& n = t.nodes[i];
    if (n.is_leaf()) {
      first[i] = n.index, count[i] = n.count;
    } else {
      first[i] = std::min(first[i + 1], first[n.index]);
      count[i] = count[i + 1] + count[n.index];
    }
  }
  std::vector<std::uint32_t> groups;
  std::vector<std::uint32_t> stack{0};
  while (!stack.empty()) {
    const std::uint32_t i = stack.back();
    stack.pop_back();
    if (count[i] <= size || t.nodes[i].is_leaf()) {
      groups.push_back(first[i]);
      continue;
    }
    stack.push_back(t.nodes[i].index), stack.push_back(i + 1);  // left first
  }
  std::sort(groups.begin(), groups.end());
  groups.push_back(static_cast<std::uint32_t>(t.prim_order.size()));
  return groups;
}

// The view's clusters in the visiting order: triangle ranges (unless `order` is null: only the
// vertex lists wanted) and vertex lists (the triangles' corners when the view has none). Every
// array is reserved at its final size (at 13.3M triangles growing them by doubling touched
// twice the memory).
void reorder_clusters(const Mesh& mesh, const ClusterView& cv, std::span<const std::uint32_t> visit,
                      std::vector<std::uint32_t>* order, std::vector<std::uint32_t>* offsets,
                      std::vector<std::uint32_t>& vertices, std::vector<std::uint32_t>& vertex_offsets) {
  const auto tris = mesh.triangles();
  const bool corners = cv.vertex_offsets.empty();
  vertices.clear(), vertex_offsets.assign(1, 0);
  vertices.reserve(corners ? 3 * cv.triangle_order.size() : cv.vertices.size());
  vertex_offsets.reserve(visit.size() + 1);
  if (order) {
    order->clear(), offsets->assign(1, 0);
    order->reserve(cv.triangle_order.size());
    offsets->reserve(visit.size() + 1);
  }
  for (std::uint32_t c : visit) {
    if (order)
      order->insert(order->end(), cv.triangle_order.begin() + cv.triangle_offsets[c],
                    cv.triangle_order.begin() + cv.triangle_offsets[c + 1]);
    if (corners) {
      for (std::uint32_t i = cv.triangle_offsets[c]; i < cv.triangle_offsets[c + 1]; ++i)
        for (std::uint32_t v : tris[cv.triangle_order[i]]) vertices.push_back(v);
    } else {
      vertices.insert(vertices.end(), cv.vertices.begin() + cv.vertex_offsets[c], cv.vertices.begin() + cv.vertex_offsets[c + 1]);
    }
    if (order) offsets->push_back(static_cast<std::uint32_t>(order->size()));
    vertex_offsets.push_back(static_cast<std::uint32_t>(vertices.size()));
  }
}

// Within each cluster: Morton order of the rest-pose centroids in the cluster's own box, ties by
// triangle id, so that consecutive groups of four are compact blocks. The grid: 10 bits per axis
// over the cube of the box's largest extent E, cell = floor((c - lo) * 1023 / E) in [0, 1023]
// (toolkit's morton_codes() quantises to 21 bits with 2^21 / E instead, which orders some
// clusters differently: only its bit interleave, morton_encode, is shared).
void sort_clusters_by_morton(std::span<const Vec3> pos, std::span<const Tri> tris, std::span<const std::uint32_t> offsets,
                             std::vector<std::uint32_t>& order) {
  // Clusters are independent: chunks of them on the caller's threads, the same order at any count.
  const std::size_t C = offsets.empty() ? 0 : offsets.size() - 1;
  std::uint32_t* const ord = order.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, C, kSetupClustersPerTask), [=](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> keyed;  // (code, triangle id)
    std::vector<Vec3> cen;
    for (std::size_t c = r.begin(); c < r.end(); ++c) {
      const std::uint32_t first = offsets[c], end = offsets[c + 1];
      Box3 box;
      cen.clear();
      for (std::uint32_t i = first; i < end; ++i) {
        const Tri& t = tris[ord[i]];
        cen.push_back(triangle_centroid(pos[t[0]], pos[t[1]], pos[t[2]]));
        box.extend(cen.back());
      }
      const Vec3 ext = box.extent();
      const double scale = ext.maxCoeff() > 0 ? 1023.0 / ext.maxCoeff() : 0.0;
      keyed.clear();
      for (std::uint32_t i = first; i < end; ++i) {
        const Vec3 q = (cen[i - first] - box.lo) * scale;
        const auto code = morton_encode(static_cast<std::uint32_t>(q.x()), static_cast<std::uint32_t>(q.y()),
                                        static_cast<std::uint32_t>(q.z()));  // < 2^30: cells < 2^10
        keyed.push_back({static_cast<std::uint32_t>(code), ord[i]});
      }
      std::sort(keyed.begin(), keyed.end());
      for (std::uint32_t i = first; i < end; ++i) ord[i] = keyed[i - first].second;
    }
  });
}

}  // namespace

std::vector<std::uint32_t> cluster_visit_order(const Mesh& mesh, const ClusterView& clusters, const SceneConfig& cfg) {
  check_view(mesh, clusters);
  const RestTree rest = rest_tree(mesh, clusters, cfg, trace_frame(mesh, cfg));
  return {rest.bvh.prim_order.begin(), rest.bvh.prim_order.end()};
}

std::vector<std::uint32_t> cluster_vertex_order(const Mesh& mesh, const ClusterView& clusters,
                                                std::span<const std::size_t> part_offsets, const SceneConfig& cfg) {
  std::vector<std::uint32_t> vertices, vertex_offsets;  // (the triangle order is not needed here)
  reorder_clusters(mesh, clusters, cluster_visit_order(mesh, clusters, cfg), nullptr, nullptr, vertices, vertex_offsets);
  return cluster_vertex_order(mesh.vertex_count(), vertex_offsets, vertices, part_offsets);
}

// The layout, once per clustering: clusters in the visiting order, their triangles in Morton
// order (Linear) or in the leaf order of their block trees (BlockTree), blocks cluster by
// cluster; then the vertex order of the per-frame pass and the first frame (a scene built once:
// its only frame, without that vertex order). The lists needed only here are freed at the end.
ClusterScene::ClusterScene(const Mesh& mesh, const ClusterView& cv, const SceneConfig& cfg)
    : tris_(mesh.shared_triangles()), cfg_(cfg) {
  check_view(mesh, cv);
  TraceData& data = f_.data;
  const FrameMap frame = trace_frame(mesh, cfg);  // (checks the rest positions)
  data.origin = frame.origin, data.scale = frame.scale;
  // The rest pose in the trace frame: finite in single precision (checked), and the BlockTree
  // layout's input below.
  frame_positions(mesh.positions(), data.frame(), f_.fpos);
  check_finite(mesh.positions(), f_.fpos, data.frame());
  // Clusters are kept in the order of the rest-pose BVH over them (cluster_visit_order): the
  // blocks are laid out in it, and the groups of the two-level build are its subtrees.
  {
    if (cfg_.builder == SahBuilder::Sweep && cfg_.cluster_group_size > 1)
      throw std::invalid_argument("the sweep builder has no two-level build: cluster_group_size must be 0 with it");
    if (cfg_.cluster_leaf == ClusterLeaf::BlockTree && cfg_.leaf_format == LeafFormatChoice::Tables)
      throw std::invalid_argument("the tables leaf format needs linear cluster leaves (block trees keep blocks)");
    if (cfg_.fallback_swelling > 0) {  // (the fallback's build would refuse them only at its first frame)
      const BuildConfig fallback_build = fallback_config().build;
      check_area_weights(fallback_build);
      check_area_eye(fallback_build);
    }
    if (cfg_.cluster_leaf == ClusterLeaf::BlockTree && cfg_.build.max_leaf_size > 1)  // (a leaf of several would bypass their trees)
      throw std::invalid_argument("block-tree cluster leaves hold one cluster each: max_leaf_size must be 1 with them (" +
                                  std::to_string(cfg_.build.max_leaf_size) + " given)");
  }
  RestTree rest = rest_tree(mesh, cv, cfg_, data.frame());
  cluster_ids_.assign(rest.bvh.prim_order.begin(), rest.bvh.prim_order.end());
  group_size_ = cluster_group_size_used(cluster_ids_.size(), cfg_);
  if (group_size_ > 1 && !rest.bvh.nodes.empty()) group_offsets_ = subtree_groups(rest.bvh, group_size_);
  if (group_offsets_.size() <= 2) group_offsets_.clear(), group_size_ = 0;  // one group: the plain build
  reorder_clusters(mesh, cv, cluster_ids_, &order_, &offsets_, vertices_, vertex_offsets_);
  const std::size_t C = offsets_.size() - 1;
  sort_clusters_by_morton(mesh.positions(), mesh.triangles(), offsets_, order_);

  weights_.resize(C);
  for (std::size_t c = 0; c < C; ++c) weights_[c] = offsets_[c + 1] - offsets_[c];
  cluster_ranges_.resize(C);
  sub_root_.assign(C, kNoTriangle);
  // Triangle id per block lane (kNoTriangle: padding); it becomes data.triangle_ids (moved, as
  // the fixed nodes below: at 13.3M triangles each copy was 30-60 MB of new memory).
  AlignedVector<std::uint32_t> lane_ids;
  if (cfg_.cluster_leaf == ClusterLeaf::Linear) layout_linear(lane_ids);
  else layout_block_trees(lane_ids);
  block_nodes_ = static_cast<std::uint32_t>(sub_nodes_.size());
  refit_groups_ = cfg_.group_trees == GroupTrees::Refit && !group_offsets_.empty();
  if (refit_groups_ || cfg_.built_once) rest_boxes(rest.boxes, rest.centres);  // (read by the groups' trees and by only_frame)
  // A scene built once with the plain build has one frame, the rest pose, whose tree is the rest
  // tree: the same builder and settings over the same boxes (the clusters now numbered in its
  // leaf order, so its primitive order becomes the identity).
  rest_is_frame_tree_ = cfg_.built_once && group_offsets_.empty() && cfg_.builder == SahBuilder::Binned &&
                        cfg_.build.max_leaf_size <= 1;
  if (rest_is_frame_tree_) {
    f_.bvh = std::move(rest.bvh);
    std::iota(f_.bvh.prim_order.begin(), f_.bvh.prim_order.end(), 0u);
  }
  rest = {};
  if (!cfg_.built_once) set_vertex_order(mesh, lane_ids);
  if (use_tables(cv.vertex_offsets.empty())) {
    layout_tables(mesh, lane_ids);  // (the clusters' ranges become ranges of groups)
  } else {
    data.blocks.resize(lane_ids.size() / 4);
    data.triangle_ids = std::move(lane_ids);
  }
  if (refit_groups_) layout_group_trees();
  sub_count_ = static_cast<std::uint32_t>(sub_nodes_.size());
  layout_wide8();
  // The fixed 4-wide nodes served the regrouping only (refit8 writes the 8-wide ones; the top
  // collapses straight into 8-wide nodes), and the groups' slot lists that of refit8's sources.
  release(sub_nodes_), release(group_slots_);
  if (cfg_.built_once) {
    only_frame();
  } else {
    triangle_area_ = mesh_area_in_frame(mesh, data.scale);
    update(mesh.positions());
  }
  // Needed only to lay the clusters out (the per-frame pass has its own vertex order).
  release(order_), release(offsets_), release(vertices_), release(vertex_offsets_);
}

// The leaf format the scene uses (SceneConfig::leaf_format; set-up, while offsets_ and
// vertex_offsets_ hold the clusters' triangles and vertices, whose estimated bytes it keeps):
// Auto takes the tables for linear leaves of a scene that is updated when tables_suit them.
// corner_lists: the view had no vertex lists, so each cluster's list is its triangles' corners
// with repeats, and its distinct ones are counted here.
bool ClusterScene::use_tables(bool corner_lists) {
  if (corner_lists) {
    std::vector<std::uint32_t> distinct(vertex_offsets_.size(), 0), tmp;
    for (std::size_t c = 0; c + 1 < vertex_offsets_.size(); ++c) {
      tmp.assign(vertices_.begin() + vertex_offsets_[c], vertices_.begin() + vertex_offsets_[c + 1]);
      std::sort(tmp.begin(), tmp.end());
      distinct[c + 1] = distinct[c] + static_cast<std::uint32_t>(std::unique(tmp.begin(), tmp.end()) - tmp.begin());
    }
    leaf_estimate_ = estimate_leaf_bytes(offsets_, distinct);
  } else {
    leaf_estimate_ = estimate_leaf_bytes(offsets_, vertex_offsets_);
  }
  switch (cfg_.leaf_format) {
    case LeafFormatChoice::Tables: return true;
    case LeafFormatChoice::Blocks: return false;
    case LeafFormatChoice::Auto: break;
  }
  return cfg_.cluster_leaf == ClusterLeaf::Linear && !cfg_.built_once && tables_suit(leaf_estimate_);
}

// The clusters' boxes and centres at the rest pose, in the scene's cluster order, into f_.boxes
// and f_.centroids: the rest tree's (rest_tree(), the same values point_group_boxes makes over
// the reordered vertex lists), permuted.
void ClusterScene::rest_boxes(std::span<const Box3f> boxes, std::span<const Vec3f> centres) {
  const double t0 = clock_ms(cfg_.clock);
  const std::size_t C = cluster_ids_.size();
  f_.boxes.resize(C), f_.centroids.resize(C);
  for (std::size_t c = 0; c < C; ++c) f_.boxes[c] = boxes[cluster_ids_[c]], f_.centroids[c] = centres[cluster_ids_[c]];
  f_.times.vertices_ms = 0.0;
  f_.times.boxes_ms = clock_ms(cfg_.clock) - t0;
}

// The one frame of a scene built once: the rest pose's cluster boxes (rest_boxes(), made by the
// constructor), the blocks filled from the lanes' triangles. The same values as update() computes
// from its own vertex order (point_group_boxes is bit for bit the same in either order, and a
// block's corners are the same floats). The frame positions and block boxes are dropped after.
void ClusterScene::only_frame() {
  add_sentinel(f_.fpos);
  build_frame();
  release(f_.fpos);
  release(block_boxes_);
}

// The fixed subtrees (block trees, then the groups' trees, which link to them) regrouped into
// 8-wide nodes once, at the rest pose, and where each of their slots takes its box from per frame
// (src8_): a block's box (a block tree's leaf), the union of clusters' boxes (a group tree's
// leaf, or its link to a cluster's block tree), or an 8-wide child's box (box8_). The refits
// (refit8) then write the 8-wide nodes directly; the fixed 4-wide nodes are never refitted (only
// their structure is read, by this function), and the top is collapsed into 8-wide nodes per frame
// (collapse_top8).
void ClusterScene::layout_wide8() {
  const std::span<const WideNode> fixed(sub_nodes_.data(), sub_count_);
  link8_.assign(sub_count_, kNoTriangle);
  std::vector<SlotSource> sources;
  for (const std::uint32_t r : sub_root_)
    if (r != kNoTriangle) link8_[r] = regroup_subtree(fixed, r, sub8_, sub_depth8_, 0, {}, &sources);
  group8_begin_ = sub8_.size();
  for (const std::uint32_t r : group_root_)
    if (r != kNoTriangle)
      link8_[r] = regroup_subtree(fixed, r, sub8_, group_depth8_, block_nodes_, link8_, &sources);
  // Per slot one box record, (kind << 30) | index: kind 0 a cluster's box (f_.boxes), 1 a
  // block's (block_boxes_), 2 an 8-wide child's (box8_), 3 multi_boxes_ (0: the empty box; the
  // others: the unions of a group tree's leaves of several clusters, multi_src_).
  src8_.resize(8 * sub8_.size());
  multi_src_.clear();
  for (std::size_t i = 0; i < 8 * sub8_.size(); ++i) {
    const WideNode8& n = sub8_[i / 8];
    const int j = static_cast<int>(i % 8);
    const SlotSource& so = sources[i];
    std::uint32_t kind = 3, index = 0;
    if (n.is_empty(j)) {
    } else if (so.node >= block_nodes_ && group_slots_[so.node - block_nodes_].count[so.slot]) {  // a group tree's leaf
      const GroupSlots& gs = group_slots_[so.node - block_nodes_];
      if (gs.count[so.slot] == 1) {
        kind = 0, index = group_leaf_clusters_[gs.first[so.slot]];
      } else {
        multi_src_.push_back({gs.first[so.slot], gs.count[so.slot]});
        index = static_cast<std::uint32_t>(multi_src_.size());
      }
    } else if (n.is_leaf(j)) {  // a block tree's leaf: one block
      kind = 1, index = n.child[j];
    } else {
      kind = 2, index = n.child[j];
    }
    if (index >= kSrcIndexLimit) throw std::length_error("ClusterScene: too many fixed nodes, blocks or clusters");
    src8_[i] = kind << 30 | index;
  }
  multi_boxes_.assign(multi_src_.size() + 1, Box3f{});
  box8_.assign(6 * sub8_.size(), 0.0f);
  sub8_count_ = sub8_.size();
  // Each group as an 8-wide child, for collapse_top8 (one load where the chain group -> 4-wide
  // root -> 8-wide root missed the cache): a link to its tree's 8-wide root, or its one cluster's
  // slot (a link to its block tree's 8-wide root, or its direct leaf).
  group_slot8_.clear();
  for (std::size_t g = 0; g < group_root_.size(); ++g)
    group_slot8_.push_back(group_root_[g] != kNoTriangle ? std::pair{link8_[group_root_[g]], 0u}
                                                         : cluster_slot8(group_offsets_[g]));
  f_.data.wide8.nodes = std::move(sub8_);
  sub8_ = {};
}

// Linear: each cluster's triangles packed in blocks of four, in the (Morton) order above.
void ClusterScene::layout_linear(AlignedVector<std::uint32_t>& lane_ids) {
  const std::size_t C = weights_.size();
  std::uint32_t blocks = 0;
  for (std::size_t c = 0; c < C; ++c) {
    cluster_ranges_[c] = {blocks, blocks_for(weights_[c]), weights_[c]};
    blocks += blocks_for(weights_[c]);
  }
  lane_ids.resize(4 * std::size_t{blocks});
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, C, kSetupClustersPerTask), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c < r.end(); ++c) {
      std::uint32_t* lanes = lane_ids.data() + 4 * std::size_t{cluster_ranges_[c].first_block};
      const std::uint32_t* ids = order_.data() + offsets_[c];
      for (std::uint32_t i = 0; i < 4 * cluster_ranges_[c].block_count; ++i) lanes[i] = i < weights_[c] ? ids[i] : kNoTriangle;
    }
  });
}

// BlockTree: per cluster a binned SAH tree over its rest-pose triangles, leaves of at most 4
// triangles = one block each, collapsed to 4-wide; blocks in leaf order; topology kept.
// (f_.fpos holds the rest pose in the trace frame.)
void ClusterScene::layout_block_trees(AlignedVector<std::uint32_t>& lane_ids) {
  const std::span<const Tri> tris = triangles();
  BuildConfig sub;
  sub.max_leaf_size = 4;
  sub.cost = cfg_.build.cost;
  std::vector<Box3f> tb;
  std::vector<Vec3f> tc;
  for (std::size_t c = 0; c < weights_.size(); ++c) {
    const std::span<const std::uint32_t> ids(order_.data() + offsets_[c], weights_[c]);
    const auto first = static_cast<std::uint32_t>(lane_ids.size() / 4);
    if (ids.size() <= 4) {  // one block: the cluster is a direct leaf
      for (std::uint32_t i = 0; i < 4; ++i) lane_ids.push_back(i < ids.size() ? ids[i] : kNoTriangle);
      cluster_ranges_[c] = {first, 1, weights_[c]};
      continue;
    }
    tb.clear(), tc.clear();
    for (std::uint32_t t : ids) {
      Box3f b;
      Vec3f m{0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const Vec3f& p = f_.fpos[tris[t][k]];
        b.extend(p);
        for (int a = 0; a < 3; ++a) m[a] += p[a] / 3.0f;
      }
      tb.push_back(b), tc.push_back(m);
    }
    const Bvh b = build_binned_sah({tb, tc, {}}, sub);
    const WideBvh w = collapse_to_wide(b);
    const auto base = static_cast<std::uint32_t>(sub_nodes_.size());
    sub_root_[c] = base + w.root;
    for (WideNode n : w.nodes) {
      for (int k = 0; k < 4; ++k) {
        if (n.is_leaf(k)) {
          const auto blk = static_cast<std::uint32_t>(lane_ids.size() / 4);
          for (std::uint32_t i = 0; i < 4; ++i)
            lane_ids.push_back(i < n.count[k] ? ids[b.prim_order[n.child[k] + i]] : kNoTriangle);
          n.child[k] = blk;  // direct leaf of count <= 4 triangles
        } else if (!n.is_empty(k)) {
          n.child[k] += base;
        }
      }
      sub_nodes_.push_back(n);
    }
    const auto end = static_cast<std::uint32_t>(lane_ids.size() / 4);
    cluster_ranges_[c] = {first, end - first, weights_[c]};
  }
}

// GroupTrees::Refit: per group, the binned SAH tree over its clusters' rest-pose boxes (the
// scene's build settings), collapsed to 4-wide and appended to sub_nodes_ after the block trees.
// A leaf child of one cluster refers to the cluster's blocks (or links to its block tree), a
// leaf of several clusters to fixed ranges; the slots remember which cluster boxes they unite.
// (f_.boxes and f_.centroids hold the clusters' rest-pose boxes: rest_boxes().)
void ClusterScene::layout_group_trees() {
  const AlignedVector<Box3f>& boxes = f_.boxes;
  const AlignedVector<Vec3f>& centres = f_.centroids;
  const std::size_t G = group_offsets_.size() - 1;
  group_top_build_ = cfg_.build;
  group_top_build_.max_leaf_size = 1;  // a leaf of the tree over the groups is one group (its tree)
  group_bvh_.resize(G);
  group_root_.assign(G, kNoTriangle);
  group_weights_.assign(G, 0);
  group_boxes_.resize(G);
  group_centres_.resize(G);
  // The groups' trees are independent: a chunk of groups is built and collapsed on the caller's
  // threads, then appended in group order (the same nodes at any thread count; chunks keep the
  // collapsed trees in the cache until they are appended).
  std::vector<WideBvh> wide(std::min(G, kSetupGroupsPerChunk));
  for (std::size_t g0 = 0; g0 < G; g0 += kSetupGroupsPerChunk) {
    const std::size_t g1 = std::min(G, g0 + kSetupGroupsPerChunk);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(g0, g1, 64), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t g = r.begin(); g < r.end(); ++g) {
        const std::uint32_t first = group_offsets_[g], n = group_offsets_[g + 1] - first;
        for (std::uint32_t i = 0; i < n; ++i) group_weights_[g] += weights_[first + i];
        group_bvh_[g] = build_binned_sah({std::span<const Box3f>(boxes.data() + first, n),
                                          std::span<const Vec3f>(centres.data() + first, n),
                                          std::span<const std::uint32_t>(weights_.data() + first, n)},
                                         cfg_.build);
        if (n > 1) collapse_to_wide(group_bvh_[g], wide[g - g0]);
      }
    });
    for (std::size_t g = g0; g < g1; ++g)
      if (group_offsets_[g + 1] - group_offsets_[g] > 1) append_group_tree(g, wide[g - g0]);
  }
}

// Group g's collapsed tree (of more than one cluster) appended to the fixed nodes: a leaf child
// of one cluster refers to its blocks (or block tree), a leaf of several to fixed ranges; the
// slots remember which clusters they unite.
void ClusterScene::append_group_tree(std::size_t g, const WideBvh& w) {
  const std::uint32_t first = group_offsets_[g];
  const Bvh& gb = group_bvh_[g];
  const auto base = static_cast<std::uint32_t>(sub_nodes_.size());
  group_root_[g] = base + w.root;
  for (WideNode nd : w.nodes) {
    GroupSlots gs{};
    for (int k = 0; k < 4; ++k) {
      if (nd.is_leaf(k)) {
        const std::uint32_t cnt = nd.count[k];
        gs.first[k] = static_cast<std::uint32_t>(group_leaf_clusters_.size());
        gs.count[k] = cnt;
        for (std::uint32_t i = 0; i < cnt; ++i) group_leaf_clusters_.push_back(first + gb.prim_order[nd.child[k] + i]);
        if (cnt == 1) {
          std::tie(nd.child[k], nd.count[k]) = cluster_slot(group_leaf_clusters_.back());
        } else {
          nd.child[k] = static_cast<std::uint32_t>(group_ranges_.size());
          nd.count[k] = cnt | kIndirectLeaf;
          for (std::uint32_t i = 0; i < cnt; ++i) group_ranges_.push_back(cluster_ranges_[group_leaf_clusters_[gs.first[k] + i]]);
        }
      } else if (!nd.is_empty(k)) {
        nd.child[k] += base;
      }
    }
    sub_nodes_.push_back(nd);
    group_slots_.push_back(gs);
  }
}

namespace {

// refit8's sweep (see there) over nodes [begin, end): compiled twice, SSE2 (the x86-64 baseline)
// and the same instructions in their VEX forms (three operands, no register copies), picked at
// run time; the same bits either way. Branch-free: every slot reads one box record (Box3f
// layout), at bases[kind] + 6 index floats.
struct Refit8Args {
  WideNode8* nodes;
  const std::uint32_t* src;
  const float* bases[4];
  float* box8;
};

[[gnu::always_inline]] inline void refit8_sweep(const Refit8Args& x, std::size_t begin, std::size_t end) {
  for (std::size_t d = end; d-- > begin;) {
    WideNode8& n = x.nodes[d];
    const std::uint32_t* src = x.src + 8 * d;
    __m128 lo[8], hi[8];
    for (int j = 0; j < 8; ++j) {
      const std::uint32_t e = src[j];
      const float* p = x.bases[e >> 30] + 6 * std::size_t{e & (kSrcIndexLimit - 1)};
      lo[j] = _mm_loadu_ps(p);  // lo x y z, hi x
      const __m128 h = _mm_loadu_ps(p + 2);  // lo z, hi x y z
      hi[j] = _mm_shuffle_ps(h, h, _MM_SHUFFLE(0, 3, 2, 1));
    }
    const __m128 alo = _mm_min_ps(_mm_min_ps(_mm_min_ps(lo[0], lo[1]), _mm_min_ps(lo[2], lo[3])),
                                  _mm_min_ps(_mm_min_ps(lo[4], lo[5]), _mm_min_ps(lo[6], lo[7])));
    const __m128 ahi = _mm_max_ps(_mm_max_ps(_mm_max_ps(hi[0], hi[1]), _mm_max_ps(hi[2], hi[3])),
                                  _mm_max_ps(_mm_max_ps(hi[4], hi[5]), _mm_max_ps(hi[6], hi[7])));
    _MM_TRANSPOSE4_PS(lo[0], lo[1], lo[2], lo[3]);
    _MM_TRANSPOSE4_PS(lo[4], lo[5], lo[6], lo[7]);
    _MM_TRANSPOSE4_PS(hi[0], hi[1], hi[2], hi[3]);
    _MM_TRANSPOSE4_PS(hi[4], hi[5], hi[6], hi[7]);
    for (int a = 0; a < 3; ++a) {
      _mm_stream_ps(&n.bounds[2 * a][0], lo[a]), _mm_stream_ps(&n.bounds[2 * a][4], lo[4 + a]);
      _mm_stream_ps(&n.bounds[2 * a + 1][0], hi[a]), _mm_stream_ps(&n.bounds[2 * a + 1][4], hi[4 + a]);
    }
    // The node's union as a Box3f record: (lo x y z, hi x), then (lo z, hi x y z) over it.
    float* bx = x.box8 + 6 * d;
    const __m128 zx = _mm_shuffle_ps(alo, ahi, _MM_SHUFFLE(0, 0, 2, 2));  // lo z, lo z, hi x, hi x
    _mm_storeu_ps(bx, _mm_shuffle_ps(alo, zx, _MM_SHUFFLE(2, 0, 1, 0)));
    _mm_storeu_ps(bx + 2, _mm_shuffle_ps(zx, ahi, _MM_SHUFFLE(2, 1, 2, 0)));
  }
}

void refit8_sse2(const Refit8Args& x, std::size_t begin, std::size_t end) { refit8_sweep(x, begin, end); }
__attribute__((target("avx2"))) void refit8_avx2(const Refit8Args& x, std::size_t begin, std::size_t end) {
  refit8_sweep(x, begin, end);
}
}  // namespace

// The fixed 8-wide nodes [begin, end) refitted, children after parents (one reverse sweep; a
// group tree's links to block trees read the clusters' boxes, not the block trees'): each slot's
// box from its record (src8_), the node's eight boxes transposed into its rows, and its union
// kept in box8_ for its parent (the group trees' leaves of several clusters read their unions
// from multi_boxes_, which refit_group_trees makes first). The rows (the node's first three cache
// lines, written whole) are streamed: the lines, last written a frame ago and evicted since by
// the fill, are not read for ownership first (twist at one thread, `ptc bench ... --threads 1
// --packets`, three alternated rounds: sah_build_ms 0.52-0.57 -> 0.46; docs/tracing.md). Fenced
// at the end, so the walks that follow see them.
// The block boxes are read by the block trees' nodes only (block_trees): the groups' trees
// never take a slot from them, and their refit may run while the fill, which sizes block_boxes_,
// runs on another thread.
void ClusterScene::refit8(std::size_t begin, std::size_t end, bool block_trees) {
  static_assert(offsetof(WideNode8, bounds) == 0 && alignof(WideNode8) >= 64 && sizeof(WideNode8::bounds) == 192,
                "the streamed rows are the node's first three cache lines");
  const Refit8Args x{f_.data.wide8.nodes.data(),
                     src8_.data(),
                     {f_.boxes.empty() ? nullptr : f_.boxes[0].lo.data(),
                      block_trees && !block_boxes_.empty() ? block_boxes_[0].lo.data() : nullptr, box8_.data(),
                      multi_boxes_[0].lo.data()},
                     box8_.data()};
  (simd::cpu_has_avx2() && cfg_.build.allow_avx2 ? refit8_avx2 : refit8_sse2)(x, begin, end);
  _mm_sfence();
}

// GroupTrees::Refit, per frame: the groups' 8-wide trees refitted from the cluster boxes, then
// one record per group for the build (its box and centre).
void ClusterScene::refit_group_trees() {
  for (std::size_t k = 0; k < multi_src_.size(); ++k) {  // (none with single-cluster leaves, the default)
    Box3f b;
    for (std::uint32_t i = 0; i < multi_src_[k].second; ++i) b.extend(f_.boxes[group_leaf_clusters_[multi_src_[k].first + i]]);
    multi_boxes_[k + 1] = b;
  }
  refit8(group8_begin_, sub8_count_, false);
  const Box3f* cb = f_.boxes.data();
  for (std::size_t g = 0; g + 1 < group_offsets_.size(); ++g) {
    Box3f b;
    if (group_root_[g] == kNoTriangle) {
      b = cb[group_offsets_[g]];
    } else {
      const float* bx = box8_.data() + 6 * std::size_t{link8_[group_root_[g]]};
      b = {{bx[0], bx[1], bx[2]}, {bx[3], bx[4], bx[5]}};
    }
    group_boxes_[g] = b;
    group_centres_[g] = b.center();
  }
}

Bvh ClusterScene::cluster_tree() const {
  if (!refit_groups_ || f_.bvh.empty()) return f_.bvh;
  const Bvh& top = f_.bvh;
  Bvh out;
  auto emit = [&](auto& self, std::uint32_t i) -> void {
    const BvhNode& n = top.nodes[i];
    if (n.is_leaf()) {
      for (std::uint32_t p = n.index; p < n.index + n.count; ++p) {  // one group (the top's leaves hold one)
        const std::uint32_t g = top.prim_order[p];
        const Bvh& gb = group_bvh_[g];
        const auto base = static_cast<std::uint32_t>(out.nodes.size());
        const auto pbase = static_cast<std::uint32_t>(out.prim_order.size());
        for (BvhNode m : gb.nodes) {
          m.index += m.is_leaf() ? pbase : base;
          out.nodes.push_back(m);
        }
        for (std::uint32_t q : gb.prim_order) out.prim_order.push_back(group_offsets_[g] + q);
      }
      return;
    }
    const auto at = out.nodes.size();
    out.nodes.push_back(n);
    self(self, i + 1);
    out.nodes[at].index = static_cast<std::uint32_t>(out.nodes.size());
    self(self, n.index);
  };
  emit(emit, 0);
  refit(out, f_.boxes, weights_, &cfg_.build.cost);
  return out;
}

double ClusterScene::sah_cost() const { return refit_groups_ ? cluster_tree().cost : f_.bvh.cost; }

// Corner vertex indices per block (read sequentially every frame instead of looking up the
// triangles of the lanes, which are scattered over the triangle array), in the vertex order of
// the per-frame pass: vertices renumbered once per clustering so that the per-frame conversion
// writes, and the box and leaf-data stages read, each cluster's vertices mostly contiguously
// (vertex_order.h). When the mesh already is in that order (renumbered once with
// cluster_vertex_order), every cluster's own vertices are consecutive input indices and the
// conversion, fused with the box stage, streams over the input: no gather, no renumbering per
// frame.
void ClusterScene::set_vertex_order(const Mesh& mesh, std::span<const std::uint32_t> lane_ids) {
  vorder_ = first_touch_order(mesh.vertex_count(), vertex_offsets_, vertices_);
  runs_ = group_runs(vorder_);
  fill_corners(mesh.triangles(), lane_ids, static_cast<std::uint32_t>(mesh.vertex_count()),
               runs_ ? nullptr : vorder_.to_new.data());
  lists_are_corners_ = runs_ && lists_are_corners(mesh.vertex_count(), lane_ids);
  if (runs_) {
    vorder_ = {};
    f_.fpos.resize(mesh.vertex_count());
    add_sentinel(f_.fpos);
  } else {
    release(vorder_.to_new);  // only needed for the corners
  }
}

// corners_ from the lanes' triangles: corner c of lane l of block b at 12 b + 4 c + l, its vertex
// renumbered by to_new (null: the mesh's numbering), the sentinel for padding lanes.
void ClusterScene::fill_corners(std::span<const Tri> tris, std::span<const std::uint32_t> lane_ids,
                                std::uint32_t sentinel, const std::uint32_t* to_new) {
  corners_.resize(lane_ids.size() * 3);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lane_ids.size() / 4, kSetupBlocksPerTask), [&](const auto& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b)
      for (int l = 0; l < 4; ++l) {
        const std::uint32_t id = lane_ids[4 * b + l];
        for (int c = 0; c < 3; ++c)
          corners_[12 * b + 4 * c + l] = id == kNoTriangle ? sentinel : to_new ? to_new[tris[id][c]] : tris[id][c];
      }
  });
}

// LeafFormat::Tables: the groups of every cluster from its blocks' lanes and corners (those of
// the per-frame pass, or for a scene built once the mesh's numbering with the sentinel after
// the last vertex), the triangle ids per group slot, and each cluster's range of groups in
// cluster_ranges_ (first group, group count, triangles). The blocks' corner indices and lanes
// are freed.
void ClusterScene::layout_tables(const Mesh& mesh, AlignedVector<std::uint32_t>& lane_ids) {
  TraceData& data = f_.data;
  const auto sentinel = static_cast<std::uint32_t>(mesh.vertex_count());
  if (cfg_.built_once) fill_corners(mesh.triangles(), lane_ids, sentinel, nullptr);  // (no per-frame vertex order)
  AlignedVector<std::uint32_t> ids;
  tables_ = make_table_layout(cluster_ranges_, lane_ids, corners_, sentinel, data.tables, ids);
  for (std::size_t c = 0; c < cluster_ranges_.size(); ++c)
    cluster_ranges_[c] = {tables_.group_offsets[c], tables_.group_offsets[c + 1] - tables_.group_offsets[c], weights_[c]};
  data.triangle_ids = std::move(ids);
  data.format = LeafFormat::Tables;
  release(corners_), release(lane_ids);
}

// Whether every cluster's vertex list (vertices_, the mesh's numbering) holds exactly the corners of
// its triangles (the lanes of its blocks), as a Clustering's lists and the corner lists made
// without them do: then boxes over the blocks' corners are the lists' boxes, bit for bit. A
// stamp per vertex: 2c for cluster c's list, 2c + 1 once a corner of c was seen there.
bool ClusterScene::lists_are_corners(std::size_t vertex_count, std::span<const std::uint32_t> lane_ids) const {
  const std::span<const Tri> tris = triangles();
  const std::size_t C = cluster_ranges_.size();
  if (C >= (std::size_t{1} << 31)) return false;
  std::vector<std::uint32_t> stamp(vertex_count, ~0u);
  for (std::size_t c = 0; c < C; ++c) {
    const auto s = static_cast<std::uint32_t>(2 * c);
    for (std::uint32_t i = vertex_offsets_[c]; i < vertex_offsets_[c + 1]; ++i) stamp[vertices_[i]] = s;
    const LeafRange& r = cluster_ranges_[c];
    for (std::size_t l = 4 * std::size_t{r.first_block}; l < 4 * (std::size_t{r.first_block} + r.block_count); ++l) {
      if (lane_ids[l] == kNoTriangle) continue;
      for (const std::uint32_t v : tris[lane_ids[l]]) {
        if ((stamp[v] | 1u) != s + 1) return false;  // a corner not in the list
        stamp[v] = s + 1;
      }
    }
    for (std::uint32_t i = vertex_offsets_[c]; i < vertex_offsets_[c + 1]; ++i)
      if (stamp[vertices_[i]] != s + 1) return false;  // a listed vertex that is no corner
  }
  return true;
}

void ClusterScene::update(std::span<const Vec3> positions) {
  update_clusters(positions);
  // With the fallback on: the swelling (counted in build_ms; box_half_areas, about 0.04 ms) and,
  // above the threshold, the frame's triangle BVH. Off, nothing: swelling() computes it on demand.
  swelling_ = std::numeric_limits<double>::quiet_NaN();
  fallback_active_ = false;
  f_.times.fallback_ms = 0.0;
  if (!(cfg_.fallback_swelling > 0)) return;
  const double t0 = clock_ms(cfg_.clock);
  swelling_ = swelling();
  f_.times.build_ms += clock_ms(cfg_.clock) - t0;
  if (swelling_ > cfg_.fallback_swelling) update_fallback(positions);
}

double ClusterScene::swelling() const {
  if (!std::isnan(swelling_) || !(triangle_area_ > 0)) return swelling_;  // (this frame's, or NaN: no area, built once)
  return box_half_areas(f_.boxes) / triangle_area_;
}

SceneConfig ClusterScene::fallback_config() const {
  SceneConfig tc = fallback_scene_defaults();
  tc.origin = f_.data.origin;
  tc.scale = f_.data.scale;
  tc.clock = cfg_.clock;
  tc.refit_growth = cfg_.refit_growth;
  tc.build.area_weights = cfg_.fallback_area_weights;
  if (cfg_.fallback_area_eye) tc.build.area_eye = to_frame(*cfg_.fallback_area_eye, f_.data.frame());  // (its trace frame)
  return tc;
}

// The frame's triangle BVH, in the cluster BVH's trace frame (the same float vertices, so the
// same hits), made at the first frame that needs it (with fallback_scene_defaults()) and then
// updated on each such frame: rebuilt, or refitted while SceneConfig::refit_growth allows.
void ClusterScene::update_fallback(std::span<const Vec3> positions) {
  const double t0 = clock_ms(cfg_.clock);
  if (!fallback_) {  // (made whole before it is used: a throw leaves the cluster BVH traced)
    auto made = std::make_unique<TriangleScene>(Mesh::sharing(tris_, std::vector<Vec3>(positions.begin(), positions.end())),
                                                fallback_config());
    fallback_ = std::move(made);
  } else {
    fallback_->update(positions);
  }
  f_.times.fallback_ms = clock_ms(cfg_.clock) - t0;
  fallback_active_ = true;
}

void ClusterScene::update_clusters(std::span<const Vec3> positions) {
  if (cfg_.built_once)
    throw std::logic_error("ClusterScene::update: the scene was built once (SceneConfig::built_once) and keeps no per-frame state");
  TraceData& data = f_.data;
  StageTimes& times = f_.times;
  const std::size_t V = runs_ ? runs_->vertex_count : vorder_.to_old.size();
  if (positions.size() != V)
    throw std::invalid_argument("ClusterScene::update: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(V) + " vertices");
  double t0 = clock_ms(cfg_.clock);
  if (runs_ && lists_are_corners_) {
    // The conversion streams over the input (f_.fpos keeps its size and sentinels), and the
    // fill, which reads every corner anyway, takes the cluster boxes (build_frame), before the
    // tree. At two threads this beat the fused conversion and boxes with the fill beside the
    // tree (docs/tracing.md, thirty-second session).
    frame_positions_streamed(positions, data.frame(), std::span<Vec3f>(f_.fpos.data(), V), cfg_.build.allow_avx2);
    times.vertices_ms = clock_ms(cfg_.clock) - t0;
    times.boxes_ms = 0.0;
    build_frame(true);
    return;
  }
  if (runs_) {  // one pass: conversion and boxes (f_.fpos keeps its size and sentinels)
    frame_positions_and_boxes(positions, data.frame(), *runs_, std::span<Vec3f>(f_.fpos.data(), V), f_.boxes,
                              f_.centroids, cfg_.build.allow_avx2);
    times.vertices_ms = 0.0;
    times.boxes_ms = clock_ms(cfg_.clock) - t0;
  } else {
    frame_positions(positions, vorder_.to_old, data.frame(), f_.fpos);
    check_finite(positions, f_.fpos, data.frame());  // (a NaN box would break the build)
    add_sentinel(f_.fpos);
    const std::span<const Vec3f> fp(f_.fpos.data(), V);
    times.vertices_ms = clock_ms(cfg_.clock) - t0;
    t0 = clock_ms(cfg_.clock);
    point_group_boxes(fp, vorder_, f_.boxes, f_.centroids);
    times.boxes_ms = clock_ms(cfg_.clock) - t0;
  }
  build_frame();
}

// Whether build_frame can write the leaf data beside the tree: more than one thread, wall-clock
// stage times (each stage's own time is then wall time too).
bool ClusterScene::overlap_possible() const {
  return cfg_.clock == StageClock::Wall && usable_threads() > 1;
}

// The frame after its cluster boxes (f_.boxes, f_.centroids) and frame positions (f_.fpos, then
// add_sentinel's two entries): the leaf data, the tree over the clusters or groups, the link and
// the refit of the fixed subtrees.
void ClusterScene::build_frame(bool boxes_from_fill) {
  TraceData& data = f_.data;
  StageTimes& times = f_.times;

  // The leaf data depends on the positions only (the blocks' layout is fixed per clustering), so
  // with more than one thread it is written while the tree is built and linked: the fill's
  // chunks run on the other threads. Each stage keeps its own time; overlap_ms is what they
  // shared, so total_ms() stays the update's wall time.
  const std::size_t B = block_nodes_;
  const bool avx2 = cfg_.build.allow_avx2;  // (the AVX2 loops when the CPU has them; the same bytes)
  auto leaf_data = [&] {
    const double tl = clock_ms(cfg_.clock);
    block_boxes_.resize(B ? data.blocks.size() : 0);
    if (data.format == LeafFormat::Tables) {  // (linear leaves: no block boxes)
      if (boxes_from_fill) f_.boxes.resize(weights_.size()), f_.centroids.resize(weights_.size());
      fill_tables(tables_, f_.fpos[0].data(), data.tables, boxes_from_fill ? f_.boxes.data() : nullptr,
                  boxes_from_fill ? f_.centroids.data() : nullptr, avx2);  // fenced
    } else if (cfg_.built_once) {  // (no corner indices: the lanes' triangles in the mesh's numbering; the sentinel last but one)
      fill_blocks_from_lanes(data.triangle_ids, triangles(), f_.fpos[0].data(),
                             static_cast<std::uint32_t>(f_.fpos.size() - 2), data.blocks,
                             B ? block_boxes_.data() : nullptr);  // fenced
    } else if (boxes_from_fill) {  // and the cluster boxes from the corners it writes
      f_.boxes.resize(weights_.size());
      f_.centroids.resize(weights_.size());
      fill_blocks_and_cluster_boxes(corners_, f_.fpos[0].data(), data.blocks, B ? block_boxes_.data() : nullptr,
                                    cluster_ranges_, f_.boxes.data(), f_.centroids.data(), avx2);  // fenced
    } else {
      fill_blocks_from_corners(corners_, f_.fpos[0].data(), data.blocks, B ? block_boxes_.data() : nullptr,
                               avx2);  // fenced
    }
    times.leaf_data_ms = clock_ms(cfg_.clock) - tl;
  };
  auto tree = [&] {
    double tb = clock_ms(cfg_.clock);
    if (rest_is_frame_tree_) {  // (f_.bvh is the rest tree: the constructor kept it)
    } else if (refit_groups_) {  // the groups' trees refitted, then the build over one record per group
      refit_group_trees();
      build_binned_sah({group_boxes_, group_centres_, group_weights_}, group_top_build_, f_.bvh, f_.ws);
    } else if (cfg_.builder == SahBuilder::Sweep) {
      f_.bvh = build_sweep_sah({f_.boxes, f_.centroids, weights_}, cfg_.build);
    } else {
      build_binned_sah({f_.boxes, f_.centroids, weights_, group_offsets_}, cfg_.build, f_.bvh, f_.ws);
    }
    times.build_ms = clock_ms(cfg_.clock) - tb;
    tb = clock_ms(cfg_.clock);
    collapse_top8();  // (the fixed subtrees' 8-wide boxes are written by their refits: refit8)
    times.collapse_ms = clock_ms(cfg_.clock) - tb;
  };
  times.overlap_ms = 0.0;
  if (boxes_from_fill) {  // the tree needs the boxes the fill makes: the fill first, then the tree
    leaf_data();
    tree();
  } else if (overlap_possible()) {
    const double t0 = clock_ms(cfg_.clock);
    tbb::task_group tg;
    tg.run(leaf_data);
    tree();
    tg.wait();
    const double wall = clock_ms(cfg_.clock) - t0;
    times.overlap_ms = std::max(0.0, times.build_ms + times.collapse_ms + times.leaf_data_ms - wall);
  } else {
    tree();
    leaf_data();
  }

  const double t0 = clock_ms(cfg_.clock);
  if (B) refit8(0, group8_begin_, true);  // the block trees
  times.refit_ms = clock_ms(cfg_.clock) - t0;
}

// A leaf slot that holds cluster c alone (child, count): a link to its block tree (its 4-wide
// root, count 0), or a direct leaf of its blocks (or table groups).
std::pair<std::uint32_t, std::uint32_t> ClusterScene::cluster_slot(std::uint32_t c) const {
  if (sub_root_[c] != kNoTriangle) return {sub_root_[c], 0};
  return {cluster_ranges_[c].first_block, cluster_ranges_[c].triangle_count};  // packed
}

// The same as an 8-wide slot: the link goes to the block tree's 8-wide root (layout_wide8).
std::pair<std::uint32_t, std::uint32_t> ClusterScene::cluster_slot8(std::uint32_t c) const {
  if (sub_root_[c] != kNoTriangle) return {link8_[sub_root_[c]], 0};
  return cluster_slot(c);
}

// Per frame: the binary tree over the groups (or clusters) collapsed straight into the 8-wide
// nodes the tracer walks, after the fixed ones [0, sub8_count_): node for node the tree
// regroup_to_8(collapse_to_wide(bvh)) makes (each 4-wide node is expanded on the fly from its
// binary node, nothing 4-wide is stored); children after parents. A leaf of one group becomes a
// link to the group's fixed 8-wide tree (or its one cluster's leaf), a leaf of one cluster a
// link to its block tree or a direct leaf of its blocks (or table groups), a leaf of several
// clusters an indirect one over `ranges`.
void ClusterScene::collapse_top8() {
  TraceData& data = f_.data;
  const Bvh& bvh = f_.bvh;
  WideBvh8& w8 = data.wide8;
  const std::size_t S8 = sub8_count_;
  if (w8.nodes.size() < S8) throw std::logic_error("ClusterScene: the fixed 8-wide nodes were lost");
  w8.nodes.resize(S8);
  if (refit_groups_) {  // the top's leaves are single groups; the groups' trees keep fixed ranges
    if (data.ranges.size() != group_ranges_.size()) data.ranges = group_ranges_;
  } else {
    data.ranges.resize(weights_.size());
    for (std::size_t i = 0; i < bvh.prim_order.size(); ++i) data.ranges[i] = cluster_ranges_[bvh.prim_order[i]];
  }
  if (bvh.nodes.empty()) {  // (no clusters: no fixed part either)
    w8.nodes.clear(), w8.root = 0, w8.depth = 0;
    return;
  }
  // A slot: a binary node; an inner one keeps its 4-wide node's children (wide_children, made
  // once per node) and its area.
  struct Slot {
    std::uint32_t bin;
    int live;  // the children it opens into; 9: a leaf (never opened)
    float area;
    std::uint32_t kids[4];
  };
  auto slot = [&](std::uint32_t b) {
    Slot s{b, 9, 0.0f, {}};
    const BvhNode& m = bvh.nodes[b];
    if (!m.is_leaf()) s.live = wide_children(bvh, b, s.kids), s.area = static_cast<float>(m.bounds.surface_area());
    return s;
  };
  using Item = Top8Item;
  std::vector<Item>& stack = top8_stack_;
  auto push = [&](const Slot& c, std::uint32_t node8, std::uint32_t depth) {
    stack.push_back({c.bin, node8, depth, {c.kids[0], c.kids[1], c.kids[2], c.kids[3]}, c.live});
  };
  stack.clear();
  w8.nodes.reserve(S8 + bvh.nodes.size() / 2);  // (no 8-wide node has fewer than two children but a root leaf)
  w8.root = static_cast<std::uint32_t>(S8);
  w8.nodes.emplace_back();
  push(slot(0), w8.root, 1);
  std::uint32_t depth = 0;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    depth = std::max(depth, it.depth);
    Slot s[8];
    int ns = 0;
    if (it.nk == 9) {
      s[ns++] = slot(it.bin);  // (a root that is a leaf: collapse_to_wide's one-slot node)
    } else {
      for (int i = 0; i < it.nk; ++i) s[ns++] = slot(it.kids[i]);
    }
    for (;;) {  // regroup_to_8: open the inner child of largest area whose children fit
      int best = -1;
      float best_area = -1.0f;
      for (int i = 0; i < ns; ++i)
        if (ns - 1 + s[i].live <= 8 && s[i].area > best_area) best = i, best_area = s[i].area;
      if (best < 0) break;
      const Slot opened = s[best];
      s[best] = slot(opened.kids[0]);  // the first child takes the opened slot, the others go last
      for (int j = 1; j < opened.live; ++j) s[ns++] = slot(opened.kids[j]);
    }
    // The node is assembled here and then streamed out whole: its lines, last written a frame ago
    // and evicted since by the fill, are not read for ownership first (slot-by-slot stores into
    // them stalled on those reads).
    alignas(64) WideNode8 dst;
    for (int i = 0; i < 8; ++i) {
      std::uint32_t child = WideNode8::kEmptySlot, count = 0;
      Box3f box;
      if (i < ns) {
        const BvhNode& m = bvh.nodes[s[i].bin];
        box = m.bounds;
        if (!m.is_leaf()) {
          child = static_cast<std::uint32_t>(w8.nodes.size());
          w8.nodes.emplace_back();
          push(s[i], child, it.depth + 1);
        } else if (refit_groups_) {
          if (m.count != 1) throw std::logic_error("ClusterScene: a leaf of the tree over the groups holds several groups");
          std::tie(child, count) = group_slot8_[bvh.prim_order[m.index]];
        } else if (m.count == 1) {
          std::tie(child, count) = cluster_slot8(bvh.prim_order[m.index]);
        } else {
          child = m.index, count = m.count | kIndirectLeaf;  // ranges [index, index + count)
        }
      }
      dst.set_child_box(i, box);
      dst.child[i] = child, dst.count[i] = count;
    }
    static_assert(sizeof(WideNode8) % 16 == 0);
    float* out = reinterpret_cast<float*>(&w8.nodes[it.node8]);
    const float* in = reinterpret_cast<const float*>(&dst);
    for (std::size_t k = 0; k < sizeof(WideNode8) / sizeof(float); k += 4) _mm_stream_ps(out + k, _mm_load_ps(in + k));
  }
  _mm_sfence();
  w8.depth = depth + group_depth8_ + sub_depth8_;
}

}  // namespace ptc::bvh
