// The GWH01 baseline objective (Garland, Willmott, Heckbert 2001, "Hierarchical face clustering
// on polygonal surfaces"; docs/method.md "Baseline clusterings" 3) as a ClusterObjective:
//   cost(A + B) = E_fit(A u B) / l^2 + a1 E_dir(A u B) + a2 E_shape(A, B),   score = -cost,
// with the terms of geometry/gwh01.h (gwh_terms, gwh_cost). Legal only while the merged cluster
// has at most MaxCount distinct vertices. Merge while any legal candidate exists
// (kMergeOnlyPositive = false: the cost is >= 0, the score <= 0); contraction also stops at
// ClusterConfig::target_clusters.
//
// Normalisation (the choice): E_fit, the mean squared distance of the points to their plane, has
// unit L^2 while E_dir and E_shape are dimensionless, so gwh_cost's sum depends on the mesh's
// scale and the paper's weights a1 = 0.2, a2 = 2 would mean different things on different meshes
// (on a mesh of size 1000 E_fit dominates, on a mesh of size 0.001 it vanishes). We divide E_fit by
// l^2, l = the mesh's mean edge length (ClusterTables::mean_edge_length; 1 when the mesh has no
// edge of positive length), so E_fit / l^2 is the plane-fit error in units of the local sampling
// and the cost is scale-free: scaling a mesh by any factor gives the same clusters (by a power of
// two, bit-identical; tested). Garland et al. publish no normalisation; on a mesh whose mean edge
// length is 1 both agree. With GwhWeight::SqrtArea (Garland's code) E_dir itself has unit 1/L and
// stays scale-dependent; only Area weights (the default, method.md's formula) give a scale-free
// cost.
//
// Incremental and exact (to rounding):
// - the point quadric of the distinct vertices: Q(A u B) = Q(A) + Q(B) - sum over the shared
//   vertices of their point quadrics (the shared vertices come from the MergeContext), expressed
//   at the union's lowest-index vertex, which is the origin gwh_terms uses;
// - E_dir = sum_i w_i (1 - n.n_i)^2 / sum_i Area_i = (W - 2 n.m1 + n^T M2 n) / sum Area_i with the
//   mergeable moments W = sum w_i, m1 = sum w_i n_i, M2 = sum w_i n_i n_i^T (expanding the
//   square; algebraically exact; its rounding, ~eps * W / Area absolutely, is measured against
//   e_dir() in clustering_objectives_test);
// - perimeter P(A u B) = P(A) + P(B) - MergeContext::boundary_removed (2 x the shared edge length
//   for manifold edges; the exact count for non-manifold ones);
// - the plane fit itself (a 3x3 symmetric eigen-solve, gwh01.h fit_plane) per evaluation.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "toolkit/clustering/objectives.h"
#include "toolkit/geometry/gwh01.h"

namespace ptc {

class Gwh01Objective {
 public:
  static constexpr bool kMergeOnlyPositive = false;
  static constexpr bool kUsesBoundary = true;

  struct Summary {
    Quadric quadric;                       ///< point quadric of the distinct vertices, origin = position of `origin_vertex`
    std::uint32_t origin_vertex = 0;       ///< the cluster's lowest vertex id
    Vec3 ref = Vec3::Zero();               ///< sum Area_i n_i (orients the fitted normal, as gwh_terms)
    double area = 0;                       ///< sum Area_i (L^2)
    double w = 0;                          ///< W = sum w_i
    Vec3 m1 = Vec3::Zero();                ///< sum w_i n_i
    Eigen::Matrix3d m2 = Eigen::Matrix3d::Zero();  ///< sum w_i n_i n_i^T
    double perimeter = 0;                  ///< P (L)
    double gamma = 0;                      ///< irregularity(P, area)
  };
  struct Evaluation : ScoreBase {
    Quadric quadric;           ///< Q(A u B)
    std::uint32_t origin_vertex = 0;
    double perimeter = 0;
    double gamma = 0;
    double e_fit = 0;          ///< E_fit(A u B) in L^2 (not normalised)
    double e_dir = 0;
    double e_shape = 0;
  };

  /// max_count >= 3 (else std::invalid_argument), params.a1, a2 >= 0 and finite.
  Gwh01Objective(const ClusterTables& tables, std::uint32_t max_count, const GwhParams& params);

  [[nodiscard]] Summary single(std::uint32_t t) const;
  [[nodiscard]] bool legal(const MergeContext& ctx) const { return ctx.vertex_count <= max_count_; }
  [[nodiscard]] Evaluation evaluate(const Summary& a, const Summary& b, const MergeContext& ctx, Precision) const;
  [[nodiscard]] Summary merge(const Summary& a, const Summary& b, const MergeContext& ctx, const Evaluation& ev) const;

  /// 1 / l^2, the factor applied to E_fit (see the file comment).
  [[nodiscard]] double fit_scale() const { return fit_scale_; }

 private:
  const ClusterTables* tables_;
  std::uint32_t max_count_;
  GwhParams params_;
  double fit_scale_;
};

}  // namespace ptc
