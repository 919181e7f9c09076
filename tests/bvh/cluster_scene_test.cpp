// The cluster scene's layout, against answers computed here: Linear leaves keep each cluster's
// triangles in Morton order of their rest-pose centroids (10-bit cells over the cluster's
// centroid box, interleaved bit by bit in this file, ties by triangle id); the scene's cluster
// order is cluster_visit_order. And the trace frame's origin rule of both scenes.
#include "bvh/cluster_scene.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <chrono>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <stdexcept>
#include <utility>
#include <vector>

#include "bvh/leaf_tables.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/morton_runs.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"
#include "bvh/scene_config.h"
#include "bvh/tracer.h"
#include "bvh/triangle_scene.h"
#include "bvh/validate.h"
#include "bvh/wide_bvh.h"
#include "test_util.h"
#include "common/brute_force.h"
#include "common/same_trace_data.h"

namespace ptc::bvh {
namespace {

// The expected order of one cluster's triangles: (code, id) sorted, code = the cell indices'
// bits interleaved x y z from the top bit down (x most significant).
std::vector<std::uint32_t> expected_cluster_order(const Mesh& m, std::vector<std::uint32_t> ids) {
  std::vector<Vec3> cen;
  Box3 box;
  for (std::uint32_t t : ids) {
    const auto c = m.corners(t);
    cen.push_back((c[0] + c[1] + c[2]) / 3.0);
    box.extend(cen.back());
  }
  const double e = (box.hi - box.lo).maxCoeff();
  const double scale = e > 0 ? 1023.0 / e : 0.0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> keyed;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const Vec3 q = (cen[i] - box.lo) * scale;
    const std::uint32_t cell[3] = {static_cast<std::uint32_t>(q.x()), static_cast<std::uint32_t>(q.y()),
                                   static_cast<std::uint32_t>(q.z())};
    std::uint32_t code = 0;
    for (int bit = 9; bit >= 0; --bit)
      for (int a = 0; a < 3; ++a) code = (code << 1) | ((cell[a] >> bit) & 1u);
    keyed.push_back({code, ids[i]});
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = keyed[i].second;
  return ids;
}

// `rays` rays from random points around the mesh's box towards random points inside it: each
// closest hit of `d` is brute force's (triangle and t), and more than 100 hit.
void expect_brute_force_hits(const TraceData& d, const Mesh& mesh, unsigned seed, int rays, const std::string& what) {
  const Box3 box = mesh.bounds();
  const Vec3 c = box.center(), e = box.extent();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int i = 0; i < rays; ++i) {
    const Vec3 org = c + 1.5 * Vec3(u(rng) * e.x(), u(rng) * e.y(), u(rng) * e.z());
    const Vec3 to = c + 0.4 * Vec3(u(rng) * e.x(), u(rng) * e.y(), u(rng) * e.z());
    const Vec3f dir{float(to.x() - org.x()), float(to.y() - org.y()), float(to.z() - org.z())};
    const Hit b = test::brute_force(mesh, d.frame(), org, dir);
    const Hit h = trace_ray(d, org, dir);
    ASSERT_EQ(h.triangle, b.triangle) << what << " ray " << i;
    ASSERT_EQ(h.t, b.t) << what << " ray " << i;
    hits += b.hit();
  }
  EXPECT_GT(hits, 100) << what;
}

TEST(ClusterScene, LinearLeavesAreInMortonOrderOfRestCentroids) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Mesh moved = test::deformed(m, 0.05);  // the order is the rest pose's, whatever the frame
  for (std::uint32_t run : {7u, 37u, 200u}) {
    const Clustering runs = ptc::morton_runs(m, run);
    for (std::uint32_t groups : {0u, 8u}) {
      SceneConfig cfg = test::two_level_defaults();
      cfg.cluster_group_size = groups;
      cfg.group_trees = GroupTrees::Rebuild;  // (the primitives of bvh() are the clusters)
      cfg.leaf_format = LeafFormatChoice::Blocks;  // (the blocks' lanes are read below)
      ClusterScene s(m, view_of(runs), cfg);
      s.update(moved.positions());
      const std::vector<std::uint32_t> visit = cluster_visit_order(m, view_of(runs), cfg);
      EXPECT_EQ(s.cluster_ids(), visit);
      // The BVH's primitive i is scene cluster prim_order[i], traced through ranges[i].
      const TraceData& d = s.data();
      ASSERT_EQ(d.ranges.size(), runs.cluster_count());
      for (std::size_t i = 0; i < d.ranges.size(); ++i) {
        const std::uint32_t c = s.cluster_ids()[s.bvh().prim_order[i]];
        const std::vector<std::uint32_t> members(runs.triangle_order.begin() + runs.triangle_offsets[c],
                                                 runs.triangle_order.begin() + runs.triangle_offsets[c + 1]);
        const LeafRange r = d.ranges[i];
        ASSERT_EQ(r.triangle_count, members.size());
        const std::vector<std::uint32_t> got(d.triangle_ids.begin() + 4 * std::size_t(r.first_block),
                                             d.triangle_ids.begin() + 4 * std::size_t(r.first_block) + members.size());
        EXPECT_EQ(got, expected_cluster_order(m, members)) << "run " << run << " cluster " << c;
      }
    }
  }
}

using test::expect_same_data;

// With more than one thread the leaf data is written while the tree is built and linked: the
// flat data must be the same bytes at 1, 2 and 4 threads, frame after frame, and the stage times
// must add up to no more than the update's wall time (overlap_ms = what two stages shared; 0 on
// one thread).
// Both per-frame passes: the gather (the file's vertex order) and, on a mesh renumbered with
// cluster_vertex_order, the streamed one, whose fill makes the cluster boxes on one thread while
// more threads fuse the boxes into the conversion and fill the blocks beside the tree: the same
// bytes and boxes either way. Also with the per-frame loops' SSE2 variants (BuildConfig::
// allow_avx2 false: conversion, fills, the 8-wide refit and the build) at 1 and 2 threads, and
// with the tables leaf format.
TEST(ClusterScene, SameDataAtAnyThreadCountAndStagesAddUpToTheWallTime) {
  const Mesh m = test::load_mesh("armadillo.off");  // 13k blocks: more than one fill chunk
  const Clustering runs = ptc::morton_runs(m, 37);
  const std::vector<std::uint32_t> to_old = cluster_vertex_order(m, view_of(runs), {}, test::two_level_defaults());
  const Mesh rm = renumber_vertices(m, to_old);
  const Clustering rruns = renumber_vertices(runs, inverse_permutation(to_old));
  const std::vector<Mesh> frames{test::deformed(m, 0.02), test::deformed(m, 0.06)};
  for (const bool renumbered : {false, true})
  for (GroupTrees trees : {GroupTrees::Rebuild, GroupTrees::Refit})
  for (const auto& [leaf, format] : {std::pair{ClusterLeaf::Linear, LeafFormatChoice::Blocks},
                                     {ClusterLeaf::BlockTree, LeafFormatChoice::Blocks},
                                     {ClusterLeaf::Linear, LeafFormatChoice::Tables}}) {
    std::vector<TraceData> want;
    std::vector<std::vector<Box3f>> want_boxes;
    for (const auto& [threads, avx2] : {std::pair{1, true}, {2, true}, {4, true}, {1, false}, {2, false}}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      SceneConfig cfg = test::two_level_defaults();
      cfg.cluster_leaf = leaf;
      cfg.leaf_format = format;
      cfg.group_trees = trees;
      cfg.build.allow_avx2 = avx2;
      ClusterScene s(renumbered ? rm : m, view_of(renumbered ? rruns : runs), cfg);
      ASSERT_EQ(s.fused_vertex_pass(), renumbered);
      for (std::size_t f = 0; f < frames.size(); ++f) {
        const auto t0 = std::chrono::steady_clock::now();
        s.update(renumbered ? renumber_vertices(frames[f], to_old).positions() : frames[f].positions());
        const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        const std::string what = std::string(renumbered ? "renumbered " : "") + to_string(leaf) + " " +
                                 to_string(format) + " " + to_string(trees) + " threads " + std::to_string(threads) +
                                 (avx2 ? "" : " sse2") + " frame " + std::to_string(f);
        const StageTimes& t = s.times();
        EXPECT_GE(t.overlap_ms, 0.0) << what;
        if (threads == 1) {
          EXPECT_EQ(t.overlap_ms, 0.0) << what;
        }
        if (renumbered) {  // the fill made the boxes, at any thread count, before the tree
          EXPECT_EQ(t.boxes_ms, 0.0) << what;
          EXPECT_EQ(t.overlap_ms, 0.0) << what;
        }
        const std::vector<Box3f> boxes(s.boxes().begin(), s.boxes().end());
        if (threads == 1 && avx2) {
          want_boxes.push_back(boxes);
        } else {
          ASSERT_EQ(boxes.size(), want_boxes[f].size()) << what;
          for (std::size_t c = 0; c < boxes.size(); ++c) ASSERT_EQ(boxes[c], want_boxes[f][c]) << what << " cluster " << c;
        }
        EXPECT_LE(t.overlap_ms, std::min(t.leaf_data_ms, t.build_ms + t.collapse_ms) + 1e-9) << what;
        EXPECT_LE(t.total_ms(), wall + 1e-6) << what;
        const TraceData& d = s.data();
        ASSERT_TRUE(validate(d, m.triangle_count(), false).empty()) << what << test::joined(validate(d, m.triangle_count(), false));
        if (threads == 1 && avx2) {
          want.push_back(d);
          continue;
        }
        expect_same_data(d, want[f], what);
      }
    }
  }
}

