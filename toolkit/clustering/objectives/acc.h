// Garanzha's objective Acc(k) = reg(k) - regBound(k) * sizeBound(k) (docs/method.md, "Quantities
// for a cluster k"), as a ClusterObjective (objectives.h). Score = Acc of the merged cluster;
// no hard limit (legal() is always true); merge only while the best score is > 0.
//
// Definitions are those of geometry/cluster_metrics.h, to the bit where it is cheap and to
// rounding otherwise: N_avg and its fallback rule (average_normal), AreaP, AreaC = pi R^2,
// regBound = N_V / MaxCount, sizeBound(SA = 4 pi R^2) with SizeBoundMode, and the sphere S(k) of
// the cluster's distinct vertices by ClusterParams::sphere on cluster-local coordinates (origin
// per axis 0 when the vertex box straddles 0, else the box minimum; vertices in ascending id
// order -- exactly as cluster_metrics calls bounding_sphere).
//
// What is incremental, and why each shortcut is exact:
// - sum n_i, sum Area_i n_i, the count of non-zero normals: sums, merged by addition.
// - AreaP = sum Area_i |N_avg . n_i| = N_avg . sum Area_i n_i WHEN every N_avg . n_i >= 0
//   (linearity). Each cluster keeps a cone (axis a, cos theta) containing its normals; if the
//   angle between N_avg and a plus theta is at most 90 degrees (tested as
//   cos(angle + theta) >= kConeMargin, far above the rounding of the test), every dot product is
//   >= 0 and the identity holds. Otherwise (normals spread over more than a hemisphere around
//   N_avg) AreaP is summed over the members, as cluster_metrics does. Either way the value is
//   the same up to rounding (~k eps relative); clustering_objectives_test measures it.
// - N_avg: when |sum n_i| < kRecomputeNormalSum * m (m non-zero normals: strong cancellation,
//   where the incremental sum's rounding would tilt N_avg), sum n_i is recomputed over the
//   members in ascending triangle id, as cluster_metrics sums it, and the fallback rule of
//   average_normal (|sum| <= kNormalSumZeroTol * m) is applied to that sum with the same code.
// - The sphere of A u B, for the minimal-sphere methods (Exact, Cgal):
//     * B adds no vertex: the vertex set is V(A), so S = S(A) (for every method);
//     * S(B) inside S(A) (or the reverse), or every added vertex inside S(A): the minimal
//       sphere of a set does not change when points inside it are added, so S = S(A) (S(B));
//     * growth (AccTuning::vertex_memo): S(A' u {v}) computed for an earlier A' of the same
//       cluster is still S(A u {v}) if every vertex added since lies inside it;
//     * otherwise S is computed on the sorted union with the points that provably cannot
//       support it left out (PointFilter, below) and, for Cgal, warm-started from the points on
//       S(A)'s and S(B)'s spheres (warm_min_sphere: min_sphere of a few seeds, then add the
//       farthest point while one lies outside; a subset's minimal sphere that contains every
//       point IS the minimal sphere). Growth's TightBound level often finds it without CGAL as
//       the minimal sphere of three points (small_support_sphere; Cgal only: with Exact the
//       oracle itself computes every sphere).
//   So the value differs from a from-scratch cluster_metrics only by the rounding of the
//   sphere code (Cgal: ~1e-15 of the extent; the warm start accepts 1e-14). For the
//   approximations (Ritter, EPOS) the result depends on every point, so only the first
//   shortcut applies and the rest is recomputed on the sorted union, as cluster_metrics does.
// - Upper bounds (minimal-sphere methods only; the approximations' radius has no lower bound, so
//   they always evaluate exactly): Acc decreases as R grows (reg = AreaP / (pi R^2); sizeBound is
//   non-decreasing in R), so any R_lb <= R gives one. Precision::UpperBoundAllowed: the exact
//   AreaP where the cone identity gives it (cheap, above; elsewhere its bound, the total area,
//   with AccTuning::area_bound) and R >= R_lb, where, with S(A) = (c_A, r_A), S(B) = (c_B, r_B) the
//   MINIMAL spheres and d = |c_A - c_B|:
//       R_lb^2 = min over x in [0, d] of max(r_A^2 + x^2, r_B^2 + (d - x)^2).
//   Proof: c_A lies in the convex hull of A's support points (on its sphere), so for any
//   center c there is a support point s with (s - c_A).(c - c_A) <= 0, hence
//   |s - c|^2 >= r_A^2 + |c - c_A|^2; the same for B; the max of the two is smallest for c on
//   the segment c_A c_B. A single added vertex v (growth) is the sphere (v, 0); then
//   R_lb = (delta^2 + r_A^2) / (2 delta), delta = |v - c_A|. Also R >= half the union's largest
//   width along the box axes, and along the 13 DOP directions with AccTuning::dop_bound; and,
//   with AccTuning::vertex_memo, the best bound found for v earlier in the same cluster (a
//   superset's minimal sphere is never smaller). For a single added vertex v (growth),
//   Precision::RefinedBound adds R >= max over p in A of |v - p| / 2 (one pass over V(A)), and
//   Precision::TightBound the radius of the minimal sphere of three points of A u {v} (three
//   passes; that sphere often contains every point and is then the exact answer). For any
//   pair, Precision::SupportBound adds the radius of the minimal sphere of three points of
//   A u B (support_r2; three passes over V(A u B); never the exact answer: the contraction keeps
//   the exact computation's sphere, sphere_of_union, as its exact value). With
//   AccTuning::large_bounds, a large A's pairs take both levels' bounds from what A keeps (ten
//   points, the normals' second moment, signed sum and horizon; see there) in O(|B|) instead.
//   Every R_lb is shrunk by 1e-12 relative and (from the
//   spheres of A and B) by the absolute rounding of their centers, so that rounding of the
//   computed spheres (~1e-15) cannot put the bound below the computed exact value.
// - Point filter for the exact computation: the center c of S(A u B) satisfies
//   |c - c_A| <= sqrt(R_ub^2 - r_A^2) (from R^2 >= r_A^2 + |c - c_A|^2 and R <= R_ub =
//   (d + r_A + r_B) / 2), so a point p of A with |p - c_A| + that < R_lb lies strictly inside
//   S(A u B) and cannot support it; likewise for B. Dropping such points leaves the minimal
//   sphere unchanged (it is the minimal sphere of its support points).
//
// Units: Acc is dimensionless; the objective is invariant under rigid motion and uniform scaling.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <unordered_map>
#include <vector>

