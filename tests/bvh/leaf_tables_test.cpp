// The per-group vertex tables (bvh/leaf_tables.h): every cluster's triangles in its groups once
// with their corners, groups within 16 triangles and 16 vertices, and tables and cluster boxes
// against the frame positions and against the blocks' fill (a second method).
#include "bvh/leaf_tables.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "bvh/leaf_blocks.h"

namespace ptc::bvh {
namespace {

// Clusters as the scene lays them out: blocks of four lanes, padding lanes kNoTriangle with the
// sentinel's corners.
struct Lanes {
  std::vector<LeafRange> ranges;
  std::vector<std::uint32_t> ids, corners;
  std::uint32_t next_id = 0;
  void add_cluster(const std::vector<std::array<std::uint32_t, 3>>& tris, std::uint32_t sentinel) {
    const auto n = static_cast<std::uint32_t>(tris.size());
    const auto first = static_cast<std::uint32_t>(ids.size() / 4);
    ranges.push_back({first, blocks_for(n), n});
    ids.resize(4 * std::size_t{first + blocks_for(n)}, kNoTriangle);
    corners.resize(12 * std::size_t{first + blocks_for(n)}, sentinel);
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::size_t b = first + i / 4, l = i % 4;
      ids[4 * b + l] = next_id++;
      for (int k = 0; k < 3; ++k) corners[12 * b + 4 * k + l] = tris[i][k];
    }
  }
};

AlignedVector<Vec3f> positions(std::size_t n, std::uint32_t seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<float> U(-10.0f, 10.0f);
  AlignedVector<Vec3f> fp(n);
  for (Vec3f& p : fp) p = {U(g), U(g), U(g)};
  return fp;
}

// Random clusters near each other's vertices, and the hard cases: one triangle, a triangle with a
// repeated corner, the same triangle 40 times, 300 triangles on 20 vertices, 100 triangles of
// distinct vertices.
Lanes hard_clusters(std::uint32_t V, std::uint32_t seed) {
  std::mt19937 g(seed);
  Lanes L;
  const std::uint32_t S = V;  // the sentinel's index
  for (int c = 0; c < 1500; ++c) {
    const auto n = static_cast<std::uint32_t>(1 + g() % 60);
    const auto lo = static_cast<std::uint32_t>(g() % (V - 40));
    std::vector<std::array<std::uint32_t, 3>> t(n);
    for (auto& tri : t)
      for (auto& v : tri) v = lo + static_cast<std::uint32_t>(g() % 40);
    L.add_cluster(t, S);
  }
  L.add_cluster({{1, 2, 3}}, S);
  L.add_cluster({{4, 4, 5}, {5, 6, 6}, {7, 7, 7}}, S);
  L.add_cluster(std::vector<std::array<std::uint32_t, 3>>(40, {8, 9, 10}), S);
  std::vector<std::array<std::uint32_t, 3>> dense(300), distinct(100);
  for (auto& tri : dense)
    for (auto& v : tri) v = 100 + static_cast<std::uint32_t>(g() % 20);
  for (std::uint32_t i = 0; i < distinct.size(); ++i) distinct[i] = {300 + 3 * i, 301 + 3 * i, 302 + 3 * i};
  L.add_cluster(dense, S);
  L.add_cluster(distinct, S);
  return L;
}

TEST(LeafTables, EveryTriangleOnceWithItsCornersInGroupsOfSixteen) {
  const std::uint32_t V = 2000;
  const Lanes L = hard_clusters(V, 5);
  const TableLayout T = make_table_layout(L.ranges, L.ids, L.corners, V);
  ASSERT_EQ(T.group_offsets.size(), L.ranges.size() + 1);
  ASSERT_EQ(T.slot_vertices.size(), 16 * T.group_count());
  ASSERT_EQ(T.corner_slots.size(), 48 * T.group_count());
  ASSERT_EQ(T.triangle_ids.size(), 16 * T.group_count());
  for (std::size_t c = 0; c < L.ranges.size(); ++c) {
    // The cluster's lanes, (id, corners), against what its groups hold.
    std::vector<std::array<std::uint32_t, 4>> want, got;
    const LeafRange& r = L.ranges[c];
    for (std::uint32_t i = 0; i < r.triangle_count; ++i) {
      const std::size_t b = r.first_block + i / 4, l = i % 4;
      want.push_back({L.ids[4 * b + l], L.corners[12 * b + l], L.corners[12 * b + 4 + l], L.corners[12 * b + 8 + l]});
    }
    ASSERT_LT(T.group_offsets[c], T.group_offsets[c + 1]) << "cluster " << c << " has no group";
    for (std::size_t g = T.group_offsets[c]; g < T.group_offsets[c + 1]; ++g) {
      const int n = T.triangle_count[g];
      ASSERT_GE(n, 1);
      ASSERT_LE(n, 16);
      EXPECT_EQ(T.lanes_in(g), (1u << n) - 1u);
      const std::uint32_t* sv = &T.slot_vertices[16 * g];
      int used = 0;
      while (used < 16 && sv[used] != V) ++used;
      for (int s = used; s < 16; ++s) ASSERT_EQ(sv[s], V) << "group " << g << ": used slots first, then the sentinel";
      for (int s = 0; s < used; ++s)
        for (int s2 = 0; s2 < s; ++s2) ASSERT_NE(sv[s], sv[s2]) << "group " << g << ": a vertex in two slots";
      std::vector<bool> referenced(16, false);
      for (int l = 0; l < 16; ++l) {
        const std::uint8_t* cs = &T.corner_slots[48 * g];
        if (l >= n) {
          EXPECT_EQ(T.triangle_ids[16 * g + l], kNoTriangle);
          for (int k = 0; k < 3; ++k) EXPECT_EQ(cs[16 * k + l], used < 16 ? used : 0) << "padding lane of group " << g;
          continue;
        }
        std::array<std::uint32_t, 4> t{T.triangle_ids[16 * g + l], 0, 0, 0};
        for (int k = 0; k < 3; ++k) {
          ASSERT_LT(cs[16 * k + l], used) << "group " << g << " lane " << l;
          t[1 + k] = sv[cs[16 * k + l]];
          referenced[cs[16 * k + l]] = true;
        }
        got.push_back(t);
      }
      for (int s = 0; s < used; ++s) EXPECT_TRUE(referenced[s]) << "group " << g << ": slot " << s << " unused";
    }
    std::sort(want.begin(), want.end());
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want) << "cluster " << c;
  }
  // The hard clusters with a known grouping (the last five): one triangle; three degenerate ones
  // on four vertices; forty copies of one triangle (16 + 16 + 8 on three slots each); 100
  // triangles of distinct vertices (five a group: 15 vertices, the 6th would need 18).
  const std::size_t C = L.ranges.size();
  auto groups = [&](std::size_t c) { return T.group_offsets[c + 1] - T.group_offsets[c]; };
  EXPECT_EQ(groups(C - 5), 1u);
  EXPECT_EQ(groups(C - 4), 1u);
  ASSERT_EQ(groups(C - 3), 3u);
  for (std::size_t g = T.group_offsets[C - 3], i = 0; i < 3; ++g, ++i) {
    EXPECT_EQ(T.triangle_count[g], i < 2 ? 16 : 8);
    EXPECT_EQ(T.slot_vertices[16 * g + 3], V);
  }
  ASSERT_EQ(groups(C - 1), 20u);
  for (std::size_t g = T.group_offsets[C - 1]; g < T.group_offsets[C]; ++g) EXPECT_EQ(T.triangle_count[g], 5);
  // 300 triangles on 20 vertices: at least 19 groups (16 triangles at most in each).
  EXPECT_GE(groups(C - 2), 19u);
}

