#include "bvh/box.h"

#include <algorithm>

namespace ptc::bvh {

std::vector<Box3f> triangle_boxes(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                  const Vec3& origin) {
  std::vector<Box3f> boxes(triangles.size());
  const double ox = origin.x(), oy = origin.y(), oz = origin.z();
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3& a = positions[triangles[t][0]];
    const Vec3& b = positions[triangles[t][1]];
    const Vec3& c = positions[triangles[t][2]];
    // Min/max first in double (exact), then one outward rounding per bound.
    Box3f& box = boxes[t];
    box.lo = {round_down(std::min({a.x(), b.x(), c.x()}) - ox), round_down(std::min({a.y(), b.y(), c.y()}) - oy),
              round_down(std::min({a.z(), b.z(), c.z()}) - oz)};
    box.hi = {round_up(std::max({a.x(), b.x(), c.x()}) - ox), round_up(std::max({a.y(), b.y(), c.y()}) - oy),
              round_up(std::max({a.z(), b.z(), c.z()}) - oz)};
  }
  return boxes;
}

std::vector<Box3f> point_group_boxes(std::span<const Vec3> positions, std::span<const std::uint32_t> offsets,
                                     std::span<const std::uint32_t> indices, const Vec3& origin) {
  const std::size_t groups = offsets.empty() ? 0 : offsets.size() - 1;
  std::vector<Box3f> boxes(groups);
  constexpr double inf = std::numeric_limits<double>::infinity();
  for (std::size_t g = 0; g < groups; ++g) {
    double lx = inf, ly = inf, lz = inf, hx = -inf, hy = -inf, hz = -inf;
    for (std::uint32_t i = offsets[g]; i < offsets[g + 1]; ++i) {
      const Vec3& p = positions[indices[i]];
      lx = std::min(lx, p.x()), ly = std::min(ly, p.y()), lz = std::min(lz, p.z());
      hx = std::max(hx, p.x()), hy = std::max(hy, p.y()), hz = std::max(hz, p.z());
    }
    if (offsets[g] == offsets[g + 1]) continue;  // empty group: empty box
    boxes[g].lo = {round_down(lx - origin.x()), round_down(ly - origin.y()), round_down(lz - origin.z())};
    boxes[g].hi = {round_up(hx - origin.x()), round_up(hy - origin.y()), round_up(hz - origin.z())};
  }
  return boxes;
}

std::vector<Vec3f> box_centers(std::span<const Box3f> boxes) {
  std::vector<Vec3f> c(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) c[i] = boxes[i].center();
  return c;
}

std::vector<Vec3f> triangle_centroids(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                      const Vec3& origin) {
  std::vector<Vec3f> c(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3 m = (positions[triangles[t][0]] + positions[triangles[t][1]] + positions[triangles[t][2]]) / 3.0;
    c[t] = to_frame(m, origin);
  }
  return c;
}

void frame_positions(std::span<const Vec3> positions, const Vec3& origin, std::vector<Vec3f>& out) {
  out.resize(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) out[v] = to_frame(positions[v], origin);
}

std::vector<Box3f> triangle_boxes(std::span<const Vec3f> fp, std::span<const Tri> triangles) {
  std::vector<Box3f> boxes(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3f& a = fp[triangles[t][0]];
    const Vec3f& b = fp[triangles[t][1]];
    const Vec3f& c = fp[triangles[t][2]];
    for (int k = 0; k < 3; ++k) {
      boxes[t].lo[k] = next_below(std::min({a[k], b[k], c[k]}));
      boxes[t].hi[k] = next_above(std::max({a[k], b[k], c[k]}));
    }
  }
  return boxes;
}

void point_group_boxes(std::span<const Vec3f> fp, std::span<const std::uint32_t> offsets,
                       std::span<const std::uint32_t> indices, std::vector<Box3f>& out) {
  const std::size_t groups = offsets.empty() ? 0 : offsets.size() - 1;
  out.assign(groups, Box3f{});
  for (std::size_t g = 0; g < groups; ++g) {
    if (offsets[g] == offsets[g + 1]) continue;
    float lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
    for (std::uint32_t i = offsets[g]; i < offsets[g + 1]; ++i) {
      const Vec3f& p = fp[indices[i]];
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    for (int k = 0; k < 3; ++k) out[g].lo[k] = next_below(lo[k]), out[g].hi[k] = next_above(hi[k]);
  }
}

std::vector<Vec3f> triangle_centroids(std::span<const Vec3f> fp, std::span<const Tri> triangles) {
  std::vector<Vec3f> c(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3f& a = fp[triangles[t][0]];
    const Vec3f& b = fp[triangles[t][1]];
    const Vec3f& d = fp[triangles[t][2]];
    for (int k = 0; k < 3; ++k) c[t][k] = (a[k] + b[k] + d[k]) * (1.0f / 3.0f);
  }
  return c;
}

Box3f union_of(std::span<const Box3f> boxes) {
  Box3f u;
  for (const Box3f& b : boxes) u.extend(b);
  return u;
}

}  // namespace ptc::bvh