#include "toolkit/clustering/objectives.h"
#include "toolkit/geometry/cluster_metrics.h"
#include "toolkit/geometry/sphere.h"

namespace ptc {

/// Accelerations of AccObjective that never change an exact score (each is exact, see the file
/// comment; area_bound changes only the keys' upper bounds, never which pair merges).
/// Each pays off in one algorithm only, so cluster_mesh picks them per method.
struct AccTuning {
  /// Remember S(A u {v}) per added vertex v for the current cluster A and reuse it after A has
  /// grown, as long as every vertex added to A since lies inside it (it is then still the minimal
  /// sphere of A u {v}). Minimal-sphere methods only. Growth: B adds at most one vertex, and the
  /// same candidate vertices come back step after step.
  /// Also keep, per vertex v, the best lower bound on R(A u {v}) found so far (any superset of A
  /// has a radius at least as large), which tightens the next steps' O(1) bound for free.
  bool vertex_memo = false;
  /// Keep a 26-DOP (extents along 13 directions) per cluster; half its largest width tightens the
  /// radius bound of two merged clusters (contraction: ~25% fewer exact evaluations on armadillo).
  /// In growth the diameter bound of Precision::RefinedBound does better and the DOP costs more
  /// than it saves.
  bool dop_bound = true;
  /// Precision::UpperBoundAllowed bounds AreaP by the members' total area (times 1 + 1e-6, which
  /// covers the sums' rounding) where the cone identity does not certify it, instead of summing
  /// it over the members: O(1) instead of O(|A| + |B|). The contraction evaluates every
  /// neighbour of a merged cluster at that level, and most of those entries go stale before
  /// they reach the top of its queue; large curved clusters (a high --max-count,
  /// --target-clusters) then paid for sums no merge read (docs/clustering.md, "Contraction to
  /// few large clusters"). Growth's bounded keys take another path (growth_prepare).
  bool area_bound = false;
  /// Keeps, for each merged cluster of at least kLargeFrom vertices or triangles, ten of its
  /// vertices (the four farthest from its sphere's center, the six extremes of its box), its
  /// normals' second moment M = sum Area_i n_i n_i^T, and their signed sum and horizon around
  /// its own N_avg (Large), so that the bounds of its pairs (Precision::UpperBoundAllowed and
  /// SupportBound) read those instead of its members: the radius from the minimal sphere of
  /// those points and B's; AreaP by Cauchy-Schwarz, sum Area_i |N.n_i| <= sqrt(sum Area_i *
  /// N^T M N), and by the signed sum with the members near the horizon bounded apart
  /// (horizon_area_bound). O(|B|) instead of O(|A| + |B|). A
  /// contraction to few large clusters (--target-clusters with a high --max-count) otherwise
  /// re-runs SupportBound's passes over the large cluster for each of its neighbours after every
  /// merge (docs/clustering.md, "Contraction to few large clusters"). Bounds only: which pair
  /// merges does not change.
  bool large_bounds = false;

