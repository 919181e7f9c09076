#include "toolkit/geometry/cluster_metrics.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "toolkit/geometry/triangle.h"

namespace ptc {

std::string_view to_string(SizeBoundMode m) { return m == SizeBoundMode::Max ? "max" : "min"; }
std::optional<SizeBoundMode> parse_size_bound_mode(std::string_view s) {
  if (s == "max") return SizeBoundMode::Max;
  if (s == "min") return SizeBoundMode::Min;
  return std::nullopt;
}


namespace {

void require_positive(double v, const char* what) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw std::invalid_argument(std::string(what) + " must be finite and > 0, got " + std::to_string(v));
}

}  // namespace

double reg_bound(std::size_t vertex_count, double max_count) {
  require_positive(max_count, "reg_bound: max_count");
  return static_cast<double>(vertex_count) / max_count;
}

double size_bound(double sphere_surface_area, double max_size, double avg_sa, SizeBoundMode mode) {
  require_positive(max_size, "size_bound: max_size");
  require_positive(avg_sa, "size_bound: avg_sa");
  if (!(sphere_surface_area >= 0.0))
    throw std::invalid_argument("size_bound: sphere_surface_area must be >= 0, got " +
                                std::to_string(sphere_surface_area));
  const double ratio = sphere_surface_area / (max_size * avg_sa);
  return mode == SizeBoundMode::Max ? std::max(1.0, ratio) : std::min(1.0, ratio);
}

NormalAverage average_normal(std::span<const Vec3> unit_normals, std::span<const double> areas) {
  if (unit_normals.size() != areas.size())
    throw std::invalid_argument("average_normal: " + std::to_string(unit_normals.size()) + " normals but " +
                                std::to_string(areas.size()) + " areas");
  Vec3 sum = Vec3::Zero();
  std::size_t nonzero = 0;
  for (const Vec3& n : unit_normals) {
    if (n.isZero(0.0)) continue;
    sum += n;
    ++nonzero;
  }
  NormalAverage r;
  const double len = safe_norm(sum);
  if (nonzero > 0 && len > kNormalSumZeroTol * static_cast<double>(nonzero)) {
    r.n = sum / len;
    r.fallback = false;
    return r;
  }
  // Fallback: normal of the largest-area triangle, lowest index among near-ties.
  double max_area = -1.0;
  for (std::size_t i = 0; i < unit_normals.size(); ++i)
    if (!unit_normals[i].isZero(0.0)) max_area = std::max(max_area, areas[i]);
  r.fallback = true;
  r.n = Vec3::UnitZ();
  if (max_area < 0.0) return r;  // every normal is zero
  const double threshold = max_area * (1.0 - kFallbackAreaTieTol);
  for (std::size_t i = 0; i < unit_normals.size(); ++i)
    if (!unit_normals[i].isZero(0.0) && areas[i] >= threshold) {
      r.n = unit_normals[i];
      break;
    }
  return r;
}

ClusterMetrics cluster_metrics(const Mesh& mesh, std::span<const std::uint32_t> triangle_ids,
                               SphereMethod sphere_method, std::span<const std::uint32_t> vertices) {
  ClusterMetrics m;
  if (triangle_ids.empty()) return m;

  const std::size_t tcount = mesh.triangle_count();
  {
    // A set of ids < tcount: checked on the ids as given when they ascend (as a Clustering's do),
    // else on a sorted copy.
    std::vector<std::uint32_t> copy;
    std::span<const std::uint32_t> ids = triangle_ids;
    if (!std::is_sorted(ids.begin(), ids.end())) {
      copy.assign(ids.begin(), ids.end());
      std::sort(copy.begin(), copy.end());
      ids = copy;
    }
    if (ids.back() >= tcount)
      throw std::invalid_argument("cluster_metrics: triangle id " + std::to_string(ids.back()) + " of " +
                                  std::to_string(tcount));
    if (const auto dup = std::adjacent_find(ids.begin(), ids.end()); dup != ids.end())
      throw std::invalid_argument("cluster_metrics: triangle id " + std::to_string(*dup) + " given twice");
  }

  const std::size_t k = triangle_ids.size();
  std::vector<Vec3> normals(k);
  std::vector<double> areas(k);
  std::vector<std::uint32_t> own;
  if (vertices.empty()) own.reserve(3 * k);
  for (std::size_t i = 0; i < k; ++i) {
    const Tri& f = mesh.triangle(triangle_ids[i]);
    const TriangleGeometry g = triangle_geometry(mesh.position(f[0]), mesh.position(f[1]), mesh.position(f[2]));
    normals[i] = g.normal;
    areas[i] = g.area;
    m.area += g.area;
    if (vertices.empty()) own.insert(own.end(), f.begin(), f.end());
  }
  if (vertices.empty()) {
    std::sort(own.begin(), own.end());
    own.erase(std::unique(own.begin(), own.end()), own.end());
  }
  const std::span<const std::uint32_t> verts = vertices.empty() ? std::span<const std::uint32_t>(own) : vertices;

  for (std::uint32_t v : verts) m.box.extend(mesh.position(v));
  // The sphere is computed on coordinates relative to a local origin o: per axis 0 when the box
  // touches or straddles 0, else the box minimum (a data coordinate). p - o is then exact for
  // far-away clusters (Sterbenz: p and o within a factor 2) and always correctly rounded, so R
  // does not depend on where the cluster sits. In absolute coordinates the center would be
  // rounded to ulp(|center|) and a containment-preserving radius inflated by as much: at a 1e7
  // offset with 1e-3 features that is ~1e-6 relative in R^2 (measured), far above 1e-12.
  Vec3 origin;
  for (int a = 0; a < 3; ++a) origin[a] = (m.box.lo[a] <= 0.0 && m.box.hi[a] >= 0.0) ? 0.0 : m.box.lo[a];
  std::vector<Vec3> points;
  points.reserve(verts.size());
  for (std::uint32_t v : verts) points.push_back(mesh.position(v) - origin);

  m.triangles = k;
  m.vertices = verts.size();
  m.sphere = bounding_sphere(sphere_method, points);
  m.sphere.center += origin;
  m.area_c = std::numbers::pi * m.sphere.radius * m.sphere.radius;

  const NormalAverage na = average_normal(normals, areas);
  m.n_avg = na.n;
  m.n_avg_fallback = na.fallback;
  for (std::size_t i = 0; i < k; ++i) m.area_p += areas[i] * std::abs(m.n_avg.dot(normals[i]));
  m.reg = m.area_c > 0.0 ? m.area_p / m.area_c : 0.0;

  m.connectivity = static_cast<double>(m.triangles) / static_cast<double>(m.vertices);

  const double box_sa = m.box.surface_area();
  m.naive = box_sa > 0.0 ? 2.0 * m.area / box_sa : 0.0;
  m.p_hit = m.naive;
  return m;
}

double cluster_acc(const ClusterMetrics& m, const ClusterParams& params) {
  const double sa = m.sphere.is_empty() ? 0.0 : 4.0 * std::numbers::pi * m.sphere.radius * m.sphere.radius;
  return acc(m.reg, reg_bound(m.vertices, params.max_count),
             size_bound(sa, params.max_size, params.avg_sa, params.size_bound_mode));
}

double cluster_acc(const Mesh& mesh, std::span<const std::uint32_t> triangle_ids, const ClusterParams& params) {
  return cluster_acc(cluster_metrics(mesh, triangle_ids, params.sphere), params);
}

}  // namespace ptc
