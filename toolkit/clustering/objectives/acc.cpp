#include "toolkit/clustering/objectives/acc.h"

#include <emmintrin.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "toolkit/core/isa.h"
#include "toolkit/geometry/triangle.h"

namespace ptc {

namespace {

// f(Area_t, n_t) for each t of `ids`, in order: the stored values read in the loop, or for lean
// tables made again (geometry_of's values either way). Inlined into the callers' loops (a call of
// geometry_of per member was a fifth of a large contraction).
template <class F>
[[gnu::always_inline]] inline void for_each_geometry(const ClusterTables& tb, std::span<const std::uint32_t> ids, F&& f) {
  if (!tb.lean) {
    const double* area = tb.area.data();
    const Vec3* normal = tb.normal.data();
    for (std::uint32_t t : ids) f(area[t], normal[t]);
  } else {
    for (std::uint32_t t : ids) {
      const TriangleGeometry g = tb.geometry_of(t);
      f(g.area, g.normal);
    }
  }
}

constexpr double kEps = 2.220446049250313e-16;

void require_positive(double v, const char* what) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw std::invalid_argument(std::string("AccObjective: ") + what + " must be finite and > 0, got " +
                                std::to_string(v));
}

/// cluster_metrics' local origin: per axis 0 when the box touches or straddles 0, else its minimum.
Vec3 local_origin(const Box3& box) {
  Vec3 o;
  for (int k = 0; k < 3; ++k) o[k] = (box.lo[k] <= 0.0 && box.hi[k] >= 0.0) ? 0.0 : box.lo[k];
  return o;
}

/// The vertex of `lists` farthest from c on cluster-local coordinates (p - o), and its squared
/// distance in d2max; the first one on ties. The first list must not be empty.
std::uint32_t farthest_vertex(std::span<const Vec3> pos, std::initializer_list<std::span<const std::uint32_t>> lists,
                              const Vec3& o, const Vec3& c, double& d2max) {
  std::uint32_t best = lists.begin()->front();
  d2max = -1.0;
  for (const std::span<const std::uint32_t> list : lists)
    for (const std::uint32_t u : list)
      if (const double d2 = (pos[u] - o - c).squaredNorm(); d2 > d2max) {
        d2max = d2;
        best = u;
      }
  return best;
}

[[gnu::always_inline]] inline double max_abs(const Vec3& v) { return v.cwiseAbs().maxCoeff(); }

/// Absolute slack for tests on sphere centers stored in absolute coordinates: the center is
/// rounded to ulp(|c|) when translated back from the local frame (cluster_metrics does the same),
/// so geometric predicates on it are only decided beyond a few ulps of the coordinates.
[[gnu::always_inline]] inline double center_slack_by(double c_abs, const Vec3& p) {
  return 8.0 * kEps * std::max(c_abs, max_abs(p));
}
[[gnu::always_inline]] inline double center_slack(const Vec3& c, const Vec3& p) { return center_slack_by(max_abs(c), p); }

/// surely_inside from its terms: the radius, center_slack(center, p) and |p - center|^2.
[[gnu::always_inline]] inline bool surely_inside_by(double radius, double slack, double d2) {
  const double r = radius - slack;
  return r > 0.0 && d2 * (1.0 + 8.0 * kEps) <= r * r;
}

/// True when the point is inside the sphere by more than the rounding of the test.
[[gnu::always_inline]] inline bool surely_inside(const Sphere& s, const Vec3& p) {
  return surely_inside_by(s.radius, center_slack(s.center, p), (p - s.center).squaredNorm());
}

/// Growth's radius bound for A u {v} (acc.h): R^2 >= ((d^2 + r_A^2) / (2 d))^2 when d > r_A,
/// d^2 = |v - c_A|^2; else r_A^2.
/// Squaring d^2 + r_A^2 overflows beyond extents of ~1e77 and loses its bits to subnormals below
/// ~1e-77; there the bound is squared from (d^2 + r_A^2) / (2 d) instead (a few ulps apart, within
/// bound_shrink's margin), and in between it keeps the bits of the direct formula.
[[gnu::always_inline]] inline double point_r2_bound(double d2, double ra) {
  if (!(d2 > ra * ra)) return ra * ra;
  const double s = d2 + ra * ra;
  const double r2 = s * s / (4.0 * d2);
  if (s >= 0x1p-500 && r2 <= std::numeric_limits<double>::max()) return r2;
  const double h = s / (2.0 * std::sqrt(d2));
  return h * h;
}

/// The factor a radius bound is shrunk by: 1e-12 relative and the absolute rounding of the
/// centers (`slack`, at most slack / r_A relative since R >= r_A), so that rounding cannot lift
/// the bound above the computed exact radius.
[[gnu::always_inline]] inline double bound_shrink(double slack, double ra) {
  return 1.0 - 1e-12 - (ra > 0.0 ? slack / ra : 1.0);
}

/// True when sphere `in` lies inside sphere `out` by more than rounding.
bool surely_contains(const Sphere& out, const Sphere& in) {
  return (in.center - out.center).norm() * (1.0 + 4.0 * kEps) + in.radius * (1.0 + 4.0 * kEps) +
             center_slack(out.center, in.center) <=
         out.radius;
}

/// Lower bound of cos(alpha + beta) given cos(alpha) = c1 and cos(beta) = c2 (angles in [0, pi]);
/// -1 when alpha + beta >= pi.
[[gnu::always_inline]] inline double cos_of_sum(double c1, double c2) {
  c1 = std::clamp(c1, -1.0, 1.0);
  c2 = std::clamp(c2, -1.0, 1.0);
  if (c1 + c2 <= 0.0) return -1.0;
  const double s1 = std::sqrt(std::max(0.0, (1.0 - c1) * (1.0 + c1)));
  const double s2 = std::sqrt(std::max(0.0, (1.0 - c2) * (1.0 + c2)));
  return c1 * c2 - s1 * s2;
}

/// The float nearest x from above, for four doubles at once (SSE2; lanes 0-1 from x01, 2-3 from
/// x23): the inward rounding of the DOP's lower ends (acc.h; the upper ends take -float_up4(-x)).
/// A double beyond the float range becomes the infinity on its side (from above: +inf for
/// x > FLT_MAX, which makes a lower end useless and the width -inf: no bound, never a wrong one).
/// The conversion rounds to nearest (MXCSR's default, as static_cast<float>); a lane that rounded
/// down steps one float up: +1 on the bits of a positive float, -1 on a negative one, the
/// smallest positive subnormal from either zero. Without branches: half of the conversions round
/// down, and single() runs for every singleton a contraction evaluates.
[[gnu::always_inline]] inline __m128 float_up4(__m128d x01, __m128d x23) {
  const __m128 f = _mm_movelh_ps(_mm_cvtpd_ps(x01), _mm_cvtpd_ps(x23));
  const __m128d back01 = _mm_cvtps_pd(f), back23 = _mm_cvtps_pd(_mm_movehl_ps(f, f));
  const __m128i below = _mm_castps_si128(_mm_shuffle_ps(_mm_castpd_ps(_mm_cmplt_pd(back01, x01)),
                                                        _mm_castpd_ps(_mm_cmplt_pd(back23, x23)), _MM_SHUFFLE(2, 0, 2, 0)));
  const __m128i bits = _mm_castps_si128(f);
  const __m128i one = _mm_set1_epi32(1);
  const __m128i zero = _mm_castps_si128(_mm_cmpeq_ps(f, _mm_setzero_ps()));
  const __m128i stepped = _mm_add_epi32(bits, _mm_or_si128(_mm_srai_epi32(bits, 31), one));  // +1 or -1
  const __m128i up = _mm_or_si128(_mm_and_si128(zero, one), _mm_andnot_si128(zero, stepped));
  return _mm_castsi128_ps(_mm_or_si128(_mm_and_si128(below, up), _mm_andnot_si128(below, bits)));
}

/// True when every normal of the part has a non-negative dot product with n (proved by its cone):
/// cos(angle(axis, n) + half-angle) >= kConeMargin.
[[gnu::always_inline]] inline bool certified(const AccObjective::Summary& part, const Vec3& n) {
  if (part.nonzero == 0) return true;
  const double c1 = part.cone_axis.dot(n), c2 = part.cone_cos;
  if (!(c1 > 0.0) || !(c2 > 0.0)) return false;
  if (c2 >= 1.0) return c1 >= AccObjective::kConeMargin;
  // c1 c2 - s1 s2 >= margin, s_i = sqrt(1 - c_i^2), without square roots: both sides squared.
  // (Rounding moves either side by ~1e-16, far below the margin.)
  const double lhs = c1 * c2 - AccObjective::kConeMargin;
  return lhs >= 0.0 && lhs * lhs >= std::max(0.0, (1.0 - c1) * (1.0 + c1)) * std::max(0.0, (1.0 - c2) * (1.0 + c2));
}

void set_cone(AccObjective::Summary& s, const Vec3& axis, double c) {
  s.cone_axis = axis;
  s.cone_cos = std::clamp(c, -1.0, 1.0);
}

}  // namespace