// The fill makes the cluster boxes (renumbered mesh) only when every cluster's vertex list is its
// triangles' corners. A view whose list holds one more vertex (a corner of another
// cluster, far away) keeps the fused pass's boxes over the lists: at 1 and 2 threads the same
// boxes, and that cluster's box contains the extra vertex.
TEST(ClusterScene, VertexListsBeyondTheCornersKeepTheListsBoxes) {
  const Mesh m = test::load_mesh("armadillo.off");
  const Clustering runs = ptc::morton_runs(m, 37);
  std::vector<std::uint32_t> verts, voffs{0};
  const std::uint32_t far_vertex = m.triangles()[runs.triangle_order[runs.triangle_offsets[runs.cluster_count() - 1]]][0];
  for (std::size_t c = 0; c < runs.cluster_count(); ++c) {
    for (std::uint32_t i = runs.vertex_offsets[c]; i < runs.vertex_offsets[c + 1]; ++i) verts.push_back(runs.vertices[i]);
    if (c == 0) verts.push_back(far_vertex);
    voffs.push_back(static_cast<std::uint32_t>(verts.size()));
  }
  const ClusterView plus{runs.triangle_order, runs.triangle_offsets, verts, voffs};
  const std::vector<std::uint32_t> to_old = cluster_vertex_order(m, plus, {}, test::two_level_defaults());
  const Mesh rm = renumber_vertices(m, to_old);
  const std::vector<std::uint32_t> to_new = inverse_permutation(to_old);
  std::vector<std::uint32_t> rverts(verts.size());
  for (std::size_t i = 0; i < verts.size(); ++i) rverts[i] = to_new[verts[i]];
  const Clustering rruns = renumber_vertices(runs, to_new);
  const ClusterView rplus{rruns.triangle_order, rruns.triangle_offsets, rverts, voffs};
  const Mesh moved = renumber_vertices(test::deformed(m, 0.05), to_old);
  std::vector<Box3f> want;
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    ClusterScene s(rm, rplus, test::two_level_defaults());
    ASSERT_TRUE(s.fused_vertex_pass());
    s.update(moved.positions());
    EXPECT_GT(s.times().boxes_ms, 0.0) << threads;  // the boxes were made over the lists
    const std::vector<Box3f> boxes(s.boxes().begin(), s.boxes().end());
    const std::size_t i0 = std::find(s.cluster_ids().begin(), s.cluster_ids().end(), 0u) - s.cluster_ids().begin();
    ASSERT_LT(i0, boxes.size());
    const Vec3f p = to_frame(moved.positions()[to_new[far_vertex]], s.data().frame());
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(boxes[i0].lo[a], p[a]) << threads;
      EXPECT_GE(boxes[i0].hi[a], p[a]) << threads;
    }
    if (threads == 1) {
      want = boxes;
      continue;
    }
    ASSERT_EQ(boxes.size(), want.size());
    for (std::size_t c = 0; c < boxes.size(); ++c) ASSERT_EQ(boxes[c], want[c]) << "cluster " << c;
  }
}

// The set-up's passes run in chunks (1024 clusters, 8192 blocks, 512 groups' trees): with
// clusters of nine triangles and groups of two there are several chunks of each. The scene must
// be the same bytes at 1, 2 and 4 threads, and its closest hits those of a loop over all
// triangles (the independent answer for the chunked append of the groups' trees), at the rest
// pose and after the mesh moved.
TEST(ClusterScene, SetUpInChunksIsTheSameAtAnyThreadCountAndHitsLikeBruteForce) {
  const Mesh m = test::load_mesh("armadillo.off");
  const Clustering runs = ptc::morton_runs(m, 9);
  ASSERT_GT(runs.cluster_count(), 4u * 1024u);
  const Mesh moved = test::deformed(m, 0.04);
  SceneConfig cfg = test::two_level_defaults();
  cfg.cluster_group_size = 2;
  cfg.group_trees = GroupTrees::Refit;
  std::vector<TraceData> want;
  for (int threads : {1, 2, 4}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    ClusterScene s(m, view_of(runs), cfg);
    ASSERT_GT(s.group_offsets().size(), 3u * 512u);
    for (int f = 0; f < 2; ++f) {
      if (f == 1) s.update(moved.positions());
      const std::string what = "threads " + std::to_string(threads) + " frame " + std::to_string(f);
      const TraceData& d = s.data();
      ASSERT_TRUE(validate(d, m.triangle_count(), false).empty()) << what;
      if (threads == 1) {
        want.push_back(d);
        const Mesh& mesh = f == 0 ? m : moved;
        ASSERT_NO_FATAL_FAILURE(expect_brute_force_hits(d, mesh, 17u + static_cast<unsigned>(f), 300, what));
        continue;
      }
      expect_same_data(d, want[static_cast<std::size_t>(f)], what);
    }
  }
}

// The clusters under every node of a binary tree, sorted (a leaf: its range of prim_order).
std::vector<std::vector<std::uint32_t>> clusters_under(const Bvh& t) {
  std::vector<std::vector<std::uint32_t>> under(t.nodes.size());
  for (std::size_t i = t.nodes.size(); i-- > 0;) {  // children have larger indices
    const BvhNode& n = t.nodes[i];
    if (n.is_leaf()) {
      under[i].assign(t.prim_order.begin() + n.index, t.prim_order.begin() + n.index + n.count);
    } else {
      under[i] = under[i + 1];
      under[i].insert(under[i].end(), under[n.index].begin(), under[n.index].end());
    }
    std::sort(under[i].begin(), under[i].end());
  }
  return under;
}

// A mesh's triangles and positions with a degenerate triangle (a repeated corner) and a copy of
// another triangle appended.
std::pair<std::vector<Tri>, std::vector<Vec3>> with_bad_triangles(const Mesh& m) {
  std::vector<Tri> tris(m.triangles().begin(), m.triangles().end());
  tris.push_back({tris[5][0], tris[5][0], tris[5][1]});
  tris.push_back(tris[7]);
  return {std::move(tris), {m.positions().begin(), m.positions().end()}};
}

