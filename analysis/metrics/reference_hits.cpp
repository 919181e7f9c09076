#include "analysis/metrics/reference_hits.h"

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "bvh/box.h"
#include "bvh/embree_peer.h"

namespace ptc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Triangles per slice: the nine corner arrays of a slice (9 x 8 x 256 = 18 KB) and its flags
// (2 KB) stay in a 32 KB L1 data cache while every ray of a block runs over them.
constexpr std::size_t kSlice = 256;
// Most rays per block: a block streams the whole triangle array from memory once (96 bytes a
// triangle: 80 MB at 832k), so 128 rays a block keep memory traffic at 1/128 of the L1 traffic
// of the slices (measured: 32 rays a block were 15% slower at 4096 rays).
constexpr std::size_t kMaxBlock = 128;

// The corners and plane normals in world coordinates, one array per coordinate.
struct TriangleSoA {
  std::vector<double> p[3][3];  // p[corner][axis]
  std::vector<double> n[3];     // (v1 - v0) x (v2 - v0)
  std::size_t size = 0;
};

TriangleSoA make_soa(std::span<const Tri> tris, std::span<const Vec3> pos) {
  TriangleSoA s;
  s.size = tris.size();
  for (auto& corner : s.p)
    for (auto& a : corner) a.resize(s.size);
  for (auto& a : s.n) a.resize(s.size);
  for (std::size_t t = 0; t < tris.size(); ++t) {
    for (int c = 0; c < 3; ++c)
      if (tris[t][c] >= pos.size()) throw std::invalid_argument("reference_hits: triangle corner out of range");
    const Vec3& v0 = pos[tris[t][0]];
    const Vec3& v1 = pos[tris[t][1]];
    const Vec3& v2 = pos[tris[t][2]];
    for (int a = 0; a < 3; ++a) s.p[0][a][t] = v0[a], s.p[1][a][t] = v1[a], s.p[2][a][t] = v2[a];
    Vec3 n = (v1 - v0).cross(v2 - v0);
    // A corner that is not finite (or a normal that overflows): a NaN normal makes every t NaN,
    // which no interval accepts, whatever its edge functions said.
    if (!(v0.allFinite() && v1.allFinite() && v2.allFinite() && n.allFinite()))
      n = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
    for (int a = 0; a < 3; ++a) s.n[a][t] = n[a];
  }
  return s;
}

// One ray's constants of the edge test: the corner arrays in the ray's axis order (kx, ky, kz)
// and the shear.
struct ShearedRay {
  const double* c[3][3];  // c[corner][0 = kx, 1 = ky, 2 = kz]
  double ox, oy, oz;      // origin in the same axis order
  double sx, sy;
};

// flag[j] = 1 when the ray's line crosses triangle `first + j` inside (inclusive edge rule),
// else 0, for j < count; returns whether any did. Branch-free so that the compiler vectorises
// it; the clones give AVX-512 or AVX2 where the CPU has it (the ifunc resolver asks cpuid once)
// and plain x86-64 (SSE2) otherwise, from this one text. (AVX-512 measured ~15% faster than AVX2
// here: the loop is bound by its mask handling as much as by its 30 flops per pair.)
__attribute__((target_clones("avx512f", "avx2", "default"))) int inside_flags(const ShearedRay& r, std::size_t first,
                                                                    std::size_t count, std::int64_t* __restrict flag) {
  const double* __restrict ax = r.c[0][0] + first;
  const double* __restrict ay = r.c[0][1] + first;
  const double* __restrict az = r.c[0][2] + first;
  const double* __restrict bx = r.c[1][0] + first;
  const double* __restrict by = r.c[1][1] + first;
  const double* __restrict bz = r.c[1][2] + first;
  const double* __restrict cx = r.c[2][0] + first;
  const double* __restrict cy = r.c[2][1] + first;
  const double* __restrict cz = r.c[2][2] + first;
  const double ox = r.ox, oy = r.oy, oz = r.oz, sx = r.sx, sy = r.sy;
  std::int64_t any = 0;
  for (std::size_t j = 0; j < count; ++j) {
    const double Az = az[j] - oz, Bz = bz[j] - oz, Cz = cz[j] - oz;
    const double Ax = (ax[j] - ox) - sx * Az, Ay = (ay[j] - oy) - sy * Az;
    const double Bx = (bx[j] - ox) - sx * Bz, By = (by[j] - oy) - sy * Bz;
    const double Cx = (cx[j] - ox) - sx * Cz, Cy = (cy[j] - oy) - sy * Cz;
    const double U = Cx * By - Cy * Bx;
    const double V = Ax * Cy - Ay * Cx;
    const double W = Bx * Ay - By * Ax;
    const bool neg = (U < 0.0) | (V < 0.0) | (W < 0.0);
    const bool pos = (U > 0.0) | (V > 0.0) | (W > 0.0);
    // Exactly one of the two: no mixed signs, not all zero (NaN corners give neither).
    const std::int64_t f = std::int64_t(neg != pos);
    flag[j] = f;
    any |= f;
  }
  return int(any != 0);
}

