#include "bvh/tracer.h"

#include <emmintrin.h>  // SSE2: the x86-64 baseline

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <vector>

#include "bvh/watertight.h"

namespace ptc::bvh {

void RayBatch::resize(std::size_t n) {
  ox.resize(n), oy.resize(n), oz.resize(n);
  dx.resize(n), dy.resize(n), dz.resize(n);
  tmin.resize(n, 0.0f), tmax.resize(n, std::numeric_limits<float>::infinity());
}

void HitBatch::resize(std::size_t n) {
  t.resize(n), u.resize(n), v.resize(n), triangle.resize(n);
  nodes_visited.resize(n), triangles_tested.resize(n);
}

namespace {

constexpr float kBig = std::numeric_limits<float>::max();
// Conservative slab test: 2^-21 > 2 gamma_3 = 6u / (1 - 3u), u = 2^-24 (see tracer.h).
constexpr float kNearScale = 1.0f - 1.0f / 2097152.0f;
constexpr float kFarScale = 1.0f + 1.0f / 2097152.0f;

struct StackEntry {
  std::uint32_t ref;    // inner: node index; leaf: first range
  std::uint32_t count;  // 0: inner; > 0: number of ranges
  float t;              // entry distance of the box (conservative)
};

// Everything a ray needs during traversal, precomputed once.
struct RayState {
  // slab test
  __m128 ox, oy, oz, inx, iny, inz, ifx, ify, ifz;
  int nx, ny, nz, fx, fy, fz;  // float offsets of the near/far rows in WideNode::bounds
  // watertight test: made when the ray reaches its first leaf (most primary rays never do)
  bool watertight_ready;
  int kx4, ky4, kz4;  // 4 * permuted axes (offsets inside a corner's 3x4 block)
  __m128 okx, oky, okz, sx, sy, sz;
  float tmin, tmax;  // tmax: the best hit so far (closest) or the ray's end
  Vec3f org, dir;
};

void prepare_watertight(RayState& r) {
  const WatertightRay w = make_watertight_ray(r.org, r.dir);
  r.kx4 = 4 * w.kx, r.ky4 = 4 * w.ky, r.kz4 = 4 * w.kz;
  r.okx = _mm_set1_ps(r.org[w.kx]), r.oky = _mm_set1_ps(r.org[w.ky]), r.okz = _mm_set1_ps(r.org[w.kz]);
  r.sx = _mm_set1_ps(w.sx), r.sy = _mm_set1_ps(w.sy), r.sz = _mm_set1_ps(w.sz);
  r.watertight_ready = true;
}

struct Result {
  float t = 0, u = 0, v = 0;
  std::uint32_t tri = kNoTriangle;
  std::uint32_t nodes = 0, tris = 0;
};

// Returns false for a ray that cannot hit (zero or non-finite direction, empty interval).
bool setup(RayState& r, const Vec3f& o, const Vec3f& d, float tmin, float tmax) {
  if (!(std::isfinite(d[0]) && std::isfinite(d[1]) && std::isfinite(d[2]))) return false;
  if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) return false;
  if (!(std::isfinite(o[0]) && std::isfinite(o[1]) && std::isfinite(o[2]))) return false;
  r.tmin = tmin;
  r.tmax = tmax < kBig ? tmax : kBig;
  if (!(r.tmin < r.tmax) || !(tmin >= 0.0f)) return false;
  float inv[3];
  int near[3];
  for (int a = 0; a < 3; ++a) {
    inv[a] = 1.0f / d[a];  // +-inf for a zero component (its sign follows the zero's sign)
    near[a] = 2 * a + (std::signbit(inv[a]) ? 1 : 0);
  }
  r.ox = _mm_set1_ps(o[0]), r.oy = _mm_set1_ps(o[1]), r.oz = _mm_set1_ps(o[2]);
  r.inx = _mm_set1_ps(inv[0] * kNearScale), r.iny = _mm_set1_ps(inv[1] * kNearScale), r.inz = _mm_set1_ps(inv[2] * kNearScale);
  r.ifx = _mm_set1_ps(inv[0] * kFarScale), r.ify = _mm_set1_ps(inv[1] * kFarScale), r.ifz = _mm_set1_ps(inv[2] * kFarScale);
  r.nx = 4 * near[0], r.ny = 4 * near[1], r.nz = 4 * near[2];
  r.fx = 4 * (near[0] ^ 1), r.fy = 4 * (near[1] ^ 1), r.fz = 4 * (near[2] ^ 1);
  r.org = o, r.dir = d;
  r.watertight_ready = false;
  return true;
}

inline int ctz(unsigned m) { return __builtin_ctz(m); }

// Four triangles of one block against the ray; updates `res` and `tmax` (closest: the
// smallest (t, id); any: the first hit). Returns true when a hit was recorded. The float
// operations and their order are those of intersect_triangle (watertight.cpp).
template <bool AnyHit>
inline bool intersect_block(const TriBlock& blk, const std::uint32_t* ids, const RayState& r, float& tmax,
                            Result& res) {
  const float* v = &blk.v[0][0][0];
  const __m128 a_x = _mm_sub_ps(_mm_load_ps(v + r.kx4), r.okx);
  const __m128 a_y = _mm_sub_ps(_mm_load_ps(v + r.ky4), r.oky);
  const __m128 a_z = _mm_sub_ps(_mm_load_ps(v + r.kz4), r.okz);
  const __m128 b_x = _mm_sub_ps(_mm_load_ps(v + 12 + r.kx4), r.okx);
  const __m128 b_y = _mm_sub_ps(_mm_load_ps(v + 12 + r.ky4), r.oky);
  const __m128 b_z = _mm_sub_ps(_mm_load_ps(v + 12 + r.kz4), r.okz);
  const __m128 c_x = _mm_sub_ps(_mm_load_ps(v + 24 + r.kx4), r.okx);
  const __m128 c_y = _mm_sub_ps(_mm_load_ps(v + 24 + r.ky4), r.oky);
  const __m128 c_z = _mm_sub_ps(_mm_load_ps(v + 24 + r.kz4), r.okz);
  const __m128 ax = _mm_sub_ps(a_x, _mm_mul_ps(r.sx, a_z)), ay = _mm_sub_ps(a_y, _mm_mul_ps(r.sy, a_z));
  const __m128 bx = _mm_sub_ps(b_x, _mm_mul_ps(r.sx, b_z)), by = _mm_sub_ps(b_y, _mm_mul_ps(r.sy, b_z));
  const __m128 cx = _mm_sub_ps(c_x, _mm_mul_ps(r.sx, c_z)), cy = _mm_sub_ps(c_y, _mm_mul_ps(r.sy, c_z));
  __m128 U = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
  __m128 V = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
  __m128 W = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
  const __m128 zero = _mm_setzero_ps();
  const int on_edge = _mm_movemask_ps(
      _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, zero), _mm_cmpeq_ps(V, zero)), _mm_cmpeq_ps(W, zero)));
  if (on_edge) [[unlikely]] {  // exact signs in double for the lanes with a zero edge function
    alignas(16) float fax[4], fay[4], fbx[4], fby[4], fcx[4], fcy[4], fu[4], fv[4], fw[4];
    _mm_store_ps(fax, ax), _mm_store_ps(fay, ay), _mm_store_ps(fbx, bx), _mm_store_ps(fby, by);
    _mm_store_ps(fcx, cx), _mm_store_ps(fcy, cy), _mm_store_ps(fu, U), _mm_store_ps(fv, V), _mm_store_ps(fw, W);
    for (int l = 0; l < 4; ++l)
      if (on_edge & (1 << l)) edge_functions_double(fax[l], fay[l], fbx[l], fby[l], fcx[l], fcy[l], fu[l], fv[l], fw[l]);
    U = _mm_load_ps(fu), V = _mm_load_ps(fv), W = _mm_load_ps(fw);
  }
  const __m128 neg = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(U, zero), _mm_cmplt_ps(V, zero)), _mm_cmplt_ps(W, zero));
  const __m128 pos = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(U, zero), _mm_cmpgt_ps(V, zero)), _mm_cmpgt_ps(W, zero));
  const __m128 det = _mm_add_ps(_mm_add_ps(U, V), W);
  const __m128 det_ok = _mm_or_ps(_mm_cmplt_ps(det, zero), _mm_cmpgt_ps(det, zero));  // false for NaN lanes
  const __m128 valid = _mm_andnot_ps(_mm_and_ps(neg, pos), det_ok);
  if (!_mm_movemask_ps(valid)) return false;
  const __m128 az = _mm_mul_ps(r.sz, a_z), bz = _mm_mul_ps(r.sz, b_z), cz = _mm_mul_ps(r.sz, c_z);
  const __m128 T = _mm_add_ps(_mm_add_ps(_mm_mul_ps(U, az), _mm_mul_ps(V, bz)), _mm_mul_ps(W, cz));
  const __m128 t = _mm_div_ps(T, det);
  const __m128 in_range = _mm_and_ps(_mm_cmpgt_ps(t, _mm_set1_ps(r.tmin)), _mm_cmple_ps(t, _mm_set1_ps(tmax)));
  int m = _mm_movemask_ps(_mm_and_ps(valid, in_range));
  if (!m) return false;
  alignas(16) float ft[4], fv[4], fw[4], fd[4];
  _mm_store_ps(ft, t), _mm_store_ps(fv, V), _mm_store_ps(fw, W), _mm_store_ps(fd, det);
  bool found = false;
  for (; m; m &= m - 1) {
    const int l = ctz(static_cast<unsigned>(m));
    const std::uint32_t id = ids[l];
    if constexpr (!AnyHit) {
      if (!(ft[l] < tmax || (ft[l] == tmax && id < res.tri))) continue;
    }
    res.t = ft[l];
    res.tri = id;
    res.u = fv[l] / fd[l];
    res.v = fw[l] / fd[l];
    found = true;
    if constexpr (AnyHit) return true;
    tmax = ft[l];
  }
  return found;
}

