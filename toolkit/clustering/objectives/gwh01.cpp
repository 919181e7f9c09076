#include "toolkit/clustering/objectives/gwh01.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ptc {

Gwh01Objective::Gwh01Objective(const ClusterTables& tables, std::uint32_t max_count, const GwhParams& params)
    : tables_(&tables), max_count_(max_count), params_(params) {
  if (max_count < 3)
    throw std::invalid_argument("Gwh01Objective: max_count must be >= 3, got " + std::to_string(max_count));
  if (!(params.a1 >= 0.0) || !(params.a2 >= 0.0) || !std::isfinite(params.a1) || !std::isfinite(params.a2))
    throw std::invalid_argument("Gwh01Objective: a1 and a2 must be finite and >= 0");
  if (!tables.with_edges || tables.edge_length.size() != tables.edges.edge_count())
    throw std::logic_error("Gwh01Objective: the tables were built without edges (ClusterTables::build with_edges)");
  const double l = tables.mean_edge_length;
  fit_scale_ = l > 0.0 && std::isfinite(1.0 / (l * l)) ? 1.0 / (l * l) : 1.0;
}

Gwh01Objective::Summary Gwh01Objective::single(std::uint32_t t) const {
  const ClusterTables& tb = *tables_;
  Summary s;
  std::uint32_t v[3];
  const int nv = tb.distinct_vertices(t, v);
  s.origin_vertex = v[0];
  s.quadric = Quadric(tb.positions[v[0]]);
  for (int i = 0; i < nv; ++i) s.quadric.add(tb.positions[v[i]]);
  const TriangleGeometry g = tb.geometry_of(t);
  const double a = g.area;
  const Vec3& n = g.normal;
  s.ref = a * n;
  s.area = a;
  s.w = params_.weight == GwhWeight::Area ? a : std::sqrt(a);
  s.m1 = s.w * n;
  s.m2 = s.w * n * n.transpose();
  s.perimeter = tb.triangle_perimeter(t);
  s.gamma = irregularity(s.perimeter, s.area);
  return s;
}

Gwh01Objective::Evaluation Gwh01Objective::evaluate(const Summary& a, const Summary& b, const MergeContext& ctx,
                                                    Precision) const {
  const ClusterTables& tb = *tables_;
  Evaluation ev;
  // Q(A u B) at the union's lowest vertex: start from the quadric that already has that origin.
  const bool a_first = a.origin_vertex <= b.origin_vertex;
  const Summary& base = a_first ? a : b;
  const Summary& other = a_first ? b : a;
  ev.quadric = base.quadric;
  ev.quadric += other.quadric;
  ev.origin_vertex = base.origin_vertex;
  for (std::uint32_t v : ctx.shared) {  // the shared vertices were counted twice
    const Vec3 d = tb.positions[v] - ev.quadric.origin;
    ev.quadric.A.noalias() -= d * d.transpose();
    ev.quadric.b -= d;
    ev.quadric.c -= 1.0;
  }
  const PlaneFit fit = fit_plane(ev.quadric, a.ref + b.ref);
  ev.e_fit = fit.e_fit;

  const double area = a.area + b.area;
  const double w = a.w + b.w;
  const Vec3 m1 = a.m1 + b.m1;
  const Eigen::Matrix3d m2 = a.m2 + b.m2;
  const Vec3& n = fit.normal;
  const double num = w - 2.0 * n.dot(m1) + n.dot(m2 * n);
  ev.e_dir = area > 0.0 ? std::max(0.0, num) / area : 0.0;

  ev.perimeter = std::max(0.0, a.perimeter + b.perimeter - ctx.boundary_removed);
  ev.gamma = irregularity(ev.perimeter, area);
  ev.e_shape = shape_cost(ev.gamma, a.gamma, b.gamma);

  const double cost = ev.e_fit * fit_scale_ + params_.a1 * ev.e_dir + params_.a2 * ev.e_shape;
  ev.score = std::isnan(cost) ? -std::numeric_limits<double>::infinity() : -cost;
  ev.exact = true;
  return ev;
}

Gwh01Objective::Summary Gwh01Objective::merge(const Summary& a, const Summary& b, const MergeContext&,
                                              const Evaluation& ev) const {
  Summary s;
  s.quadric = ev.quadric;
  s.origin_vertex = ev.origin_vertex;
  s.ref = a.ref + b.ref;
  s.area = a.area + b.area;
  s.w = a.w + b.w;
  s.m1 = a.m1 + b.m1;
  s.m2 = a.m2 + b.m2;
  s.perimeter = ev.perimeter;
  s.gamma = ev.gamma;
  return s;
}

}  // namespace ptc
