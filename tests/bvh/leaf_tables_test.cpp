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
  ASSERT_EQ(T.wide.size(), T.group_count());
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
      // Slots in use: the mask, the count, and each chunk's slots in use first in the chunk; a
      // group of at most 16 vertices on slots 0 .. vertices - 1.
      std::uint32_t mask = 0;
      for (std::size_t s = 0; s < S; ++s) mask |= sv[s] != V ? 1u << s : 0u;
      ASSERT_EQ(G.slot_mask, mask) << "group " << g;
      // The fill's half flag: whether a slot of 16-31 holds a vertex (else it reads and writes
      // only the first halves).
      bool upper = false;
      for (std::size_t s = 16; s < S; ++s) upper = upper || sv[s] != V;
      EXPECT_EQ(T.wide[g], upper ? 1 : 0) << "group " << g;
      const auto used = static_cast<std::size_t>(__builtin_popcount(mask));
      EXPECT_EQ(G.vertices, used) << "group " << g;
      for (std::size_t s = 1; s < S; ++s) {
        if (s % 8 != 0 && (mask >> s & 1)) {
          ASSERT_TRUE(mask >> (s - 1) & 1) << "group " << g << ": a gap before slot " << s;
        }
      }
      if (used <= 16) {
        EXPECT_EQ(mask, (std::uint32_t{1} << used) - 1) << "group " << g;
      }
      for (std::size_t s = 0; s < S; ++s) {
        if (!(mask >> s & 1)) {
          for (int a = 0; a < 3; ++a) EXPECT_TRUE(std::isnan(G.v[a][s])) << "group " << g << ": an unused slot not NaN";
        }
      }
      for (std::size_t s = 0; s < S; ++s) {
        for (std::size_t s2 = 0; s2 < s; ++s2) {
          if (sv[s] != V) {
            ASSERT_NE(sv[s], sv[s2]) << "group " << g << ": a vertex in two slots";
          }
        }
      }
      const std::uint8_t pad = mask == ~0u ? 0 : static_cast<std::uint8_t>(__builtin_ctz(~mask));
      std::vector<bool> referenced(S, false);
      for (std::size_t l = 0; l < S; ++l) {
        if (l >= n) {
          EXPECT_EQ(M.ids[S * g + l], kNoTriangle);
          for (int k = 0; k < 3; ++k) EXPECT_EQ(G.corner[k][l], pad) << "padding lane of group " << g;
          continue;
        }
        std::array<std::uint32_t, 4> t{M.ids[S * g + l], 0, 0, 0};
        const std::uint8_t pair = G.pair[l / 8];
        ASSERT_LE(pair, 3) << "group " << g;
        for (int k = 0; k < 3; ++k) {
          const std::uint8_t slot = G.corner[k][l];
          ASSERT_TRUE(slot < S && (mask >> slot & 1)) << "group " << g << " lane " << l;
          const int chunk = slot & ~7;
          ASSERT_TRUE(chunk == table_even_chunk(pair) || chunk == table_odd_chunk(pair))
              << "group " << g << " lane " << l << ": slot " << int(slot) << " outside its test's chunks";
          t[1 + k] = sv[slot];
          referenced[slot] = true;
        }
        got.push_back(t);
      }
      for (std::size_t s = 0; s < S; ++s)
        EXPECT_EQ(referenced[s], (mask >> s & 1) != 0) << "group " << g << ": slot " << s << " in use but unreferenced";
    }
    std::sort(want.begin(), want.end());
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want) << "cluster " << c;
  }
  // The hard clusters with a known grouping (the last five): one triangle; three degenerate ones
  // on four vertices; forty copies of one triangle (32 + 8 on three slots each); 100 triangles of
  // distinct vertices (five a group: six would put 18 vertices in one test of eight, which two
  // chunks cannot hold).
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
  ASSERT_EQ(groups(C - 1), 20u);
  for (std::size_t g = T.group_offsets[C - 1]; g < T.group_offsets[C]; ++g) EXPECT_EQ(M.count(g), 5u);
  // 300 triangles on 20 vertices: at least 10 groups (32 triangles at most in each).
  EXPECT_GE(groups(C - 2), 10u);
}