// The documented grouping rule written plainly (a placed flag per triangle instead of the
// library's in-place reordering, sets for the new vertices): the whole layout must be the same.
TableLayout reference_layout(const Lanes& L, std::uint32_t sentinel) {
  TableLayout T;
  T.group_offsets.push_back(0);
  for (const LeafRange& r : L.ranges) {
    std::vector<std::array<std::uint32_t, 4>> tris;  // id, corners
    for (std::uint32_t i = 0; i < r.triangle_count; ++i) {
      const std::size_t b = r.first_block + i / 4, l = i % 4;
      tris.push_back({L.ids[4 * b + l], L.corners[12 * b + l], L.corners[12 * b + 4 + l], L.corners[12 * b + 8 + l]});
    }
    std::vector<bool> placed(tris.size(), false);
    std::size_t left = tris.size();
    while (left > 0) {
      std::vector<std::uint32_t> slots;
      std::vector<std::size_t> members;
      while (members.size() < 16) {
        std::vector<std::size_t> window;
        for (std::size_t i = 0; i < tris.size() && window.size() < 64; ++i)
          if (!placed[i]) window.push_back(i);
        std::size_t best = tris.size(), best_add = 4;
        for (const std::size_t i : window) {
          std::set<std::uint32_t> fresh;
          for (int k = 1; k <= 3; ++k)
            if (std::find(slots.begin(), slots.end(), tris[i][k]) == slots.end()) fresh.insert(tris[i][k]);
          if (slots.size() + fresh.size() <= 16 && fresh.size() < best_add) best = i, best_add = fresh.size();
        }
        if (best == tris.size()) break;
        placed[best] = true, --left;
        members.push_back(best);
        for (int k = 1; k <= 3; ++k)
          if (std::find(slots.begin(), slots.end(), tris[best][k]) == slots.end()) slots.push_back(tris[best][k]);
      }
      for (std::size_t s = 0; s < 16; ++s) T.slot_vertices.push_back(s < slots.size() ? slots[s] : sentinel);
      for (int k = 1; k <= 3; ++k)
        for (std::size_t l = 0; l < 16; ++l) {
          const auto pad = static_cast<std::uint8_t>(slots.size() < 16 ? slots.size() : 0);
          T.corner_slots.push_back(
              l < members.size()
                  ? static_cast<std::uint8_t>(std::find(slots.begin(), slots.end(), tris[members[l]][k]) - slots.begin())
                  : pad);
        }
      for (std::size_t l = 0; l < 16; ++l) T.triangle_ids.push_back(l < members.size() ? tris[members[l]][0] : kNoTriangle);
      T.triangle_count.push_back(static_cast<std::uint8_t>(members.size()));
    }
    T.group_offsets.push_back(static_cast<std::uint32_t>(T.triangle_count.size()));
  }
  return T;
}

