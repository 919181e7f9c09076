// The one closest-hit agreement check (analysis/metrics/hit_agreement.h), ray by ray.
#include <gtest/gtest.h>

#include "analysis/metrics/hit_agreement.h"

namespace ptc {
namespace {

bvh::HitBatch batch(std::vector<std::uint32_t> tri, std::vector<float> t) {
  bvh::HitBatch h;
  h.resize(tri.size());
  for (std::size_t i = 0; i < tri.size(); ++i) h.triangle[i] = tri[i], h.t[i] = t[i];
  return h;
}

TEST(HitAgreement, MissesOtherTrianglesAndTies) {
  const std::uint32_t miss = bvh::kNoTriangle;
  const auto ref = batch({1, 2, miss, 4, 5, 6, miss}, {1.0f, 2.0f, 0.0f, 4.0f, 5.0f, 6.0f, 0.0f});
  const auto got = batch({1, miss, 3, 9, 8, 6, miss}, {1.0f, 0.0f, 3.0f, 4.0f + 2e-5f, 5.0f + 1e-3f, 6.0f, 0.0f});
  const HitAgreement a = compare_hits(ref, got);  // default tie: 1e-5 relative
  EXPECT_EQ(a.rays, 7u);
  EXPECT_EQ(a.hit_miss, 2u);        // rays 1 and 2
  EXPECT_EQ(a.ties, 1u);            // ray 3: 2e-5 / 4 = 5e-6
  EXPECT_EQ(a.other_triangle, 1u);  // ray 4: 1e-3 / 5 = 2e-4
  EXPECT_EQ(a.mismatches(), 3u);
  // A looser tie rule turns ray 4 into a tie.
  const HitAgreement loose = compare_hits(ref, got, TieRule{1e-3});
  EXPECT_EQ(loose.ties, 2u);
  EXPECT_EQ(loose.other_triangle, 0u);
  EXPECT_EQ(compare_hits(ref, ref).mismatches(), 0u);
  EXPECT_THROW((void)compare_hits(ref, batch({1}, {1.0f})), std::invalid_argument);
}

}  // namespace
}  // namespace ptc