// A scene built once (SceneConfig::built_once, the one BVH of a static scene in ptc trace) keeps no
// per-frame state: it fills its blocks from the lanes' triangles in the mesh's numbering, where a
// scene made for animation gathers them through corner indices in its own vertex order. Its trace
// data must be the bytes of the animated scene's first frame, with the same cluster boxes and
// tree: both leaf modes, plain and two-level builds, the mesh as given and renumbered in the
// clusters' vertex order (the animated scene's fused pass), a view without vertex lists, at 1
// and 2 threads. The mesh has an unreferenced vertex, a triangle with a repeated corner and a
// duplicated triangle; clusters of nine triangles make more than one fill chunk.
//
// One exception, with the plain build: a scene built once takes the rest tree as its tree (no
// second build), while the animated scene builds again over the same boxes in its cluster order.
// The builder keeps a node of two clusters in the order its partitions leave them, so the two
// trees may list the two children of such a node the other way round; every node covers the same
// clusters with the same box, and the tree's cost is the same. The hits are checked against brute
// force then, ray by ray.
TEST(ClusterScene, ASceneBuiltOnceIsTheFirstFrameOfAnAnimatedOne) {
  const Mesh arm = test::load_mesh("armadillo.off");
  auto [tris, pos] = with_bad_triangles(arm);
  pos.push_back(arm.bounds().hi + Vec3(3.0, -1.0, 2.0));  // referenced by no triangle
  const Mesh m(std::move(tris), std::move(pos));
  const Clustering runs = ptc::morton_runs(m, 9);
  const std::vector<std::uint32_t> to_old = cluster_vertex_order(m, view_of(runs), {}, test::two_level_defaults());
  const Mesh rm = renumber_vertices(m, to_old);
  const Clustering rruns = renumber_vertices(runs, inverse_permutation(to_old));
  struct Case {
    const Mesh* mesh;
    const Clustering* cl;
    bool vertex_lists;
    const char* name;
  };
  for (const Case& k : {Case{&m, &runs, true, "as given"}, Case{&rm, &rruns, true, "renumbered"},
                        Case{&m, &runs, false, "no vertex lists"}})
  for (ClusterLeaf leaf : {ClusterLeaf::Linear, ClusterLeaf::BlockTree})
  for (std::uint32_t group : {0u, 4u})
  for (GroupTrees trees : {GroupTrees::Rebuild, GroupTrees::Refit}) {
    if (group == 0 && trees == GroupTrees::Rebuild) continue;  // (the plain build has no group trees)
    SceneConfig cfg = test::two_level_defaults();
    cfg.cluster_leaf = leaf;
    cfg.cluster_group_size = group;
    cfg.group_trees = trees;
    cfg.leaf_format = LeafFormatChoice::Blocks;  // (a scene built once keeps blocks: its animated twin too)
    ClusterView v = view_of(*k.cl);
    if (!k.vertex_lists) v.vertices = {}, v.vertex_offsets = {};
    const std::string what = std::string(k.name) + " " + to_string(leaf) + " groups " + std::to_string(group) + " " +
                             to_string(trees);
    const ClusterScene animated(*k.mesh, v, cfg);
    // (both per-frame passes of the animated scene are covered: the fused one and the gather)
    ASSERT_EQ(animated.fused_vertex_pass(), std::string(k.name) == "renumbered") << what;
    cfg.built_once = true;
    for (int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      ClusterScene once(*k.mesh, v, cfg);
      const std::string w = what + " threads " + std::to_string(threads);
      if (group == 0) {  // the rest tree (see above): the same tree up to the children's order in nodes of two
        const TraceData &d = once.data(), &a = animated.data();
        ASSERT_EQ(d.blocks.size(), a.blocks.size()) << w;
        EXPECT_TRUE(test::same_bytes(d.blocks.data(), a.blocks.data(), a.blocks.size())) << w;
        EXPECT_TRUE(std::equal(d.triangle_ids.begin(), d.triangle_ids.end(), a.triangle_ids.begin(), a.triangle_ids.end())) << w;
        ASSERT_EQ(d.wide8.nodes.size(), a.wide8.nodes.size()) << w;
        const Bvh &tb = once.bvh(), &ta = animated.bvh();
        ASSERT_EQ(tb.nodes.size(), ta.nodes.size()) << w;
        const auto ub = clusters_under(tb), ua = clusters_under(ta);
        int swapped = 0;
        for (std::size_t i = 0; i < tb.nodes.size(); ++i) {
          ASSERT_EQ(tb.nodes[i].is_leaf(), ta.nodes[i].is_leaf()) << w << " node " << i;
          if (tb.nodes[i].is_leaf()) continue;  // (checked with its parent)
          ASSERT_EQ(ub[i], ua[i]) << w << " node " << i;
          ASSERT_EQ(tb.nodes[i].bounds, ta.nodes[i].bounds) << w << " node " << i;
          const std::size_t l = i + 1, r = tb.nodes[i].index;
          ASSERT_EQ(r, ta.nodes[i].index) << w << " node " << i;
          const bool same = ub[l] == ua[l] && ub[r] == ua[r] && tb.nodes[l].bounds == ta.nodes[l].bounds &&
                            tb.nodes[r].bounds == ta.nodes[r].bounds;
          const bool two_swapped = tb.nodes[l].is_leaf() && tb.nodes[r].is_leaf() && ub[l] == ua[r] && ub[r] == ua[l] &&
                                   tb.nodes[l].bounds == ta.nodes[r].bounds && tb.nodes[r].bounds == ta.nodes[l].bounds;
          ASSERT_TRUE(same || two_swapped) << w << " node " << i;
          swapped += !same;
        }
        EXPECT_LT(swapped, 10) << w;
        ASSERT_NO_FATAL_FAILURE(expect_brute_force_hits(d, *k.mesh, 5u, 400, w));
      } else {
        expect_same_data(once.data(), animated.data(), w);
      }
      ASSERT_EQ(once.boxes().size(), animated.boxes().size()) << w;
      for (std::size_t c = 0; c < once.boxes().size(); ++c) ASSERT_EQ(once.boxes()[c], animated.boxes()[c]) << w << " cluster " << c;
      EXPECT_EQ(once.cluster_ids(), animated.cluster_ids()) << w;
      EXPECT_EQ(once.sah_cost(), animated.sah_cost()) << w;
      EXPECT_EQ(once.subtree_nodes(), animated.subtree_nodes()) << w;
      EXPECT_FALSE(once.fused_vertex_pass()) << w;
      EXPECT_TRUE(validate(once.data(), k.mesh->triangle_count(), false).empty()) << w;
      EXPECT_THROW(once.update(k.mesh->positions()), std::logic_error) << w;
    }
  }
  // The sweep builder (plain build), and an empty mesh.
  SceneConfig sweep = test::two_level_defaults();
  sweep.builder = SahBuilder::Sweep;
  sweep.cluster_group_size = 0;
  const ClusterScene animated(m, view_of(runs), sweep);
  sweep.built_once = true;
  expect_same_data(ClusterScene(m, view_of(runs), sweep).data(), animated.data(), "sweep");
  const Mesh empty;
  const Clustering none;
  SceneConfig cfg = test::two_level_defaults();
  const ClusterScene empty_animated(empty, view_of(none), cfg);
  cfg.built_once = true;
  const ClusterScene empty_once(empty, view_of(none), cfg);
  expect_same_data(empty_once.data(), empty_animated.data(), "empty mesh");
  EXPECT_TRUE(empty_once.data().blocks.empty());
}

