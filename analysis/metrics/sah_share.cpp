#include "analysis/metrics/sah_share.h"

namespace ptc {
namespace {

struct Sub {
  bvh::Box3f box;
  double weight = 0;
};

}  // namespace

SahShares sah_shares(const bvh::Bvh& t, std::span<const bvh::Box3f> boxes, std::span<const std::uint32_t> weights,
                     const bvh::SahCostModel& m) {
  SahShares s;
  s.contribution.assign(boxes.size(), 0.0);
  s.share.assign(boxes.size(), 0.0);
  if (t.nodes.empty()) return s;
  auto w = [&](std::uint32_t p) { return weights.empty() ? 1.0 : static_cast<double>(weights[p]); };
  // Bottom-up: every node's box and weight, from the primitive boxes (children have larger
  // indices than their parent, so one reverse sweep suffices).
  std::vector<Sub> sub(t.nodes.size());
  for (std::size_t i = t.nodes.size(); i-- > 0;) {
    const bvh::BvhNode& n = t.nodes[i];
    Sub& x = sub[i];
    if (n.is_leaf()) {
      for (std::uint32_t k = n.index; k < n.index + n.count; ++k) {
        x.box.extend(boxes[t.prim_order[k]]);
        x.weight += w(t.prim_order[k]);
      }
    } else {
      x.box = sub[i + 1].box;
      x.box.extend(sub[n.index].box);
      x.weight = sub[i + 1].weight + sub[n.index].weight;
    }
  }
  const double root_area = sub[0].box.surface_area();
  auto ratio = [&](const bvh::Box3f& b) { return root_area > 0 ? b.surface_area() / root_area : 1.0; };
  // Top-down: the inner nodes' cost per unit weight accumulated along each path.
  std::vector<std::pair<std::uint32_t, double>> stack{{0u, 0.0}};
  while (!stack.empty()) {
    const auto [i, per_weight] = stack.back();
    stack.pop_back();
    const bvh::BvhNode& n = t.nodes[i];
    if (n.is_leaf()) {
      const double leaf = m.intersection * ratio(sub[i].box);
      for (std::uint32_t k = n.index; k < n.index + n.count; ++k) {
        const std::uint32_t p = t.prim_order[k];
        s.contribution[p] = w(p) * (per_weight + leaf);
      }
      continue;
    }
    const double here = sub[i].weight > 0 ? m.traversal * ratio(sub[i].box) / sub[i].weight : 0.0;
    stack.push_back({n.index, per_weight + here});
    stack.push_back({i + 1, per_weight + here});
  }
  for (double c : s.contribution) s.cost += c;
  if (s.cost > 0)
    for (std::size_t p = 0; p < s.share.size(); ++p) s.share[p] = s.contribution[p] / s.cost;
  return s;
}

}  // namespace ptc
