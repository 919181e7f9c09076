#include "bvh/bvh.h"

#include <algorithm>
#include <utility>

namespace ptc::bvh {

BvhStats stats(const Bvh& bvh) {
  BvhStats s;
  if (bvh.nodes.empty()) return s;
  std::vector<std::pair<std::uint32_t, std::size_t>> stack{{0u, std::size_t{1}}};
  std::size_t prims = 0;
  while (!stack.empty()) {
    const auto [node, depth] = stack.back();
    stack.pop_back();
    const BvhNode& nd = bvh.nodes[node];
    s.max_depth = std::max(s.max_depth, depth);
    if (nd.is_leaf()) {
      ++s.leaves;
      prims += nd.count;
      s.max_leaf_size = std::max<std::size_t>(s.max_leaf_size, nd.count);
    } else {
      ++s.inner;
      stack.push_back({nd.index, depth + 1});
      stack.push_back({node + 1, depth + 1});
    }
  }
  s.mean_leaf_size = s.leaves ? static_cast<double>(prims) / static_cast<double>(s.leaves) : 0.0;
  return s;
}

}  // namespace ptc::bvh