// LeafFormat::Tables against the blocks (a second layout of the same triangles): on a mesh with
// a degenerate triangle, a duplicated one and two fans of 40 triangles around one vertex (a
// non-manifold vertex; clusters beyond 32 vertices, so several groups a cluster), clustered in
// runs of 9 and of 60 triangles, in every per-frame mode (the input's vertex order, renumbered,
// built once; plain, two-level, leaves of several clusters) and at two frames: validate() finds
// nothing, the cluster boxes and trees are the blocks' scene's, and a batch of rays gives the
// same closest hits bit for bit (t, u, v, triangle and the counters) with single rays and
// packets at every instruction set, the same rays occluded, and brute force's hits.
TEST(ClusterScene, TheTablesFormatTracesTheBlocksHits) {
  const Mesh arm = test::load_mesh("armadillo.off");
  auto [tris, pos] = with_bad_triangles(arm);
  const Box3 b = arm.bounds();
  const auto hub = static_cast<std::uint32_t>(pos.size());
  pos.push_back(b.center() + Vec3(0.0, 0.0, 0.6 * b.extent().z()));
  for (int fan = 0; fan < 2; ++fan) {
    const auto first = static_cast<std::uint32_t>(pos.size());
    for (int i = 0; i <= 40; ++i) {
      const double a = 0.05 * i;
      const Vec3 dir = fan == 0 ? Vec3(std::cos(a), std::sin(a), 0.1) : Vec3(0.1, std::cos(a), std::sin(a));
      pos.push_back(pos[hub] + 0.2 * b.extent().norm() * dir);
    }
    for (std::uint32_t i = 0; i < 40; ++i) tris.push_back({hub, first + i, first + i + 1});
  }
  const Mesh m(std::move(tris), std::move(pos));
  const Mesh moved = test::deformed(m, 0.04);
  for (std::uint32_t run : {9u, 60u}) {
    const Clustering runs = ptc::morton_runs(m, run);
    const std::vector<std::uint32_t> to_old = cluster_vertex_order(m, view_of(runs), {}, test::two_level_defaults());
    const Mesh rm = renumber_vertices(m, to_old), rmoved = renumber_vertices(moved, to_old);
    const Clustering rruns = renumber_vertices(runs, inverse_permutation(to_old));
    for (int mode = 0; mode < 3; ++mode)  // input order, renumbered (the fused pass), built once
    for (int build = 0; build < 3; ++build) {  // plain, two-level with fixed group trees, leaves of several clusters
      const bool renumbered = mode == 1;
      const Mesh& mesh = renumbered ? rm : m;
      const Mesh& next = renumbered ? rmoved : moved;
      const ClusterView v = view_of(renumbered ? rruns : runs);
      SceneConfig cfg = test::two_level_defaults();
      cfg.cluster_group_size = build == 1 ? 4 : 0;
      if (build == 2) cfg.build.max_leaf_size = 4, cfg.build.cost.traversal = 50.0;
      cfg.built_once = mode == 2;
      cfg.leaf_format = LeafFormatChoice::Blocks;
      ClusterScene blocks(mesh, v, cfg);
      cfg.leaf_format = LeafFormatChoice::Tables;
      ClusterScene tables(mesh, v, cfg);
      const std::string what = "runs of " + std::to_string(run) + " mode " + std::to_string(mode) + " build " +
                               std::to_string(build);
      EXPECT_EQ(blocks.fused_vertex_pass(), renumbered) << what;
      for (int f = 0; f < (mode == 2 ? 1 : 2); ++f) {
        if (f == 1) {
          blocks.update(next.positions());
          tables.update(next.positions());
        }
        const Mesh& now = f == 0 ? mesh : next;
        const std::string w = what + " frame " + std::to_string(f);
        const TraceData &dt = tables.data(), &db = blocks.data();
        ASSERT_EQ(dt.format, LeafFormat::Tables) << w;
        ASSERT_TRUE(dt.blocks.empty()) << w;
        const auto issues = validate(dt, now.triangle_count(), false);
        ASSERT_TRUE(issues.empty()) << w << ": " << issues.front();
        if (run == 60) {
          EXPECT_GT(dt.tables.size(), tables.boxes().size()) << w << ": clusters of several groups";
          // (groups of more than 16 vertices, whose tests read the chunks from slot 16 on)
          std::size_t upper = 0;
          for (const TableGroup& g : dt.tables)
            for (int j = 0; j < kTableTests; ++j) upper += 8 * j < static_cast<int>(g.count) && g.pair[j] != 0;
          EXPECT_GT(upper, 10u) << w << ": tests on chunks beyond the first two";
        }
        // leaf_shape against counts made here: each group's distinct mesh vertices from its
        // triangles' ids, its lanes in runs of eight; the blocks' lanes four a block.
        const LeafShape st = leaf_shape(dt), sb = leaf_shape(db);
        std::size_t vertices = 0, lanes = 0;
        for (std::size_t g = 0; g < dt.tables.size(); ++g) {
          std::vector<std::uint32_t> vs;
          std::size_t n = 0;
          for (std::size_t l = 0; l < kTableSlots; ++l) {
            const std::uint32_t id = dt.triangle_ids[kTableSlots * g + l];
            if (id == kNoTriangle) continue;
            ++n;
            for (const std::uint32_t x : now.triangles()[id]) vs.push_back(x);
          }
          std::sort(vs.begin(), vs.end());
          vertices += static_cast<std::size_t>(std::unique(vs.begin(), vs.end()) - vs.begin());
          lanes += 8 * ((n + 7) / 8);
        }
        EXPECT_EQ(st.format, LeafFormat::Tables) << w;
        EXPECT_EQ(st.units, dt.tables.size()) << w;
        EXPECT_EQ(st.triangles, now.triangle_count()) << w;
        EXPECT_EQ(st.vertices, vertices) << w;
        EXPECT_EQ(st.lanes, lanes) << w;
        EXPECT_EQ(sb.format, LeafFormat::Blocks) << w;
        EXPECT_EQ(sb.units, db.blocks.size()) << w;
        EXPECT_EQ(sb.triangles, now.triangle_count()) << w;
        EXPECT_EQ(sb.vertices, 0u) << w;
        EXPECT_EQ(sb.lanes, 4 * db.blocks.size()) << w;
        ASSERT_EQ(tables.boxes().size(), blocks.boxes().size()) << w;
        for (std::size_t c = 0; c < tables.boxes().size(); ++c) ASSERT_EQ(tables.boxes()[c], blocks.boxes()[c]) << w;
        ASSERT_EQ(dt.wide8.nodes.size(), db.wide8.nodes.size()) << w;
        EXPECT_EQ(tables.sah_cost(), blocks.sah_cost()) << w;
        if (mode == 0 && build == 0) {
          ASSERT_NO_FATAL_FAILURE(expect_brute_force_hits(dt, now, 23u + static_cast<unsigned>(f), 300, w));
        }
        // Rays from around the mesh into it, and from the fans' hub through their rims.
        RayBatch rays;
        std::mt19937 rng(7u + static_cast<unsigned>(f));
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        const Box3 box = now.bounds();
        const Vec3 c = box.center(), e = box.extent();
        rays.resize(2003);
        for (std::size_t i = 0; i < rays.size(); ++i) {
          const Vec3 org = i % 3 == 0 ? c + 1.5 * Vec3(u(rng) * e.x(), u(rng) * e.y(), u(rng) * e.z())
                                      : c + 0.3 * Vec3(u(rng) * e.x(), u(rng) * e.y(), u(rng) * e.z());
          const Vec3 to = i % 7 == 0 ? now.position(static_cast<std::uint32_t>(now.vertex_count() - 1 - i % 80))
                                     : c + 0.4 * Vec3(u(rng) * e.x(), u(rng) * e.y(), u(rng) * e.z());
          rays.set(i, org, {float(to.x() - org.x()), float(to.y() - org.y()), float(to.z() - org.z())});
        }
        for (HitMode hm : {HitMode::Closest, HitMode::Any})
          for (TraceIsa isa : {TraceIsa::Sse2, TraceIsa::Avx2, TraceIsa::Avx512Vl, TraceIsa::Avx512})
            for (bool packets : {false, true}) {
              if (packets && isa == TraceIsa::Sse2) continue;
              TraceOptions opt;
              opt.mode = hm, opt.isa = isa, opt.packets = packets, opt.threads = 1;
              HitBatch hb, ht;
              const TraceTotals tb = trace(db, rays, hb, opt), tt = trace(dt, rays, ht, opt);
              const std::string x = w + " " + to_string(isa) + (packets ? " packets" : " single") +
                                    (hm == HitMode::Any ? " any" : " closest");
              EXPECT_EQ(tt.hits, tb.hits) << x;
              EXPECT_GT(tt.hits, 300u) << x;
              for (std::size_t i = 0; i < rays.size(); ++i) {
                ASSERT_EQ(ht.triangle[i] != kNoTriangle, hb.triangle[i] != kNoTriangle) << x << " ray " << i;
                if (hm == HitMode::Any) continue;
                ASSERT_EQ(ht.triangle[i], hb.triangle[i]) << x << " ray " << i;
                ASSERT_EQ(std::memcmp(&ht.t[i], &hb.t[i], 4), 0) << x << " ray " << i;
                ASSERT_EQ(std::memcmp(&ht.u[i], &hb.u[i], 4), 0) << x << " ray " << i;
                ASSERT_EQ(std::memcmp(&ht.v[i], &hb.v[i], 4), 0) << x << " ray " << i;
                ASSERT_EQ(ht.nodes_visited[i], hb.nodes_visited[i]) << x << " ray " << i;
                ASSERT_EQ(ht.triangles_tested[i], hb.triangles_tested[i]) << x << " ray " << i;
              }
            }
      }
    }
  }
  // Block trees keep blocks: the tables are refused with them.
  SceneConfig bad = test::two_level_defaults();
  bad.cluster_leaf = ClusterLeaf::BlockTree;
  bad.build.max_leaf_size = 1;
  bad.leaf_format = LeafFormatChoice::Tables;
  const Clustering runs = ptc::morton_runs(m, 9);
  EXPECT_THROW(ClusterScene(m, view_of(runs), bad), std::invalid_argument);
}