static_assert(sizeof(AccObjective::Summary) == 264, "acc.h: Summary is meant to stay at 264 bytes");
static_assert(sizeof(AccObjective::Stored) == 184, "acc.h: Stored is the summary without its 80-byte DOP");

AccObjective::AccObjective(const ClusterTables& tables, const ClusterParams& params, const AccTuning& tuning)
    : tables_(&tables), params_(params), tuning_(tuning) {
  require_positive(params.max_count, "max_count");
  require_positive(params.max_size, "max_size");
  require_positive(params.avg_sa, "avg_sa");
  minimal_ = params.sphere == SphereMethod::Exact || params.sphere == SphereMethod::Cgal;
  inv_max_count_ = 1.0 / params.max_count;
  inv_size_unit_ = 1.0 / (params.max_size * params.avg_sa);
  next_serial_ = std::uint64_t{tables.triangle_count()} + 1;  // singleton {t} has serial t + 1
  if (tuning_.vertex_memo) {
    lb_r2_.assign(tables.positions.size(), 0.0);
    lb_owner_.assign(tables.positions.size(), 0);
  }
}

PTC_ISA_CLONES
AccObjective::Summary AccObjective::single(std::uint32_t t) {
  const ClusterTables& tb = *tables_;
  Summary s;
  s.serial = std::uint64_t{t} + 1;  // the same for every summary of {t}: they describe one cluster
  const TriangleGeometry g = tb.geometry_of(t);
  const Vec3& n = g.normal;
  s.area_sum = g.area;
  if (!n.isZero(0.0)) {
    s.normal_sum = n;
    s.area_normal_sum = g.area * n;
    s.nonzero = 1;
    set_cone(s, n, 1.0);  // N_avg of any merge is recomputed from the sums (evaluate)
  }
  s.dop_lo.fill(std::numeric_limits<float>::infinity());
  s.dop_hi.fill(-std::numeric_limits<float>::infinity());
  s.box = triangle_box(t);
  if (!tuning_.dop_bound) {  // growth and the contraction: the box only
    s.pending = t;
    return s;
  }
  // The extents in pairs of directions: _mm_min_pd(p, lo) is std::min(lo, p) and _mm_max_pd(p, hi)
  // is std::max(hi, p), to the bit (NaN and signed zeros included).
  __m128d lo[5], hi[5];
  for (int k = 0; k < 5; ++k) lo[k] = _mm_set1_pd(std::numeric_limits<double>::infinity()), hi[k] = -lo[k];
  for (std::uint32_t v : tb.triangles[t]) {
    const Vec3& p = tb.positions[v];
    const double x = p.x(), y = p.y(), z = p.z();
    const __m128d proj[5] = {_mm_set_pd(x + y - z, x + y + z), _mm_set_pd(-x + y + z, x - y + z),
                             _mm_set_pd(x - y, x + y), _mm_set_pd(x - z, x + z), _mm_set_pd(y - z, y + z)};
    for (int k = 0; k < 5; ++k) {
      lo[k] = _mm_min_pd(proj[k], lo[k]);
      hi[k] = _mm_max_pd(proj[k], hi[k]);
    }
  }
  // Rounded inwards four at a time: lower ends up (float_up4), upper ends down (-float_up4(-x)).
  const __m128d sign_d = _mm_set1_pd(-0.0);
  const __m128 sign_f = _mm_set1_ps(-0.0f);
  auto down4 = [&](__m128d x01, __m128d x23) {
    return _mm_xor_ps(float_up4(_mm_xor_pd(x01, sign_d), _mm_xor_pd(x23, sign_d)), sign_f);
  };
  _mm_storeu_ps(&s.dop_lo[0], float_up4(lo[0], lo[1]));
  _mm_storeu_ps(&s.dop_lo[4], float_up4(lo[2], lo[3]));
  _mm_storel_pi(reinterpret_cast<__m64*>(&s.dop_lo[8]), float_up4(lo[4], lo[4]));
  _mm_storeu_ps(&s.dop_hi[0], down4(hi[0], hi[1]));
  _mm_storeu_ps(&s.dop_hi[4], down4(hi[2], hi[3]));
  _mm_storel_pi(reinterpret_cast<__m64*>(&s.dop_hi[8]), down4(hi[4], hi[4]));
  s.pending = t;  // the sphere is computed when first needed (growth rarely needs a candidate's)
  return s;
}

