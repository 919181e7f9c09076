// Morton order against a brute force written from the header's definition: bit-by-bit
// interleaving and a plain sort of (code, id) pairs. Degenerate inputs first.
#include "toolkit/geometry/morton.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

namespace ptc {
namespace {

std::uint64_t interleave_bit_by_bit(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  std::uint64_t code = 0;
  for (int i = 0; i < kMortonBits; ++i) {
    code |= static_cast<std::uint64_t>((x >> i) & 1u) << (3 * i + 2);
    code |= static_cast<std::uint64_t>((y >> i) & 1u) << (3 * i + 1);
    code |= static_cast<std::uint64_t>((z >> i) & 1u) << (3 * i);
  }
  return code;
}

// The header's definition, spelled out independently.
std::vector<std::uint32_t> brute_force_order(const std::vector<Vec3>& pos, const std::vector<Tri>& tris,
                                             MortonGrid grid) {
  if (tris.empty()) return {};
  std::vector<Vec3> c;
  for (const Tri& t : tris) c.push_back((pos[t[0]] + pos[t[1]] + pos[t[2]]) / 3.0);
  Vec3 lo = c[0], hi = c[0];
  for (const Vec3& v : c) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  const Vec3 e = hi - lo;
  const double cells = std::ldexp(1.0, kMortonBits);
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    std::uint32_t q[3];
    for (int a = 0; a < 3; ++a) {
      const double ext = grid == MortonGrid::Cube ? e.maxCoeff() : e[a];
      const double s = ext > 0 ? cells / ext : 0.0;
      const double f = std::floor((c[t][a] - lo[a]) * s);
      q[a] = static_cast<std::uint32_t>(std::min(f, cells - 1));
    }
    keyed.emplace_back(interleave_bit_by_bit(q[0], q[1], q[2]), t);
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> order;
  for (const auto& k : keyed) order.push_back(k.second);
  return order;
}

TEST(MortonEncode, MatchesBitByBitInterleaving) {
  const std::uint32_t max = (1u << kMortonBits) - 1;
  EXPECT_EQ(morton_encode(0, 0, 0), 0u);
  EXPECT_EQ(morton_encode(1, 0, 0), 4u);
  EXPECT_EQ(morton_encode(0, 1, 0), 2u);
  EXPECT_EQ(morton_encode(0, 0, 1), 1u);
  EXPECT_EQ(morton_encode(max, max, max), (std::uint64_t{1} << 63) - 1);
  EXPECT_EQ(morton_encode(max + 1, 0, 0), 0u);  // bits above 21 ignored
  std::mt19937_64 rng(61);
  std::uniform_int_distribution<std::uint32_t> u(0, max);
  for (int i = 0; i < 100000; ++i) {
    const std::uint32_t x = u(rng), y = u(rng), z = u(rng);
    ASSERT_EQ(morton_encode(x, y, z), interleave_bit_by_bit(x, y, z)) << x << " " << y << " " << z;
  }
}

TEST(MortonOrder, EmptyInput) {
  EXPECT_TRUE(morton_order({}, {}).empty());
  const std::vector<Vec3> p{{1, 2, 3}};
  EXPECT_TRUE(morton_order(p, {}).empty());
  EXPECT_TRUE(morton_codes(p, {}).empty());
}

TEST(MortonOrder, OutOfRangeIndexThrows) {
  const std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}};
  const std::vector<Tri> t{{0, 1, 2}};
  EXPECT_THROW((void)morton_order(p, t), std::invalid_argument);
}

TEST(MortonOrder, AllCentroidsEqualGivesIdOrder) {
  // Different triangles, same centroid (0,0,0): every code 0, ties by id.
  const std::vector<Vec3> p{{1, 0, 0}, {-1, 0, 0}, {0, 0, 0}, {0, 2, 0}, {0, -2, 0}, {0, 0, 5}, {0, 0, -5}};
  const std::vector<Tri> t{{0, 1, 2}, {3, 4, 2}, {5, 6, 2}, {2, 2, 2}, {0, 1, 2}};
  for (MortonGrid g : {MortonGrid::Cube, MortonGrid::PerAxis}) {
    EXPECT_EQ(morton_order(p, t, g), (std::vector<std::uint32_t>{0, 1, 2, 3, 4}));
    for (std::uint64_t c : morton_codes(p, t, g)) EXPECT_EQ(c, 0u);
  }
  // A single triangle.
  const std::vector<Tri> one{{3, 4, 5}};
  EXPECT_EQ(morton_order(p, one), (std::vector<std::uint32_t>{0}));
}

