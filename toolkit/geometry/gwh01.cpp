#include "toolkit/geometry/gwh01.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "toolkit/geometry/triangle.h"

namespace ptc {

std::string_view to_string(GwhWeight w) { return w == GwhWeight::Area ? "area" : "sqrt-area"; }
std::optional<GwhWeight> parse_gwh_weight(std::string_view s) {
  if (s == "area") return GwhWeight::Area;
  if (s == "sqrt-area") return GwhWeight::SqrtArea;
  return std::nullopt;
}


void Quadric::add(const Vec3& p, double w) {
  if (!has_origin) {
    origin = p;
    has_origin = true;
  }
  const Vec3 q = p - origin;
  A.noalias() += w * q * q.transpose();
  b += w * q;
  c += w;
}

Quadric Quadric::shifted(const Vec3& new_origin) const {
  // q' = p - o' = q + d with d = o - o':  A' = A + b d^T + d b^T + c d d^T, b' = b + c d.
  Quadric r(new_origin);
  const Vec3 d = origin - new_origin;
  r.A = A + b * d.transpose() + d * b.transpose() + c * d * d.transpose();
  r.b = b + c * d;
  r.c = c;
  return r;
}

Quadric& Quadric::operator+=(const Quadric& other) {
  if (other.c == 0) return *this;
  if (!has_origin && c == 0) {  // empty and without origin: adopt the other's
    *this = other;
    return *this;
  }
  // (A quadric filled by hand without has_origin is taken to be at origin 0.)
  const Quadric s = other.origin == origin ? other : other.shifted(origin);
  A += s.A;
  b += s.b;
  c += s.c;
  has_origin = true;
  return *this;
}

PlaneFit fit_plane(const Quadric& q, const Vec3& ref) {
  PlaneFit f;
  f.centroid = q.origin;
  if (!(q.c > 0)) return f;
  const Vec3 mean = q.b / q.c;  // relative to the origin
  Eigen::Matrix3d Z = q.A - q.b * mean.transpose();
  Z = 0.5 * (Z + Z.transpose()).eval();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.compute(Z);  // not computeDirect: see header
  Vec3 n = es.eigenvectors().col(0).normalized();
  double dot = n.dot(ref);
  if (!(std::abs(dot) > kOrientationTol * safe_norm(ref))) {  // no usable reference: canonical sign
    Eigen::Index i = 0;
    n.cwiseAbs().maxCoeff(&i);
    dot = n[i];
  }
  if (dot < 0.0) n = -n;
  f.normal = n;
  f.e_fit = std::max(0.0, es.eigenvalues()[0] / q.c);
  f.centroid = q.origin + mean;
  f.offset = -n.dot(f.centroid);
  return f;
}

double e_dir(const Vec3& plane_normal, std::span<const Vec3> unit_normals, std::span<const double> areas,
             GwhWeight weight) {
  if (unit_normals.size() != areas.size())
    throw std::invalid_argument("e_dir: " + std::to_string(unit_normals.size()) + " normals but " +
                                std::to_string(areas.size()) + " areas");
  double num = 0, den = 0;
  for (std::size_t i = 0; i < areas.size(); ++i) {
    const double w = weight == GwhWeight::Area ? areas[i] : std::sqrt(areas[i]);
    const double d = 1.0 - plane_normal.dot(unit_normals[i]);
    num += w * d * d;
    den += areas[i];
  }
  return den > 0.0 ? num / den : 0.0;
}

double irregularity(double perimeter, double area) {
  if (area == 0.0) return std::numeric_limits<double>::infinity();
  return perimeter * perimeter / (4.0 * std::numbers::pi * area);
}

double shape_cost(double gamma_new, double gamma_1, double gamma_2) {
  if (std::isnan(gamma_new) || std::isnan(gamma_1) || std::isnan(gamma_2))
    return std::numeric_limits<double>::quiet_NaN();
  const double before = std::max(gamma_1, gamma_2);
  if (!(gamma_new > before)) return 0.0;
  if (std::isinf(gamma_new)) return 1.0;
  return (gamma_new - before) / gamma_new;
}

GwhTerms gwh_terms(const Mesh& mesh, std::span<const std::uint32_t> triangle_ids, GwhWeight weight) {
  GwhTerms t;
  t.gamma = std::numeric_limits<double>::infinity();
  if (triangle_ids.empty()) return t;

  const std::size_t tcount = mesh.triangle_count();
  {
    std::vector<std::uint32_t> ids(triangle_ids.begin(), triangle_ids.end());
    std::sort(ids.begin(), ids.end());
    if (ids.back() >= tcount)
      throw std::invalid_argument("gwh_terms: triangle id " + std::to_string(ids.back()) + " of " +
                                  std::to_string(tcount));
    if (const auto dup = std::adjacent_find(ids.begin(), ids.end()); dup != ids.end())
      throw std::invalid_argument("gwh_terms: triangle id " + std::to_string(*dup) + " given twice");
  }

  const std::size_t k = triangle_ids.size();
  std::vector<Vec3> normals(k);
  std::vector<double> areas(k);
  std::vector<std::uint32_t> verts;
  verts.reserve(3 * k);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;  // one entry per (triangle, distinct edge)
  edges.reserve(3 * k);
  Vec3 ref = Vec3::Zero();
  for (std::size_t i = 0; i < k; ++i) {
    const Tri& f = mesh.triangle(triangle_ids[i]);
    const TriangleGeometry g = triangle_geometry(mesh.position(f[0]), mesh.position(f[1]), mesh.position(f[2]));
    normals[i] = g.normal;
    areas[i] = g.area;
    t.area += g.area;
    ref += g.area * g.normal;
    verts.insert(verts.end(), f.begin(), f.end());
    std::pair<std::uint32_t, std::uint32_t> own[3];
    int n_own = 0;
    for (int s = 0; s < 3; ++s) {
      const std::uint32_t a = f[s], b = f[(s + 1) % 3];
      if (a == b) continue;  // collapsed side: not an edge
      const std::pair<std::uint32_t, std::uint32_t> e{std::min(a, b), std::max(a, b)};
      if (std::find(own, own + n_own, e) == own + n_own) own[n_own++] = e;  // (a, b, a) lists {a, b} once
    }
    edges.insert(edges.end(), own, own + n_own);
  }
  std::sort(verts.begin(), verts.end());
  verts.erase(std::unique(verts.begin(), verts.end()), verts.end());

  Quadric q(mesh.position(verts.front()));
  for (std::uint32_t v : verts) q.add(mesh.position(v));
  t.fit = fit_plane(q, ref);
  t.e_dir = e_dir(t.fit.normal, normals, areas, weight);

  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) t.perimeter += safe_norm(mesh.position(edges[i].second) - mesh.position(edges[i].first));
    i = j;
  }
  t.gamma = irregularity(t.perimeter, t.area);
  return t;
}

double gwh_cost(const GwhTerms& merged, const GwhTerms& part1, const GwhTerms& part2, const GwhParams& params) {
  return merged.fit.e_fit + params.a1 * merged.e_dir + params.a2 * shape_cost(merged.gamma, part1.gamma, part2.gamma);
}

}  // namespace ptc