  [[nodiscard]] static AccTuning for_growth() { return {true, false, false, false}; }
  /// The contraction without the DOP: its SupportBound level leaves the DOP about 6% of the time
  /// at 832k, and without it a merged cluster's summary is kept in 184 bytes instead of 264
  /// (AccObjective::Stored; docs/scale.md, "Contraction in one run: the memory").
  [[nodiscard]] static AccTuning for_contraction() { return {false, false, true, true}; }
};

class AccObjective {
 public:
  static constexpr bool kMergeOnlyPositive = true;
  static constexpr bool kUsesBoundary = false;
  /// Certification margin of the AreaP identity (see the file comment): cos(angle + theta) must
  /// be at least this. The test's own rounding is below 1e-8 rad (sqrt(1 - c^2) near c = 1), so
  /// a margin of 1e-6 cannot certify a negative dot product.
  static constexpr double kConeMargin = 1e-6;
  /// Relative size of |sum n_i| (per non-zero normal) below which sum n_i is recomputed in
  /// ascending triangle order (see the file comment).
  static constexpr double kRecomputeNormalSum = 0.05;
  /// A merged cluster of at least this many vertices or triangles keeps what
  /// AccTuning::large_bounds reads.
  static constexpr std::size_t kLargeFrom = 64;

  /// A cluster's summary without its 26-DOP: what the contraction keeps of a merged cluster
  /// when the tuning has no DOP bound (AccTuning::dop_bound; the DOP is always empty then), in
  /// 184 bytes (docs/scale.md, "Contraction in one run: what was left"; 176 before area_sum).
  struct Stored {
    Vec3 normal_sum = Vec3::Zero();       ///< sum of the unit normals n_i (zero normals add nothing)
    Vec3 area_normal_sum = Vec3::Zero();  ///< sum Area_i n_i (L^2)
    std::uint32_t nonzero = 0;            ///< number of non-zero normals
    /// Singleton whose sphere is not computed yet: its triangle id (see `sphere`).
    mutable std::uint32_t pending = 0xffffffffu;
    Vec3 cone_axis = Vec3::UnitZ();       ///< unit axis of a cone containing every non-zero n_i
    double cone_cos = 1;                  ///< cos of that cone's half-angle (any value when nonzero = 0)
    /// S(k), see the file comment; for a singleton made by single() computed on first use (see
    /// `pending`) and kept here, read it via sphere_of(). Mutable: a cache, not a value (no
    /// per-triangle table of spheres: 32 bytes a triangle at 13M triangles).
    mutable Sphere sphere;
    Box3 box;                             ///< box of the distinct vertices (the sphere's local origin)
    /// Keys the memo: t + 1 for the singleton {t} (every summary single(t) makes describes the
    /// same cluster), unique for a merged one (T + 1 on).
    std::uint64_t serial = 0;
    double area_sum = 0;                  ///< sum of Area_i (L^2): AreaP <= it (AccTuning::area_bound)
  };
  /// 264 bytes: contraction keeps one per merged cluster alive (docs/scale.md, "Contraction in one
  /// run"), so nothing is stored that a function of the rest gives to the bit (N_avg and its
  /// fallback flag are recomputed from the sums by evaluate(), the cone's sine from its cosine).
  struct Summary : Stored {
    /// Extent of the vertices along the 4 cube diagonals (x+y+z, x+y-z, x-y+z, -x+y+z) and the 6
    /// cube edge directions (x+y, x-y, x+z, x-z, y+z, y-z), unnormalised: with the box a 26-DOP
    /// (EPOS-26's directions), merged by min/max; its widths bound the sphere's radius from
    /// below. Floats rounded INWARDS (lo up, hi down; rounding is monotone, so the min/max of
    /// merges commute with it): a stored width is never above the true one, so the bound stays a
    /// bound. Empty (+inf, -inf) without AccTuning::dop_bound.
    std::array<float, 10> dop_lo{}, dop_hi{};
  };
  /// True when stored() and expand() keep a summary whole (no DOP bound in the tuning).
  [[nodiscard]] bool stores_whole() const { return !tuning_.dop_bound; }
  [[nodiscard]] static Stored stored(const Summary& s) { return s; }
  /// The summary `stored` was made from (when stores_whole()): its fields, and the empty DOP.
  static void expand(const Stored& st, Summary& s) {
    static_cast<Stored&>(s) = st;
    s.dop_lo.fill(std::numeric_limits<float>::infinity());
    s.dop_hi.fill(-std::numeric_limits<float>::infinity());
  }

