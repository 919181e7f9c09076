// The "SAH clusters" baseline objective of Garanzha 2009 (docs/method.md, "Baseline clusterings"
// 2): Naive(k) = sum_i 2 Area_i / SA(box(k)), the SAH hit probability of the surface inside its
// axis-aligned box (geometry/cluster_metrics.h: both sides count). Score = Naive of the merged
// cluster; legal only while the merged cluster has at most MaxCount distinct vertices.
//
// Stop rule. Naive is never negative (it is 0 only for zero-area clusters), so "merge while the
// best score is positive" would never stop; instead the algorithms merge while ANY legal
// candidate exists (kMergeOnlyPositive = false). What that implies:
// - the vertex limit alone decides when a cluster is closed: growth fills every cluster until
//   no neighbour fits (clusters end with close to MaxCount vertices, except where the free
//   neighbours ran out); contraction merges until every remaining pair of adjacent clusters would
//   exceed MaxCount, so a cluster stops only when all its neighbours are "too big to join";
// - the score only decides the ORDER of the merges, and with it the shape: box-filling (flat,
//   axis-aligned) groups first; a round, well-connected cluster is not preferred over a thin or
//   folded one with the same box fill (the objective ignores regularity and connectivity);
// - unlike Acc the result is not rotation invariant (the box is axis-aligned), only invariant
//   under translations, axis permutations and uniform scaling.
//
// Incremental and exact: the area is a sum, the merged box is the union of the two boxes, so
// evaluate() is O(1) and equals cluster_metrics' `naive` up to the order of the area sum.
#pragma once

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "toolkit/clustering/objectives.h"

namespace ptc {

class NaiveObjective {
 public:
  static constexpr bool kMergeOnlyPositive = false;
  static constexpr bool kUsesBoundary = false;

  struct Summary {
    double area = 0;  ///< sum Area_i (one side, L^2)
    Box3 box;         ///< box of the distinct vertices
  };
  struct Evaluation : ScoreBase {
    Box3 box;
  };

  /// max_count: MaxCount, the hard vertex limit per cluster (>= 3, else std::invalid_argument:
  /// a triangle with three distinct vertices must fit).
  NaiveObjective(const ClusterTables& tables, std::uint32_t max_count) : tables_(&tables), max_count_(max_count) {
    if (max_count < 3)
      throw std::invalid_argument("NaiveObjective: max_count must be >= 3, got " + std::to_string(max_count));
  }

  [[nodiscard]] Summary single(std::uint32_t t) const {
    Summary s;
    s.area = tables_->geometry_of(t).area;
    for (std::uint32_t v : tables_->triangles[t]) s.box.extend(tables_->positions[v]);
    return s;
  }
  [[nodiscard]] bool legal(const MergeContext& ctx) const { return ctx.vertex_count <= max_count_; }
  [[nodiscard]] Evaluation evaluate(const Summary& a, const Summary& b, const MergeContext&, Precision) const {
    Evaluation ev;
    ev.box = a.box;
    ev.box.extend(b.box);
    const double sa = ev.box.surface_area();
    ev.score = sa > 0.0 ? 2.0 * (a.area + b.area) / sa : 0.0;  // cluster_metrics' convention for SA = 0
    ev.exact = true;
    return ev;
  }
  [[nodiscard]] Summary merge(const Summary& a, const Summary& b, const MergeContext&, const Evaluation& ev) const {
    return {a.area + b.area, ev.box};
  }

  [[nodiscard]] std::uint32_t max_count() const { return max_count_; }

 private:
  const ClusterTables* tables_;
  std::uint32_t max_count_;
};

}  // namespace ptc