const Sphere& AccObjective::sphere_of(const Summary& s) {
  if (s.pending == 0xffffffffu) return s.sphere;
  Sphere& out = s.sphere;
  const ClusterTables& tb = *tables_;
  const Vec3 o = local_origin(s.box);
  if (params_.sphere == SphereMethod::Cgal) {  // closed form, minimal to rounding (local coordinates)
    const Tri& f = tb.triangles[s.pending];
    out = triangle_min_sphere(tb.positions[f[0]] - o, tb.positions[f[1]] - o, tb.positions[f[2]] - o);
  } else {  // the method itself (Exact: the oracle; approximations: shortcuts rely on S(k) being
            // the method's sphere of V(k))
    std::uint32_t v[3];
    const int nv = tb.distinct_vertices(s.pending, v);
    Vec3 pts[3];
    for (int i = 0; i < nv; ++i) pts[i] = tb.positions[v[i]] - o;
    out = bounding_sphere(params_.sphere, std::span<const Vec3>(pts, static_cast<std::size_t>(nv)));
  }
  out.center += o;
  s.pending = 0xffffffffu;
  return out;
}

// Inlined into its callers (all in this file), their instruction-set clones included.
[[gnu::always_inline]] inline
double AccObjective::score_of(double area_p, double r2, std::uint32_t vertex_count, double* reg_out) const {
  // The expressions of cluster_metrics / cluster_acc, from R^2 (bounds come as R^2: no root).
  const double area_c = std::numbers::pi * r2;
  const double reg = area_c > 0.0 ? area_p / area_c : 0.0;
  const double sa = 4.0 * area_c;
  const double rb = static_cast<double>(vertex_count) * inv_max_count_;  // within an ulp of N_V / MaxCount
  const double ratio = sa * inv_size_unit_;
  const double sb = params_.size_bound_mode == SizeBoundMode::Max ? std::max(1.0, ratio) : std::min(1.0, ratio);
  if (reg_out) *reg_out = reg;
  const double acc = reg - rb * sb;
  return std::isnan(acc) ? -std::numeric_limits<double>::infinity() : acc;
}

PTC_ISA_CLONES
Sphere AccObjective::sphere_of_union(const MergeContext& ctx, const Box3& box, const PointFilter* filter) {
  const Vec3 o = local_origin(box);
  const auto& pos = tables_->positions;
  // A point p of A is dropped when |p - c_A| + d_A < keep_from, i.e. |p - c_A|^2 < (keep_from - d_A)^2.
  const double lim_a = filter ? filter->keep_from - filter->da : -1.0;
  const double lim_b = filter ? filter->keep_from - filter->db : -1.0;
  const double lim_a2 = lim_a > 0.0 ? lim_a * lim_a : -1.0, lim_b2 = lim_b > 0.0 ? lim_b * lim_b : -1.0;
  // Seeds of the warm start (Cgal): the points on (or within 1e-6 of) S(A)'s and S(B)'s spheres.
  const bool warm = filter && params_.sphere == SphereMethod::Cgal;
  const double near_a2 = warm ? filter->ra * filter->ra * (1.0 - 1e-6) : 0.0;
  const double near_b2 = warm ? filter->rb * filter->rb * (1.0 - 1e-6) : 0.0;
  scratch_points_.clear();
  scratch_seeds_.clear();
  auto ia = ctx.a_vertices.begin(), ea = ctx.a_vertices.end();
  auto ib = ctx.added.begin(), eb = ctx.added.end();
  while (ia != ea || ib != eb) {  // ascending merge of two disjoint sorted lists
    const bool from_a = ib == eb || (ia != ea && *ia < *ib);
    const std::uint32_t v = from_a ? *ia++ : *ib++;
    if (filter) {
      const double d2 = (pos[v] - (from_a ? filter->ca : filter->cb)).squaredNorm();
      if (d2 < (from_a ? lim_a2 : lim_b2)) continue;  // surely inside S(A u B)
      if (warm && d2 >= (from_a ? near_a2 : near_b2))
        scratch_seeds_.push_back(static_cast<std::uint32_t>(scratch_points_.size()));
    }
    scratch_points_.push_back(pos[v] - o);
  }
  ++sphere_computations_;
  Sphere s = warm && !scratch_seeds_.empty() && scratch_seeds_.size() < scratch_points_.size()
                 ? warm_min_sphere()
                 : bounding_sphere(params_.sphere, scratch_points_);
  s.center += o;
  return s;
}

PTC_ISA_CLONES
Sphere AccObjective::warm_min_sphere() {
  // Minimal sphere of scratch_points_ from a few of them (the seeds): min_sphere of the seeds;
  // if a point lies outside, add the farthest one and repeat. When every point is inside, the
  // seeds' minimal sphere is the minimal sphere of all (a subset's is never larger), so this is
  // the same sphere as min_sphere on all points, to rounding (the acceptance test allows
  // 1e-14 relative). Usually one or two small solves instead of one on the whole set.
  const std::span<const Vec3> pts = scratch_points_;
  for (int iter = 0; iter < 8; ++iter) {
    scratch_seed_points_.clear();
    for (std::uint32_t i : scratch_seeds_) scratch_seed_points_.push_back(pts[i]);
    Sphere s = min_sphere(scratch_seed_points_);
    double far2 = 0;
    std::uint32_t far = 0;
    for (std::uint32_t i = 0; i < pts.size(); ++i)
      if (const double d2 = (pts[i] - s.center).squaredNorm(); d2 > far2) {
        far2 = d2;
        far = i;
      }
    const double accept = s.radius * (1.0 + 1e-14);
    if (far2 <= accept * accept) {
      s.radius = std::max(s.radius, std::sqrt(far2));  // containment of every point, as min_sphere
      return s;
    }
    if (std::find(scratch_seeds_.begin(), scratch_seeds_.end(), far) != scratch_seeds_.end()) break;  // rounding
    scratch_seeds_.push_back(far);
  }
  return min_sphere(pts);
}

PTC_ISA_CLONES
double AccObjective::area_p_of(const Summary& part, std::span<const std::uint32_t> members, const Vec3& n) const {
  if (part.nonzero == 0) return 0.0;
  double s = 0;
  for_each_geometry(*tables_, members, [&](double area, const Vec3& normal) { s += area * std::abs(n.dot(normal)); });
  return s;
}

void AccObjective::enter_lineage(const Summary& a) {
  if (memo_serial_ == a.serial) return;
  memo_.clear();  // another cluster: nothing remembered applies
  memo_serial_ = a.serial;
  ++lineage_;
}

double AccObjective::known_r2(std::uint32_t v) const { return lb_owner_[v] == lineage_ ? lb_r2_[v] : 0.0; }

const Sphere* AccObjective::memo_find(std::uint32_t v) const {
  for (const MemoEntry& e : memo_)
    if (e.vertex == v) return &e.sphere;
  return nullptr;
}