TEST(LeafTables, TheLayoutIsTheDocumentedGreedyRule) {
  const std::uint32_t V = 2000;
  Lanes L = hard_clusters(V, 11);
  // Sixteen one-vertex triangles: one group of 16 slots (a corner counted once however often it
  // repeats).
  std::vector<std::array<std::uint32_t, 3>> points;
  for (std::uint32_t i = 0; i < 16; ++i) points.push_back({700 + i, 700 + i, 700 + i});
  L.add_cluster(points, V);
  // The fewest new vertices over the next triangle: A, then C (one new), then B (three).
  const std::uint32_t a = L.next_id;
  L.add_cluster({{800, 801, 802}, {810, 811, 812}, {800, 801, 803}}, V);
  // The look-ahead of 64: t0, then t1 .. t79 of fresh vertices but t75, a copy of t0 out of the
  // first group's reach (its window ends at t68): the first group is t0 .. t4 (15 vertices).
  const std::uint32_t w = L.next_id;
  std::vector<std::array<std::uint32_t, 3>> far(80);
  for (std::uint32_t i = 0; i < 80; ++i) far[i] = {1000 + 3 * i, 1001 + 3 * i, 1002 + 3 * i};
  far[75] = far[0];
  L.add_cluster(far, V);

  const TableLayout T = make_table_layout(L.ranges, L.ids, L.corners, V);
  const TableLayout R = reference_layout(L, V);
  ASSERT_EQ(T.group_offsets, R.group_offsets);
  ASSERT_EQ(T.triangle_count, R.triangle_count);
  for (std::size_t g = 0; g < R.group_count(); ++g) {
    for (int s = 0; s < 16; ++s) ASSERT_EQ(T.slot_vertices[16 * g + s], R.slot_vertices[16 * g + s]) << "group " << g;
    for (int i = 0; i < 48; ++i) ASSERT_EQ(T.corner_slots[48 * g + i], R.corner_slots[48 * g + i]) << "group " << g;
    for (int l = 0; l < 16; ++l) ASSERT_EQ(T.triangle_ids[16 * g + l], R.triangle_ids[16 * g + l]) << "group " << g;
  }
  const std::size_t C = L.ranges.size();
  const std::size_t gp = T.group_offsets[C - 3], ga = T.group_offsets[C - 2], gw = T.group_offsets[C - 1];
  EXPECT_EQ(T.group_offsets[C - 2] - gp, 1u);
  EXPECT_EQ(T.triangle_count[gp], 16);
  EXPECT_EQ(T.slot_vertices[16 * gp + 15], 715u);
  EXPECT_EQ(T.triangle_ids[16 * ga], a);
  EXPECT_EQ(T.triangle_ids[16 * ga + 1], a + 2);
  EXPECT_EQ(T.triangle_ids[16 * ga + 2], a + 1);
  ASSERT_EQ(T.triangle_count[gw], 5);
  for (std::uint32_t l = 0; l < 5; ++l) EXPECT_EQ(T.triangle_ids[16 * gw + l], w + l);
}