// Whether a group's tests of eight fit chunk pairs (TableGroup), written plainly: every
// combination of pairs (the first test's too), and for each a maximum flow (augmenting paths
// found by breadth-first search) from the vertices to the chunks their tests share, eight a
// chunk. `tris`: (id, corners); `members`: the group's triangles in order.
bool fits_chunks(const std::vector<std::array<std::uint32_t, 4>>& tris, const std::vector<std::size_t>& members) {
  std::vector<std::uint32_t> verts;
  for (const std::size_t m : members)
    for (int k = 1; k <= 3; ++k)
      if (std::find(verts.begin(), verts.end(), tris[m][k]) == verts.end()) verts.push_back(tris[m][k]);
  const std::size_t V = verts.size(), T = (members.size() + 7) / 8;
  if (V > S) return false;
  if (V <= 16) return true;
  std::vector<unsigned> tests_of(V, 0);
  for (std::size_t i = 0; i < members.size(); ++i)
    for (int k = 1; k <= 3; ++k)
      tests_of[std::find(verts.begin(), verts.end(), tris[members[i]][k]) - verts.begin()] |= 1u << (i / 8);
  for (std::size_t j = 0; j < T; ++j) {  // (a test of more than 16 vertices fits no two chunks)
    std::size_t n = 0;
    for (std::size_t v = 0; v < V; ++v) n += tests_of[v] >> j & 1;
    if (n > 16) return false;
  }
  for (unsigned c = 0; c < 1u << (2 * T); ++c) {
    // nodes: 0 source, 1 .. V vertices, V + 1 .. V + 4 chunks, V + 5 sink
    const std::size_t N = V + 6, src = 0, sink = V + 5;
    std::array<std::array<int, S + 6>, S + 6> cap{};
    bool every_vertex_has_a_chunk = true;
    for (std::size_t v = 0; v < V; ++v) {
      cap[src][1 + v] = 1;
      bool any = false;
      for (int k = 0; k < 4; ++k) {
        bool ok = true;
        for (std::size_t j = 0; j < T; ++j) {
          if (!(tests_of[v] >> j & 1)) continue;
          const std::uint8_t code = static_cast<std::uint8_t>(c >> (2 * j) & 3u);
          ok = ok && (8 * k == table_even_chunk(code) || 8 * k == table_odd_chunk(code));
        }
        if (ok) cap[1 + v][V + 1 + k] = 1, any = true;
      }
      every_vertex_has_a_chunk = every_vertex_has_a_chunk && any;
    }
    if (!every_vertex_has_a_chunk) continue;
    for (int k = 0; k < 4; ++k) cap[V + 1 + k][sink] = 8;
    std::vector<std::vector<std::size_t>> adj(N);  // both directions of every edge
    for (std::size_t a = 0; a < N; ++a)
      for (std::size_t b = 0; b < N; ++b)
        if (cap[a][b] > 0) adj[a].push_back(b), adj[b].push_back(a);
    std::size_t flow = 0;
    for (;;) {
      std::array<int, S + 6> from;
      from.fill(-1);
      from[src] = static_cast<int>(src);
      std::array<std::size_t, S + 6> queue{src};
      std::size_t queued = 1;
      for (std::size_t q = 0; q < queued && from[sink] < 0; ++q)
        for (const std::size_t w : adj[queue[q]])
          if (from[w] < 0 && cap[queue[q]][w] > 0) from[w] = static_cast<int>(queue[q]), queue[queued++] = w;
      if (from[sink] < 0) break;
      for (std::size_t w = sink; w != src; w = static_cast<std::size_t>(from[w])) --cap[from[w]][w], ++cap[w][from[w]];
      ++flow;
    }
    if (flow == V) return true;
  }
  return false;
}