void AccObjective::learn_r2(std::uint32_t v, double r2) {
  if (lb_owner_[v] != lineage_) {
    lb_owner_[v] = lineage_;
    lb_r2_[v] = r2;
  } else {
    lb_r2_[v] = std::max(lb_r2_[v], r2);
  }
}

void AccObjective::remember(const MergeContext& ctx, const Sphere& s) {
  if (!tuning_.vertex_memo || !minimal_ || ctx.added.size() != 1) return;
  memo_.push_back({ctx.added[0], s});
  learn_r2(ctx.added[0], s.radius * s.radius);
}

PTC_ISA_CLONES
bool AccObjective::small_support_sphere(const MergeContext& ctx, const Box3& box, Sphere& out) const {
  // On cluster-local coordinates, as every sphere here. Three scans of V(A):
  //   p  = the point farthest from v; D = the sphere with diameter v p;
  //   q  = the point farthest from D's center: inside D -> D is minimal (a subset's minimal
  //        sphere that contains every point is the minimal sphere of all);
  //   T  = triangle_min_sphere(v, p, q) (closed form, minimal to rounding); the point farthest
  //        from T's center inside -> T is minimal; otherwise T's radius is a lower bound.
  // "Inside" allows 1e-14 relative, and the radius is then raised to the farthest point, as
  // min_sphere does: the result agrees with min_sphere on all points to ~1e-14.
  const auto& pos = tables_->positions;
  const Vec3 o = local_origin(box);
  const Vec3 v = pos[ctx.added[0]] - o;
  auto farthest = [&](const Vec3& c, double& d2max) { return farthest_vertex(pos, {ctx.a_vertices}, o, c, d2max); };
  auto accept = [&](Sphere s, double far2) {
    const double r = s.radius * (1.0 + 1e-14);
    if (!(far2 <= r * r)) return false;
    s.radius = std::max(s.radius, std::sqrt(far2));
    s.center += o;
    out = s;
    return true;
  };
  double d2;
  const Vec3 p = pos[farthest(v, d2)] - o;
  Sphere s{0.5 * (v + p), 0.5 * std::sqrt(d2)};
  const Vec3 q = pos[farthest(s.center, d2)] - o;
  if (accept(s, d2)) return true;
  s = triangle_min_sphere(v, p, q);
  farthest(s.center, d2);
  if (accept(s, d2)) return true;
  out = s;  // a lower bound only (center meaningless)
  out.center += o;
  return false;
}

// R^2 of the minimal sphere of three points of the lists (the point farthest from the center of
// `box`, the point farthest from it, the point farthest from their sphere) on local coordinates,
// shrunk by 1e-12 relative: a lower bound on R^2 of any set the lists' points belong to (see
// support_r2); 0 when not finite. With `holds_all`: whether that sphere holds every point of the
// lists (to 1e-14 relative), when it is their minimal sphere (one more pass).
PTC_ISA_CLONES
static double three_point_r2(std::span<const Vec3> pos, std::initializer_list<std::span<const std::uint32_t>> lists,
                             const Box3& box, bool* holds_all = nullptr) {
  const Vec3 o = local_origin(box);
  auto farthest = [&](const Vec3& c, double& d2max) { return Vec3(pos[farthest_vertex(pos, lists, o, c, d2max)] - o); };
  double d2;
  const Vec3 p1 = farthest(0.5 * (box.lo + box.hi) - o, d2);
  const Vec3 p2 = farthest(p1, d2);
  const Sphere diametral{0.5 * (p1 + p2), 0.5 * std::sqrt(d2)};
  const Vec3 p3 = farthest(diametral.center, d2);
  double r = diametral.radius;
  if (holds_all) *holds_all = true;  // p3, the farthest, inside the diametral sphere: all are
  if (d2 > r * r) {
    const Sphere t = triangle_min_sphere(p1, p2, p3);
    r = std::max(r, t.radius);
    if (holds_all) {
      farthest(t.center, d2);
      *holds_all = d2 <= t.radius * t.radius * (1.0 + 1e-14);
    }
  }
  constexpr double kShrink = 1.0 - 1e-12;
  const double r2 = r * r * (kShrink * kShrink);
  return std::isfinite(r2) ? r2 : 0.0;
}

PTC_ISA_CLONES
double AccObjective::support_r2(const MergeContext& ctx, const Box3& box) const {
  // On cluster-local coordinates, the points sphere_of_union gives the exact computation. The
  // minimal sphere of a subset is never larger than the union's. Its computed radius is the
  // largest distance from a computed center (triangle_min_sphere: the circumcenter from the
  // corner of the largest angle, well conditioned, on edges scaled to unit size, so at any
  // scale), within a few ulps of the subset's minimal radius; the exact sphere contains every
  // point up to ~1e-14 relative. The 1e-12 shrink covers both.
  return three_point_r2(tables_->positions, {ctx.a_vertices, ctx.added}, box);
}

PTC_ISA_CLONES
AccObjective::Evaluation AccObjective::evaluate(const Summary& a, const Summary& b, const MergeContext& ctx,
                                                Precision precision) {
  const bool memo = tuning_.vertex_memo && minimal_ && ctx.added.size() == 1;
  if (memo) enter_lineage(a);
  Evaluation ev;
  // A large A (AccTuning::large_bounds): its pairs' bounds read what it keeps, not its members.
  LargePair pair;
  if ((precision == Precision::UpperBoundAllowed || precision == Precision::SupportBound) && minimal_ &&
      tuning_.area_bound)
    pair = {large_of(a), large_of(b)};
  const LargePair* large = pair.a ? &pair : nullptr;
  sums_and_area(a, b, ctx, ev, tuning_.area_bound && (precision == Precision::UpperBoundAllowed || large), large);
  union_sphere_and_score(a, &b, ctx, precision, memo, ev, large);
  if (ev.area_bounded) {  // a bound whatever the sphere: AreaP is (reg and the sphere are not kept)
    // With a large A and the exact sphere, SupportBound would give this same bound (the same
    // AreaP bound, the sphere itself): only the exact evaluation can tighten it.
    ev.settled = large != nullptr && ev.exact;
    ev.exact = false;
    ev.reg = 0;
  }
  return ev;
}

PTC_ISA_CLONES
AccObjective::Evaluation AccObjective::evaluate_with(const Summary& a, const Summary& b, const MergeContext& ctx,
                                                     const Known& sphere) {
  Evaluation ev;
  sums_and_area(a, b, ctx, ev);
  ev.sphere = sphere;
  ev.exact = true;  // as evaluate() ends every exact evaluation
  ev.score = score_of(ev.area_p, ev.sphere.radius * ev.sphere.radius, ctx.vertex_count, &ev.reg);
  return ev;
}