// LeafFormatChoice::Auto against bytes counted here from each clustering (per cluster its
// triangles and its triangles' distinct corners): the blocks' count must be the bytes of the
// blocks a scene lays out, the tables' count at most those of its table groups, and Auto must
// take the tables exactly when they count at most kAutoTablesMaxShare of the blocks, with the
// same data as the explicit format. The cases fall on both sides: connected clusters of a mesh
// (tables), runs of four triangles and a triangle soup (blocks); a scene built once and block
// trees keep blocks whatever the bytes. The scene's own estimate must be these counts, also from
// a view without vertex lists (whose corners it then counts once each).
TEST(ClusterScene, AutoLeafFormatFollowsTheEstimatedBytes) {
  const Mesh m = test::load_mesh("bunny00.off");
  std::vector<Tri> st;
  std::vector<Vec3> sp;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const auto c = m.corners(t);
    const auto b = static_cast<std::uint32_t>(sp.size());
    st.push_back({b, b + 1, b + 2});
    for (int k = 0; k < 3; ++k) sp.push_back(c[k]);
  }
  const Mesh soup(st, sp);
  ClusterConfig cc;
  cc.method = ClusterMethod::Growth;
  cc.objective = ObjectiveKind::Acc;
  cc.max_count = 32;
  cc.max_size = 32;
  struct Case {
    const Mesh* mesh;
    Clustering cl;
    bool tables;
    const char* what;
  };
  std::vector<Case> cases;
  cases.push_back({&m, cluster_mesh(m, cc), true, "growth 32"});
  cc.max_count = 50;
  cc.max_size = 50;
  cases.push_back({&m, cluster_mesh(m, cc), true, "growth 50"});
  cases.push_back({&m, ptc::morton_runs(m, 4), false, "runs of 4"});
  cases.push_back({&soup, ptc::morton_runs(soup, 32), false, "soup, runs of 32"});
  for (const Case& k : cases) {
    std::uint64_t blocks = 0, tables = 0;
    for (std::size_t c = 0; c < k.cl.cluster_count(); ++c) {
      std::vector<std::uint32_t> corners;
      for (const std::uint32_t t : k.cl.triangles_of(c))
        for (const std::uint32_t v : k.mesh->triangles()[t]) corners.push_back(v);
      std::sort(corners.begin(), corners.end());
      const std::uint64_t n = k.cl.triangles_of(c).size();
      const auto v = static_cast<std::uint64_t>(std::unique(corners.begin(), corners.end()) - corners.begin());
      blocks += 144 * ((n + 3) / 4);
      tables += 512 * ((std::max(n, v) + 31) / 32);
    }
    SceneConfig cfg = test::two_level_defaults();
    cfg.leaf_format = LeafFormatChoice::Blocks;
    const ClusterScene b(*k.mesh, view_of(k.cl), cfg);
    cfg.leaf_format = LeafFormatChoice::Tables;
    const ClusterScene t(*k.mesh, view_of(k.cl), cfg);
    cfg.leaf_format = LeafFormatChoice::Auto;
    const ClusterScene a(*k.mesh, view_of(k.cl), cfg);
    EXPECT_EQ(blocks, b.data().blocks.size() * sizeof(TriBlock)) << k.what;
    EXPECT_EQ(a.leaf_bytes_estimate().blocks, blocks) << k.what;
    EXPECT_EQ(a.leaf_bytes_estimate().tables, tables) << k.what;
    {  // a view without vertex lists (the corners serve): the same estimate and choice
      ClusterView bare = view_of(k.cl);
      bare.vertices = {}, bare.vertex_offsets = {};
      const ClusterScene nl(*k.mesh, bare, cfg);
      EXPECT_EQ(nl.leaf_bytes_estimate().blocks, blocks) << k.what;
      EXPECT_EQ(nl.leaf_bytes_estimate().tables, tables) << k.what;
      EXPECT_EQ(nl.data().format, a.data().format) << k.what;
    }
    EXPECT_LE(tables, t.data().tables.size() * sizeof(TableGroup)) << k.what;
    const bool want = static_cast<double>(tables) <= kAutoTablesMaxShare * static_cast<double>(blocks);
    EXPECT_EQ(want, k.tables) << k.what << ": " << tables << " against " << blocks << " bytes";
    ASSERT_EQ(a.data().format, want ? LeafFormat::Tables : LeafFormat::Blocks) << k.what;
    test::expect_same_data(a.data(), want ? t.data() : b.data(), k.what);
    // Built once, or block trees: blocks.
    cfg.built_once = true;
    EXPECT_EQ(ClusterScene(*k.mesh, view_of(k.cl), cfg).data().format, LeafFormat::Blocks) << k.what;
    cfg.built_once = false;
    cfg.cluster_leaf = ClusterLeaf::BlockTree;
    cfg.build.max_leaf_size = 1;
    EXPECT_EQ(ClusterScene(*k.mesh, view_of(k.cl), cfg).data().format, LeafFormat::Blocks) << k.what;
  }
}

// GroupTrees::Refit builds each group's tree once, over the rest-pose cluster boxes, with the
// same builder settings the two-level rebuild uses inside a group, and builds the top over the
// same group records: at the rest pose its tree over the clusters (cluster_tree(): the top with
// the groups' trees spliced in) must be the rebuilt one, node for node and leaf for leaf, with
// the same cost.
TEST(ClusterScene, FixedGroupTreesAtTheRestPoseAreTheRebuiltTree) {
  const Mesh m = test::load_mesh("armadillo.off");
  for (std::uint32_t run : {9u, 37u})
    for (std::uint32_t groups : {2u, 3u, 8u, 16u}) {
      const std::string what = "run " + std::to_string(run) + " groups " + std::to_string(groups);
      const Clustering runs = ptc::morton_runs(m, run);
      SceneConfig cfg = test::two_level_defaults();
      cfg.cluster_group_size = groups;
      cfg.group_trees = GroupTrees::Rebuild;
      const ClusterScene rebuilt(m, view_of(runs), cfg);
      cfg.group_trees = GroupTrees::Refit;
      const ClusterScene fixed(m, view_of(runs), cfg);
      ASSERT_EQ(fixed.group_offsets(), rebuilt.group_offsets()) << what;
      ASSERT_GT(fixed.group_offsets().size(), 3u) << what;
      EXPECT_EQ(fixed.bvh().primitive_count(), fixed.group_offsets().size() - 1) << what;  // one record per group
      const Bvh a = fixed.cluster_tree(), &b = rebuilt.bvh();
      ASSERT_EQ(a.nodes.size(), b.nodes.size()) << what;
      // (The leaves may refer to their primitives at other positions of prim_order: compare the
      // primitives a leaf holds.)
      for (std::size_t i = 0; i < a.nodes.size(); ++i) {
        const BvhNode &x = a.nodes[i], &y = b.nodes[i];
        ASSERT_TRUE(x.count == y.count && x.bounds == y.bounds && (x.is_leaf() || x.index == y.index)) << what << " node " << i;
        for (std::uint32_t k = 0; k < x.count; ++k)
          ASSERT_EQ(a.prim_order[x.index + k], b.prim_order[y.index + k]) << what << " node " << i;
      }
      EXPECT_NEAR(fixed.sah_cost(), rebuilt.sah_cost(), 1e-9 * rebuilt.sah_cost()) << what;
    }
}

