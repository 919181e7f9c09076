#include "render/rays.h"
#include "toolkit/geometry/triangle.h"
#include "toolkit/core/stopwatch.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ptc {
namespace {

// f(begin, end) over [0, n) on `threads` workers (0 = all, 1 = the calling thread).
template <class F>
void parallel_ranges(std::size_t n, unsigned threads, F&& f) {
  if (threads == 1 || n < 4096) {
    f(std::size_t(0), n);
    return;
  }
  tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : static_cast<int>(threads));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); });
  });
}

bvh::Vec3f to_f(const Vec3& d) {
  return {static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z())};
}

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Secondary rays are made and traced in chunks of at most 2^20 rays (about 44 MiB of rays).
constexpr std::size_t kChunkRays = std::size_t(1) << 20;

// The one loop of the secondary passes: any-hit rays for the surface points `points`, `per_point`
// consecutive rays each, made and traced in chunks of at most kChunkRays rays (memory stays
// bounded for any points x samples). make(rays, first_slot, point) writes a point's rays (in
// parallel); take(hits, first_slot, point) reads its results back.
template <class Make, class Take>
void any_hit_pass(const TraceTarget& scene, const std::vector<std::uint32_t>& points, std::size_t per_point,
                  unsigned threads, PassStats& stats, Make&& make, Take&& take, bool packets = false) {
  bvh::TraceOptions opt;
  opt.mode = bvh::HitMode::Any;
  opt.threads = threads;
  opt.packets = packets;
  bvh::RayBatch rays;
  bvh::HitBatch hits;
  const std::size_t points_per_chunk = std::max<std::size_t>(1, kChunkRays / per_point);
  for (std::size_t first = 0; first < points.size(); first += points_per_chunk) {
    const std::size_t np = std::min(points_per_chunk, points.size() - first);
    rays.resize(np * per_point);
    parallel_ranges(np, threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t j = b; j < e; ++j) make(rays, j * per_point, points[first + j]);
    });
    hits.resize(rays.size());  // allocated (and first touched) outside the timed trace
    Stopwatch t0;
    const bvh::TraceTotals tt = scene.trace(rays, hits, opt);
    stats.add(tt, t0.ms());
    for (std::size_t j = 0; j < np; ++j) take(hits, j * per_point, points[first + j]);
  }
}

}  // namespace

namespace {
// The same target with `set` applied to the options of every call.
template <class Set>
TraceTarget with_options(TraceTarget target, Set set) {
  auto inner = std::move(target.trace);
  target.trace = [inner = std::move(inner), set](const bvh::RayBatch& r, bvh::HitBatch& h, const bvh::TraceOptions& o) {
    bvh::TraceOptions c = o;
    set(c);
    return inner(r, h, c);
  };
  return target;
}
}  // namespace

TraceTarget with_counters(TraceTarget target) {
  return with_options(std::move(target), [](bvh::TraceOptions& o) { o.counters = true; });
}

TraceTarget with_coherence(TraceTarget target, bool coherent) {
  return with_options(std::move(target), [coherent](bvh::TraceOptions& o) { o.coherent = coherent; });
}

TraceTarget with_isa(TraceTarget target, bvh::TraceIsa isa) {
  return with_options(std::move(target), [isa](bvh::TraceOptions& o) { o.isa = isa; });
}

void PassStats::add(const bvh::TraceTotals& t, double ms) {
  rays += t.rays, hits += t.hits, nodes_visited += t.nodes_visited, triangles_tested += t.triangles_tested;
  trace_ms += ms;
}

SurfaceHits surface_hits(const Mesh& mesh, const bvh::RayBatch& rays, const bvh::HitBatch& hits) {
  SurfaceHits s;
  const std::size_t n = hits.size();
  s.point.assign(n, Vec3::Zero());
  s.normal.assign(n, Vec3::Zero());
  s.hit.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t t = hits.triangle[i];
    if (t == bvh::kNoTriangle || t >= mesh.triangle_count()) continue;
    const auto c = mesh.corners(t);
    const double u = hits.u[i], v = hits.v[i];
    s.point[i] = (1.0 - u - v) * c[0] + u * c[1] + v * c[2];
    const Vec3 d(rays.dx[i], rays.dy[i], rays.dz[i]);
    Vec3 nrm = (c[1] - c[0]).cross(c[2] - c[0]);
    const double len = nrm.norm();
    nrm = len > 0 && std::isfinite(len) ? Vec3(nrm / len) : Vec3(-d.normalized());
    if (nrm.dot(d) > 0) nrm = -nrm;  // face the side the ray came from
    s.normal[i] = nrm;
    s.hit[i] = 1;
  }
  return s;
}

