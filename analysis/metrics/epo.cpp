#include "analysis/metrics/epo.h"

#include "toolkit/geometry/clip.h"

namespace ptc {
namespace {

bool overlap(const Box3& a, const Box3& b) {
  return (a.lo.array() <= b.hi.array()).all() && (b.lo.array() <= a.hi.array()).all();
}

}  // namespace

EpoResult end_point_overlap(const bvh::Bvh& t, std::span<const Tri> tris, std::span<const Vec3> pos,
                            std::span<const std::uint32_t> prim_offsets, std::span<const std::uint32_t> prim_triangles,
                            const bvh::SahCostModel& m) {
  EpoResult r;
  r.node_overlap.assign(t.nodes.size(), 0.0);
  for (const Tri& f : tris) r.total_area += 0.5 * (pos[f[1]] - pos[f[0]]).cross(pos[f[2]] - pos[f[0]]).norm();
  if (t.nodes.empty()) return r;
  const bool identity = prim_offsets.empty();
  auto triangles_of = [&](std::uint32_t p) {
    return identity ? std::span<const std::uint32_t>() : prim_triangles.subspan(prim_offsets[p], prim_offsets[p + 1] - prim_offsets[p]);
  };
  std::vector<Box3> tri_boxes(tris.size());
  for (std::size_t id = 0; id < tris.size(); ++id)
    for (std::uint32_t v : tris[id]) tri_boxes[id].extend(pos[v]);
  auto tri_box = [&](std::uint32_t id) -> const Box3& { return tri_boxes[id]; };
  // Bottom-up: node boxes in double, and the end of each subtree in pre-order (the subtree of
  // node i is nodes [i, end[i])).
  const std::size_t N = t.nodes.size();
  std::vector<Box3> box(N);
  std::vector<std::uint32_t> end(N);
  std::vector<Box3> prim_box(t.prim_order.size());
  for (std::size_t p = 0; p < prim_box.size(); ++p) {
    if (identity) {
      prim_box[p] = tri_box(static_cast<std::uint32_t>(p));
    } else {
      for (std::uint32_t id : triangles_of(static_cast<std::uint32_t>(p))) prim_box[p].extend(tri_box(id));
    }
  }
  for (std::size_t i = N; i-- > 0;) {
    const bvh::BvhNode& n = t.nodes[i];
    if (n.is_leaf()) {
      for (std::uint32_t k = n.index; k < n.index + n.count; ++k) box[i].extend(prim_box[t.prim_order[k]]);
      end[i] = static_cast<std::uint32_t>(i + 1);
    } else {
      box[i] = box[i + 1];
      box[i].extend(box[n.index]);
      end[i] = end[n.index];
    }
  }
  // Per node: the overlap query on the tree itself.
  std::vector<std::uint32_t> stack;
  for (std::size_t i = 0; i < N; ++i) {
    const Box3& q = box[i];
    double area = 0;
    stack.assign(1, 0u);
    while (!stack.empty()) {
      const std::uint32_t j = stack.back();
      stack.pop_back();
      if (j >= i && j < end[i]) continue;  // the node's own subtree
      if (!overlap(box[j], q)) continue;
      const bvh::BvhNode& n = t.nodes[j];
      if (!n.is_leaf()) {
        // A subtree that contains node i is entered: it holds outside geometry too.
        stack.push_back(n.index);
        stack.push_back(j + 1);
        continue;
      }
      for (std::uint32_t k = n.index; k < n.index + n.count; ++k) {
        const std::uint32_t p = t.prim_order[k];
        auto add = [&](std::uint32_t id) {
          if (!overlap(tri_box(id), q)) return;
          const Tri& f = tris[id];
          area += clipped_area(pos[f[0]], pos[f[1]], pos[f[2]], q);
        };
        if (identity) add(p);
        else for (std::uint32_t id : triangles_of(p)) add(id);
      }
    }
    r.node_overlap[i] = area;
    double c = m.traversal;
    if (t.nodes[i].is_leaf()) {
      std::size_t n = 0;
      for (std::uint32_t k = t.nodes[i].index; k < t.nodes[i].index + t.nodes[i].count; ++k)
        n += identity ? 1 : triangles_of(t.prim_order[k]).size();
      c = m.intersection * double(n);
    }
    r.epo += c * area;
  }
  r.epo = r.total_area > 0 ? r.epo / r.total_area : 0.0;
  return r;
}

}  // namespace ptc