  struct Evaluation : ScoreBase {
    Sphere sphere;                ///< S(A u B) (exact evaluations only)
    Box3 box;                     ///< box of A u B
    Vec3 n_avg = Vec3::UnitZ();   ///< N_avg(A u B)
    bool fallback = true;
    Vec3 normal_sum = Vec3::Zero();  ///< sum n_i of A u B as used (possibly recomputed)
    double area_p = 0;            ///< AreaP(A u B), or an upper bound of it (area_bounded)
    bool area_bounded = false;    ///< area_p is the total area's bound (AccTuning::area_bound; never exact)
    /// A bound no level short of Exact tightens (a large A's pair with its exact sphere: the
    /// contraction keys it as a SupportBound key).
    bool settled = false;
    double reg = 0;               ///< reg(A u B) (exact evaluations only)
  };

  /// params: max_count > 0, max_size > 0, avg_sa > 0 (finite), else std::invalid_argument.
  /// params.sphere is the sphere inside the loop.
  AccObjective(const ClusterTables& tables, const ClusterParams& params, const AccTuning& tuning = {});

  [[nodiscard]] Summary single(std::uint32_t t);
  [[nodiscard]] bool legal(const MergeContext&) const { return true; }
  [[nodiscard]] Evaluation evaluate(const Summary& a, const Summary& b, const MergeContext& ctx, Precision p);
  [[nodiscard]] Summary merge(const Summary& a, const Summary& b, const MergeContext& ctx, const Evaluation& ev);
  /// What of an exact evaluation is dear to make again: the sphere of A u B. The contraction
  /// keeps it for pairs that wait in its queue; evaluate_with(a, b, ctx, known_of(ev)) for ev =
  /// evaluate(a, b, ctx, Precision::Exact) is ev again, to the bit (the same code makes the rest),
  /// without the sphere's computation. No memo side effects (AccTuning::vertex_memo: growth's).
  using Known = Sphere;
  [[nodiscard]] static Known known_of(const Evaluation& ev) { return ev.sphere; }
  [[nodiscard]] Evaluation evaluate_with(const Summary& a, const Summary& b, const MergeContext& ctx, const Known& sphere);

  /// Growth's cheapest level without evaluate()'s generality (docs/scale.md, "Open (issue 15)",
  /// growth), in two passes over the candidates of one step so that their chains of square roots
  /// and divisions overlap: for a candidate triangle t that adds exactly one vertex v to A = a,
  /// the key that evaluate(a, single(t), ctx, Precision::UpperBoundAllowed) returns, with the
  /// same side effects, when that evaluation returns a bound -- the same operations in the same
  /// order, so the same bits.
  ///   growth_prepare(a, q, out): what depends on A and t only (no side effects);
  ///   growth_key(p, v, vertex_count, key), in the candidates' order, interleaved with the
  ///   evaluate() calls of the other candidates: the memo and the learnt bounds, then the key.
  /// False (in `GrowthPrepared::general` or from growth_key) when that evaluation would be exact
  /// or take one of its rare paths (normals that cancel, cones that do not certify AreaP, v inside
  /// S(A) or in the memo): the caller then calls evaluate(), which repeats nothing this did in a
  /// way that could change it. vertex_count = |V(A)| + 1. Only when growth_bound_applies().
  struct GrowthQuery {
    std::uint32_t t, v;
    const Box3* triangle_box;  ///< single(t).box
  };
  struct GrowthPrepared {
    double r2, shrink, area_p;
    bool general;
    Vec3 normal_sum, n_avg;  // of A u {t}: evaluate()'s values
    Box3 box;
  };
  [[nodiscard]] bool growth_bound_applies() const { return minimal_ && tuning_.vertex_memo && !tuning_.dop_bound; }
  void growth_prepare(const Summary& a, std::span<const GrowthQuery> queries, GrowthPrepared* out);
  [[nodiscard]] bool growth_key(const GrowthPrepared& p, std::uint32_t v, std::uint32_t vertex_count, double& key);
  /// Asks for vertex v's entries of the learnt bounds (read by growth_key) ahead of their use.
  void prefetch_vertex(std::uint32_t v) const {
    if (v < lb_owner_.size()) __builtin_prefetch(lb_owner_.data() + v), __builtin_prefetch(lb_r2_.data() + v);
  }
  /// evaluate(a, single(t), ctx, precision) for a candidate growth_prepare did not mark general,
  /// at any level (growth's refinements): the same Evaluation and side effects, without
  /// recomputing what growth_prepare kept, and without single(t).
  [[nodiscard]] Evaluation growth_refine(const Summary& a, const GrowthPrepared& p, const MergeContext& ctx,
                                         Precision precision);

