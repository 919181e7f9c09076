// Morton runs (toolkit/clustering/morton_runs.h) against a direct cut of the Morton order.
#include <gtest/gtest.h>

#include <algorithm>

#include "test_meshes.h"
#include "toolkit/clustering/morton_runs.h"
#include "toolkit/geometry/morton.h"

namespace ptc {
namespace {

TEST(MortonRuns, ConsecutiveRunsOfTheMortonOrder) {
  const Mesh m = test_meshes::load("elephant.off");
  const auto order = morton_order(m.positions(), m.triangles());
  for (const MortonRunsConfig cfg : {MortonRunsConfig{64, 64, 1}, MortonRunsConfig{7, 130, 3}, MortonRunsConfig{1, 1, 1}}) {
    const Clustering c = morton_runs(m, cfg);
    ASSERT_EQ(c.triangle_count(), m.triangle_count());
    std::size_t first = 0;
    for (std::size_t k = 0; k < c.cluster_count(); ++k) {
      const auto t = c.triangles_of(k);
      const std::size_t n = t.size();
      // Every run but the last has a length in [min_run, max_run].
      if (k + 1 < c.cluster_count()) {
        EXPECT_GE(n, cfg.min_run);
        EXPECT_LE(n, cfg.max_run);
      }
      std::vector<std::uint32_t> want(order.begin() + std::ptrdiff_t(first), order.begin() + std::ptrdiff_t(first + n));
      std::sort(want.begin(), want.end());
      ASSERT_EQ(std::vector<std::uint32_t>(t.begin(), t.end()), want) << "run " << k;
      std::vector<std::uint32_t> vs;
      for (std::uint32_t tri : want)
        for (std::uint32_t v : m.triangle(tri)) vs.push_back(v);
      std::sort(vs.begin(), vs.end());
      vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
      const auto got = c.vertices_of(k);
      ASSERT_EQ(std::vector<std::uint32_t>(got.begin(), got.end()), vs) << "run " << k;
      first += n;
    }
    EXPECT_EQ(first, order.size());
  }
  // Seeded: the same runs every time; another seed other runs.
  EXPECT_EQ(morton_runs(m, {7, 130, 3}).triangle_offsets, morton_runs(m, {7, 130, 3}).triangle_offsets);
  EXPECT_NE(morton_runs(m, {7, 130, 3}).triangle_offsets, morton_runs(m, {7, 130, 4}).triangle_offsets);
}

TEST(MortonRuns, EmptyMeshAndBadConfigurations) {
  EXPECT_EQ(morton_runs(Mesh{}, 8).cluster_count(), 0u);
  const Mesh m = test_meshes::load("cube.off");
  EXPECT_THROW((void)morton_runs(m, 0), std::invalid_argument);
  EXPECT_THROW((void)morton_runs(m, MortonRunsConfig{5, 4, 1}), std::invalid_argument);
  EXPECT_EQ(morton_runs(m, 100).cluster_count(), 1u);
}

}  // namespace
}  // namespace ptc
