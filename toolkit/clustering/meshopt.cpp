#include "toolkit/clustering/meshopt.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <meshoptimizer.h>

namespace ptc {

namespace {
constexpr std::uint32_t kMaxVertices = 255;   // meshoptimizer 0.18 kMeshletMaxVertices
constexpr std::uint32_t kMaxTriangles = 512;  // meshoptimizer 0.18 kMeshletMaxTriangles

Tri sorted(Tri f) {
  std::sort(f.begin(), f.end());
  return f;
}
}  // namespace

ClusterLimits meshopt_limits(const ClusterConfig& config) {
  if (config.max_count < 3 || config.max_count > kMaxVertices)
    throw std::invalid_argument(
        fmt::format("meshopt: max_count (vertices per cluster) must be in [3, {}] for meshoptimizer 0.18, got {}",
                    kMaxVertices, config.max_count));
  const std::uint32_t requested = config.max_triangles != 0 ? config.max_triangles : 2 * config.max_count;
  if (requested < 4 || requested > kMaxTriangles)
    throw std::invalid_argument(fmt::format(
        "meshopt: max_triangles must be in [4, {}] for meshoptimizer 0.18 (0 = 2 * max_count), got {}{}",
        kMaxTriangles, config.max_triangles, config.max_triangles == 0 ? fmt::format(" -> {}", requested) : ""));
  ClusterLimits lim;
  lim.max_vertices = config.max_count;
  lim.max_triangles = requested / 4 * 4;  // 0.18 needs a multiple of 4; rounding down keeps the limit
  return lim;
}

std::vector<std::uint32_t> meshlet_labels(std::span<const Tri> triangles, std::span<const std::uint32_t> meshlet_offsets,
                                          std::span<const Tri> meshlet_triangles) {
  if (meshlet_offsets.empty() || meshlet_offsets.front() != 0 || meshlet_offsets.back() != meshlet_triangles.size() ||
      !std::is_sorted(meshlet_offsets.begin(), meshlet_offsets.end()))
    throw std::invalid_argument("meshlet_labels: inconsistent meshlet offsets");
  const std::size_t T = triangles.size();
  // Input triangles sorted by (sorted vertex triple, id): each vertex set is one run, ids ascending.
  struct Key {
    Tri v;
    std::uint32_t t;
  };
  std::vector<Key> keys(T);
  for (std::size_t t = 0; t < T; ++t) keys[t] = {sorted(triangles[t]), static_cast<std::uint32_t>(t)};
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) { return a.v != b.v ? a.v < b.v : a.t < b.t; });
  std::vector<std::size_t> next_free(T);  // per run start: next untaken position in the run
  for (std::size_t i = 0; i < T; ++i) next_free[i] = i;

  std::vector<std::uint32_t> label(T, kNoCluster);
  const std::size_t meshlet_count = meshlet_offsets.size() - 1;
  for (std::size_t m = 0; m < meshlet_count; ++m)
    for (std::uint32_t j = meshlet_offsets[m]; j < meshlet_offsets[m + 1]; ++j) {
      const Tri v = sorted(meshlet_triangles[j]);
      const auto run = std::lower_bound(keys.begin(), keys.end(), v, [](const Key& k, const Tri& x) { return k.v < x; });
      const auto start = static_cast<std::size_t>(run - keys.begin());
      if (run == keys.end() || run->v != v)
        throw std::logic_error(fmt::format("meshlet {} has triangle ({}, {}, {}), which is not an input triangle", m,
                                           meshlet_triangles[j][0], meshlet_triangles[j][1], meshlet_triangles[j][2]));
      const std::size_t pos = next_free[start];
      if (pos >= T || keys[pos].v != v)
        throw std::logic_error(fmt::format("meshlet {} has triangle ({}, {}, {}) more often than the input", m,
                                           meshlet_triangles[j][0], meshlet_triangles[j][1], meshlet_triangles[j][2]));
      label[keys[pos].t] = static_cast<std::uint32_t>(m);
      next_free[start] = pos + 1;
    }
  auto next = static_cast<std::uint32_t>(meshlet_count);
  for (std::size_t t = 0; t < T; ++t)
    if (label[t] == kNoCluster) label[t] = next++;  // not emitted: a cluster of its own
  return label;
}

Clustering meshopt_meshlets(const Mesh& mesh, const ClusterConfig& config) {
  const ClusterLimits lim = meshopt_limits(config);
  const std::size_t T = mesh.triangle_count();
  if (T == 0) return {};
  if (T > 0xffffffffu / 3) throw std::invalid_argument("meshopt: more than 2^32 / 3 triangles");

  // Similarity to the unit box (see header), then float.
  const Box3 box = mesh.referenced_bounds();  // (an unused vertex far away would collapse the floats)
  const Vec3 center = box.center();
  const double extent = box.extent().maxCoeff();
  const double scale = extent > 0 && std::isfinite(1.0 / extent) ? 1.0 / extent : 1.0;
  std::vector<float> pos(3 * mesh.vertex_count());
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a) pos[3 * v + a] = static_cast<float>((mesh.position(v)[a] - center[a]) * scale);
  std::vector<unsigned int> indices(3 * T);
  for (std::size_t t = 0; t < T; ++t)
    for (int k = 0; k < 3; ++k) indices[3 * t + k] = mesh.triangle(t)[k];

  const std::size_t bound = meshopt_buildMeshletsBound(indices.size(), lim.max_vertices, lim.max_triangles);
  std::vector<meshopt_Meshlet> meshlets(bound);
  std::vector<unsigned int> meshlet_vertices(bound * lim.max_vertices);
  std::vector<unsigned char> meshlet_tris(bound * lim.max_triangles * 3);
  const std::size_t count =
      meshopt_buildMeshlets(meshlets.data(), meshlet_vertices.data(), meshlet_tris.data(), indices.data(),
                            indices.size(), pos.data(), mesh.vertex_count(), 3 * sizeof(float), lim.max_vertices,
                            lim.max_triangles, /*cone_weight=*/0.0f);

  std::vector<std::uint32_t> offsets{0};
  std::vector<Tri> triples;
  triples.reserve(T);
  for (std::size_t m = 0; m < count; ++m) {
    const meshopt_Meshlet& ml = meshlets[m];
    for (std::uint32_t j = 0; j < ml.triangle_count; ++j) {
      const unsigned char* local = &meshlet_tris[ml.triangle_offset + 3 * j];
      triples.push_back({meshlet_vertices[ml.vertex_offset + local[0]], meshlet_vertices[ml.vertex_offset + local[1]],
                         meshlet_vertices[ml.vertex_offset + local[2]]});
    }
    offsets.push_back(static_cast<std::uint32_t>(triples.size()));
  }
  const std::vector<std::uint32_t> label = meshlet_labels(mesh.triangles(), offsets, triples);
  return clustering_from_labels(label, mesh.triangles());
}

Clustering meshopt_clusters(const Mesh& mesh, const ClusterConfig& config) {
  const Clustering meshlets = meshopt_meshlets(mesh, config);
  return split_disconnected(meshlets, mesh.triangles());
}

}  // namespace ptc
