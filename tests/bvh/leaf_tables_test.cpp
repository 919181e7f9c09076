// The per-group vertex tables (bvh/leaf_tables.h): every cluster's triangles in its groups once
// with their corners, groups within 32 triangles and 32 vertices, the layout against a plainly
// written reference of its rule, and the fill's rows and cluster boxes against the frame
// positions and against the blocks' fill (a second method).
#include "bvh/leaf_tables.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "test_util.h"

#include "bvh/leaf_blocks.h"

namespace ptc::bvh {
namespace {

using test::random_frame_positions;

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

// Random clusters near each other's vertices (1-60 triangles on a window of 40 or 60 vertices),
// and the hard cases: one triangle, triangles with repeated corners, the same triangle 40 times,
// 300 triangles on 20 vertices, 100 triangles of distinct vertices.
Lanes hard_clusters(std::uint32_t V, std::uint32_t seed) {
  std::mt19937 g(seed);
  Lanes L;
  const std::uint32_t S = V;  // the sentinel's index
  for (int c = 0; c < 1500; ++c) {
    const auto n = static_cast<std::uint32_t>(1 + g() % 60);
    const std::uint32_t span = c % 2 ? 40 : 60;
    const auto lo = static_cast<std::uint32_t>(g() % (V - span));
    std::vector<std::array<std::uint32_t, 3>> t(n);
    for (auto& tri : t)
      for (auto& v : tri) v = lo + static_cast<std::uint32_t>(g() % span);
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

// The layout with its groups (make_table_layout's outputs together).
struct Made {
  TableLayout layout;
  AlignedVector<TableGroup> groups;
  AlignedVector<std::uint32_t> ids;
  [[nodiscard]] std::size_t count(std::size_t g) const { return groups[g].count; }
};
Made make(const Lanes& L, std::uint32_t sentinel) {
  Made m;
  m.layout = make_table_layout(L.ranges, L.ids, L.corners, sentinel, m.groups, m.ids);
  return m;
}
constexpr std::size_t S = kTableSlots;

TEST(LeafTables, EveryTriangleOnceWithItsCornersInGroupsOfThirtyTwo) {
  const std::uint32_t V = 2000;
  const Lanes L = hard_clusters(V, 5);
  const Made M = make(L, V);
  const TableLayout& T = M.layout;
  ASSERT_EQ(T.group_offsets.size(), L.ranges.size() + 1);
  ASSERT_EQ(M.groups.size(), T.group_count());
  ASSERT_EQ(M.ids.size(), S * T.group_count());
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
      const TableGroup& G = M.groups[g];
      const std::size_t n = G.count;
      ASSERT_GE(n, 1u);
      ASSERT_LE(n, S);
      EXPECT_EQ(G.last, g + 1 == T.group_offsets[c + 1] ? 1u : 0u) << "group " << g;
      const std::uint32_t* sv = &T.slot_vertices[S * g];
      std::size_t used = 0;
      while (used < S && sv[used] != V) ++used;
      EXPECT_EQ(G.vertices, used) << "group " << g;
      for (std::size_t s = used; s < S; ++s) {
        ASSERT_EQ(sv[s], V) << "group " << g << ": used slots first, then the sentinel";
        for (int a = 0; a < 3; ++a) EXPECT_TRUE(std::isnan(G.v[a][s])) << "group " << g << ": an unused slot not NaN";
      }
      for (std::size_t s = 0; s < used; ++s)
        for (std::size_t s2 = 0; s2 < s; ++s2) ASSERT_NE(sv[s], sv[s2]) << "group " << g << ": a vertex in two slots";
      std::vector<bool> referenced(S, false);
      for (std::size_t l = 0; l < S; ++l) {
        if (l >= n) {
          EXPECT_EQ(M.ids[S * g + l], kNoTriangle);
          for (int k = 0; k < 3; ++k) EXPECT_EQ(G.corner[k][l], used < S ? used : 0) << "padding lane of group " << g;
          continue;
        }
        std::array<std::uint32_t, 4> t{M.ids[S * g + l], 0, 0, 0};
        for (int k = 0; k < 3; ++k) {
          ASSERT_LT(G.corner[k][l], used) << "group " << g << " lane " << l;
          t[1 + k] = sv[G.corner[k][l]];
          referenced[G.corner[k][l]] = true;
        }
        got.push_back(t);
      }
      for (std::size_t s = 0; s < used; ++s) EXPECT_TRUE(referenced[s]) << "group " << g << ": slot " << s << " unused";
    }
    std::sort(want.begin(), want.end());
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want) << "cluster " << c;
  }
  // The hard clusters with a known grouping (the last five): one triangle; three degenerate ones
  // on four vertices; forty copies of one triangle (32 + 8 on three slots each); 100 triangles of
  // distinct vertices (ten a group: 30 vertices, the 11th would need 33).
  const std::size_t C = L.ranges.size();
  auto groups = [&](std::size_t c) { return T.group_offsets[c + 1] - T.group_offsets[c]; };
  EXPECT_EQ(groups(C - 5), 1u);
  EXPECT_EQ(groups(C - 4), 1u);
  EXPECT_EQ(M.groups[T.group_offsets[C - 4]].vertices, 4u);
  ASSERT_EQ(groups(C - 3), 2u);
  for (std::size_t g = T.group_offsets[C - 3], i = 0; i < 2; ++g, ++i) {
    EXPECT_EQ(M.count(g), i == 0 ? 32u : 8u);
    EXPECT_EQ(M.groups[g].vertices, 3u);
  }
  ASSERT_EQ(groups(C - 1), 10u);
  for (std::size_t g = T.group_offsets[C - 1]; g < T.group_offsets[C]; ++g) EXPECT_EQ(M.count(g), 10u);
  // 300 triangles on 20 vertices: at least 10 groups (32 triangles at most in each).
  EXPECT_GE(groups(C - 2), 10u);
}

// The documented grouping rule written plainly (a placed flag per triangle instead of the
// library's in-place reordering, sets for the new vertices): the whole layout must be the same.
struct Reference {
  std::vector<std::uint32_t> group_offsets, slot_vertices, ids, count;
  std::vector<std::uint8_t> corner;  // 3 S per group, [k][l]
};
Reference reference_layout(const Lanes& L, std::uint32_t sentinel) {
  Reference T;
  T.group_offsets.push_back(0);
  auto emit = [&](const std::vector<std::array<std::uint32_t, 4>>& tris, const std::vector<std::size_t>& members) {
    std::vector<std::uint32_t> slots;
    for (const std::size_t m : members)
      for (int k = 1; k <= 3; ++k)
        if (std::find(slots.begin(), slots.end(), tris[m][k]) == slots.end()) slots.push_back(tris[m][k]);
    for (std::size_t s = 0; s < S; ++s) T.slot_vertices.push_back(s < slots.size() ? slots[s] : sentinel);
    const auto pad = static_cast<std::uint8_t>(slots.size() < S ? slots.size() : 0);
    for (int k = 1; k <= 3; ++k)
      for (std::size_t l = 0; l < S; ++l)
        T.corner.push_back(l < members.size() ? static_cast<std::uint8_t>(
                                                    std::find(slots.begin(), slots.end(), tris[members[l]][k]) - slots.begin())
                                              : pad);
    for (std::size_t l = 0; l < S; ++l) T.ids.push_back(l < members.size() ? tris[members[l]][0] : kNoTriangle);
    T.count.push_back(static_cast<std::uint32_t>(members.size()));
  };
  for (const LeafRange& r : L.ranges) {
    std::vector<std::array<std::uint32_t, 4>> tris;  // id, corners
    for (std::uint32_t i = 0; i < r.triangle_count; ++i) {
      const std::size_t b = r.first_block + i / 4, l = i % 4;
      tris.push_back({L.ids[4 * b + l], L.corners[12 * b + l], L.corners[12 * b + 4 + l], L.corners[12 * b + 8 + l]});
    }
    std::set<std::uint32_t> all;
    for (const auto& t : tris) all.insert({t[1], t[2], t[3]});
    if (tris.size() <= S && all.size() <= S) {  // the whole cluster, in lane order
      std::vector<std::size_t> members(tris.size());
      std::iota(members.begin(), members.end(), std::size_t{0});
      emit(tris, members);
      T.group_offsets.push_back(static_cast<std::uint32_t>(T.count.size()));
      continue;
    }
    std::vector<bool> placed(tris.size(), false);
    std::size_t left = tris.size();
    while (left > 0) {
      std::set<std::uint32_t> slots;
      std::vector<std::size_t> members;
      while (members.size() < S) {
        std::vector<std::size_t> window;
        for (std::size_t i = 0; i < tris.size() && window.size() < 64; ++i)
          if (!placed[i]) window.push_back(i);
        std::size_t best = tris.size(), best_add = 4;
        for (const std::size_t i : window) {
          std::set<std::uint32_t> fresh;
          for (int k = 1; k <= 3; ++k)
            if (!slots.count(tris[i][k])) fresh.insert(tris[i][k]);
          if (slots.size() + fresh.size() <= S && fresh.size() < best_add) best = i, best_add = fresh.size();
        }
        if (best == tris.size()) break;
        placed[best] = true, --left;
        members.push_back(best);
        for (int k = 1; k <= 3; ++k) slots.insert(tris[best][k]);
      }
      emit(tris, members);
    }
    T.group_offsets.push_back(static_cast<std::uint32_t>(T.count.size()));
  }
  return T;
}

TEST(LeafTables, TheLayoutIsTheDocumentedRule) {
  const std::uint32_t V = 2000;
  Lanes L = hard_clusters(V, 11);
  // 32 one-vertex triangles: one group of 32 slots (a corner counted once however often it
  // repeats).
  std::vector<std::array<std::uint32_t, 3>> points;
  for (std::uint32_t i = 0; i < 32; ++i) points.push_back({700 + i, 700 + i, 700 + i});
  L.add_cluster(points, V);
  // Beyond 32 triangles, the fewest new vertices over the next triangle: A, then C (one new),
  // then B (three), then the others of fresh vertices.
  const std::uint32_t a = L.next_id;
  std::vector<std::array<std::uint32_t, 3>> fewest{{800, 801, 802}, {810, 811, 812}, {800, 801, 803}};
  for (std::uint32_t i = 0; i < 31; ++i) fewest.push_back({820 + 3 * i, 821 + 3 * i, 822 + 3 * i});
  L.add_cluster(fewest, V);
  // The look-ahead of 64: t0, then t1 .. t79 of fresh vertices but t75, a copy of t0 out of the
  // first group's reach (its window ends at t73): the first group is t0 .. t9 (30 vertices).
  const std::uint32_t w = L.next_id;
  std::vector<std::array<std::uint32_t, 3>> far(80);
  for (std::uint32_t i = 0; i < 80; ++i) far[i] = {1100 + 3 * i, 1101 + 3 * i, 1102 + 3 * i};
  far[75] = far[0];
  L.add_cluster(far, V);

  const Made M = make(L, V);
  const TableLayout& T = M.layout;
  const Reference R = reference_layout(L, V);
  ASSERT_EQ(T.group_offsets, R.group_offsets);
  ASSERT_EQ(T.group_count(), R.count.size());
  for (std::size_t g = 0; g < R.count.size(); ++g) {
    ASSERT_EQ(M.count(g), R.count[g]) << "group " << g;
    for (std::size_t s = 0; s < S; ++s) ASSERT_EQ(T.slot_vertices[S * g + s], R.slot_vertices[S * g + s]) << "group " << g;
    for (int k = 0; k < 3; ++k)
      for (std::size_t l = 0; l < S; ++l) ASSERT_EQ(M.groups[g].corner[k][l], R.corner[3 * S * g + S * k + l]) << "group " << g;
    for (std::size_t l = 0; l < S; ++l) ASSERT_EQ(M.ids[S * g + l], R.ids[S * g + l]) << "group " << g;
  }
  const std::size_t C = L.ranges.size();
  const std::size_t gp = T.group_offsets[C - 3], ga = T.group_offsets[C - 2], gw = T.group_offsets[C - 1];
  EXPECT_EQ(T.group_offsets[C - 2] - gp, 1u);
  EXPECT_EQ(M.count(gp), 32u);
  EXPECT_EQ(T.slot_vertices[S * gp + 31], 731u);
  EXPECT_EQ(M.ids[S * ga], a);
  EXPECT_EQ(M.ids[S * ga + 1], a + 2);
  EXPECT_EQ(M.ids[S * ga + 2], a + 1);
  ASSERT_EQ(M.count(gw), 10u);
  for (std::uint32_t l = 0; l < 10; ++l) EXPECT_EQ(M.ids[S * gw + l], w + l);
}

TEST(LeafTables, RowsAreTheFramePositionsAndBoxesThoseOfTheBlocks) {
  const std::uint32_t V = 2000;
  AlignedVector<Vec3f> fp = random_frame_positions(V, 7);
  fp[1] = {0.0f, -0.0f, 0.0f}, fp[2] = {-0.0f, 0.0f, -0.0f};
  fp[3] = {3e38f, -3e38f, 1e-38f}, fp[4] = {-1e-45f, 1e-45f, 2e38f};
  add_sentinel(fp);
  const Lanes L = hard_clusters(V, 9);
  const Made M = make(L, V);
  const TableLayout& T = M.layout;
  // The second method: the blocks' fill and its cluster boxes.
  const std::size_t nb = L.ids.size() / 4;
  AlignedVector<TriBlock> blocks(nb);
  AlignedVector<Box3f> want_boxes(L.ranges.size());
  AlignedVector<Vec3f> want_centres(L.ranges.size());
  fill_blocks_and_cluster_boxes(L.corners, fp[0].data(), blocks, nullptr, L.ranges, want_boxes.data(),
                                want_centres.data());
  AlignedVector<TableGroup> first;
  for (const auto& [threads, avx2] : {std::pair{1, true}, {2, true}, {4, true}, {1, false}, {2, false}}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    AlignedVector<TableGroup> groups = M.groups;
    AlignedVector<Box3f> boxes(L.ranges.size());
    AlignedVector<Vec3f> centres(L.ranges.size());
    fill_tables(T, fp[0].data(), groups, boxes.data(), centres.data(), avx2);
    const std::string what = "threads " + std::to_string(threads) + (avx2 ? "" : " sse2");
    for (std::size_t g = 0; g < T.group_count(); ++g) {
      ASSERT_EQ(std::memcmp(groups[g].corner, M.groups[g].corner, sizeof groups[g].corner), 0) << what;
      ASSERT_EQ(groups[g].count, M.groups[g].count);
      for (std::size_t s = 0; s < S; ++s)
        for (int a = 0; a < 3; ++a) {
          const float v = groups[g].v[a][s];
          const std::uint32_t vi = T.slot_vertices[S * g + s];
          if (vi == V) {
            ASSERT_TRUE(std::isnan(v)) << what << " group " << g << " slot " << s;
          } else {
            ASSERT_EQ(std::memcmp(&v, &fp[vi][a], sizeof v), 0) << what << " group " << g << " slot " << s;
          }
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
      first = groups;
    } else {
      ASSERT_EQ(std::memcmp(first.data(), groups.data(), sizeof(TableGroup) * groups.size()), 0) << what;
    }
  }
  // Without boxes the rows are the same.
  AlignedVector<TableGroup> rows_only = M.groups;
  fill_tables(T, fp[0].data(), rows_only, nullptr, nullptr);
  EXPECT_EQ(std::memcmp(first.data(), rows_only.data(), sizeof(TableGroup) * rows_only.size()), 0);
}

TEST(LeafTables, MismatchedSizesAreRefused) {
  const std::vector<LeafRange> ranges{{0, 1, 3}};
  const std::vector<std::uint32_t> ids{0, 1, 2, kNoTriangle};
  AlignedVector<TableGroup> groups;
  AlignedVector<std::uint32_t> tids;
  EXPECT_THROW((void)make_table_layout(ranges, ids, std::vector<std::uint32_t>(11, 0), 9, groups, tids),
               std::invalid_argument);
  EXPECT_THROW((void)make_table_layout(std::vector<LeafRange>{{0, 2, 5}}, ids, std::vector<std::uint32_t>(12, 0), 9,
                                       groups, tids),
               std::invalid_argument);
  const TableLayout T = make_table_layout(ranges, ids, std::vector<std::uint32_t>(12, 0), 9, groups, tids);
  AlignedVector<TableGroup> none;
  EXPECT_THROW(fill_tables(T, nullptr, none, nullptr, nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace ptc::bvh
