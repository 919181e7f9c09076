// Shared helpers of the bvh tests: meshes, seeded random boxes, brute-force references.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "bvh/box.h"
#include "bvh/scene_config.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/mesh.h"

namespace ptc::bvh::test {

/// cluster_scene_defaults() with groups of exactly up to 16 clusters (min_cluster_groups 0, the
/// group size of the defaults before the thirty-first session): the test meshes have a few
/// hundred clusters, which the defaults would build plainly, and these tests exercise the
/// two-level build.
inline SceneConfig two_level_defaults() {
  SceneConfig c = cluster_scene_defaults();
  c.cluster_group_size = 16;
  c.min_cluster_groups = 0;
  return c;
}

inline Mesh load_mesh(const std::string& name) {
  return read_mesh(std::string(PTC_TEST_DATA) + "/meshes/" + name).mesh;
}

/// n random boxes in [0, 100]^3 with extents in [0, max_extent] (seeded).
inline std::vector<Box3f> random_boxes(std::size_t n, std::uint32_t seed, float max_extent = 5.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(0.0f, 100.0f), ext(0.0f, max_extent);
  std::vector<Box3f> boxes(n);
  for (Box3f& b : boxes)
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = pos(rng);
      b.hi[a] = b.lo[a] + ext(rng);
    }
  return boxes;
}

/// n seeded random frame positions in [-10, 10]^3 (the fills' input, before add_sentinel).
inline AlignedVector<Vec3f> random_frame_positions(std::size_t n, std::uint32_t seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<float> U(-10.0f, 10.0f);
  AlignedVector<Vec3f> fp(n);
  for (Vec3f& p : fp) p = {U(g), U(g), U(g)};
  return fp;
}

/// The mesh moved by a seeded, smooth, non-rigid deformation (for refit and animation tests).
inline Mesh deformed(const Mesh& m, double amplitude, double freq = 3.0) {
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  const Box3 b = m.bounds();
  const double s = (b.hi - b.lo).maxCoeff();
  for (Vec3& q : p) {
    const Vec3 u = (q - b.lo) / s;
    q += amplitude * s * Vec3(std::sin(freq * u.y()), std::sin(freq * u.z() + 1.0), std::sin(freq * u.x() + 2.0));
  }
  return m.with_positions(std::move(p));
}

}  // namespace ptc::bvh::test

namespace ptc::bvh::test {
/// All messages joined (for assertion output).
inline std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += x + "\n";
  return s;
}
}  // namespace ptc::bvh::test

#include <cmath>
#include <limits>

#include "bvh/tracer.h"
#include "bvh/watertight.h"
#include "common/brute_force.h"

namespace ptc::bvh::test {

/// Generalised winding number of point p w.r.t. a closed mesh (sum of signed solid angles /
/// 4 pi, van Oosterom & Strackee 1983), in double: ~+-1 inside, ~0 outside.
inline double winding_number(const Mesh& m, const Vec3& p) {
  double sum = 0.0;
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    const auto c = m.corners(t);
    const Vec3 a = c[0] - p, b = c[1] - p, d = c[2] - p;
    const double la = a.norm(), lb = b.norm(), ld = d.norm();
    const double num = a.dot(b.cross(d));
    const double den = la * lb * ld + a.dot(b) * ld + b.dot(d) * la + d.dot(a) * lb;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * M_PI);
}

/// The closed surface of the cube [-1, 1]^3 * scale + offset, each face an n x n grid of
/// quads split into two triangles (many coplanar, axis-aligned triangles; grid vertices at
/// multiples of 2 * scale / n).
inline Mesh grid_cube(int n, double scale = 1.0, const Vec3& offset = Vec3::Zero()) {
  std::vector<Vec3> pos;
  std::vector<Tri> tris;
  std::map<std::array<long, 3>, std::uint32_t> index;  // integer grid coordinates -> vertex
  auto vertex = [&](std::array<long, 3> g) {
    auto [it, inserted] = index.try_emplace(g, static_cast<std::uint32_t>(pos.size()));
    if (inserted) pos.push_back(offset + scale * Vec3(2.0 * double(g[0]) / n - 1.0, 2.0 * double(g[1]) / n - 1.0, 2.0 * double(g[2]) / n - 1.0));
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          std::array<long, 3> q[4];
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            q[k][axis] = side ? n : 0;
            q[k][u] = i + di[k];
            q[k][v] = j + dj[k];
          }
          std::uint32_t w[4];
          for (int k = 0; k < 4; ++k) w[k] = vertex(q[k]);
          if (side) {  // outward orientation
            tris.push_back({w[0], w[1], w[2]}), tris.push_back({w[0], w[2], w[3]});
          } else {
            tris.push_back({w[0], w[2], w[1]}), tris.push_back({w[0], w[3], w[2]});
          }
        }
    }
  return Mesh(std::move(tris), std::move(pos));
}

}  // namespace ptc::bvh::test
