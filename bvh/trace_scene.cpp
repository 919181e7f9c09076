#include "bvh/trace_scene.h"

#include "bvh/stage_clock.h"

#include <emmintrin.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace ptc::bvh {

namespace {


std::uint32_t blocks_for(std::uint32_t triangles) { return (triangles + 3) / 4; }

// A scene's rest positions and origin must be finite (they fix the trace frame, the layout and,
// for clusters, the rest-pose tree): std::invalid_argument naming the first bad vertex.
Vec3 default_origin(const Mesh& mesh, const SceneConfig& cfg) {
  const auto p = mesh.positions();
  for (std::size_t v = 0; v < p.size(); ++v)
    if (!p[v].allFinite())
      throw std::invalid_argument("vertex " + std::to_string(v) + ": rest position (" + std::to_string(p[v].x()) + ", " +
                                  std::to_string(p[v].y()) + ", " + std::to_string(p[v].z()) + ") is not finite");
  if (cfg.origin && !cfg.origin->allFinite()) throw std::invalid_argument("scene: the trace frame's origin is not finite");
  if (cfg.origin) return *cfg.origin;
  const Box3 b = mesh.bounds();
  return b.empty() ? Vec3::Zero() : b.center();
}

// The frame positions with a NaN sentinel vertex at index V (for padding lanes) and one more
// element, so that a 16-byte load at any vertex stays inside the array.
void add_sentinel(std::vector<Vec3f>& fp) {
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  fp.push_back({nan, nan, nan});
  fp.push_back({0.0f, 0.0f, 0.0f});
}

// One block from four triangle ids (kNoTriangle: padding): corners gathered with one 16-byte
// load per vertex and transposed to SoA. When `box` is given it receives the block's exact
// float box (NaN lanes ignored: _mm_min_ps(x, acc) returns acc for a NaN x).
inline void fill_block_corners(const std::uint32_t (&v)[3][4], const float* fp, TriBlock& out, Box3f* box);

inline void fill_block(const std::uint32_t* ids, std::span<const Tri> tris, const float* fp, std::uint32_t sentinel,
                       TriBlock& out, Box3f* box) {
  std::uint32_t v[3][4];
  for (int l = 0; l < 4; ++l) {
    if (ids[l] != kNoTriangle) {
      const Tri& t = tris[ids[l]];
      v[0][l] = t[0], v[1][l] = t[1], v[2][l] = t[2];
    } else {
      v[0][l] = v[1][l] = v[2][l] = sentinel;
    }
  }
  fill_block_corners(v, fp, out, box);
}

// v[corner][lane]: vertex indices (the sentinel for padding lanes).
inline void fill_block_corners(const std::uint32_t (&v)[3][4], const float* fp, TriBlock& out, Box3f* box) {
  __m128 lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = _mm_set1_ps(kInf), hi[a] = _mm_set1_ps(-kInf);
  for (int c = 0; c < 3; ++c) {
    __m128 r0 = _mm_loadu_ps(fp + 3 * std::size_t(v[c][0])), r1 = _mm_loadu_ps(fp + 3 * std::size_t(v[c][1]));
    __m128 r2 = _mm_loadu_ps(fp + 3 * std::size_t(v[c][2])), r3 = _mm_loadu_ps(fp + 3 * std::size_t(v[c][3]));
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);  // r0 = x of the 4 lanes, r1 = y, r2 = z
    // Streaming stores: the blocks (tens of MB) are written once per frame and not read back by
    // this pass, so they bypass the caches instead of evicting the vertex data being gathered.
    _mm_stream_ps(out.v[c][0], r0), _mm_stream_ps(out.v[c][1], r1), _mm_stream_ps(out.v[c][2], r2);
    if (box) {
      lo[0] = _mm_min_ps(r0, lo[0]), lo[1] = _mm_min_ps(r1, lo[1]), lo[2] = _mm_min_ps(r2, lo[2]);
      hi[0] = _mm_max_ps(r0, hi[0]), hi[1] = _mm_max_ps(r1, hi[1]), hi[2] = _mm_max_ps(r2, hi[2]);
    }
  }
  if (box) {
    for (int a = 0; a < 3; ++a) {
      __m128 l = lo[a], h = hi[a];
      l = _mm_min_ps(l, _mm_shuffle_ps(l, l, _MM_SHUFFLE(1, 0, 3, 2)));
      l = _mm_min_ps(l, _mm_shuffle_ps(l, l, _MM_SHUFFLE(2, 3, 0, 1)));
      h = _mm_max_ps(h, _mm_shuffle_ps(h, h, _MM_SHUFFLE(1, 0, 3, 2)));
      h = _mm_max_ps(h, _mm_shuffle_ps(h, h, _MM_SHUFFLE(2, 3, 0, 1)));
      box->lo[a] = _mm_cvtss_f32(l), box->hi[a] = _mm_cvtss_f32(h);
    }
  }
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
// cluster_group_size clusters are the groups of the two-level build. A checked view.
Bvh rest_tree(const Mesh& mesh, const ClusterView& cv, const SceneConfig& cfg, const Vec3& origin) {
  const std::size_t C = cv.triangle_offsets.size() - 1;
  std::vector<std::uint32_t> offs, idx;
  std::span<const std::uint32_t> o = cv.vertex_offsets, v = cv.vertices;
  if (cv.vertex_offsets.empty()) {
    const auto tris = mesh.triangles();
    offs.assign(1, 0);
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
  const std::vector<Box3f> boxes = point_group_boxes(mesh.positions(), o, v, origin);
  const std::vector<Vec3f> centres = box_centers(boxes);
  std::vector<std::uint32_t> weights(C);
  for (std::size_t c = 0; c < C; ++c) weights[c] = cv.triangle_offsets[c + 1] - cv.triangle_offsets[c];
  BuildConfig b = cfg.build;
  b.max_leaf_size = 1;
  return build_binned_sah({boxes, centres, weights}, b);
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

// The view's clusters in the visiting order: triangle ranges and vertex lists (the triangles'
// corners when the view has none).
void reorder_clusters(const Mesh& mesh, const ClusterView& cv, std::span<const std::uint32_t> visit,
                      std::vector<std::uint32_t>& order, std::vector<std::uint32_t>& offsets,
                      std::vector<std::uint32_t>& vertices, std::vector<std::uint32_t>& vertex_offsets) {
  const auto tris = mesh.triangles();
  order.clear(), offsets.assign(1, 0), vertices.clear(), vertex_offsets.assign(1, 0);
  for (std::uint32_t c : visit) {
    for (std::uint32_t i = cv.triangle_offsets[c]; i < cv.triangle_offsets[c + 1]; ++i) {
      order.push_back(cv.triangle_order[i]);
      if (cv.vertex_offsets.empty())
        for (std::uint32_t v : tris[cv.triangle_order[i]]) vertices.push_back(v);
    }
    if (!cv.vertex_offsets.empty())
      vertices.insert(vertices.end(), cv.vertices.begin() + cv.vertex_offsets[c], cv.vertices.begin() + cv.vertex_offsets[c + 1]);
    offsets.push_back(static_cast<std::uint32_t>(order.size()));
    vertex_offsets.push_back(static_cast<std::uint32_t>(vertices.size()));
  }
}

void fill_ids(std::span<const std::uint32_t> ids, std::uint32_t* first_id) {
  const auto n = static_cast<std::uint32_t>(ids.size());
  for (std::uint32_t i = 0; i < 4 * blocks_for(n); ++i) first_id[i] = i < n ? ids[i] : kNoTriangle;
}

}  // namespace

const char* to_string(ClusterLeaf l) { return l == ClusterLeaf::Linear ? "linear" : "block_tree"; }

SceneConfig triangle_scene_defaults() {
  SceneConfig c;
  c.build.cost = {1.0, 0.3};
  c.build.max_leaf_size = 8;
  return c;
}

SceneConfig cluster_scene_defaults() {
  SceneConfig c;
  c.build.cost = {1.0, 0.3};
  c.build.max_leaf_size = 1;
  c.build.median_split_below = 4;  // see BuildConfig: 6% faster build, SAH cost +0.3%
  c.cluster_group_size = 8;        // two-level build: see SceneConfig (bench/bvh_bench.cpp --groups)
  return c;
}

// ---------------------------------------------------------------------------------------------

TriangleScene::TriangleScene(const Mesh& mesh, const SceneConfig& cfg) : tris_(mesh.shared_triangles()), cfg_(cfg) {
  data_.origin = default_origin(mesh, cfg);
  update(mesh.positions());
}

void TriangleScene::update(std::span<const Vec3> positions) {
  const std::span<const Tri> tris = tris_ ? std::span<const Tri>(*tris_) : std::span<const Tri>();
  double t0 = clock_ms(cfg_.clock);
  frame_positions(positions, data_.origin, fpos_);
  check_finite(positions, fpos_, data_.origin);  // (a NaN box would break the build)
  const auto V = static_cast<std::uint32_t>(fpos_.size());
  add_sentinel(fpos_);
  const std::span<const Vec3f> fp(fpos_.data(), V);
  times_.vertices_ms = clock_ms(cfg_.clock) - t0;

  t0 = clock_ms(cfg_.clock);
  boxes_ = triangle_boxes(fp, tris);
  centroids_ = triangle_centroids(fp, tris);
  times_.boxes_ms = clock_ms(cfg_.clock) - t0;

  t0 = clock_ms(cfg_.clock);
  build_binned_sah({boxes_, centroids_, {}}, cfg_.build, bvh_, ws_);
  times_.build_ms = clock_ms(cfg_.clock) - t0;

  t0 = clock_ms(cfg_.clock);
  data_.wide = collapse_to_wide(bvh_);
  times_.collapse_ms = clock_ms(cfg_.clock) - t0;

  // Leaf data: blocks in the order the leaves appear in the wide nodes; leaves become direct.
  t0 = clock_ms(cfg_.clock);
  std::uint32_t nblocks = 0;
  for (const WideNode& n : data_.wide.nodes)
    for (int k = 0; k < 4; ++k)
      if (n.is_leaf(k)) nblocks += blocks_for(n.count[k]);
  data_.blocks.resize(nblocks);
  data_.triangle_ids.resize(4 * static_cast<std::size_t>(nblocks));
  data_.ranges.clear();
  std::uint32_t next = 0;
  for (WideNode& n : data_.wide.nodes)
    for (int k = 0; k < 4; ++k) {
      if (!n.is_leaf(k)) continue;
      const std::span<const std::uint32_t> ids(bvh_.prim_order.data() + n.child[k], n.count[k]);
      std::uint32_t* lane_ids = data_.triangle_ids.data() + 4 * std::size_t(next);
      fill_ids(ids, lane_ids);
      for (std::uint32_t j = 0; j < blocks_for(n.count[k]); ++j)
        fill_block(lane_ids + 4 * j, tris, fpos_[0].data(), V, data_.blocks[next + j], nullptr);
      n.child[k] = next;  // direct leaf: count stays the triangle count
      next += blocks_for(n.count[k]);
    }
  _mm_sfence();  // the streaming stores are visible before the blocks are traced
  times_.leaf_data_ms = clock_ms(cfg_.clock) - t0;
  times_.refit_ms = 0.0;
}

// ---------------------------------------------------------------------------------------------

std::vector<std::uint32_t> cluster_visit_order(const Mesh& mesh, const ClusterView& clusters, const SceneConfig& cfg) {
  check_view(mesh, clusters);
  return rest_tree(mesh, clusters, cfg, default_origin(mesh, cfg)).prim_order;
}

std::vector<std::uint32_t> cluster_vertex_order(const Mesh& mesh, const ClusterView& clusters,
                                                std::span<const std::size_t> part_offsets, const SceneConfig& cfg) {
  std::vector<std::uint32_t> order, offsets, vertices, vertex_offsets;
  reorder_clusters(mesh, clusters, cluster_visit_order(mesh, clusters, cfg), order, offsets, vertices, vertex_offsets);
  return cluster_vertex_order(mesh.vertex_count(), vertex_offsets, vertices, part_offsets);
}

ClusterScene::ClusterScene(const Mesh& mesh, const ClusterView& cv, const SceneConfig& cfg)
    : tris_(mesh.shared_triangles()), cfg_(cfg) {
  check_view(mesh, cv);
  data_.origin = default_origin(mesh, cfg);  // (checks the rest positions)
  // The rest pose in the trace frame: finite in single precision (checked), and the BlockTree
  // layout's input below.
  frame_positions(mesh.positions(), data_.origin, fpos_);
  check_finite(mesh.positions(), fpos_, data_.origin);
  // Clusters are kept in the order of the rest-pose BVH over them (cluster_visit_order): the
  // blocks are laid out in it, and the groups of the two-level build are its subtrees.
  {
    const Bvh rest = rest_tree(mesh, cv, cfg_, data_.origin);
    cluster_ids_ = rest.prim_order;
    if (cfg_.cluster_group_size > 1 && !rest.nodes.empty()) group_offsets_ = subtree_groups(rest, cfg_.cluster_group_size);
    if (group_offsets_.size() <= 2) group_offsets_.clear();  // one group: the plain build
  }
  reorder_clusters(mesh, cv, cluster_ids_, order_, offsets_, vertices_, vertex_offsets_);
  const std::size_t C = offsets_.size() - 1;
  const std::span<const Tri> tris = mesh.triangles();

  // Within each cluster: Morton order of the rest-pose centroids in the cluster's own box (10
  // bits per axis), ties by triangle id, so that consecutive groups of four are compact blocks.
  const auto pos = mesh.positions();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> keyed;
  for (std::size_t c = 0; c < C; ++c) {
    Box3 box;
    std::vector<Vec3> cen;
    for (std::uint32_t i = offsets_[c]; i < offsets_[c + 1]; ++i) {
      const Tri& t = tris[order_[i]];
      cen.push_back((pos[t[0]] + pos[t[1]] + pos[t[2]]) / 3.0);
      box.extend(cen.back());
    }
    const Vec3 ext = box.extent();
    const double scale = ext.maxCoeff() > 0 ? 1023.0 / ext.maxCoeff() : 0.0;
    keyed.clear();
    for (std::uint32_t i = offsets_[c]; i < offsets_[c + 1]; ++i) {
      std::uint32_t code = 0;
      const Vec3 q = (cen[i - offsets_[c]] - box.lo) * scale;
      const auto x = static_cast<std::uint32_t>(q.x()), y = static_cast<std::uint32_t>(q.y()),
                 z = static_cast<std::uint32_t>(q.z());
      for (int bit = 9; bit >= 0; --bit)
        code = (code << 3) | (((x >> bit) & 1u) << 2) | (((y >> bit) & 1u) << 1) | ((z >> bit) & 1u);
      keyed.push_back({code, order_[i]});
    }
    std::sort(keyed.begin(), keyed.end());
    for (std::uint32_t i = offsets_[c]; i < offsets_[c + 1]; ++i) order_[i] = keyed[i - offsets_[c]].second;
  }

  weights_.resize(C);
  for (std::size_t c = 0; c < C; ++c) weights_[c] = offsets_[c + 1] - offsets_[c];
  cluster_ranges_.resize(C);
  sub_root_.assign(C, kNoTriangle);
  std::vector<std::uint32_t> lane_ids;  // triangle id per block lane (kNoTriangle: padding)
  if (cfg_.cluster_leaf == ClusterLeaf::Linear) {
    for (std::size_t c = 0; c < C; ++c) {
      const auto first = static_cast<std::uint32_t>(lane_ids.size() / 4);
      for (std::uint32_t i = 0; i < 4 * blocks_for(weights_[c]); ++i)
        lane_ids.push_back(i < weights_[c] ? order_[offsets_[c] + i] : kNoTriangle);
      cluster_ranges_[c] = {first, blocks_for(weights_[c]), weights_[c]};
    }
  } else {
    // BlockTree: per cluster a binned SAH tree over its rest-pose triangles, leaves of at most 4
    // triangles = one block each, collapsed to 4-wide; blocks in leaf order; topology kept.
    // (fpos_ holds the rest pose in the trace frame, converted above.)
    BuildConfig sub;
    sub.max_leaf_size = 4;
    sub.cost = cfg_.build.cost;
    std::vector<Box3f> tb;
    std::vector<Vec3f> tc;
    for (std::size_t c = 0; c < C; ++c) {
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
          const Vec3f& p = fpos_[tris[t][k]];
          b.extend(p);
          for (int a = 0; a < 3; ++a) m[a] += p[a] / 3.0f;
        }
        tb.push_back(b), tc.push_back(m);
      }
      const Bvh b = build_binned_sah({tb, tc, {}}, sub);
      const WideBvh w = collapse_to_wide(b);
      const auto base = static_cast<std::uint32_t>(sub_nodes_.size());
      sub_root_[c] = base + w.root;
      sub_depth_ = std::max(sub_depth_, w.depth);
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
  data_.blocks.resize(lane_ids.size() / 4);
  data_.triangle_ids.assign(lane_ids.begin(), lane_ids.end());
  // Corner vertex indices per block (read sequentially every frame instead of looking up the
  // triangles of the lanes, which are scattered over the triangle array).
  // Vertices renumbered once per clustering so that the per-frame conversion writes, and the box
  // and leaf-data stages read, each cluster's vertices mostly contiguously (box.h).
  // When the mesh already is in that order (renumbered once with cluster_vertex_order), every
  // cluster's own vertices are consecutive input indices and the conversion, fused with the box
  // stage, streams over the input: no gather, no renumbering per frame.
  vorder_ = first_touch_order(mesh.vertex_count(), vertex_offsets_, vertices_);
  runs_ = group_runs(vorder_);
  const auto sentinel = static_cast<std::uint32_t>(mesh.vertex_count());
  corners_.resize(lane_ids.size() * 3);
  for (std::size_t b = 0; b < lane_ids.size() / 4; ++b)
    for (int l = 0; l < 4; ++l) {
      const std::uint32_t id = lane_ids[4 * b + l];
      for (int c = 0; c < 3; ++c)
        corners_[12 * b + 4 * c + l] = id == kNoTriangle ? sentinel : runs_ ? tris[id][c] : vorder_.to_new[tris[id][c]];
    }
  if (runs_) {
    vorder_ = {};
    fpos_.resize(mesh.vertex_count());
    add_sentinel(fpos_);
  } else {
    vorder_.to_new = {};  // only needed for the corners
  }
  update(pos);
}

void ClusterScene::refit_subtrees() {
  WideNode* nodes = data_.wide.nodes.data();
  for (std::size_t i = sub_nodes_.size(); i-- > 0;) {
    WideNode& n = nodes[i];
    for (int k = 0; k < 4; ++k) {
      if (n.is_leaf(k)) {
        n.set_child_box(k, block_boxes_[n.child[k]]);
      } else if (!n.is_empty(k)) {
        const WideNode& c = nodes[n.child[k]];
        for (int row = 0; row < 6; ++row) {  // lo rows: min over the 4 children, hi rows: max
          __m128 x = _mm_load_ps(c.bounds[row]);
          if (row % 2 == 0) {
            x = _mm_min_ps(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(1, 0, 3, 2)));
            x = _mm_min_ps(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(2, 3, 0, 1)));
          } else {
            x = _mm_max_ps(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(1, 0, 3, 2)));
            x = _mm_max_ps(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(2, 3, 0, 1)));
          }
          n.bounds[row][k] = _mm_cvtss_f32(x);
        }
      }
    }
  }
}