// The top's 8-wide nodes are collapsed straight from the binary tree (collapse_top8); they must
// be, node for node, what the two passes it replaced make: regroup_to_8(collapse_to_wide(bvh)),
// with the leaves mapped to the clusters' blocks (one cluster) or ranges (several). Plain build
// (the top is the whole tree), leaves of one or several clusters, a single-cluster tree (a root
// that is a leaf), after motion.
TEST(ClusterScene, TheTopIsTheRegroupedCollapseOfTheBinaryTree) {
  const Mesh m = test::load_mesh("armadillo.off");
  for (std::uint32_t run : {7u, 23u, 1000000u})
    for (std::uint32_t leaf : {1u, 4u}) {
      SceneConfig cfg = test::two_level_defaults();
      cfg.cluster_group_size = 0;
      cfg.build.max_leaf_size = leaf;
      if (leaf > 1) cfg.build.cost.traversal = 1000.0;  // leaves as large as allowed
      const Clustering runs = ptc::morton_runs(m, run);
      ClusterScene s(m, view_of(runs), cfg);
      for (double amp : {0.0, 0.1}) {
        if (amp > 0) s.update(test::deformed(m, amp).positions());
        const std::string what = "runs of " + std::to_string(run) + " leaf " + std::to_string(leaf) + " amplitude " +
                                 std::to_string(amp);
        const TraceData& d = s.data();
        ASSERT_EQ(s.subtree_nodes(), 0u) << what;
        WideBvh8 want;
        regroup_to_8(collapse_to_wide(s.bvh()), want);
        ASSERT_EQ(d.wide8.nodes.size(), want.nodes.size()) << what;
        ASSERT_EQ(d.wide8.root, want.root) << what;
        ASSERT_EQ(d.wide8.depth, want.depth) << what;
        std::size_t several = 0;
        for (std::size_t i = 0; i < want.nodes.size(); ++i) {
          const WideNode8 &a = d.wide8.nodes[i], &b = want.nodes[i];
          ASSERT_EQ(std::memcmp(a.bounds, b.bounds, sizeof a.bounds), 0) << what << " node " << i;
          for (int k = 0; k < 8; ++k) {
            const std::string at = what + " node " + std::to_string(i) + " slot " + std::to_string(k);
            if (b.is_empty(k)) {
              ASSERT_TRUE(a.is_empty(k)) << at;
            } else if (!b.is_leaf(k)) {
              ASSERT_TRUE(a.count[k] == 0 && a.child[k] == b.child[k]) << at;
            } else if (b.count[k] == 1) {  // one cluster: a direct leaf of its blocks
              const LeafRange& r = d.ranges[b.child[k]];
              ASSERT_TRUE(a.child[k] == r.first_block && a.count[k] == r.triangle_count) << at;
            } else {
              ++several;
              ASSERT_TRUE(a.child[k] == b.child[k] && a.count[k] == (b.count[k] | kIndirectLeaf)) << at;
            }
          }
        }
        if (leaf > 1 && run < 1000000u) {
          EXPECT_GT(several, 0u) << what;
        }
        if (run == 1000000u) {
          EXPECT_EQ(want.nodes.size(), 1u) << what;  // (one cluster: the root is a leaf)
        }
      }
    }
}

// After the mesh moves, the fixed trees are refitted: every inner box of the traced tree is the
// exact union of its children's (validate with exact unions, linear leaves), every leaf child of
// the kept nodes has its cluster's box of the frame, those nodes keep the rest pose's children
// (only boxes change), and the tree over the clusters is a valid BVH with its SAH cost
// (Tracer.AccClustersMatchBruteForce checks the hits against brute force).
TEST(ClusterScene, FixedGroupTreesAreRefittedExactly) {
  const Mesh m = test::load_mesh("armadillo.off");
  const Clustering runs = ptc::morton_runs(m, 23);
  SceneConfig cfg = test::two_level_defaults();
  cfg.group_trees = GroupTrees::Refit;
  cfg.leaf_format = LeafFormatChoice::Blocks;  // (block boxes are compared below)
  ClusterScene s(m, view_of(runs), cfg);
  const std::size_t S = s.subtree_nodes();
  ASSERT_GT(S, 100u);
  const std::vector<WideNode8> rest(s.data().wide8.nodes.begin(), s.data().wide8.nodes.begin() + S);
  // The scene cluster whose blocks start at a block: the clustering's cluster of its first lane.
  std::vector<std::uint32_t> scene_of(runs.cluster_count());
  for (std::size_t i = 0; i < s.cluster_ids().size(); ++i) scene_of[s.cluster_ids()[i]] = static_cast<std::uint32_t>(i);
  std::vector<std::uint32_t> cluster_of_triangle(m.triangle_count());
  for (std::size_t c = 0; c < runs.cluster_count(); ++c)
    for (std::uint32_t t : runs.triangles_of(c)) cluster_of_triangle[t] = static_cast<std::uint32_t>(c);
  for (double amp : {0.03, 0.12}) {
    const Mesh moved = test::deformed(m, amp);
    s.update(moved.positions());
    const std::string what = "amplitude " + std::to_string(amp);
    const TraceData& d = s.data();
    const auto issues = validate(d, m.triangle_count(), true);
    ASSERT_TRUE(issues.empty()) << what << test::joined(issues);
    std::size_t leaves = 0;
    for (std::size_t i = 0; i < S; ++i) {
      const WideNode8& n = d.wide8.nodes[i];
      for (int k = 0; k < 8; ++k) {
        ASSERT_TRUE(n.child[k] == rest[i].child[k] && n.count[k] == rest[i].count[k]) << what << " node " << i;
        if (!n.is_leaf(k) || (n.count[k] & kIndirectLeaf)) continue;
        const std::uint32_t c = scene_of[cluster_of_triangle[d.triangle_ids[4 * std::size_t(n.child[k])]]];
        ASSERT_EQ(n.child_box(k), s.boxes()[c]) << what << " node " << i << " slot " << k;
        ++leaves;
      }
    }
    EXPECT_GT(leaves, S) << what;
    const Bvh t = s.cluster_tree();
    ValidateOptions vo;
    vo.weights = s.weights();
    vo.model = cfg.build.cost;
    const auto tree_issues = validate(t, s.boxes(), vo);  // (and its cost against sah_cost())
    ASSERT_TRUE(tree_issues.empty()) << what << test::joined(tree_issues);
  }
  EXPECT_STREQ(to_string(GroupTrees::Refit), "refit");
  EXPECT_EQ(parse_group_trees("rebuild"), GroupTrees::Rebuild);
  EXPECT_EQ(parse_group_trees("refit"), GroupTrees::Refit);
  EXPECT_FALSE(parse_group_trees("Refit"));
}

// The swelling recomputed here, for a scene made at `rest` and now at `now`: each cluster's box
// from its triangles' corners in the trace frame `f` (to_frame, as the scene's floats), its half
// area (xy + yz + zx) in double, over the triangles' areas at `rest` in double, scaled into the
// frame.
double expected_swelling(const Mesh& rest, const Mesh& now, const Clustering& cl, const FrameMap& f) {
  double tri = 0, box = 0;
  for (std::size_t t = 0; t < rest.triangle_count(); ++t) {
    const auto c = rest.corners(t);
    tri += 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).norm();
  }
  tri *= f.scale * f.scale;
  for (std::size_t k = 0; k + 1 < cl.triangle_offsets.size(); ++k) {
    Box3f b;
    for (std::uint32_t i = cl.triangle_offsets[k]; i < cl.triangle_offsets[k + 1]; ++i)
      for (const Vec3& p : now.corners(cl.triangle_order[i])) {
        const Vec3f q = to_frame(p, f);
        for (int a = 0; a < 3; ++a) b.lo[a] = std::min(b.lo[a], q[a]), b.hi[a] = std::max(b.hi[a], q[a]);
      }
    const double ex = double(b.hi[0]) - b.lo[0], ey = double(b.hi[1]) - b.lo[1], ez = double(b.hi[2]) - b.lo[2];
    box += ex * ey + ey * ez + ez * ex;
  }
  return box / tri;
}

// The mesh with every vertex moved by its own seeded random offset of up to `amplitude` box
// diagonals per axis: the triangles stretch and the clusters' boxes swell.
Mesh scattered(const Mesh& m, double amplitude, unsigned seed) {
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  const double d = m.bounds().extent().norm();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Vec3& q : p) q += amplitude * d * Vec3(u(rng), u(rng), u(rng));
  return m.with_positions(std::move(p));
}