  /// single(t).box: the box of triangle t's corners (growth's candidates keep it instead of the summary).
  [[nodiscard]] Box3 triangle_box(std::uint32_t t) const {
    Box3 b;
    for (std::uint32_t v : tables_->triangles[t]) b.extend(tables_->positions[v]);
    return b;
  }

  /// Precision::SupportBound's R^2: that of the minimal sphere of three points of V(A) u added
  /// (the point farthest from the center of `box`, the box of A u B; the point farthest from it;
  /// the point farthest from their sphere), shrunk by 1e-12 relative. A lower bound on R^2 of
  /// S(A u B) as evaluate() computes it; 0 when not finite.
  [[nodiscard]] double support_r2(const MergeContext& ctx, const Box3& box) const;

  /// S(k) of a summary (computes a singleton's sphere on first use and keeps it in the summary).
  [[nodiscard]] const Sphere& sphere_of(const Summary& s);

  [[nodiscard]] const ClusterParams& params() const { return params_; }
  /// True for Exact and Cgal: the sphere is the minimal one (to rounding), so the containment
  /// shortcuts and the upper bound apply.
  [[nodiscard]] bool minimal_sphere() const { return minimal_; }
  /// Spheres computed from scratch so far (work counter for the benchmark).
  [[nodiscard]] std::uint64_t sphere_computations() const { return sphere_computations_; }

 private:
  /// AccTuning::large_bounds: what a large merged cluster keeps (see there), by serial.
  using Moment = std::array<double, 6>;  ///< sum Area_i n_i n_i^T: xx, yy, zz, xy, xz, yz
  /// Horizon thresholds of Large::horizon.
  static constexpr std::array<double, 6> kHorizon = {0x1p-16, 0x1p-12, 0x1p-8, 0x1p-6, 0x1p-4, 0x1p-2};
  struct Large {
    std::array<std::uint32_t, 10> points{};  ///< vertices: the 4 farthest from S's center, the box's 6 extremes
    Moment moment{};
    /// For AreaP near the cluster's own N_avg n_ref: g = sum s_i Area_i n_i with s_i the sign of
    /// n_ref.n_i, and horizon[k] = the area of the members with |n_ref.n_i| <= kHorizon[k].
    Vec3 n_ref = Vec3::Zero(), g = Vec3::Zero();
    std::array<double, 6> horizon{};
    std::size_t full_members = 0;  ///< members at the last pass over all of them (AccObjective::keep_large)
  };
  /// A large A's pair, for its bounds: what A keeps, and what B keeps (null for a small B, whose
  /// members are read instead).
  struct LargePair {
    const Large* a = nullptr;
    const Large* b = nullptr;
  };
  [[nodiscard]] double score_of(double area_p, double r2, std::uint32_t vertex_count, double* reg) const;
  /// evaluate() up to the sphere: the box, N_avg with its fallback, the normal sum and AreaP.
  /// allow_area_bound (Precision::UpperBoundAllowed with AccTuning::area_bound): AreaP may be
  /// the total area's bound (ev.area_bounded; N_avg and the sums are then not made).
  /// With `large` (a large A's pair), that bound is also Cauchy-Schwarz's and the horizon's.
  void sums_and_area(const Summary& a, const Summary& b, const MergeContext& ctx, Evaluation& ev,
                     bool allow_area_bound = false, const LargePair* large = nullptr);
  /// evaluate() from the sphere of A u B on (ev holds the box, N_avg, sums and AreaP); b may be
  /// null when ctx adds one vertex and the tuning has no DOP (it is not read then).
  void union_sphere_and_score(const Summary& a, const Summary* b, const MergeContext& ctx, Precision precision,
                              bool memo, Evaluation& ev, const LargePair* large = nullptr);
  /// Which points may support S(A u B) (minimal spheres only; see evaluate()).
  struct PointFilter {
    Vec3 ca = Vec3::Zero(), cb = Vec3::Zero();
    double ra = 0, rb = 0;  // radii of S(A) and of B's sphere (0 for a single added point)
    double da = 0, db = 0, keep_from = 0;
  };
  [[nodiscard]] Sphere sphere_of_union(const MergeContext& ctx, const Box3& box, const PointFilter* filter);
  [[nodiscard]] Sphere warm_min_sphere();
  /// Growth's case (one added vertex v): the minimal sphere of A u {v} from at most three of
  /// its points when that suffices (true, exact to rounding), else a sphere whose radius is a
  /// lower bound (false). O(|V(A)|).
  [[nodiscard]] bool small_support_sphere(const MergeContext& ctx, const Box3& box, Sphere& out) const;

