// Vertex orders of the per-frame cluster boxes: the first-touch renumbering, the gather-mode
// boxes over it and the fused conversion + box pass over a renumbered mesh (both instruction
// sets), each against brute-force boxes over the original indices, bit for bit; bad input first
// where there is any.
#include "bvh/vertex_order.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <span>
#include <stdexcept>
#include <utility>

#include "test_util.h"

namespace ptc::bvh {
namespace {

// Independent answer for a group box: scalar min/max over the group's ORIGINAL indices, then one
// ulp outwards (next_below / next_above; +-0 both widen to -+denorm_min).
Box3f brute_group_box(std::span<const Vec3f> fp_old, std::span<const std::uint32_t> idx) {
  Box3f b;
  if (idx.empty()) return b;
  for (int a = 0; a < 3; ++a) {
    float lo = fp_old[idx[0]][a], hi = lo;
    for (std::uint32_t v : idx) lo = std::min(lo, fp_old[v][a]), hi = std::max(hi, fp_old[v][a]);
    b.lo[a] = next_below(lo), b.hi[a] = next_above(hi);
  }
  return b;
}

// First-touch renumbering: a permutation; group g's vertex set = its own contiguous range plus
// its shared list (earlier groups' vertices, each once); unreferenced vertices last. Boxes and
// centres from the renumbered positions equal the brute-force ones over the original indices
// and the plain point_group_boxes, bit for bit: random clusterings (overlapping groups,
// duplicates inside a group, empty groups, 1..70 vertices so both the 4-vertex steps and the
// tails run, the last vertex of the array), zero and negative-zero coordinates, unreferenced
// vertices, reused outputs.
TEST(VertexOrder, FirstTouchOrderBoxesEqualBruteForce) {
  std::mt19937 g32(23);
  auto g = [&g32] { return static_cast<std::uint32_t>(g32()); };
  for (int trial = 0; trial < 60; ++trial) {
    const std::uint32_t V = 1 + g() % 400;
    std::uniform_real_distribution<float> U(trial % 3 == 0 ? -1e-30f : -5.0f, trial % 3 == 0 ? 1e-30f : 5.0f);
    const auto u = [&] { return U(g32); };
    AlignedVector<Vec3f> fp_old(V);
    for (Vec3f& p : fp_old) p = {u(), u(), u()};
    fp_old[g() % V] = {0.0f, -0.0f, 0.0f};
    fp_old[g() % V] = {-0.0f, -0.0f, -0.0f};
    if (trial % 4 == 1) fp_old[V - 1] = {1e30f, -1e30f, 3.0f};
    const std::uint32_t groups = g() % 40;
    std::vector<std::uint32_t> offsets{0}, idx;
    const std::uint32_t used = std::max<std::uint32_t>(1, V - V / 4);  // the last V/4 vertices: unreferenced...
    for (std::uint32_t k = 0; k < groups; ++k) {
      const std::uint32_t n = (g() % 5 == 0) ? 0 : 1 + g() % 70;
      const std::uint32_t start = g() % used;
      for (std::uint32_t i = 0; i < n; ++i)  // a window (neighbouring groups overlap) with some jumps
        idx.push_back(g() % 8 == 0 ? g() % used : (start + i) % used);
      if (trial % 2 == 0 && n > 0) idx.push_back(V - 1);  // ...but sometimes the last one is
      offsets.push_back(static_cast<std::uint32_t>(idx.size()));
    }
    const GroupVertexOrder o = first_touch_order(V, offsets, idx);
    // A permutation, and its inverse.
    ASSERT_EQ(o.to_old.size(), V);
    ASSERT_EQ(o.to_new.size(), V);
    for (std::uint32_t i = 0; i < V; ++i) {
      ASSERT_LT(o.to_old[i], V);
      EXPECT_EQ(o.to_new[o.to_old[i]], i);
    }
    ASSERT_EQ(o.own_offsets.size(), offsets.size());
    ASSERT_EQ(o.shared_offsets.size(), offsets.size());
    std::vector<std::uint8_t> referenced(V, 0);
    for (std::uint32_t v : idx) referenced[v] = 1;
    for (std::uint32_t k = 0; k < groups; ++k) {
      std::vector<std::uint32_t> want(idx.begin() + offsets[k], idx.begin() + offsets[k + 1]), got;
      std::sort(want.begin(), want.end());
      want.erase(std::unique(want.begin(), want.end()), want.end());
      for (std::uint32_t i = o.own_offsets[k]; i < o.own_offsets[k + 1]; ++i) got.push_back(o.to_old[i]);
      for (std::uint32_t i = o.shared_offsets[k]; i < o.shared_offsets[k + 1]; ++i) {
        EXPECT_LT(o.shared[i], o.own_offsets[k]) << "shared vertex not owned by an earlier group";
        got.push_back(o.to_old[o.shared[i]]);
      }
      const std::size_t with_dups = got.size();
      std::sort(got.begin(), got.end());
      got.erase(std::unique(got.begin(), got.end()), got.end());
      EXPECT_EQ(got.size(), with_dups) << "a vertex listed twice in group " << k;
      EXPECT_EQ(got, want) << "group " << k;
    }
    // Unreferenced vertices come last, in their original order.
    const std::uint32_t first_unref = groups ? o.own_offsets[groups] : 0;
    for (std::uint32_t i = 0; i < V; ++i) {
      EXPECT_EQ(i < first_unref, bool(referenced[o.to_old[i]])) << i;
      if (i > first_unref) {
        EXPECT_LT(o.to_old[i - 1], o.to_old[i]);
      }
    }
    // Boxes: positions converted in the new order (as ClusterScene::update does).
    std::vector<Vec3> pos(V);
    for (std::uint32_t v = 0; v < V; ++v) pos[v] = Vec3(fp_old[v][0], fp_old[v][1], fp_old[v][2]);
    AlignedVector<Vec3f> fp_new;
    frame_positions(pos, o.to_old, Vec3::Zero(), fp_new);
    for (std::uint32_t i = 0; i < V; ++i) ASSERT_EQ(fp_new[i], fp_old[o.to_old[i]]);
    AlignedVector<Box3f> boxes(7), plain;
    AlignedVector<Vec3f> centers, plain_centers(2);
    point_group_boxes(fp_new, o, boxes, centers);
    point_group_boxes(fp_old, offsets, idx, plain, plain_centers);
    ASSERT_EQ(boxes.size(), groups);
    ASSERT_EQ(centers.size(), groups);
    for (std::uint32_t k = 0; k < groups; ++k) {
      const Box3f want =
          brute_group_box(fp_old, std::span<const std::uint32_t>(idx.data() + offsets[k], offsets[k + 1] - offsets[k]));
      EXPECT_EQ(boxes[k], want) << "trial " << trial << " group " << k;
      EXPECT_EQ(boxes[k], plain[k]) << "trial " << trial << " group " << k;
      if (want.empty()) continue;  // (the centre of the empty box is NaN)
      EXPECT_EQ(centers[k], want.center()) << k;
      EXPECT_EQ(centers[k], plain_centers[k]) << k;
    }
  }
}

TEST(VertexOrder, FirstTouchOrderRejectsBadInput) {
  const std::vector<std::uint32_t> idx{0, 1, 2, 5};
  EXPECT_THROW((void)first_touch_order(5, std::vector<std::uint32_t>{0, 2, 4}, idx), std::invalid_argument);
  EXPECT_THROW((void)first_touch_order(6, std::vector<std::uint32_t>{0, 3, 2, 4}, idx), std::invalid_argument);
  EXPECT_THROW((void)first_touch_order(6, std::vector<std::uint32_t>{0, 3}, idx), std::invalid_argument);
  EXPECT_THROW((void)first_touch_order(6, std::vector<std::uint32_t>{1, 4}, idx), std::invalid_argument);
  const GroupVertexOrder o = first_touch_order(6, std::vector<std::uint32_t>{0, 2, 4}, idx);
  EXPECT_EQ(o.to_old, (std::vector<std::uint32_t>{0, 1, 2, 5, 3, 4}));
  const GroupVertexOrder none = first_touch_order(3, {}, {});
  EXPECT_EQ(none.to_old, (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_TRUE(none.own_offsets.size() <= 1);
}


// The fused per-frame pass (conversion + group boxes in one pass over a mesh renumbered with
// cluster_vertex_order) against the plain conversion and a brute-force box per group, bit for
// bit, on both instruction sets; groups with shared, repeated and unreferenced vertices, +-0,
// huge and tiny coordinates, a far origin; optionally parts that the renumbering keeps in place.
TEST(VertexOrder, FusedPassOnRenumberedVerticesEqualsBruteForce) {
  std::mt19937 g32(71);
  auto g = [&g32] { return static_cast<std::uint32_t>(g32()); };
  for (int trial = 0; trial < 80; ++trial) {
    const std::uint32_t V = 1 + g() % 400;
    const bool parts_mode = trial % 3 == 2;
    std::vector<std::size_t> parts{0};
    if (parts_mode) {
      while (parts.back() < V) parts.push_back(std::min<std::size_t>(V, parts.back() + 1 + g() % 120));
    } else {
      parts.push_back(V);
    }
    const double scale = trial % 5 == 0 ? 1e-30 : trial % 5 == 1 ? 1e30 : 3.0;
    const Vec3 origin = trial % 4 == 3 ? Vec3(1e7, -2e7, 5e6) : Vec3::Zero();
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    std::vector<Vec3> pos(V);
    for (Vec3& p : pos) p = origin + scale * Vec3(U(g32), U(g32), U(g32));
    pos[g() % V] = Vec3(0.0, -0.0, 0.0);
    pos[g() % V] = Vec3(-0.0, -0.0, -0.0);
    // Groups inside one part each (as clusters inside one mesh of a scene).
    const std::uint32_t groups = g() % 40;
    std::vector<std::uint32_t> offsets{0}, idx;
    for (std::uint32_t k = 0; k < groups; ++k) {
      const std::size_t part = g() % (parts.size() - 1);
      const auto a = static_cast<std::uint32_t>(parts[part]), span = static_cast<std::uint32_t>(parts[part + 1] - a);
      const std::uint32_t used = std::max<std::uint32_t>(1, span - span / 4);  // the rest unreferenced
      const std::uint32_t n = (g() % 6 == 0) ? 0 : 1 + g() % 70;
      const std::uint32_t start = g() % used;
      for (std::uint32_t i = 0; i < n; ++i) idx.push_back(a + (g() % 8 == 0 ? g() % used : (start + i) % used));
      offsets.push_back(static_cast<std::uint32_t>(idx.size()));
    }
    const std::vector<std::uint32_t> to_old =
        parts_mode ? cluster_vertex_order(V, offsets, idx, parts) : cluster_vertex_order(V, offsets, idx);
    ASSERT_EQ(to_old.size(), V);
    std::vector<std::uint32_t> to_new(V, ~0u);
    for (std::uint32_t i = 0; i < V; ++i) {
      ASSERT_LT(to_old[i], V);
      ASSERT_EQ(to_new[to_old[i]], ~0u) << "not a permutation";
      to_new[to_old[i]] = i;
    }
    for (std::size_t p = 0; p + 1 < parts.size(); ++p)
      for (std::size_t i = parts[p]; i < parts[p + 1]; ++i) {
        ASSERT_GE(to_old[i], parts[p]) << "part " << p;
        ASSERT_LT(to_old[i], parts[p + 1]) << "part " << p;
      }
    std::vector<Vec3> pos_new(V);
    for (std::uint32_t i = 0; i < V; ++i) pos_new[i] = pos[to_old[i]];
    std::vector<std::uint32_t> idx_new(idx.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx_new[i] = to_new[idx[i]];
    const auto runs = group_runs(first_touch_order(V, offsets, idx_new));
    ASSERT_TRUE(runs.has_value()) << "trial " << trial;
    AlignedVector<Vec3f> plain;
    frame_positions(pos_new, origin, plain);
    for (const bool avx2 : {true, false}) {
      AlignedVector<Vec3f> fp(V + 2, Vec3f{7.0f, 7.0f, 7.0f});
      AlignedVector<Box3f> boxes(3);
      AlignedVector<Vec3f> centers;
      frame_positions_and_boxes(pos_new, origin, *runs, fp, boxes, centers, avx2);
      for (std::uint32_t v = 0; v < V; ++v) ASSERT_EQ(fp[v], plain[v]) << "trial " << trial << " vertex " << v;
      EXPECT_EQ(fp[V], (Vec3f{7.0f, 7.0f, 7.0f})) << "wrote past the vertices";
      ASSERT_EQ(boxes.size(), groups);
      ASSERT_EQ(centers.size(), groups);
      for (std::uint32_t k = 0; k < groups; ++k) {
        const Box3f want = brute_group_box(
            plain, std::span<const std::uint32_t>(idx_new.data() + offsets[k], offsets[k + 1] - offsets[k]));
        EXPECT_EQ(boxes[k], want) << "trial " << trial << " group " << k << " avx2 " << avx2;
        if (!want.empty()) {
          EXPECT_EQ(centers[k], want.center()) << k;
        }
      }
    }
    // The streamed conversion (ClusterScene on one thread): the same floats, nothing past them.
    for (const bool avx2 : {true, false}) {
      AlignedVector<Vec3f> fp(V + 2, Vec3f{7.0f, 7.0f, 7.0f});
      frame_positions_streamed(pos_new, origin, fp, avx2);
      for (std::uint32_t v = 0; v < V; ++v) ASSERT_EQ(fp[v], plain[v]) << "trial " << trial << " vertex " << v;
      EXPECT_EQ(fp[V], (Vec3f{7.0f, 7.0f, 7.0f})) << "wrote past the vertices";
    }
    // Outputs that start off a 16-byte boundary (the AVX2 path streams from the first one on):
    // the same floats, nothing before or past them.
    for (std::size_t shift = 1; shift < 4; ++shift) {
      AlignedVector<Vec3f> big(V + 2 + shift, Vec3f{7.0f, 7.0f, 7.0f});
      frame_positions_streamed(pos_new, origin, std::span<Vec3f>(big).subspan(shift));
      for (std::uint32_t v = 0; v < V; ++v) ASSERT_EQ(big[shift + v], plain[v]) << "shift " << shift << " vertex " << v;
      EXPECT_EQ(big[shift - 1], (Vec3f{7.0f, 7.0f, 7.0f})) << "wrote before the vertices, shift " << shift;
      EXPECT_EQ(big[shift + V], (Vec3f{7.0f, 7.0f, 7.0f})) << "wrote past the vertices, shift " << shift;
    }
    AlignedVector<Vec3f> fp2(V + 2), c2;
    AlignedVector<Box3f> b2;
    // A position that is not finite in the frame (any vertex, grouped or not): refused on both
    // paths, and by the streamed conversion.
    for (const bool avx2 : {true, false}) {
      std::vector<Vec3> bad = pos_new;
      bad[g() % V] = Vec3(0, std::nan(""), 0);
      EXPECT_THROW(frame_positions_and_boxes(bad, origin, *runs, fp2, b2, c2, avx2), std::invalid_argument);
      EXPECT_THROW(frame_positions_streamed(bad, origin, fp2, avx2), std::invalid_argument);
      bad = pos_new;
      bad[V - 1] = Vec3(-std::numeric_limits<double>::infinity(), 0, 0);
      EXPECT_THROW(frame_positions_and_boxes(bad, origin, *runs, fp2, b2, c2, avx2), std::invalid_argument);
      EXPECT_THROW(frame_positions_streamed(bad, origin, fp2, avx2), std::invalid_argument);
    }
    EXPECT_THROW(frame_positions_streamed(pos_new, origin, std::span<Vec3f>(fp2).first(V - 1)), std::invalid_argument);
    EXPECT_THROW(frame_positions_and_boxes(std::span<const Vec3>(pos_new).first(V - 1), origin, *runs, fp2, b2, c2),
                 std::invalid_argument);
    EXPECT_THROW(frame_positions_and_boxes(pos_new, origin, *runs, std::span<Vec3f>(fp2).first(V - 1), b2, c2),
                 std::invalid_argument);
  }
}

// The fused pass runs chunks of groups on the caller's threads: with many chunks, at 1, 2 and 4
// threads, the positions and every box equal the brute force, and a position that is not finite
// in a late chunk is refused at every count.
TEST(VertexOrder, FusedPassIsTheSameAtAnyThreadCount) {
  const std::uint32_t groups = 2048 * 6 + 5;
  std::vector<std::uint32_t> offsets{0}, idx;
  for (std::uint32_t k = 0; k < groups; ++k) {  // 12 vertices, the first two shared with group k - 1
    for (std::uint32_t i = 0; i < 12; ++i) idx.push_back(10 * k + i);
    offsets.push_back(static_cast<std::uint32_t>(idx.size()));
  }
  const std::uint32_t V = 10 * groups + 2;
  std::mt19937 g32(79);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const Vec3 origin(1e3, -2e3, 5e2);
  std::vector<Vec3> pos(V);
  for (Vec3& p : pos) p = origin + 40.0 * Vec3(U(g32), U(g32), U(g32));
  const auto runs = group_runs(first_touch_order(V, offsets, idx));
  ASSERT_TRUE(runs.has_value());
  AlignedVector<Vec3f> plain;
  frame_positions(pos, origin, plain);
  for (int threads : {1, 2, 4}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    AlignedVector<Vec3f> fp(V + 2);
    AlignedVector<Box3f> boxes;
    AlignedVector<Vec3f> centers;
    frame_positions_and_boxes(pos, origin, *runs, fp, boxes, centers);
    for (std::uint32_t v = 0; v < V; ++v) ASSERT_EQ(fp[v], plain[v]) << "threads " << threads << " vertex " << v;
    ASSERT_EQ(boxes.size(), groups);
    for (std::uint32_t k = 0; k < groups; ++k) {
      const Box3f want =
          brute_group_box(plain, std::span<const std::uint32_t>(idx.data() + offsets[k], offsets[k + 1] - offsets[k]));
      ASSERT_EQ(boxes[k], want) << "threads " << threads << " group " << k;
      ASSERT_EQ(centers[k], want.center()) << k;
    }
    std::vector<Vec3> bad = pos;
    bad[V - 40] = Vec3(0, std::nan(""), 0);
    EXPECT_THROW(frame_positions_and_boxes(bad, origin, *runs, fp, boxes, centers), std::invalid_argument) << threads;
    // The streamed conversion in chunks of vertices (more than one here): the same floats.
    AlignedVector<Vec3f> fs(V + 2);
    frame_positions_streamed(pos, origin, fs);
    for (std::uint32_t v = 0; v < V; ++v) ASSERT_EQ(fs[v], plain[v]) << "threads " << threads << " vertex " << v;
    EXPECT_THROW(frame_positions_streamed(bad, origin, fs), std::invalid_argument) << threads;
  }
}

TEST(VertexOrder, GroupRunsNeedConsecutiveOwnVertices) {
  // Group 0 owns 0 and 2 (not consecutive): no runs; renumbered, it owns 0 and 1.
  const std::vector<std::uint32_t> offsets{0, 2, 4}, idx{0, 2, 2, 1};
  EXPECT_FALSE(group_runs(first_touch_order(4, offsets, idx)).has_value());
  const std::vector<std::uint32_t> to_old = cluster_vertex_order(4, offsets, idx);
  EXPECT_EQ(to_old, (std::vector<std::uint32_t>{0, 2, 1, 3}));
  const std::vector<std::uint32_t> renamed{0, 1, 1, 2};
  const auto runs = group_runs(first_touch_order(4, offsets, renamed));
  ASSERT_TRUE(runs.has_value());
  EXPECT_EQ(runs->own_begin, (std::vector<std::uint32_t>{0, 2}));
  EXPECT_EQ(runs->own_count, (std::vector<std::uint32_t>{2, 1}));
  EXPECT_EQ(runs->shared, (std::vector<std::uint32_t>{1}));
  ASSERT_EQ(runs->gaps.size(), 1u);
  EXPECT_EQ(runs->gaps[0], (std::pair<std::uint32_t, std::uint32_t>{3, 4}));
  // Part offsets must span the vertices and ascend.
  const std::vector<std::size_t> bad1{0, 3}, bad2{0, 3, 2, 4}, bad3{1, 4};
  EXPECT_THROW((void)cluster_vertex_order(4, offsets, idx, bad1), std::invalid_argument);
  EXPECT_THROW((void)cluster_vertex_order(4, offsets, idx, bad2), std::invalid_argument);
  EXPECT_THROW((void)cluster_vertex_order(4, offsets, idx, bad3), std::invalid_argument);
  // A group spanning two parts: the order stays inside the parts (and the runs may be lost).
  const std::vector<std::size_t> parts{0, 2, 4};
  const std::vector<std::uint32_t> across = cluster_vertex_order(4, offsets, idx, parts);
  EXPECT_EQ(across, (std::vector<std::uint32_t>{0, 1, 2, 3}));
}

}  // namespace
}  // namespace ptc::bvh