// ClusterScene::swelling() against the recomputation above, frame by frame, for the gathered and
// the fused (renumbered) per-frame pass and every leaf kind (the boxes come from the box pass,
// the blocks' fill or the tables' fill); and the triangle fallback (SceneConfig::
// fallback_swelling) with a threshold between the rest pose's swelling and a scattered frame's:
// on exactly the frames above it the scene traces a triangle BVH (blocks, in the cluster BVH's
// trace frame, its update in StageTimes::fallback_ms within the update's wall time), elsewhere
// the cluster BVH (data() is cluster_data()); every frame's traced data is valid and hits like
// brute force, the same bytes at one and two threads, and the cluster BVH, still updated under
// the fallback, stays valid. Off (the default), no frame falls back.
TEST(ClusterScene, SwellingAndTheTriangleFallback) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering cl = ptc::morton_runs(m, 24);
  const std::vector<std::uint32_t> to_old = cluster_vertex_order(m, view_of(cl), {}, test::two_level_defaults());
  const Mesh rm = renumber_vertices(m, to_old);
  const Clustering rcl = renumber_vertices(cl, inverse_permutation(to_old));
  const std::vector<Mesh> frames{m, scattered(m, 0.06, 5u), test::deformed(m, 0.05), scattered(m, 0.002, 6u),
                                 scattered(m, 0.1, 7u), m};
  struct Case {
    bool renumbered;
    std::uint32_t groups;
    ClusterLeaf leaf;
    LeafFormatChoice format;
    bool fallback;  // (the fallback's checks, with brute force, on two of them)
  };
  const Case cases[] = {{false, 0, ClusterLeaf::Linear, LeafFormatChoice::Blocks, true},
                        {true, 8, ClusterLeaf::Linear, LeafFormatChoice::Tables, true},
                        {false, 8, ClusterLeaf::Linear, LeafFormatChoice::Tables, false},
                        {true, 8, ClusterLeaf::Linear, LeafFormatChoice::Blocks, false},
                        {false, 8, ClusterLeaf::BlockTree, LeafFormatChoice::Blocks, false},
                        {true, 0, ClusterLeaf::BlockTree, LeafFormatChoice::Blocks, false}};
  for (const Case& k : cases) {
    const std::string name = std::string(k.renumbered ? "renumbered " : "") + to_string(k.leaf) + " " +
                             to_string(k.format) + " groups " + std::to_string(k.groups);
    const Mesh& mesh = k.renumbered ? rm : m;
    const Clustering& clusters = k.renumbered ? rcl : cl;
    auto positions = [&](std::size_t f) { return k.renumbered ? renumber_vertices(frames[f], to_old) : frames[f]; };
    SceneConfig cfg = test::two_level_defaults();
    cfg.cluster_group_size = k.groups;
    cfg.cluster_leaf = k.leaf;
    cfg.leaf_format = k.format;
    std::vector<double> sw;
    {
      ClusterScene off(mesh, view_of(clusters), cfg);  // (fallback_swelling 0: the default)
      ASSERT_EQ(off.fused_vertex_pass(), k.renumbered) << name;
      for (std::size_t f = 0; f < frames.size(); ++f) {
        const Mesh now = positions(f);
        if (f > 0) off.update(now.positions());
        sw.push_back(off.swelling());
        const double want = expected_swelling(mesh, now, clusters, off.cluster_data().frame());
        EXPECT_NEAR(sw.back(), want, 1e-4 * want) << name << " frame " << f;
        EXPECT_FALSE(off.fallback_active());
        EXPECT_EQ(&off.data(), &off.cluster_data());
        EXPECT_EQ(off.times().fallback_ms, 0.0);
      }
    }
    ASSERT_GT(sw[0], 1.0) << name;
    ASSERT_GT(sw[1], 4.0 * sw[0]) << name;  // (the scattered frames swell, the smooth one hardly)
    ASSERT_LT(sw[2], 1.5 * sw[0]) << name;
    if (!k.fallback) continue;
    cfg.fallback_swelling = std::sqrt(sw[0] * sw[1]);
    int fell = 0, kept = 0, refitted = 0;
    // The fallback rebuilt on every frame, kept and refitted on every frame after its first (a
    // limit no growth reaches: frame 4 refits frame 1's tree to its own positions), and the
    // commands' default limit (whatever it keeps, the hits are brute force's).
    for (const double refit : {0.0, 1e9, kAutoFallbackRefitGrowth}) {
      cfg.refit_growth = refit;
      std::vector<TraceData> first;  // each frame's traced data at one thread
      for (int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        ClusterScene s(mesh, view_of(clusters), cfg);
        bool made = false;  // (the fallback exists: its next frame is a refit with the limit on)
        for (std::size_t f = 0; f < frames.size(); ++f) {
          const Mesh now = positions(f);
          double wall = 0;
          if (f > 0) {
            const auto t0 = std::chrono::steady_clock::now();
            s.update(now.positions());
            wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
          }
          const std::string what = name + " threads " + std::to_string(threads) + " frame " + std::to_string(f);
          EXPECT_EQ(s.swelling(), sw[f]) << what;  // (the same boxes at any thread count)
          const bool above = sw[f] > cfg.fallback_swelling;
          ASSERT_EQ(s.fallback_active(), above) << what;
          const TraceData& d = s.data();
          if (above) {
            ++fell;
            if (refit != kAutoFallbackRefitGrowth) {
              ASSERT_EQ(s.fallback_scene()->refitted(), refit > 0 && made) << what;
            }
            refitted += s.fallback_scene()->refitted() ? 1 : 0;
            made = true;
            EXPECT_NE(&d, &s.cluster_data()) << what;
            EXPECT_EQ(d.format, LeafFormat::Blocks) << what;
            EXPECT_GT(s.times().fallback_ms, 0.0) << what;
            EXPECT_EQ(d.origin, s.cluster_data().origin) << what;
            EXPECT_EQ(d.scale, s.cluster_data().scale) << what;
            EXPECT_TRUE(validate(s.cluster_data(), m.triangle_count(), false).empty()) << what;
          } else {
            ++kept;
            EXPECT_EQ(&d, &s.cluster_data()) << what;
            EXPECT_EQ(s.times().fallback_ms, 0.0) << what;
          }
          if (f > 0) {
            EXPECT_LE(s.times().total_ms(), wall + 1e-6) << what;
          }
          ASSERT_TRUE(validate(d, m.triangle_count(), false).empty()) << what << test::joined(validate(d, m.triangle_count(), false));
          if (threads == 1) {  // (at two threads: the same traced bytes)
            ASSERT_NO_FATAL_FAILURE(expect_brute_force_hits(d, now, 31u + static_cast<unsigned>(f), 200, what));
            first.push_back(d);
          } else {
            expect_same_data(d, first[f], what);
          }
        }
      }
    }
    EXPECT_GE(fell, 12) << name;  // (frames 1 and 4 at least, twice each way)
    EXPECT_GE(kept, 18) << name;
    EXPECT_GE(refitted, 2) << name;  // (frame 4 at least, at both thread counts)
  }
}