double RayFrame::offset_eps(const Vec3& p) const {
  double m = (p - origin).cwiseAbs().maxCoeff();
  if (!bounds.empty()) m = std::max({m, (bounds.lo - origin).cwiseAbs().maxCoeff(), (bounds.hi - origin).cwiseAbs().maxCoeff()});
  return kRayOffsetScale * std::max(m, 1e-300);
}

double RayFrame::diagonal() const { return bounds.empty() ? 0.0 : (bounds.hi - bounds.lo).norm(); }

TraceTarget target_of(const bvh::TraceData& data) {
  return {[&data](const bvh::RayBatch& rays, bvh::HitBatch& hits, const bvh::TraceOptions& opt) {
            return bvh::trace(data, rays, hits, opt);
          },
          data.origin};
}

ShadowResult trace_shadows(const bvh::TraceData& scene, const SurfaceHits& s, const Vec3& light, const RayFrame& frame,
                           unsigned threads) {
  return trace_shadows(target_of(scene), s, light, frame, threads);
}

AoResult trace_ao(const bvh::TraceData& scene, const SurfaceHits& s, const AoConfig& cfg, const RayFrame& frame,
                  unsigned threads) {
  return trace_ao(target_of(scene), s, cfg, frame, threads);
}

ShadowResult trace_shadows(const TraceTarget& scene, const SurfaceHits& s, const Vec3& light, const RayFrame& frame,
                           unsigned threads, bool packets, std::span<const std::uint32_t> order) {
  if (!order.empty() && order.size() != s.size())
    throw std::invalid_argument("trace_shadows: the order has " + std::to_string(order.size()) + " points, the surface " +
                                std::to_string(s.size()));
  ShadowResult r;
  r.lit.assign(s.size(), 0);
  // Points that face the light get a ray; the others stay unlit.
  std::vector<std::uint32_t> idx;
  for (std::size_t k = 0; k < s.size(); ++k) {
    const std::size_t i = order.empty() ? k : order[k];
    if (s.hit[i] && s.normal[i].dot(light - s.point[i]) > 0) idx.push_back(static_cast<std::uint32_t>(i));
  }
  any_hit_pass(
      scene, idx, 1, threads, r.stats,
      [&](bvh::RayBatch& rays, std::size_t slot, std::uint32_t i) {
        const Vec3 o = frame.offset_origin(s.point[i], s.normal[i]);
        const Vec3 l = light - o;
        double dist = l.norm();
        Vec3 dir = l / dist;
        // A light so far that the squares overflow (1e308): the same direction without them, and
        // a distance of inf where it is beyond double (the ray then has no end short of the light).
        if (!std::isfinite(dist)) dist = l.stableNorm(), dir = unit_vector(l);
        // The direction is unit, so t is a distance; stop just short of the light itself.
        rays.set(slot, o, to_f(dir), 0.0f, static_cast<float>(dist * (1.0 - 1.0 / 1048576.0)));
      },
      [&](const bvh::HitBatch& hits, std::size_t slot, std::uint32_t i) {
        r.lit[i] = hits.triangle[slot] == bvh::kNoTriangle;
      },
      packets);
  return r;
}

namespace {
// The 21 low bits of x, spread to every third bit.
std::uint64_t spread3(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}
}  // namespace