PTC_ISA_CLONES
void AccObjective::sums_and_area(const Summary& a, const Summary& b, const MergeContext& ctx, Evaluation& ev,
                                 bool allow_area_bound, const LargePair* large) {
  const ClusterTables& tb = *tables_;
  ev.box = a.box;
  ev.box.extend(b.box);

  // N_avg (average_normal's rule), with the recomputation under strong cancellation.
  const std::uint32_t m = a.nonzero + b.nonzero;
  Vec3 ns = a.normal_sum + b.normal_sum;
  double len = ns.norm();  // |ns| <= m: no overflow, so the plain norm (average_normal's hypot agrees to rounding)
  // AreaP <= sum Area_i (|N_avg . n_i| <= 1; 1 + 1e-6 covers the rounding of both sums, about
  // k eps relative for k < 2^32 members), for any N_avg: where the cone identity could not
  // certify it, a key need not make N_avg in order or sum over the members.
  // With the union's second moment M = sum Area_i n_i n_i^T (a large A), also Cauchy-Schwarz:
  // sum Area_i |N.n_i| <= sqrt(W N^T M N), W = sum Area_i, for any N; N^T M N <= M's largest
  // eigenvalue <= its largest Gershgorin row sum when N_avg is not made. Each entry of M is
  // within k eps W of the true sum (|n_j n_k| <= 1), so N^T M N within 3 k eps W < 2e-6 W for
  // k < 2^32 members: the 4e-6 W added covers it, and the last factor the square root's and
  // W's rounding.
  // And with the horizon sums (horizon_area_bound), at N_avg or near it.
  const auto area_bound = [&](const Vec3* n, double delta) {
    const double w = a.area_sum + b.area_sum;
    ev.area_p = w * (1.0 + 1e-6);
    // (W >= 2^-900: the sums' absolute rounding where terms fall below the normal range,
    // 2^-1075 an operation, stays far below the relative margins; smaller, the total area only.)
    if (large && w >= 0x1p-900) {
      Moment M = large->a->moment;  // the union's: A's kept, B's kept or summed (only here)
      const Moment mb = large->b ? large->b->moment : moment_of(ctx.b_triangles);
      for (std::size_t k = 0; k < M.size(); ++k) M[k] += mb[k];
      const double q = n && delta == 0.0 ? M[0] * n->x() * n->x() + M[1] * n->y() * n->y() + M[2] * n->z() * n->z() +
                               2.0 * (M[3] * n->x() * n->y() + M[4] * n->x() * n->z() + M[5] * n->y() * n->z())
                         : std::max({M[0] + std::abs(M[3]) + std::abs(M[4]), M[1] + std::abs(M[3]) + std::abs(M[5]),
                                     M[2] + std::abs(M[4]) + std::abs(M[5])});
      // (Two square roots: W and N^T M N scale as a length^2 each, their product under- or
      // overflows at lengths beyond 1e+-77.)
      const double cs = std::sqrt(w) * std::sqrt(std::max(0.0, q + 4e-6 * w)) * (1.0 + 1e-6);
      if (cs < ev.area_p) ev.area_p = cs;  // (a NaN keeps the total area's bound)
      if (n) {
        const double h = horizon_area_bound(*large, b, ctx, *n, delta, w);
        if (h < ev.area_p) ev.area_p = h;
      }
    }
    ev.area_bounded = true;
  };
  if (allow_area_bound && m > 0 && len < kRecomputeNormalSum * static_cast<double>(m)) {
    // The recomputed sum (members in ascending order) and this one are within m^2 eps of the
    // exact sum each (|n_i| <= 1 per coordinate), so within e = 4 m^2 eps of each other, and
    // their directions within 2 e / (len - e). Beyond the fallback's threshold the recomputed
    // N_avg is that direction; nearer, the fallback rule might choose another: no N then.
    if (large) {
      const double md = m, e = 4.0 * md * md * 0x1p-53;
      if (len - e > kNormalSumZeroTol * md) {
        const Vec3 n = ns * (1.0 / len);
        return area_bound(&n, 2.0 * e / (len - e) + 1e-15);
      }
    }
    return area_bound(nullptr, 0.0);
  }
  bool sorted_ready = false;
  auto sort_members = [&] {
    if (sorted_ready) return;
    const auto& ma = ctx.a_triangles;
    const auto& mb = ctx.b_triangles;
    if (std::is_sorted(ma.begin(), ma.end()) && std::is_sorted(mb.begin(), mb.end())) {  // the contraction's lists
      scratch_ids_.resize(ma.size() + mb.size());
      std::merge(ma.begin(), ma.end(), mb.begin(), mb.end(), scratch_ids_.begin());
    } else {
      scratch_ids_.assign(ma.begin(), ma.end());
      scratch_ids_.insert(scratch_ids_.end(), mb.begin(), mb.end());
      std::sort(scratch_ids_.begin(), scratch_ids_.end());
    }
    sorted_ready = true;
  };
  bool recomputed = false;
  if (m > 0 && len < kRecomputeNormalSum * static_cast<double>(m)) {
    recomputed = true;
    sort_members();
    ns = Vec3::Zero();
    for_each_geometry(tb, scratch_ids_, [&](double, const Vec3& nt) {
      if (!nt.isZero(0.0)) ns += nt;
    });
    len = safe_norm(ns);  // the same sum and norm as average_normal
  }
  ev.normal_sum = ns;
  if (m > 0 && len > kNormalSumZeroTol * static_cast<double>(m)) {
    ev.n_avg = recomputed ? Vec3(ns / len) : Vec3(ns * (1.0 / len));  // recomputed: average_normal's exact bits
    ev.fallback = false;
  } else {  // rare: the fallback rule needs the members in ascending order
    sort_members();
    scratch_normals_.clear();
    scratch_areas_.clear();
    for (std::uint32_t t : scratch_ids_) {
      const TriangleGeometry g = tb.geometry_of(t);
      scratch_normals_.push_back(g.normal);
      scratch_areas_.push_back(g.area);
    }
    const NormalAverage na = average_normal(scratch_normals_, scratch_areas_);
    ev.n_avg = na.n;
    ev.fallback = na.fallback;
  }

  // AreaP: the identity when both cones certify it, the sum (or for a key its bound) otherwise.
  if (!ev.fallback && certified(a, ev.n_avg) && certified(b, ev.n_avg))
    ev.area_p = std::max(0.0, ev.n_avg.dot(a.area_normal_sum + b.area_normal_sum));
  else if (allow_area_bound)
    area_bound(&ev.n_avg, 0.0);
  else
    ev.area_p = area_p_of(a, ctx.a_triangles, ev.n_avg) + area_p_of(b, ctx.b_triangles, ev.n_avg);
}

