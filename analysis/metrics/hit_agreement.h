// Agreement of two closest-hit batches over the same rays, ray by ray: the one mismatch check of
// every comparison (ours against brute force, Embree against ours).
//
// A ray disagrees when one side hits and the other misses (hit_miss), or both hit different
// triangles at t values differing by more than the tie rule allows (other_triangle). Different
// triangles within the tie rule are a tie (rays through shared edges and vertices, where both
// triangles are a correct closest hit), counted apart. mismatches = hit_miss + other_triangle.
#pragma once

#include <cstdint>

#include "bvh/tracer.h"

namespace ptc {

/// Different triangles count as a tie when |t_got - t_ref| <= rel_t * |t_ref|.
struct TieRule {
  double rel_t = 1e-5;
};

struct HitAgreement {
  std::uint64_t rays = 0, hit_miss = 0, other_triangle = 0, ties = 0;
  [[nodiscard]] std::uint64_t mismatches() const { return hit_miss + other_triangle; }
};

/// `ref` and `got` of the same rays (equal sizes; std::invalid_argument otherwise).
[[nodiscard]] HitAgreement compare_hits(const bvh::HitBatch& ref, const bvh::HitBatch& got, const TieRule& rule = {});

}  // namespace ptc