struct Flat {  // raw views of TraceData for the hot loop
  const WideNode* nodes;
  const LeafRange* ranges;
  const TriBlock* blocks;
  const std::uint32_t* ids;
  std::uint32_t root;
  bool empty;
};

// Tests the triangles of one leaf child (direct: `count` triangles from block `ref`;
// indirect: the ranges ranges[ref .. ref + n)). Returns true for an any-hit query's hit.
template <bool AnyHit>
inline bool intersect_leaf(const Flat& d, std::uint32_t ref, std::uint32_t count, RayState& r, float& tmax,
                           Result& res, std::uint32_t& tris) {
  if (!r.watertight_ready) [[unlikely]] prepare_watertight(r);
  LeafRange one{ref, (count + 3) / 4, count};
  const LeafRange* ranges = &one;
  std::uint32_t nr = 1;
  if (count & kIndirectLeaf) ranges = d.ranges + ref, nr = count & ~kIndirectLeaf;
  for (std::uint32_t i = 0; i < nr; ++i) {
    const LeafRange lr = ranges[i];
    tris += lr.triangle_count;
    const std::uint32_t end = lr.first_block + lr.block_count;
    for (std::uint32_t bk = lr.first_block; bk < end; ++bk)
      if (intersect_block<AnyHit>(d.blocks[bk], d.ids + 4 * std::size_t(bk), r, tmax, res) && AnyHit) return true;
  }
  return false;
}