PTC_ISA_CLONES
void AccObjective::union_sphere_and_score(const Summary& a, const Summary* b_ptr, const MergeContext& ctx,
                                          Precision precision, bool memo, Evaluation& ev, const LargePair* large) {
  const ClusterTables& tb = *tables_;
  // The sphere of the union.
  bool have = false;
  PointFilter filter;
  bool use_filter = false;
  const Sphere sa = sphere_of(a);
  if (ctx.added.empty()) {  // same vertex set as A
    ev.sphere = sa;
    have = true;
  } else if (minimal_) {
    double rb = 0;
    if (ctx.added.size() == 1) {  // A u B = A u {v}: the point sphere (v, 0) stands for B
      filter.cb = tb.positions[ctx.added[0]];
      have = surely_inside(sa, filter.cb);
      if (!have && memo)
        if (const Sphere* known = memo_find(ctx.added[0])) {
          ev.sphere = *known;
          have = true;
        }
      if (have && ev.sphere.is_empty()) ev.sphere = sa;
    } else {
      const Sphere& sb = sphere_of(*b_ptr);
      filter.cb = sb.center;
      rb = sb.radius;
      if (surely_contains(sa, sb)) {
        ev.sphere = sa;
        have = true;
      } else if (surely_contains(sb, sa)) {
        ev.sphere = sb;
        have = true;
      } else if (std::all_of(ctx.added.begin(), ctx.added.end(),
                             [&](std::uint32_t v) { return surely_inside(sa, tb.positions[v]); })) {
        ev.sphere = sa;
        have = true;
      }
    }
    if (!have) {
      // Bounds on the radius of S(A u B) from the two minimal spheres (see the header), as R^2.
      filter.ca = sa.center;
      const double ra = sa.radius;
      filter.ra = ra;
      filter.rb = rb;
      const double d2 = (filter.cb - filter.ca).squaredNorm();
      double r2;
      if (rb == 0.0) {  // a point: R >= (d^2 + r_A^2) / (2 d) when d > r_A
        r2 = point_r2_bound(d2, ra);
      } else if (d2 > 0.0) {
        const double d = std::sqrt(d2);
        const double x = std::clamp((d2 + rb * rb - ra * ra) / (2.0 * d), 0.0, d);
        r2 = std::max(ra * ra + x * x, rb * rb + (d - x) * (d - x));
      } else {
        r2 = std::max(ra * ra, rb * rb);
      }
      // Also R >= half the largest width of the union's box / 26-DOP (two of its points are at
      // least that far apart; the unnormalised directions have lengths sqrt(3) and sqrt(2)).
      double half_width = 0.5 * ev.box.extent().maxCoeff();
      if (tuning_.dop_bound) {
        auto width = [&](int k) {  // the stored widths are at most the true ones (acc.h)
          return double{std::max(a.dop_hi[k], b_ptr->dop_hi[k])} - double{std::min(a.dop_lo[k], b_ptr->dop_lo[k])};
        };
        for (int k = 0; k < 4; ++k) half_width = std::max(half_width, width(k) * (0.5 / std::numbers::sqrt3));
        for (int k = 4; k < 10; ++k) half_width = std::max(half_width, width(k) * (0.5 / std::numbers::sqrt2));
      }
      r2 = std::max(r2, half_width * half_width);
      // RefinedBound, one added vertex v: R >= |v - p| / 2 for every p of A (both are in the
      // union). For a round cluster the point opposite v makes this nearly (r_A + |v - c_A|) / 2,
      // the upper limit of R, so the bound becomes almost tight.
      if (precision == Precision::RefinedBound && ctx.added.size() == 1) {
        double far2 = 0;
        for (std::uint32_t u : ctx.a_vertices) far2 = std::max(far2, (tb.positions[u] - filter.cb).squaredNorm());
        r2 = std::max(r2, 0.25 * far2);
      }
      // TightBound, one added vertex v: the minimal sphere of at most three points of the union
      // (v, the point p of A farthest from v, then the point farthest from their sphere) is a
      // lower bound -- and the exact sphere when it already contains every point, which is the
      // common case (see small_support_sphere).
      if (precision == Precision::TightBound && ctx.added.size() == 1) {
        Sphere small;  // with SphereMethod::Exact the closed form serves as a bound only
        if (small_support_sphere(ctx, ev.box, small) && params_.sphere == SphereMethod::Cgal) {
          ev.sphere = small;
          have = true;
        } else {
          r2 = std::max(r2, small.radius * small.radius);
        }
      }
      if (have) {
        remember(ctx, ev.sphere);
        ev.exact = true;
        ev.score = score_of(ev.area_p, ev.sphere.radius * ev.sphere.radius, ctx.vertex_count, &ev.reg);
        return;
      }
      if (memo) {  // a lower bound learnt for A' u {v}, A' a subset of A, holds for A u {v}
        r2 = std::max(r2, known_r2(ctx.added[0]));
        learn_r2(ctx.added[0], r2);
      }
      const double slack = center_slack(filter.ca, filter.cb);
      const double shrink = bound_shrink(slack, ra);
      const double r2_lb = r2 * shrink * shrink;
      // The key's R^2: r2_lb when the shrink leaves a bound, and SupportBound's three points (a
      // bound of its own, made from the points, not from the spheres). r2_lb alone still sets
      // the filter of the exact computation below, as for Precision::Exact.
      double key_r2 = shrink > 0.0 ? r2_lb : 0.0;
      if (precision == Precision::SupportBound) {
        // Less the centers' absolute rounding, as r2_lb: far from the origin the exact
        // computation's radius (S(A) reused when the added points are surely inside it, centers
        // in global coordinates) may lie that much below the points' minimal sphere (a review
        // found 9.5e-9 relative at an offset of 3e7 with the kept points' tight sphere).
        const double sr = std::sqrt(large ? large_support_r2(*large, ctx, ev.box) : support_r2(ctx, ev.box)) - slack;
        if (sr > 0.0) key_r2 = std::max(key_r2, sr * sr);
      }
      if (key_r2 > 0.0 && precision != Precision::Exact) {
        ev.exact = false;
        ev.score = score_of(ev.area_p, key_r2, ctx.vertex_count, nullptr);
        return;
      }
      // Points that are surely inside S(A u B) cannot support it: leave them out of the exact
      // computation (same sphere, fewer points). The center c of S(A u B) satisfies
      // |c - c_A| <= sqrt(R_ub^2 - r_A^2) (from R^2 >= r_A^2 + |c - c_A|^2 and R <= R_ub), so a
      // point p of A with |p - c_A| + that < R_lb is strictly inside; the same for B.
      const double r_lb = std::sqrt(std::max(0.0, r2_lb));
      const double r_ub = 0.5 * (std::sqrt(d2) + ra + rb) * (1.0 + 1e-12) + slack;
      filter.da = std::sqrt(std::max(0.0, r_ub * r_ub - ra * ra));
      filter.db = std::sqrt(std::max(0.0, r_ub * r_ub - rb * rb));
      filter.keep_from = r_lb * (1.0 - 1e-9) - slack;
      use_filter = shrink > 0.0 && filter.keep_from > 0.0;
    }
  }
  if (!have) {
    ev.sphere = sphere_of_union(ctx, ev.box, use_filter ? &filter : nullptr);
    remember(ctx, ev.sphere);
  }
  ev.exact = true;
  ev.score = score_of(ev.area_p, ev.sphere.radius * ev.sphere.radius, ctx.vertex_count, &ev.reg);
}