// One ray's running answer: the best (t, id) and the t of every hit within the tie window of the
// current best (pruned when the best moves closer; a ray hits few triangles at all).
struct RayState {
  double o[3] = {0, 0, 0}, d[3] = {0, 0, 0};
  double tmin = 0, tmax = 0;  // tmax = the largest finite double when unbounded: t must be finite
  bool live = false;          // origin finite, direction finite and not zero
  ShearedRay sheared{};
  double best = kInf;
  std::uint32_t id = bvh::kNoTriangle;
  std::vector<double> near;

  void offer(double t, std::uint32_t tri, double rel) {
    if (t < best) {  // ids arrive in ascending order: an equal t keeps the lower id
      best = t, id = tri;
      const double lim = t + rel * std::abs(t);
      std::erase_if(near, [lim](double x) { return x > lim; });
      near.push_back(t);
    } else if (t <= best + rel * std::abs(best)) {
      near.push_back(t);
    }
  }
};

void setup_ray(RayState& s, const bvh::RayBatch& rays, std::size_t i, const TriangleSoA& soa,
               const ReferenceConfig& cfg) {
  Vec3 o(rays.ox[i], rays.oy[i], rays.oz[i]);
  if (cfg.start == RayStart::AsTraced) {
    const bvh::Vec3f f = bvh::to_frame(o, {cfg.frame, cfg.frame_scale});
    o = cfg.frame + Vec3(double(f[0]), double(f[1]), double(f[2])) / cfg.frame_scale;  // (a power of two: exact)
  }
  const double d[3] = {double(rays.dx[i]), double(rays.dy[i]), double(rays.dz[i])};
  for (int a = 0; a < 3; ++a) s.o[a] = o[a], s.d[a] = d[a];
  s.tmin = double(rays.tmin[i]);
  s.tmax = std::min(double(rays.tmax[i]), std::numeric_limits<double>::max());
  const bool finite = std::isfinite(o.x()) && std::isfinite(o.y()) && std::isfinite(o.z()) && std::isfinite(d[0]) &&
                      std::isfinite(d[1]) && std::isfinite(d[2]);
  s.live = finite && (d[0] != 0.0 || d[1] != 0.0 || d[2] != 0.0) && !(s.tmin > s.tmax);
  if (!s.live) return;
  int kz = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(d[a]) > std::abs(d[kz])) kz = a;
  const int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
  const int axes[3] = {kx, ky, kz};
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) s.sheared.c[c][k] = soa.p[c][axes[k]].data();
  s.sheared.ox = s.o[kx], s.sheared.oy = s.o[ky], s.sheared.oz = s.o[kz];
  s.sheared.sx = d[kx] / d[kz], s.sheared.sy = d[ky] / d[kz];
}

// t of the plane of triangle j along the ray (NaN or +-inf when the ray is parallel to it or
// the triangle has no area, which the interval test rejects).
double plane_t(const RayState& s, const TriangleSoA& soa, std::size_t j) {
  double num = 0.0, den = 0.0;
  for (int a = 0; a < 3; ++a) {
    num += (soa.p[0][a][j] - s.o[a]) * soa.n[a][j];
    den += s.d[a] * soa.n[a][j];
  }
  return num / den;
}

}  // namespace