template <bool AnyHit>
void traverse(const Flat& d, const RayState& ray, Result& res, StackEntry* stack) {
  if (d.empty) return;
  RayState r = ray;  // a local copy: no aliasing with the stack and result stores
  float tmax = r.tmax;
  __m128 tmax4 = _mm_set1_ps(tmax);
  const __m128 tmin4 = _mm_set1_ps(r.tmin);
  StackEntry* sp = stack;
  *sp++ = {d.root, 0, -kBig};
  std::uint32_t nodes = 0, tris = 0;
  while (sp != stack) {
    const StackEntry e = *--sp;
    if (!AnyHit && e.t > tmax) continue;  // a closer hit was found after this entry was pushed
    std::uint32_t ref = e.ref, cnt = e.count;
    bool miss = false;
    while (cnt == 0) {
      const WideNode& n = d.nodes[ref];
      ++nodes;
      const float* b = &n.bounds[0][0];
      const __m128 tnx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + r.nx), r.ox), r.inx);
      const __m128 tny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + r.ny), r.oy), r.iny);
      const __m128 tnz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + r.nz), r.oz), r.inz);
      const __m128 tfx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + r.fx), r.ox), r.ifx);
      const __m128 tfy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + r.fy), r.oy), r.ify);
      const __m128 tfz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(b + r.fz), r.oz), r.ifz);
      // _mm_max_ps(a, b) returns b when either is NaN: candidates first, running bound second.
      const __m128 tn = _mm_max_ps(tnz, _mm_max_ps(tny, _mm_max_ps(tnx, tmin4)));
      const __m128 tf = _mm_min_ps(tfz, _mm_min_ps(tfy, _mm_min_ps(tfx, tmax4)));
      unsigned mask = static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(tn, tf)));
      if (!mask) {
        miss = true;
        break;
      }
      alignas(16) float dist[4];
      _mm_store_ps(dist, tn);
      const int i0 = ctz(mask);
      mask &= mask - 1;
      if (!mask) {
        ref = n.child[i0], cnt = n.count[i0];
        continue;
      }
      const int i1 = ctz(mask);
      mask &= mask - 1;
      if (!mask) {
        const bool first_near = dist[i0] <= dist[i1];
        const int nearer = first_near ? i0 : i1, farther = first_near ? i1 : i0;
        *sp++ = {n.child[farther], n.count[farther], dist[farther]};
        ref = n.child[nearer], cnt = n.count[nearer];
        continue;
      }
      // Three or four children: sort by entry distance, farthest pushed first.
      StackEntry c[4];
      int k = 0;
      c[k++] = {n.child[i0], n.count[i0], dist[i0]};
      c[k++] = {n.child[i1], n.count[i1], dist[i1]};
      for (; mask; mask &= mask - 1) {
        const int i = ctz(mask);
        c[k++] = {n.child[i], n.count[i], dist[i]};
      }
      if constexpr (!AnyHit) {
        for (int i = 1; i < k; ++i)  // insertion sort, descending distance
          for (int j = i; j > 0 && c[j - 1].t < c[j].t; --j) std::swap(c[j - 1], c[j]);
      }
      for (int i = 0; i < k - 1; ++i) *sp++ = c[i];
      ref = c[k - 1].ref, cnt = c[k - 1].count;
    }
    if (miss) continue;
    const float before = tmax;
    if (intersect_leaf<AnyHit>(d, ref, cnt, r, tmax, res, tris)) break;  // any hit: done
    if (tmax != before) tmax4 = _mm_set1_ps(tmax);
  }
  res.nodes = nodes, res.tris = tris;
}