PTC_ISA_CLONES
void AccObjective::growth_prepare(const Summary& a, std::span<const GrowthQuery> queries, GrowthPrepared* out) {
  // evaluate()'s path for ctx.added = {v} at Precision::UpperBoundAllowed, up to the memo.
  const ClusterTables& tb = *tables_;
  enter_lineage(a);
  const Sphere sa = sphere_of(a);
  const double ra = sa.radius;
  const double sa_center_abs = max_abs(sa.center);
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const GrowthQuery& q = queries[i];
    GrowthPrepared& p = out[i];
    p.general = true;
    const Vec3& n = tb.normal[q.t];
    const bool b_nonzero = !n.isZero(0.0);
    const std::uint32_t m = a.nonzero + (b_nonzero ? 1u : 0u);
    const Vec3 ns = a.normal_sum + (b_nonzero ? n : Vec3(Vec3::Zero()));
    const double len = ns.norm();
    if (!(m > 0 && len > kNormalSumZeroTol * static_cast<double>(m))) continue;  // the fallback rule
    if (len < kRecomputeNormalSum * static_cast<double>(m)) continue;           // recomputed in order
    const Vec3 n_avg = ns * (1.0 / len);
    // certified(single(t), n_avg): no normal, or the cone of one normal (cos 1).
    if (!certified(a, n_avg) || (b_nonzero && !(n.dot(n_avg) >= kConeMargin))) continue;
    const Vec3 b_area_normal = b_nonzero ? Vec3(tb.area[q.t] * n) : Vec3(Vec3::Zero());
    p.area_p = std::max(0.0, n_avg.dot(a.area_normal_sum + b_area_normal));
    p.normal_sum = ns;
    p.n_avg = n_avg;
    const Vec3& cb = tb.positions[q.v];
    // surely_inside(sa, cb) and center_slack(sa.center, cb) with their common terms computed once
    const double slack = center_slack_by(sa_center_abs, cb);
    const double d2 = (cb - sa.center).squaredNorm();
    if (surely_inside_by(ra, slack, d2)) continue;
    const double r2 = point_r2_bound(d2, ra);
    Box3& box = p.box;
    box = a.box;
    box.extend(*q.triangle_box);
    const double half_width = 0.5 * box.extent().maxCoeff();
    p.r2 = std::max(r2, half_width * half_width);
    p.shrink = bound_shrink(slack, ra);
    p.general = false;
  }
}

PTC_ISA_CLONES
AccObjective::Evaluation AccObjective::growth_refine(const Summary& a, const GrowthPrepared& p,
                                                     const MergeContext& ctx, Precision precision) {
  // evaluate(a, single(t), ctx, precision) with what growth_prepare computed of it (the same
  // values: there is one code path from the sphere on, union_sphere_and_score).
  enter_lineage(a);
  Evaluation ev;
  ev.box = p.box;
  ev.normal_sum = p.normal_sum;
  ev.n_avg = p.n_avg;
  ev.fallback = false;
  ev.area_p = p.area_p;
  union_sphere_and_score(a, nullptr, ctx, precision, true, ev);  // B = single(t) is not read: one added vertex, no DOP
  return ev;
}

PTC_ISA_CLONES
bool AccObjective::growth_key(const GrowthPrepared& p, std::uint32_t v, std::uint32_t vertex_count, double& key) {
  if (p.general || memo_find(v)) return false;
  const double r2 = std::max(p.r2, known_r2(v));
  learn_r2(v, r2);
  const double r2_lb = r2 * p.shrink * p.shrink;
  if (!(p.shrink > 0.0 && r2_lb > 0.0)) return false;  // evaluate() computes it exactly (learn_r2 is idempotent)
  key = score_of(p.area_p, r2_lb, vertex_count, nullptr);
  return true;
}

PTC_ISA_CLONES
AccObjective::Summary AccObjective::merge(const Summary& a, const Summary& b, const MergeContext& ctx,
                                          const Evaluation& ev) {
  Summary s;
  s.serial = next_serial_++;
  if (memo_serial_ == a.serial) {  // carry the memo (and the lineage) over to A u B (see the header)
    std::erase_if(memo_, [&](const MemoEntry& e) {
      for (std::uint32_t v : ctx.added)
        if (v == e.vertex || !surely_inside(e.sphere, tables_->positions[v])) return true;
      return false;
    });
    memo_serial_ = s.serial;
  }
  s.normal_sum = ev.normal_sum;
  s.area_normal_sum = a.area_normal_sum + b.area_normal_sum;
  s.nonzero = a.nonzero + b.nonzero;
  s.area_sum = a.area_sum + b.area_sum;
  s.sphere = ev.sphere;
  s.box = ev.box;
  for (int k = 0; k < 10; ++k) {
    s.dop_lo[k] = std::min(a.dop_lo[k], b.dop_lo[k]);
    s.dop_hi[k] = std::max(a.dop_hi[k], b.dop_hi[k]);
  }
  if (a.nonzero == 0) {
    set_cone(s, b.cone_axis, b.cone_cos);
  } else if (b.nonzero == 0) {
    set_cone(s, a.cone_axis, a.cone_cos);
  } else {  // a cone around a's axis containing b's cone; widened a little against rounding
    set_cone(s, a.cone_axis, std::min(a.cone_cos, cos_of_sum(a.cone_axis.dot(b.cone_axis), b.cone_cos) - 1e-12));
  }
  if (s.nonzero > 0 && !certified(s, ev.n_avg)) {  // rebuild the cone around N_avg (O(k), exact dots)
    double c = 1.0;
    for (auto members : {ctx.a_triangles, ctx.b_triangles})
      for (std::uint32_t t : members) {
        const Vec3 nt = tables_->geometry_of(t).normal;
        if (!nt.isZero(0.0)) c = std::min(c, ev.n_avg.dot(nt));
      }
    set_cone(s, ev.n_avg, c - 1e-15);
  }
  if (tuning_.large_bounds && minimal_) keep_large(a, b, ctx, s, ev.n_avg);
  return s;
}

namespace {
[[gnu::always_inline]] inline void add_moment(std::array<double, 6>& m, double area, const Vec3& n) {  // (AccObjective::Moment)
  m[0] += area * n.x() * n.x();
  m[1] += area * n.y() * n.y();
  m[2] += area * n.z() * n.z();
  m[3] += area * n.x() * n.y();
  m[4] += area * n.x() * n.z();
  m[5] += area * n.y() * n.z();
}
}  // namespace