std::vector<std::uint32_t> morton_order(const SurfaceHits& s, const Box3& bounds) {
  const std::size_t n = s.size();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> key;
  key.reserve(n);
  const bool box = !bounds.empty() && bounds.lo.allFinite() && bounds.hi.allFinite();
  const Vec3 lo = box ? bounds.lo : Vec3::Zero();
  const Vec3 ext = box ? Vec3(bounds.hi - bounds.lo) : Vec3::Ones();
  constexpr double kCells = 2097151.0;  // 2^21 - 1
  for (std::size_t i = 0; i < n; ++i) {
    if (!s.hit[i]) continue;  // (the misses follow the hits, in index order)
    std::uint64_t code = 0;
    for (int a = 0; a < 3; ++a) {
      // (a flat box side: every point in cell 0; a point outside the box: the nearest cell)
      const double f = ext[a] > 0 ? (s.point[i][a] - lo[a]) / ext[a] * kCells : 0.0;
      const double c = f > 0 ? (f < kCells ? f : kCells) : 0.0;  // (NaN: 0)
      code |= spread3(static_cast<std::uint64_t>(c)) << a;
    }
    key.push_back({code, static_cast<std::uint32_t>(i)});
  }
  // LSD radix sort on the 63-bit codes, 11 bits a pass (stable: ties keep index order). A
  // comparison sort of all pixels took 100 ms a frame at 1024 x 1024.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> tmp(key.size());
  for (int shift = 0; shift < 63; shift += 11) {
    std::size_t count[2049] = {};
    for (const auto& k : key) ++count[((k.first >> shift) & 2047) + 1];
    for (int d = 0; d < 2048; ++d) count[d + 1] += count[d];
    for (const auto& k : key) tmp[count[(k.first >> shift) & 2047]++] = k;
    key.swap(tmp);
  }
  std::vector<std::uint32_t> order;
  order.reserve(n);
  for (const auto& k : key) order.push_back(k.second);
  for (std::size_t i = 0; i < n; ++i)
    if (!s.hit[i]) order.push_back(static_cast<std::uint32_t>(i));
  return order;
}

std::pair<double, double> ao_uniforms(std::uint64_t seed, std::uint64_t i, std::uint64_t k) {
  const std::uint64_t h = splitmix64(splitmix64(splitmix64(seed) ^ i) ^ (k * 0x632be59bd9b4e019ull));
  const std::uint64_t h2 = splitmix64(h);
  return {double(h >> 11) * 0x1.0p-53, double(h2 >> 11) * 0x1.0p-53};
}

Vec3 cosine_hemisphere(const Vec3& n, double u1, double u2) {
  // Orthonormal basis (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 2017).
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double b = n.x() * n.y() * a;
  const Vec3 t1(1.0 + sign * n.x() * n.x() * a, sign * b, -sign * n.x());
  const Vec3 t2(b, sign + n.y() * n.y() * a, -n.y());
  const double r = std::sqrt(u1), phi = 2.0 * M_PI * u2;
  const double z = std::max(std::sqrt(std::max(0.0, 1.0 - u1)), 1.0 / 4096.0);
  return (r * std::cos(phi) * t1 + r * std::sin(phi) * t2 + z * n).normalized();
}

AoResult trace_ao(const TraceTarget& scene, const SurfaceHits& s, const AoConfig& cfg, const RayFrame& frame,
                  unsigned threads) {
  if (cfg.samples < 1) throw std::invalid_argument("trace_ao: samples must be >= 1");
  if (!(cfg.max_distance_rel > 0.0) || !std::isfinite(cfg.max_distance_rel))
    throw std::invalid_argument("trace_ao: max_distance_rel must be positive");
  AoResult r;
  r.ao.assign(s.size(), 0.0f);
  std::vector<std::uint32_t> idx;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.hit[i]) idx.push_back(static_cast<std::uint32_t>(i));
  const auto spp = static_cast<std::size_t>(cfg.samples);
  const double dmax = cfg.max_distance_rel * frame.diagonal();
  const float tmax = static_cast<float>(dmax);
  any_hit_pass(
      scene, idx, spp, threads, r.stats,
      [&](bvh::RayBatch& rays, std::size_t slot, std::uint32_t i) {
        const Vec3 o = frame.offset_origin(s.point[i], s.normal[i]);
        for (std::size_t k = 0; k < spp; ++k) {
          const auto [u1, u2] = ao_uniforms(cfg.seed, i, k);
          rays.set(slot + k, o, to_f(cosine_hemisphere(s.normal[i], u1, u2)), 0.0f, tmax);
        }
      },
      [&](const bvh::HitBatch& hits, std::size_t slot, std::uint32_t i) {
        std::size_t open = 0;
        for (std::size_t k = 0; k < spp; ++k) open += hits.triangle[slot + k] == bvh::kNoTriangle;
        r.ao[i] = static_cast<float>(double(open) / double(spp));
      });
  return r;
}

}  // namespace ptc