void ClusterScene::update(std::span<const Vec3> positions) {
  const std::span<const Tri> tris = tris_ ? std::span<const Tri>(*tris_) : std::span<const Tri>();
  const std::size_t C = weights_.size();
  const std::size_t V = runs_ ? runs_->vertex_count : vorder_.to_old.size();
  if (positions.size() != V)
    throw std::invalid_argument("ClusterScene::update: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(V) + " vertices");
  double t0 = clock_ms(cfg_.clock);
  if (runs_) {  // one pass: conversion and boxes (fpos_ keeps its size and sentinels)
    frame_positions_and_boxes(positions, data_.origin, *runs_, std::span<Vec3f>(fpos_.data(), V), boxes_, centroids_);
    times_.vertices_ms = 0.0;
    times_.boxes_ms = clock_ms(cfg_.clock) - t0;
  } else {
    frame_positions(positions, vorder_.to_old, data_.origin, fpos_);
    check_finite(positions, fpos_, data_.origin);  // (a NaN box would break the build)
    add_sentinel(fpos_);
    const std::span<const Vec3f> fp(fpos_.data(), V);
    times_.vertices_ms = clock_ms(cfg_.clock) - t0;
    t0 = clock_ms(cfg_.clock);
    point_group_boxes(fp, vorder_, boxes_, centroids_);
    times_.boxes_ms = clock_ms(cfg_.clock) - t0;
  }

  t0 = clock_ms(cfg_.clock);
  build_binned_sah({boxes_, centroids_, weights_, group_offsets_}, cfg_.build, bvh_, ws_);
  times_.build_ms = clock_ms(cfg_.clock) - t0;

  // Collapse, then link: nodes [0, S) are the per-cluster trees (kept from frame to frame),
  // the top tree follows; a leaf of one cluster becomes a link to its tree (BlockTree) or a
  // direct leaf, a leaf of several clusters an indirect one.
  t0 = clock_ms(cfg_.clock);
  WideBvh top = collapse_to_wide(bvh_);
  const auto S = static_cast<std::uint32_t>(sub_nodes_.size());
  if (data_.wide.nodes.size() < S) data_.wide.nodes.assign(sub_nodes_.begin(), sub_nodes_.end());
  data_.wide.nodes.resize(S + top.nodes.size());
  data_.ranges.resize(C);
  for (std::size_t i = 0; i < bvh_.prim_order.size(); ++i) data_.ranges[i] = cluster_ranges_[bvh_.prim_order[i]];
  for (std::size_t i = 0; i < top.nodes.size(); ++i) {
    WideNode n = top.nodes[i];
    for (int k = 0; k < 4; ++k) {
      if (n.is_leaf(k)) {
        if (n.count[k] == 1) {
          const std::uint32_t c = bvh_.prim_order[n.child[k]];
          if (sub_root_[c] != kNoTriangle) {
            n.child[k] = sub_root_[c], n.count[k] = 0;
          } else {
            n.child[k] = cluster_ranges_[c].first_block, n.count[k] = cluster_ranges_[c].triangle_count;  // packed
          }
        } else {
          n.count[k] |= kIndirectLeaf;
        }
      } else if (!n.is_empty(k)) {
        n.child[k] += S;
      }
    }
    data_.wide.nodes[S + i] = n;
  }
  data_.wide.root = S;
  data_.wide.bounds = top.bounds;
  data_.wide.depth = top.depth + sub_depth_;
  data_.wide.leaves = top.leaves;
  if (top.nodes.empty()) data_.wide.nodes.clear();
  times_.collapse_ms = clock_ms(cfg_.clock) - t0;

  t0 = clock_ms(cfg_.clock);
  const std::size_t nb = data_.blocks.size();
  block_boxes_.resize(S ? nb : 0);
  for (std::size_t b = 0; b < nb; ++b)
    fill_block_corners(*reinterpret_cast<const std::uint32_t(*)[3][4]>(corners_.data() + 12 * b), fpos_[0].data(),
                       data_.blocks[b], S ? &block_boxes_[b] : nullptr);
  _mm_sfence();  // the streaming stores are visible before the blocks are traced
  times_.leaf_data_ms = clock_ms(cfg_.clock) - t0;

  t0 = clock_ms(cfg_.clock);
  if (S) refit_subtrees();
  times_.refit_ms = clock_ms(cfg_.clock) - t0;
}

// ---------------------------------------------------------------------------------------------

std::vector<std::string> validate(const TraceData& d, std::size_t triangle_count, bool exact_unions) {
  std::vector<std::string> issues;
  auto fail = [&](std::string s) {
    if (issues.size() < 20) issues.push_back(std::move(s));
  };
  const auto& nodes = d.wide.nodes;
  if (d.triangle_ids.size() != 4 * d.blocks.size()) fail("triangle_ids size is not 4 per block");
  if (nodes.empty()) {
    if (triangle_count != 0) fail("no nodes for " + std::to_string(triangle_count) + " triangles");
    return issues;
  }
  if (d.wide.root >= nodes.size()) {
    fail("root out of range");
    return issues;
  }
  std::vector<std::uint8_t> reached(nodes.size(), 0), tri_seen(triangle_count, 0), lane_used(d.triangle_ids.size(), 0);
  std::vector<std::uint32_t> stack{d.wide.root};
  reached[d.wide.root] = 1;
  while (!stack.empty()) {
    const std::uint32_t i = stack.back();
    stack.pop_back();
    const WideNode& n = nodes[i];
    for (int k = 0; k < 4; ++k) {
      const Box3f box = n.child_box(k);
      const std::string where = "node " + std::to_string(i) + " child " + std::to_string(k);
      if (n.is_empty(k)) {
        if (!box.empty()) fail(where + ": empty slot with a box");
        continue;
      }
      if (!n.is_leaf(k)) {
        const std::uint32_t c = n.child[k];
        if (c >= nodes.size()) {
          fail(where + ": child index " + std::to_string(c) + " out of range");
          continue;
        }
        if (reached[c]++) {
          fail("node " + std::to_string(c) + " is reached twice");
          continue;
        }
        stack.push_back(c);
        Box3f u;
        for (int j = 0; j < 4; ++j) u.extend(nodes[c].child_box(j));
        if (exact_unions ? !(u == box) : !box.contains(u))
          fail(where + ": box is not the union of (does not contain) its children's boxes");
        continue;
      }
      std::vector<LeafRange> leaf_ranges;
      if (n.count[k] & kIndirectLeaf) {
        const std::uint32_t nr = n.count[k] & ~kIndirectLeaf;
        if (static_cast<std::uint64_t>(n.child[k]) + nr > d.ranges.size()) {
          fail(where + ": ranges out of bounds");
          continue;
        }
        leaf_ranges.assign(d.ranges.begin() + n.child[k], d.ranges.begin() + n.child[k] + nr);
      } else {
        leaf_ranges.push_back({n.child[k], (n.count[k] + 3) / 4, n.count[k]});
      }
      for (std::size_t r = 0; r < leaf_ranges.size(); ++r) {
        const LeafRange lr = leaf_ranges[r];
        const std::uint64_t nb = lr.block_count;
        if (lr.triangle_count == 0 || lr.triangle_count > 4 * nb || lr.first_block + nb > d.blocks.size()) {
          fail(where + ": range " + std::to_string(r) + " empty or past the blocks");
          continue;
        }
        std::uint32_t real = 0;
        for (std::uint32_t j = 0; j < 4 * nb; ++j) {
          const std::size_t lane = 4 * std::size_t(lr.first_block) + j;
          const TriBlock& blk = d.blocks[lane / 4];
          const std::uint32_t id = d.triangle_ids[lane];
          if (lane_used[lane]++) fail(where + ": lane " + std::to_string(lane) + " referenced twice");
          if (id == kNoTriangle) {
            if (!std::isnan(blk.v[0][0][lane % 4])) fail(where + ": padding lane not padded");
            continue;
          }
          ++real;
          if (id >= triangle_count) {
            fail(where + ": triangle id " + std::to_string(id) + " out of range");
            continue;
          }
          if (tri_seen[id]++) fail("triangle " + std::to_string(id) + " appears twice");
          for (int c = 0; c < 3; ++c) {
            Box3f pb;
            pb.extend(Vec3f{blk.v[c][0][lane % 4], blk.v[c][1][lane % 4], blk.v[c][2][lane % 4]});
            if (!box.contains(pb)) fail(where + ": triangle " + std::to_string(id) + " corner outside the leaf box");
          }
        }
        if (real != lr.triangle_count) fail(where + ": range " + std::to_string(r) + " holds " + std::to_string(real) +
                                            " triangles, not " + std::to_string(lr.triangle_count));
      }
    }
  }
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (!reached[i]) {
      fail("node " + std::to_string(i) + " is unreachable");
      break;
    }
  for (std::size_t t = 0; t < triangle_count; ++t)
    if (!tri_seen[t]) {
      fail("triangle " + std::to_string(t) + " is in no leaf");
      break;
    }
  return issues;
}

}  // namespace ptc::bvh