TEST(MortonOrder, UnitCubeCornersFollowZOrder) {
  // Degenerate "triangles" (all corners equal) at the 8 corners of [0,1]^3, listed in reverse
  // Z-order: the order must be x-major, then y, then z (x is the most significant axis).
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (int i = 7; i >= 0; --i) {
    p.emplace_back(i >> 2 & 1, i >> 1 & 1, i & 1);
    const auto v = static_cast<std::uint32_t>(p.size() - 1);
    t.push_back({v, v, v});
  }
  EXPECT_EQ(morton_order(p, t), (std::vector<std::uint32_t>{7, 6, 5, 4, 3, 2, 1, 0}));
  // The far corner lands in the last cell on every axis (clamped), the near one in cell 0.
  const auto codes = morton_codes(p, t);
  EXPECT_EQ(codes[0], (std::uint64_t{1} << 63) - 1);
  EXPECT_EQ(codes[7], 0u);
}

TEST(MortonOrder, FlatAlongAnAxisMatchesBruteForce) {
  std::mt19937_64 rng(67);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int flat = 0; flat < 3; ++flat) {
    std::vector<Vec3> p;
    for (int i = 0; i < 300; ++i) {
      Vec3 v(u(rng), u(rng), u(rng));
      v[flat] = 1.25;  // every centroid shares this coordinate
      p.push_back(v);
    }
    std::uniform_int_distribution<std::uint32_t> ui(0, 299);
    std::vector<Tri> t;
    for (int i = 0; i < 500; ++i) t.push_back({ui(rng), ui(rng), ui(rng)});
    for (MortonGrid g : {MortonGrid::Cube, MortonGrid::PerAxis}) {
      EXPECT_EQ(morton_order(p, t, g), brute_force_order(p, t, g)) << "flat axis " << flat;
      // The flat axis contributes no bit.
      const std::uint64_t mask = interleave_bit_by_bit(flat == 0 ? ~0u : 0u, flat == 1 ? ~0u : 0u, flat == 2 ? ~0u : 0u);
      for (std::uint64_t c : morton_codes(p, t, g)) EXPECT_EQ(c & mask, 0u);
    }
  }
}