  void remember(const MergeContext& ctx, const Sphere& s);
  void enter_lineage(const Summary& a);
  [[nodiscard]] double known_r2(std::uint32_t v) const;
  /// The memo's S(A u {v}), or null.
  [[nodiscard]] const Sphere* memo_find(std::uint32_t v) const;
  void learn_r2(std::uint32_t v, double r2);
  [[nodiscard]] double area_p_of(const Summary& part, std::span<const std::uint32_t> members, const Vec3& n) const;

  std::unordered_map<std::uint64_t, Large> large_;
  [[nodiscard]] const Large* large_of(const Summary& s) const {
    if (large_.empty()) return nullptr;
    const auto it = large_.find(s.serial);
    return it == large_.end() ? nullptr : &it->second;
  }
  /// After merge(a, b) made s: keeps s's Large when it is large, forgets a's and b's.
  void keep_large(const Summary& a, const Summary& b, const MergeContext& ctx, const Summary& s, const Vec3& n_avg);
  /// sum Area_i n_i n_i^T over `members`.
  [[nodiscard]] Moment moment_of(std::span<const std::uint32_t> members) const;
  /// Precision::SupportBound's R^2 for a large A: the minimal sphere of A's kept points and B's
  /// (kept, or V(B) \ V(A) for a small B), shrunk as support_r2's.
  [[nodiscard]] double large_support_r2(const LargePair& large, const MergeContext& ctx, const Box3& box);
  /// AreaP(A u B) at the exact N_avg, which is within delta of n, bounded from what the large A
  /// (and B) keep; w = the union's total area.
  [[nodiscard]] double horizon_area_bound(const LargePair& large, const Summary& b, const MergeContext& ctx,
                                          const Vec3& n, double delta, double w) const;
  std::vector<Vec3> scratch_bound_points_;

  const ClusterTables* tables_;
  ClusterParams params_;
  bool minimal_;
  double inv_max_count_ = 0, inv_size_unit_ = 0;  // 1 / MaxCount, 1 / (MaxSize AvgSA)
  AccTuning tuning_;
  std::uint64_t sphere_computations_ = 0;
  std::uint64_t next_serial_ = 1;
  struct MemoEntry {
    std::uint32_t vertex;
    Sphere sphere;
  };
  std::uint64_t memo_serial_ = 0;  // the summary the memo belongs to (0: none)
  std::vector<MemoEntry> memo_;
  // Lower bounds on R(A u {v})^2 per vertex v for the current cluster's lineage (the chain of
  // summaries merged from one another, so each A is a superset of the earlier ones and a bound
  // stays valid): lb_r2_[v] counts while lb_owner_[v] == lineage_.
  std::uint32_t lineage_ = 0;
  std::vector<double> lb_r2_;
  std::vector<std::uint32_t> lb_owner_;
  std::vector<std::uint32_t> scratch_ids_;
  std::vector<Vec3> scratch_points_, scratch_seed_points_;
  std::vector<std::uint32_t> scratch_seeds_;
  std::vector<Vec3> scratch_normals_;
  std::vector<double> scratch_areas_;
};

}  // namespace ptc