Flat flat_of(const TraceData& s) {
  return {s.wide.nodes.data(), s.ranges.data(), s.blocks.data(), s.triangle_ids.data(), s.wide.root,
          s.wide.nodes.empty()};
}

std::size_t stack_size(const TraceData& s) { return 3 * std::size_t(s.wide.depth) + 8; }

Result trace_single(const TraceData& s, const Flat& f, const Vec3& org, const Vec3f& dir, float tmin, float tmax,
                    HitMode mode, StackEntry* stack) {
  Result res;
  RayState r;
  if (!setup(r, to_frame(org, s.origin), dir, tmin, tmax)) return res;
  if (mode == HitMode::Closest)
    traverse<false>(f, r, res, stack);
  else
    traverse<true>(f, r, res, stack);
  if (res.tri == kNoTriangle) res.t = 0.0f;
  return res;
}

}  // namespace

TraceTotals trace(const TraceData& scene, const RayBatch& rays, HitBatch& hits, const TraceOptions& opt) {
  const std::size_t n = rays.size();
  hits.resize(n);
  if (!opt.counters) hits.nodes_visited.clear(), hits.triangles_tested.clear();
  const Flat f = flat_of(scene);
  const std::size_t ss = stack_size(scene);
  constexpr std::size_t kTile = 64;  // rays per task: 64 * 4 bytes = 4 cache lines per array
  const std::size_t tiles = (n + kTile - 1) / kTile;
  tbb::enumerable_thread_specific<TraceTotals> totals;
  tbb::enumerable_thread_specific<std::vector<StackEntry>> stacks([ss] { return std::vector<StackEntry>(ss); });
  auto body = [&](const tbb::blocked_range<std::size_t>& range) {
    TraceTotals& tot = totals.local();
    StackEntry* stack = stacks.local().data();
    for (std::size_t tile = range.begin(); tile != range.end(); ++tile) {
      const std::size_t end = std::min(n, (tile + 1) * kTile);
      for (std::size_t i = tile * kTile; i < end; ++i) {
        const Result res = trace_single(scene, f, Vec3(rays.ox[i], rays.oy[i], rays.oz[i]),
                                        {rays.dx[i], rays.dy[i], rays.dz[i]}, rays.tmin[i], rays.tmax[i], opt.mode, stack);
        hits.t[i] = res.t, hits.u[i] = res.u, hits.v[i] = res.v, hits.triangle[i] = res.tri;
        if (opt.counters) hits.nodes_visited[i] = res.nodes, hits.triangles_tested[i] = res.tris;
        tot.rays += 1;
        tot.hits += res.tri != kNoTriangle;
        tot.nodes_visited += res.nodes;
        tot.triangles_tested += res.tris;
      }
    }
  };
  if (opt.threads == 1) {
    body(tbb::blocked_range<std::size_t>(0, tiles));
  } else {
    tbb::task_arena arena(opt.threads == 0 ? tbb::task_arena::automatic : static_cast<int>(opt.threads));
    arena.execute([&] { tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles, 1), body); });
  }
  TraceTotals sum;
  for (const TraceTotals& t : totals) {
    sum.rays += t.rays, sum.hits += t.hits, sum.nodes_visited += t.nodes_visited;
    sum.triangles_tested += t.triangles_tested;
  }
  return sum;
}

Hit trace_ray(const TraceData& scene, const Vec3& org, const Vec3f& dir, HitMode mode, float tmin, float tmax) {
  std::vector<StackEntry> stack(stack_size(scene));
  const Result r = trace_single(scene, flat_of(scene), org, dir, tmin, tmax, mode, stack.data());
  return {r.t, r.u, r.v, r.tri, r.nodes, r.tris};
}

}  // namespace ptc::bvh