TEST(MortonOrder, RandomMeshesMatchBruteForce) {
  std::mt19937_64 rng(71);
  for (int rep = 0; rep < 20; ++rep) {
    // Anisotropic box, a far offset on some repetitions, duplicated triangles (ties by id).
    const Vec3 off = rep % 3 == 0 ? Vec3(1e7, -1e7, 3e6) : Vec3::Zero();
    std::uniform_real_distribution<double> ux(-5, 20), uy(0, 1), uz(100, 100.5);
    std::vector<Vec3> p;
    const int nv = 50 + rep * 40;
    for (int i = 0; i < nv; ++i) p.push_back(off + Vec3(ux(rng), uy(rng), uz(rng)));
    std::uniform_int_distribution<std::uint32_t> ui(0, static_cast<std::uint32_t>(nv - 1));
    std::vector<Tri> t;
    for (int i = 0; i < 3 * nv; ++i) t.push_back({ui(rng), ui(rng), ui(rng)});
    for (int i = 0; i < nv / 5; ++i) t.push_back(t[static_cast<std::size_t>(i * 2)]);
    for (MortonGrid g : {MortonGrid::Cube, MortonGrid::PerAxis}) {
      const auto order = morton_order(p, t, g);
      ASSERT_EQ(order, brute_force_order(p, t, g)) << "rep " << rep;
      // A permutation of 0..T-1.
      std::vector<std::uint32_t> sorted = order;
      std::sort(sorted.begin(), sorted.end());
      for (std::uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
    }
  }
}

TEST(MortonOrder, LargeInputWithManyEqualCodesMatchesBruteForce) {
  // 120k triangles: most in 40 tiny clumps (equal codes, so the order among them is by id), a few
  // far away (codes that differ in the top bytes only).
  std::mt19937_64 rng(73);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Vec3> p;
  for (int c = 0; c < 40; ++c) {
    const Vec3 base(u(rng), u(rng), u(rng));
    for (int i = 0; i < 30; ++i) p.push_back(base + 1e-12 * Vec3(u(rng), u(rng), u(rng)));
  }
  p.push_back(Vec3(1e3, 0, 0));
  p.push_back(Vec3(-1e3, 5e2, 0));
  std::uniform_int_distribution<std::uint32_t> ui(0, static_cast<std::uint32_t>(p.size() - 1));
  std::vector<Tri> t;
  for (int i = 0; i < 120000; ++i) {
    const std::uint32_t a = ui(rng);
    const std::uint32_t clump = a < 1200 ? a / 30 * 30 : a;  // corners from one clump, or a far point
    t.push_back({a, clump, a < 1200 ? clump + 29 : a});
  }
  for (MortonGrid g : {MortonGrid::Cube, MortonGrid::PerAxis}) {
    const std::vector<std::uint32_t> expected = brute_force_order(p, t, g);
    for (int threads : {1, 2, 4}) {  // the buckets are sorted on the caller's threads
      std::vector<std::uint32_t> order;
      tbb::task_arena(threads).execute([&] { order = morton_order(p, t, g); });
      ASSERT_EQ(order, expected) << threads << " threads";
    }
  }
}

TEST(MortonOrder, LargeBucketsOfDistinctCodesMatchBruteForce) {
  // 150k point triangles in a small corner of the unit cube (two points at opposite corners
  // span it): all but one share the top 11 bits of their codes, so one bucket holds about 150k
  // ids, scattered by the next 11 bits into sub-buckets of a few thousand distinct codes each,
  // with a few hundred exact duplicates (ties by id) among them.
  std::mt19937_64 rng(79);
  std::uniform_real_distribution<double> u(0, 0.02);
  std::vector<Vec3> p{{0, 0, 0}, {1, 1, 1}};
  std::vector<Tri> t{{0, 0, 0}, {1, 1, 1}};
  for (std::uint32_t i = 2; i < 150000; ++i) {
    p.emplace_back(u(rng), u(rng), u(rng));
    t.push_back({i, i, i});
  }
  for (std::uint32_t i = 0; i < 500; ++i) t.push_back(t[7 * i]);
  const std::vector<std::uint32_t> expected = brute_force_order(p, t, MortonGrid::Cube);
  std::vector<std::size_t> bucket_size(2048, 0);
  for (std::uint64_t c : morton_codes(p, t)) ++bucket_size[c >> (3 * kMortonBits - 11)];
  EXPECT_GE(*std::max_element(bucket_size.begin(), bucket_size.end()), 100000u);  // the two-level path is taken
  for (int threads : {1, 2}) {
    std::vector<std::uint32_t> order;
    tbb::task_arena(threads).execute([&] { order = morton_order(p, t); });
    ASSERT_EQ(order, expected) << threads << " threads";
  }
}

TEST(MortonOrder, CubeGridKeepsRunsCompactOnThinMeshes) {
  // Points on a long thin grid 256 x 4 (x by y), one degenerate triangle each. With cubic cells a
  // run of 16 consecutive triangles is a compact block (ideal: 4 x 4, x-extent 3); stretching
  // the 4 rows over the whole y range (PerAxis) makes runs of 16 span about 16 columns.
  // Measured as the mean x-extent of the runs (measured: 3 and 15).
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (int x = 0; x < 256; ++x)
    for (int y = 0; y < 4; ++y) {
      p.emplace_back(x, y, 0);
      const auto v = static_cast<std::uint32_t>(p.size() - 1);
      t.push_back({v, v, v});
    }
  auto mean_run_extent = [&](MortonGrid g) {
    const auto order = morton_order(p, t, g);
    double sum = 0;
    for (std::size_t r = 0; r < order.size(); r += 16) {
      double lo = 1e9, hi = -1e9;
      for (std::size_t i = r; i < r + 16; ++i) lo = std::min(lo, p[order[i]].x()), hi = std::max(hi, p[order[i]].x());
      sum += hi - lo;
    }
    return sum / static_cast<double>(order.size() / 16);
  };
  EXPECT_LE(mean_run_extent(MortonGrid::Cube), 4.0);
  EXPECT_GE(mean_run_extent(MortonGrid::PerAxis), 3 * mean_run_extent(MortonGrid::Cube));
}

}  // namespace
}  // namespace ptc