// SceneConfig::fallback_area_weights reach the fallback: its traced data is, byte for byte, that
// of a triangle scene built at the frame's positions with fallback_scene_defaults(), the cluster
// BVH's trace frame and those weights (uneven weights give another tree than the plain SAH's),
// and it hits like brute force.
TEST(ClusterScene, TheFallbackIsBuiltWithItsAreaWeights) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering cl = ptc::morton_runs(m, 24);
  const Mesh far = scattered(m, 0.1, 7u);
  SceneConfig cfg = test::two_level_defaults();
  {
    ClusterScene probe(m, view_of(cl), cfg);
    const double rest = probe.swelling();
    probe.update(far.positions());
    ASSERT_GT(probe.swelling(), 4.0 * rest);
    cfg.fallback_swelling = 2.0 * rest;
  }
  std::vector<TraceData> made;
  const Vec3 eye = m.bounds().center() + Vec3(0.3, 0.2, 1.5) * m.bounds().extent().norm();  // (a camera's, in the world)
  for (int k = 0; k < 3; ++k) {
    const std::array<float, 3> w = k == 1 ? std::array<float, 3>{0.05f, 0.2f, 1.9f} : std::array<float, 3>{1, 1, 1};
    const std::string what = "weights " + std::to_string(w[0]) + " " + std::to_string(w[1]) + " " + std::to_string(w[2]) +
                             (k == 2 ? " and an eye" : "");
    cfg.fallback_area_weights = w;
    cfg.fallback_area_eye = k == 2 ? std::optional<Vec3>(eye) : std::nullopt;
    ClusterScene s(m, view_of(cl), cfg);
    s.update(far.positions());
    ASSERT_TRUE(s.fallback_active()) << what;
    SceneConfig tc = fallback_scene_defaults();
    tc.origin = s.cluster_data().origin;
    tc.scale = s.cluster_data().scale;
    tc.build.area_weights = w;
    if (k == 2) tc.build.area_eye = to_frame(eye, s.cluster_data().frame());  // (in the trace frame)
    const TriangleScene direct(far, tc);
    expect_same_data(s.data(), direct.data(), what);
    ASSERT_NO_FATAL_FAILURE(expect_brute_force_hits(s.data(), far, 41u, 300, what));
    made.push_back(s.data());
  }
  ASSERT_EQ(made.size(), 3u);
  for (const int k : {1, 2})
    EXPECT_FALSE(made[0].wide.nodes.size() == made[k].wide.nodes.size() &&
                 test::same_bytes(made[0].wide.nodes.data(), made[k].wide.nodes.data(), made[0].wide.nodes.size()))
        << k;
  // Bad weights are refused when the scene is made (not at its first fallback frame), and only
  // with the fallback on.
  for (const float bad : {0.0f, -2.0f, std::nanf(""), std::numeric_limits<float>::infinity()}) {
    cfg.fallback_area_weights = {1.0f, bad, 1.0f};
    EXPECT_THROW(ClusterScene(m, view_of(cl), cfg), std::invalid_argument) << bad;
    SceneConfig no_fallback = cfg;
    no_fallback.fallback_swelling = 0.0;
    EXPECT_NO_THROW(ClusterScene(m, view_of(cl), no_fallback)) << bad;
  }
  cfg.fallback_area_weights = {1.0f, 1.0f, 1.0f};
  cfg.fallback_area_eye = Vec3(0.0, std::numeric_limits<double>::infinity(), 0.0);
  EXPECT_THROW(ClusterScene(m, view_of(cl), cfg), std::invalid_argument);
}

// Hard cases of the swelling: the same mesh a thousand times smaller and a million units away
// has the same swelling (both sums are taken in the trace frame; the tolerance covers the
// doubles' rounding of the moved positions); a mesh whose triangles all
// have zero area (collinear corners) has none (NaN), and no threshold makes it fall back.
TEST(ClusterScene, SwellingIsScaleFreeAndNaNWithoutArea) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering cl = ptc::morton_runs(m, 24);
  std::vector<Vec3> far(m.positions().begin(), m.positions().end());
  for (Vec3& p : far) p = 1e-3 * p + Vec3(1e6, -1e6, 3e5);
  const Mesh small_far = m.with_positions(std::move(far));
  SceneConfig cfg = test::two_level_defaults();
  const ClusterScene a(m, view_of(cl), cfg), b(small_far, view_of(cl), cfg);
  EXPECT_NEAR(b.swelling(), a.swelling(), 1e-3 * a.swelling());
  EXPECT_GT(a.swelling(), 1.0);

  std::vector<Vec3> line;
  for (std::size_t v = 0; v < m.vertex_count(); ++v) line.push_back(Vec3(double(v % 97), 2.0 * double(v % 97), 0.0));
  const Mesh flat = m.with_positions(std::move(line));
  cfg.fallback_swelling = 1.5;
  ClusterScene c(flat, view_of(cl), cfg);
  EXPECT_TRUE(std::isnan(c.swelling()));
  EXPECT_FALSE(c.fallback_active());
  c.update(m.positions());  // (areas are those of the positions the scene was made with)
  EXPECT_TRUE(std::isnan(c.swelling()));
  EXPECT_FALSE(c.fallback_active());
}

TEST(ClusterScene, TheSweepBuilderHasNoTwoLevelBuild) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering runs = ptc::morton_runs(m, 20);
  SceneConfig cfg = test::two_level_defaults();
  cfg.builder = SahBuilder::Sweep;
  cfg.cluster_group_size = 8;
  EXPECT_THROW(ClusterScene(m, view_of(runs), cfg), std::invalid_argument);
  cfg.cluster_group_size = 0;
  const ClusterScene s(m, view_of(runs), cfg);
  EXPECT_EQ(s.data().ranges.size(), runs.cluster_count());
  EXPECT_STREQ(to_string(SahBuilder::Sweep), "sweep");
  EXPECT_STREQ(to_string(SahBuilder::Binned), "binned");
}

TEST(SceneConfig, TraceFrameOrigin) {
  EXPECT_EQ(trace_frame_origin(Mesh(), SceneConfig{}), Vec3::Zero());
  const Mesh m = test::grid_cube(2, 1.0, Vec3(10, 20, 30));
  EXPECT_EQ(trace_frame_origin(m, SceneConfig{}), Vec3(10, 20, 30));  // the bounds' centre
  SceneConfig at;
  at.origin = Vec3(1, 2, 3);
  EXPECT_EQ(trace_frame_origin(m, at), Vec3(1, 2, 3));
  at.origin = Vec3(1, std::numeric_limits<double>::infinity(), 3);
  EXPECT_THROW((void)trace_frame_origin(m, at), std::invalid_argument);
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  p[5].y() = std::numeric_limits<double>::quiet_NaN();
  try {
    (void)trace_frame_origin(m.with_positions(std::move(p)), SceneConfig{});
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 5"), std::string::npos) << e.what();
  }
}

// The group size used: the configured N, but (min_cluster_groups M > 0) at most clusters / M, and
// the plain build (0) when that is 1 or less. Hand values around the defaults' thresholds, then
// scenes: a small one takes the plain build with the defaults and groups of exactly 16 with
// min_cluster_groups 0; one of more than 2,048 clusters gets groups of at most clusters / 1024,
// at least 1024 of them.
TEST(SceneConfig, GroupSizeUsedKeepsAtLeastTheMinimumOfGroups) {
  const SceneConfig d = cluster_scene_defaults();
  EXPECT_EQ(d.cluster_group_size, 32u);
  EXPECT_EQ(d.min_cluster_groups, 1024u);
  const std::pair<std::size_t, std::uint32_t> want[] = {{0, 0},      {1, 0},      {2047, 0},   {2048, 2},
                                                        {3071, 2},   {3072, 3},   {32767, 31}, {32768, 32},
                                                        {100000, 32}, {1u << 30, 32}};
  for (const auto& [clusters, g] : want) EXPECT_EQ(cluster_group_size_used(clusters, d), g) << clusters;
  SceneConfig exact = d;
  exact.min_cluster_groups = 0;
  for (const std::size_t clusters : {std::size_t{0}, std::size_t{5}, std::size_t{100000}})
    EXPECT_EQ(cluster_group_size_used(clusters, exact), 32u) << clusters;
  exact.cluster_group_size = 1;
  EXPECT_EQ(cluster_group_size_used(100000, exact), 0u);
  SceneConfig plain = d;
  plain.cluster_group_size = 0;
  EXPECT_EQ(cluster_group_size_used(100000, plain), 0u);

  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering runs = ptc::morton_runs(m, 50);
  ASSERT_LT(runs.cluster_count(), 2048u);
  const ClusterScene small(m, view_of(runs), d);
  EXPECT_EQ(small.group_size(), 0u);
  EXPECT_TRUE(small.group_offsets().empty());
  const ClusterScene grouped(m, view_of(runs), test::two_level_defaults());
  EXPECT_EQ(grouped.group_size(), 16u);
  EXPECT_FALSE(grouped.group_offsets().empty());

  const Mesh cube = test::grid_cube(30);  // 10,800 triangles
  const Clustering pairs = ptc::morton_runs(cube, 2);
  const std::size_t C = pairs.cluster_count();
  ASSERT_GE(C, 3 * 1024u);
  const ClusterScene big(cube, view_of(pairs), d);
  EXPECT_EQ(big.group_size(), C / 1024);
  const auto& go = big.group_offsets();
  ASSERT_GE(go.size(), 1025u);
  for (std::size_t g = 0; g + 1 < go.size(); ++g) EXPECT_LE(go[g + 1] - go[g], big.group_size()) << g;
  EXPECT_EQ(go.back(), C);
}

}  // namespace
}  // namespace ptc::bvh