ReferenceHits reference_hits(std::span<const Tri> tris, std::span<const Vec3> positions_world,
                             const bvh::RayBatch& rays, std::span<const std::size_t> sample,
                             const ReferenceConfig& cfg) {
  if (!(cfg.tie_rel > 0.0)) throw std::invalid_argument("reference_hits: tie_rel must be > 0");
  for (const std::size_t i : sample)
    if (i >= rays.size()) throw std::invalid_argument("reference_hits: sample index out of range");
  if (tris.size() >= bvh::kUnknownTriangle)
    throw std::invalid_argument("reference_hits: too many triangles for 32-bit ids");
  const TriangleSoA soa = make_soa(tris, positions_world);
  ReferenceHits out;
  const std::size_t n = sample.size();
  out.triangle.assign(n, bvh::kNoTriangle);
  out.t.assign(n, 0.0);
  out.ties.assign(n, 0);
  if (n == 0) return out;

  // Blocks small enough that every worker gets about four (a sample of 256 rays on many cores
  // still runs in parallel), at most kMaxBlock rays.
  const std::size_t workers = std::size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
  const std::size_t block = std::clamp<std::size_t>((n + 4 * workers - 1) / (4 * workers), 1, kMaxBlock);
  const std::size_t blocks = (n + block - 1) / block;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<RayState> state(block);
    std::vector<std::int64_t> flag(kSlice);
    for (std::size_t b = range.begin(); b != range.end(); ++b) {
      const std::size_t first = b * block, count = std::min(block, n - first);
      for (std::size_t q = 0; q < count; ++q) {
        state[q] = RayState{};
        setup_ray(state[q], rays, sample[first + q], soa, cfg);
      }
      for (std::size_t s0 = 0; s0 < soa.size; s0 += kSlice) {
        const std::size_t m = std::min(kSlice, soa.size - s0);
        for (std::size_t q = 0; q < count; ++q) {
          RayState& s = state[q];
          if (!s.live || !inside_flags(s.sheared, s0, m, flag.data())) continue;
          for (std::size_t j = 0; j < m; ++j) {
            if (!flag[j]) continue;
            const double t = plane_t(s, soa, s0 + j);
            if (t > s.tmin && t <= s.tmax) s.offer(t, std::uint32_t(s0 + j), cfg.tie_rel);
          }
        }
      }
      for (std::size_t q = 0; q < count; ++q) {
        const RayState& s = state[q];
        if (s.id == bvh::kNoTriangle) continue;
        out.triangle[first + q] = s.id;
        out.t[first + q] = s.best;
        out.ties[first + q] = std::uint32_t(s.near.size());
      }
    }
  });
  return out;
}

HitErrors hit_errors(const ReferenceHits& ref, const bvh::HitBatch& got, std::span<const std::size_t> sample,
                     double tie_rel) {
  if (ref.size() != sample.size()) throw std::invalid_argument("hit_errors: reference and sample of different sizes");
  if (!(tie_rel >= 0.0)) throw std::invalid_argument("hit_errors: tie_rel must be >= 0");
  HitErrors e;
  std::vector<double> rel;
  for (std::size_t i = 0; i < sample.size(); ++i) {
    if (sample[i] >= got.size()) throw std::invalid_argument("hit_errors: sample index out of range of the hits");
    const std::uint32_t gt = got.triangle[sample[i]], rt = ref.triangle[i];
    if (gt == bvh::kUnknownTriangle) throw std::invalid_argument("hit_errors: an any-hit batch (no triangle ids)");
    const bool r = rt != bvh::kNoTriangle, g = gt != bvh::kNoTriangle;
    ++e.rays;
    e.ref_hits += r;
    e.ref_edge += r && ref.ties[i] > 1;
    if (r != g) {
      ++(r ? e.missed : e.spurious);
      continue;
    }
    if (!r) continue;
    const double tr = ref.t[i], tg = double(got.t[sample[i]]), diff = std::abs(tg - tr);
    if (gt == rt) {
      ++e.same_triangle;
      // t_ref > tmin >= 0 for every ray the tracers accept; a zero t_ref (tmin < 0) has no
      // relative error, only equality.
      rel.push_back(tr != 0.0 ? diff / std::abs(tr) : (diff == 0.0 ? 0.0 : kInf));
    } else if (diff <= tie_rel * std::abs(tr)) {
      ++e.ties;
    } else {
      ++e.other_triangle;
    }
  }
  e.t_rel = summarize(rel);
  return e;
}

std::vector<std::size_t> sample_rays(std::size_t n, std::size_t k, std::uint64_t seed) {
  std::vector<std::size_t> out;
  if (k >= n) {
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i) out[i] = i;
    return out;
  }
  std::uint64_t state = seed;
  auto next = [&state] {  // SplitMix64 (Steele, Lea & Flood 2014)
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  };
  // Uniform in [0, bound] without modulo bias: reject the top 2^64 mod (bound + 1) values.
  auto uniform = [&next](std::uint64_t bound) {
    const std::uint64_t range = bound + 1;
    if (range == 0) return next();  // bound = 2^64 - 1
    const std::uint64_t reject = (0 - range) % range;  // 2^64 mod range
    std::uint64_t x;
    do x = next();
    while (x < reject);
    return x % range;
  };
  // Floyd's algorithm (Bentley & Floyd, CACM 30(9), 1987): k draws, each index equally likely
  // in every position of the set, no rejection loop on collisions.
  std::unordered_set<std::size_t> chosen;
  chosen.reserve(k);
  out.reserve(k);
  for (std::size_t j = n - k; j < n; ++j) {
    const std::size_t r = std::size_t(uniform(j));
    const std::size_t pick = chosen.contains(r) ? j : r;  // j itself is never in the set yet
    chosen.insert(pick);
    out.push_back(pick);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace ptc