TEST(LeafTables, TablesAreTheFramePositionsAndBoxesThoseOfTheBlocks) {
  const std::uint32_t V = 2000;
  AlignedVector<Vec3f> fp = positions(V, 7);
  fp[1] = {0.0f, -0.0f, 0.0f}, fp[2] = {-0.0f, 0.0f, -0.0f};
  fp[3] = {3e38f, -3e38f, 1e-38f}, fp[4] = {-1e-45f, 1e-45f, 2e38f};
  add_sentinel(fp);
  const Lanes L = hard_clusters(V, 9);
  const TableLayout T = make_table_layout(L.ranges, L.ids, L.corners, V);
  // The second method: the blocks' fill and its cluster boxes.
  const std::size_t nb = L.ids.size() / 4;
  AlignedVector<TriBlock> blocks(nb);
  AlignedVector<Box3f> want_boxes(L.ranges.size());
  AlignedVector<Vec3f> want_centres(L.ranges.size());
  fill_blocks_and_cluster_boxes(L.corners, fp[0].data(), blocks, nullptr, L.ranges, want_boxes.data(),
                                want_centres.data());
  AlignedVector<VertexTable> first;
  for (int threads : {1, 2, 4}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    AlignedVector<VertexTable> tables(T.group_count());
    AlignedVector<Box3f> boxes(L.ranges.size());
    AlignedVector<Vec3f> centres(L.ranges.size());
    fill_tables_and_cluster_boxes(T, fp[0].data(), tables, boxes.data(), centres.data());
    const std::string what = "threads " + std::to_string(threads);
    for (std::size_t g = 0; g < T.group_count(); ++g)
      for (int s = 0; s < 16; ++s)
        for (int a = 0; a < 3; ++a) {
          const float v = tables[g].v[a][s];
          const std::uint32_t vi = T.slot_vertices[16 * g + s];
          if (vi == V) {
            ASSERT_TRUE(std::isnan(v)) << what << " group " << g << " slot " << s;
          } else {
            ASSERT_EQ(std::memcmp(&v, &fp[vi][a], sizeof v), 0) << what << " group " << g << " slot " << s;
          }
        }
    for (std::size_t c = 0; c < L.ranges.size(); ++c) {
      ASSERT_EQ(boxes[c], want_boxes[c]) << what << " cluster " << c;
      ASSERT_EQ(centres[c], want_centres[c]) << what << " cluster " << c;
      // and a brute-force box of the cluster's corners, widened one ulp
      Box3f b;
      const LeafRange& r = L.ranges[c];
      for (std::uint32_t i = 0; i < r.triangle_count; ++i)
        for (int k = 0; k < 3; ++k) b.extend(fp[L.corners[12 * (r.first_block + i / 4) + 4 * k + i % 4]]);
      for (int a = 0; a < 3; ++a) b.lo[a] = next_below(b.lo[a]), b.hi[a] = next_above(b.hi[a]);
      ASSERT_EQ(boxes[c], b) << what << " cluster " << c;
    }
    if (first.empty()) {
      first = tables;
    } else {
      ASSERT_EQ(std::memcmp(first.data(), tables.data(), sizeof(VertexTable) * tables.size()), 0) << what;
    }
  }
}

TEST(LeafTables, MismatchedSizesAreRefused) {
  const std::vector<LeafRange> ranges{{0, 1, 3}};
  const std::vector<std::uint32_t> ids{0, 1, 2, kNoTriangle};
  EXPECT_THROW((void)make_table_layout(ranges, ids, std::vector<std::uint32_t>(11, 0), 9), std::invalid_argument);
  EXPECT_THROW((void)make_table_layout(std::vector<LeafRange>{{0, 2, 5}}, ids, std::vector<std::uint32_t>(12, 0), 9),
               std::invalid_argument);
  const TableLayout T = make_table_layout(ranges, ids, std::vector<std::uint32_t>(12, 0), 9);
  AlignedVector<VertexTable> none;
  EXPECT_THROW(fill_tables_and_cluster_boxes(T, nullptr, none, nullptr, nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace ptc::bvh