AccObjective::Moment AccObjective::moment_of(std::span<const std::uint32_t> members) const {
  Moment m{};
  for_each_geometry(*tables_, members, [&](double area, const Vec3& n) { add_moment(m, area, n); });
  return m;
}

void AccObjective::keep_large(const Summary& a, const Summary& b, const MergeContext& ctx, const Summary& s,
                              const Vec3& n_avg) {
  const std::size_t members = ctx.a_triangles.size() + ctx.b_triangles.size();
  const bool large = ctx.vertex_count >= kLargeFrom || members >= kLargeFrom;
  if (!large || ctx.a_vertices.empty()) {
    if (!large_.empty()) {
      large_.erase(a.serial);
      large_.erase(b.serial);
    }
    return;
  }
  const auto& pos = tables_->positions;
  const Large* la = large_of(a);
  // A large A and a small B whose merge leaves N_avg near A's reference: B's members are added
  // to A's sums around the same reference. Otherwise one pass over the union's members around
  // its own N_avg; and again once A has grown by a quarter. The points: one pass over the
  // union's vertices (cheaper than its members' geometry; points kept from A alone missed the
  // new support points often enough to double the exact evaluations).
  const bool incremental = la && !large_of(b) && (n_avg - la->n_ref).norm() <= 0x1p-10 &&
                           4 * members < 5 * la->full_members;
  Large l;
  auto add_members = [&](std::span<const std::uint32_t> ids) {
    for_each_geometry(*tables_, ids, [&](double area, const Vec3& n) {
      if (n.isZero(0.0)) return;
      add_moment(l.moment, area, n);
      const double c = l.n_ref.dot(n);
      l.g += c >= 0.0 ? Vec3(area * n) : Vec3(-area * n);
      const double ac = std::abs(c);
      for (std::size_t k = 0; k < kHorizon.size(); ++k)
        if (ac <= kHorizon[k]) l.horizon[k] += area;
    });
  };
  // The four vertices farthest from S(A u B)'s center (its support points, where at most four
  // lie on it) and the box's extremes, among the candidates.
  const Vec3 c = s.sphere.center;
  std::array<double, 4> far2;
  far2.fill(-1.0);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  std::array<std::uint32_t, 10> pts;
  pts.fill(ctx.a_vertices[0]);
  auto visit = [&](std::uint32_t v) {
    const Vec3& p = pos[v];
    const double d2 = (p - c).squaredNorm();
    if (d2 > far2[3]) {
      std::size_t i = 3;
      for (; i > 0 && d2 > far2[i - 1]; --i) {
        far2[i] = far2[i - 1];
        pts[i] = pts[i - 1];
      }
      far2[i] = d2;
      pts[i] = v;
    }
    for (int k = 0; k < 3; ++k) {
      if (p[k] < lo[k]) lo[k] = p[k], pts[4 + k] = v;
      if (p[k] > hi[k]) hi[k] = p[k], pts[7 + k] = v;
    }
  };
  if (incremental) {
    l = *la;
    add_members(ctx.b_triangles);
  } else {
    l.n_ref = n_avg;
    l.full_members = members;
    add_members(ctx.a_triangles);
    add_members(ctx.b_triangles);
  }
  for (std::uint32_t v : ctx.a_vertices) visit(v);
  for (std::uint32_t v : ctx.added) visit(v);
  l.points = pts;
  large_.erase(a.serial);
  large_.erase(b.serial);
  large_.insert_or_assign(s.serial, l);
}

double AccObjective::horizon_area_bound(const LargePair& large, const Summary& b, const MergeContext& ctx,
                                        const Vec3& n, double delta, double w) const {
  // For a part with Large l, any unit N within delta of n: with s_i the sign of n_ref.n_i,
  //   sum Area_i |N.n_i| = N.g + 2 sum over the flipped members (s_i N.n_i < 0) of Area_i |N.n_i|,
  // and a flipped member has |N.n_i| <= |(N - n_ref).n_i| <= d and |n_ref.n_i| <= d, with
  // d = |n - n_ref| + delta: so the sum is at most n.g + delta |g| + 2 d horizon(d). (The 1e-12
  // added to d covers the rounding of the signs and of the horizon's classification.) A small B
  // is summed at n, plus delta times its area. The rounding of g, the horizon and the sums is
  // below 16 (k + 16) eps of the total area for k members.
  auto part = [&](const Large& l) {
    const double d = (n - l.n_ref).norm() + delta + 1e-12;
    double h = -1.0;
    for (std::size_t k = 0; k < kHorizon.size(); ++k)
      if (d <= kHorizon[k]) {
        h = l.horizon[k];
        break;
      }
    if (h < 0.0) return std::numeric_limits<double>::infinity();  // far from n_ref: no use
    return n.dot(l.g) + delta * l.g.norm() + 2.0 * d * h;
  };
  double sum = part(*large.a);
  if (large.b) {
    sum += part(*large.b);
  } else {
    double sb = 0;
    for_each_geometry(*tables_, ctx.b_triangles, [&](double area, const Vec3& nt) { sb += area * std::abs(n.dot(nt)); });
    sum += sb + delta * b.area_sum;
  }
  const double k = static_cast<double>(ctx.a_triangles.size() + ctx.b_triangles.size());
  return sum + 16.0 * (k + 16.0) * 0x1p-53 * w;
}

double AccObjective::large_support_r2(const LargePair& large, const MergeContext& ctx, const Box3& box) {
  // The minimal sphere of A's kept points and B's (a subset's is never larger than the union's):
  // three of them when that sphere holds them all, else CGAL's on all. min_sphere's radius is
  // minimal to ~1e-15 of the points' extent on local coordinates, and so is the exact
  // computation's: the 1e-12 shrink covers both, as in support_r2.
  const auto& pos = tables_->positions;
  const std::span<const std::uint32_t> bs = large.b ? std::span<const std::uint32_t>(large.b->points) : ctx.added;
  bool holds_all = false;
  const double r2 = three_point_r2(pos, {large.a->points, bs}, box, &holds_all);
  if (holds_all) return r2;
  const Vec3 o = local_origin(box);
  auto& pts = scratch_bound_points_;
  pts.clear();
  for (const auto list : {std::span<const std::uint32_t>(large.a->points), bs})
    for (std::uint32_t v : list) pts.push_back(pos[v] - o);
  const double r = min_sphere(pts).radius;
  constexpr double kShrink = 1.0 - 1e-12;
  const double cgal_r2 = r * r * (kShrink * kShrink);
  return std::isfinite(cgal_r2) ? cgal_r2 : 0.0;
}

}  // namespace ptc
