#include "analysis/metrics/hit_agreement.h"

#include <cmath>
#include <stdexcept>

namespace ptc {

HitAgreement compare_hits(const bvh::HitBatch& ref, const bvh::HitBatch& got, const TieRule& rule) {
  if (ref.size() != got.size()) throw std::invalid_argument("compare_hits: batches of different sizes");
  HitAgreement a;
  a.rays = ref.size();
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const bool r = ref.triangle[i] != bvh::kNoTriangle, g = got.triangle[i] != bvh::kNoTriangle;
    if (r != g) {
      ++a.hit_miss;
    } else if (r && ref.triangle[i] != got.triangle[i]) {
      if (std::abs(double(ref.t[i]) - double(got.t[i])) <= rule.rel_t * std::abs(double(ref.t[i])))
        ++a.ties;
      else
        ++a.other_triangle;
    }
  }
  return a;
}

}  // namespace ptc