// The documented grouping rule written plainly (a placed flag per triangle instead of the
// library's in-place reordering, sets for the new vertices, fits_chunks): the groups, their
// triangles in order and the vertices they hold must be the library's; the slots of a group of
// at most 16 vertices too.
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
    std::vector<std::size_t> everything(tris.size());
    std::iota(everything.begin(), everything.end(), std::size_t{0});
    if (tris.size() <= S && fits_chunks(tris, everything)) {  // the whole cluster, in lane order
      emit(tris, everything);
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
      while (!fits_chunks(tris, members)) placed[members.back()] = false, ++left, members.pop_back();
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
  // first group's reach (its window ends at t73): the first group takes t0 .. t9 (30 vertices),
  // then gives back t5 .. t9 (six triangles of fresh vertices would need 18 slots in one test).
  const std::uint32_t w = L.next_id;
  std::vector<std::array<std::uint32_t, 3>> far(80);
  for (std::uint32_t i = 0; i < 80; ++i) far[i] = {1100 + 3 * i, 1101 + 3 * i, 1102 + 3 * i};
  far[75] = far[0];
  L.add_cluster(far, V);
  // A triangle given back after it was taken out of lane order returns to its lane's place: t0 ..
  // t79 of fresh vertices but t70, which shares two with t5. The first group takes t0 .. t6, then
  // t70 (one new vertex; t6's placing brought it into the window of 64), t7, t8, t9, and gives
  // back t9 .. t5. The second then takes t5, t6 (t70 is beyond its window until t6 is placed),
  // t70, t7, t8, t9: had t70 come back beside t5, it would have followed t5 at once.
  const std::uint32_t kb = L.next_id;
  std::vector<std::array<std::uint32_t, 3>> back(80);
  for (std::uint32_t i = 0; i < 80; ++i) back[i] = {1400 + 3 * i, 1401 + 3 * i, 1402 + 3 * i};
  back[70] = {back[5][0], back[5][1], 1399};
  L.add_cluster(back, V);

  const Made M = make(L, V);
  const TableLayout& T = M.layout;
  const Reference R = reference_layout(L, V);
  ASSERT_EQ(T.group_offsets, R.group_offsets);
  ASSERT_EQ(T.group_count(), R.count.size());
  std::size_t chunked = 0;  // groups of more than 16 vertices
  for (std::size_t g = 0; g < R.count.size(); ++g) {
    ASSERT_EQ(M.count(g), R.count[g]) << "group " << g;
    for (std::size_t l = 0; l < S; ++l) ASSERT_EQ(M.ids[S * g + l], R.ids[S * g + l]) << "group " << g;
    if (M.groups[g].vertices <= 16) {  // the slots in the order taken
      for (std::size_t s = 0; s < S; ++s) ASSERT_EQ(T.slot_vertices[S * g + s], R.slot_vertices[S * g + s]) << "group " << g;
      for (int k = 0; k < 3; ++k)
        for (std::size_t l = 0; l < S; ++l)
          ASSERT_EQ(M.groups[g].corner[k][l], R.corner[3 * S * g + S * k + l]) << "group " << g;
      continue;
    }
    ++chunked;  // the same vertices, and each corner on its vertex (the slots are the library's choice)
    std::vector<std::uint32_t> got(T.slot_vertices.begin() + S * g, T.slot_vertices.begin() + S * (g + 1));
    std::vector<std::uint32_t> want(R.slot_vertices.begin() + S * g, R.slot_vertices.begin() + S * (g + 1));
    std::sort(got.begin(), got.end()), std::sort(want.begin(), want.end());
    ASSERT_EQ(got, want) << "group " << g;
    for (int k = 0; k < 3; ++k)
      for (std::size_t l = 0; l < M.count(g); ++l)
        ASSERT_EQ(T.slot_vertices[S * g + M.groups[g].corner[k][l]], R.slot_vertices[S * g + R.corner[3 * S * g + S * k + l]])
            << "group " << g << " lane " << l;
  }
  EXPECT_GT(chunked, 50u) << "too few groups of more than 16 vertices to test their chunks";
  const std::size_t C = L.ranges.size() - 1;  // (the last cluster, `back`, is checked below)
  const std::size_t gp = T.group_offsets[C - 3], ga = T.group_offsets[C - 2], gw = T.group_offsets[C - 1];
  EXPECT_EQ(T.group_offsets[C - 2] - gp, 1u);
  EXPECT_EQ(M.count(gp), 32u);
  EXPECT_EQ(M.groups[gp].vertices, 32u);
  EXPECT_EQ(M.groups[gp].slot_mask, ~0u);
  EXPECT_EQ(M.ids[S * ga], a);
  EXPECT_EQ(M.ids[S * ga + 1], a + 2);
  EXPECT_EQ(M.ids[S * ga + 2], a + 1);
  ASSERT_EQ(M.count(gw), 5u);
  for (std::uint32_t l = 0; l < 5; ++l) EXPECT_EQ(M.ids[S * gw + l], w + l);
  EXPECT_EQ(M.ids[S * (gw + 1)], w + 5) << "the triangles given back come first again";
  const std::size_t gk = T.group_offsets[C];
  ASSERT_EQ(M.count(gk), 5u);
  for (std::uint32_t l = 0; l < 5; ++l) EXPECT_EQ(M.ids[S * gk + l], kb + l);
  ASSERT_EQ(M.count(gk + 1), 6u);
  const std::uint32_t second[6] = {kb + 5, kb + 6, kb + 70, kb + 7, kb + 8, kb + 9};
  for (std::uint32_t l = 0; l < 6; ++l) EXPECT_EQ(M.ids[S * (gk + 1) + l], second[l]) << "lane " << l;
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
  TableLayout no_flags = T;  // (a layout made elsewhere without the half flags)
  no_flags.wide.clear();
  EXPECT_THROW(fill_tables(no_flags, nullptr, groups, nullptr, nullptr), std::invalid_argument);
  // The estimate of LeafFormatChoice::Auto: offset lists of different lengths, or decreasing.
  const std::vector<std::uint32_t> two{0, 5}, three{0, 5, 9}, down{0, 5, 3};
  EXPECT_THROW((void)estimate_leaf_bytes(two, three), std::invalid_argument);
  EXPECT_THROW((void)estimate_leaf_bytes(down, three), std::invalid_argument);
  EXPECT_THROW((void)estimate_leaf_bytes(three, down), std::invalid_argument);
  // (no clusters: no bytes, and no tables)
  const std::vector<std::uint32_t> zero{0};
  EXPECT_EQ(estimate_leaf_bytes(zero, zero).blocks, 0u);
  EXPECT_FALSE(tables_suit(estimate_leaf_bytes(zero, zero)));
}

}  // namespace
}  // namespace ptc::bvh
