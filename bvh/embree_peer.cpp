#include "bvh/embree_peer.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "bvh/scene_config.h"

namespace ptc::bvh {

const char* to_string(EmbreeMode m) {
  switch (m) {
    case EmbreeMode::StaticMedium: return "embree_static_medium";
    case EmbreeMode::DynamicLow: return "embree_dynamic_low";
    case EmbreeMode::DynamicRefit: return "embree_dynamic_refit";
  }
  return "?";
}

namespace {


void check(RTCDevice dev, const char* what) {
  const RTCError e = rtcGetDeviceError(dev);
  if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("Embree error ") + std::to_string(int(e)) + " in " + what);
}

}  // namespace

struct EmbreeScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  RTCGeometry geom = nullptr;
  float* vertices = nullptr;  // owned by the geometry (rtcSetNewGeometryBuffer)
  std::size_t vertex_count = 0;
  FrameMap frame;  // the trace frame of our scenes: origin and power-of-two scale (trace_frame_scale)
};

EmbreeScene::EmbreeScene(const Mesh& mesh, const Vec3& origin, const EmbreeConfig& cfg)
    : impl_(std::make_unique<Impl>()), clock_(cfg.clock) {
  Impl& im = *impl_;
  // Embree asserts (and aborts) on a ray whose origin or direction exceeds 1.8e18 and drops
  // triangles beyond it: it gets the positions in our scenes' scaled frame, and the rays' t
  // scaled with them (trace_packets).
  im.frame = FrameMap(origin, trace_frame_scale(mesh, origin));
  std::string conf = cfg.threads ? "threads=" + std::to_string(cfg.threads) : std::string();
  if (!cfg.isa.empty()) conf += (conf.empty() ? "isa=" : ",isa=") + cfg.isa;
  im.device = rtcNewDevice(conf.empty() ? nullptr : conf.c_str());
  if (!im.device) throw std::runtime_error("Embree: rtcNewDevice failed");
  im.scene = rtcNewScene(im.device);
  const bool dynamic = cfg.mode != EmbreeMode::StaticMedium;
  rtcSetSceneFlags(im.scene, dynamic ? RTC_SCENE_FLAG_DYNAMIC : RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(im.scene, dynamic ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_MEDIUM);
  im.geom = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (cfg.mode == EmbreeMode::DynamicRefit) rtcSetGeometryBuildQuality(im.geom, RTC_BUILD_QUALITY_REFIT);
  else if (cfg.mode == EmbreeMode::DynamicLow) rtcSetGeometryBuildQuality(im.geom, RTC_BUILD_QUALITY_LOW);
  im.vertex_count = mesh.vertex_count();
  // 3 floats per vertex; Embree reads 16 bytes per vertex, so the buffer ends with padding.
  im.vertices = static_cast<float*>(rtcSetNewGeometryBuffer(im.geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                            3 * sizeof(float), im.vertex_count + 1));
  auto* idx = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(im.geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangle_count()));
  check(im.device, "buffers");
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) idx[3 * t + k] = mesh.triangle(t)[k];
  rtcAttachGeometry(im.scene, im.geom);
  update(mesh.positions());
}

EmbreeScene::~EmbreeScene() {
  if (!impl_) return;
  if (impl_->geom) rtcReleaseGeometry(impl_->geom);
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

void EmbreeScene::update(std::span<const Vec3> positions) {
  Impl& im = *impl_;
  double t0 = clock_ms(clock_);
  const std::size_t n = std::min(positions.size(), im.vertex_count);
  for (std::size_t v = 0; v < n; ++v) {
    const Vec3f p = to_frame(positions[v], im.frame);
    im.vertices[3 * v] = p[0], im.vertices[3 * v + 1] = p[1], im.vertices[3 * v + 2] = p[2];
  }
  rtcUpdateGeometryBuffer(im.geom, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(im.geom);
  vertex_ms_ = clock_ms(clock_) - t0;
  t0 = clock_ms(clock_);
  rtcCommitScene(im.scene);
  commit_ms_ = clock_ms(clock_) - t0;
  check(im.device, "commit");
}

namespace {

// One ray's answer into the batch (misses: triangle kNoTriangle, t = u = v = 0).
inline void record(HitBatch& hits, std::size_t i, std::uint32_t tri, float t, float u, float v, TraceTotals& tot) {
  hits.t[i] = t, hits.u[i] = u, hits.v[i] = v, hits.triangle[i] = tri;
  hits.nodes_visited[i] = 0, hits.triangles_tested[i] = 0;
  tot.rays += 1;
  tot.hits += tri != kNoTriangle;
}

// The largest coordinate of a ray origin Embree accepts (its FLT_LARGE, 1.844e18, with a margin;
// beyond it rtcIntersect asserts), as the bits of a float: a NaN's bits are larger.
constexpr std::uint32_t kEmbreeLargeBits = std::bit_cast<std::uint32_t>(1.0e18f);

inline std::uint32_t abs_bits(float x) { return std::bit_cast<std::uint32_t>(x) & 0x7fffffffu; }

// Whether Embree takes ray i: each |coordinate| of its origin in Embree's frame and of its
// direction <= 1e18, none NaN.
bool within_reach(const RayBatch& rays, std::size_t i, const FrameMap& frame) {
  const Vec3f o = to_frame(Vec3(rays.ox[i], rays.oy[i], rays.oz[i]), frame);
  const std::uint32_t a = std::max(abs_bits(o[0]), std::max(abs_bits(o[1]), abs_bits(o[2])));
  const std::uint32_t d = std::max(abs_bits(rays.dx[i]), std::max(abs_bits(rays.dy[i]), abs_bits(rays.dz[i])));
  return std::max(a, d) <= kEmbreeLargeBits;
}

[[noreturn]] void throw_out_of_reach(const RayBatch& rays, std::size_t i) {
  std::ostringstream m;
  m << "a ray from (" << rays.ox[i] << ", " << rays.oy[i] << ", " << rays.oz[i] << ") in direction (" << rays.dx[i]
    << ", " << rays.dy[i] << ", " << rays.dz[i]
    << ") is beyond what Embree accepts (1e18 units of the mesh's trace frame): move --eye or --light closer to the mesh";
  throw std::invalid_argument(m.str());
}

// A ray's interval in Embree's frame: t times the frame's scale (the positions are scaled, the
// direction is not), and a hit's t back; exact, the scale being a power of two in [2^-100,
// 2^100] (a float), unless a product leaves the float range.
struct TScale {
  float to, back;
  explicit TScale(double scale) : to(static_cast<float>(scale)), back(static_cast<float>(1.0 / scale)) {}
};

// Rays [begin, end) with rtcIntersect1 / rtcOccluded1.
void trace_singles(RTCScene scene, const FrameMap& frame, const RayBatch& rays, HitBatch& hits, HitMode mode,
                   std::size_t begin, std::size_t end, TraceTotals& tot) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  const TScale ts(frame.scale);
  for (std::size_t i = begin; i != end; ++i) {
    RTCRayHit rh;
    const Vec3f o = to_frame(Vec3(rays.ox[i], rays.oy[i], rays.oz[i]), frame);  // (check_rays: within reach)
    rh.ray.org_x = o[0], rh.ray.org_y = o[1], rh.ray.org_z = o[2];
    rh.ray.dir_x = rays.dx[i], rh.ray.dir_y = rays.dy[i], rh.ray.dir_z = rays.dz[i];
    rh.ray.tnear = rays.tmin[i] * ts.to;
    rh.ray.tfar = rays.tmax[i] * ts.to;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    std::uint32_t tri = kNoTriangle;
    float t = 0, u = 0, v = 0;
    if (mode == HitMode::Closest) {
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &ctx, &rh);
      if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
        tri = rh.hit.primID, t = rh.ray.tfar * ts.back, u = rh.hit.u, v = rh.hit.v;
    } else {
      rtcOccluded1(scene, &ctx, &rh.ray);
      if (rh.ray.tfar < 0.0f) tri = kUnknownTriangle, t = rays.tmax[i];  // occluded (rtcOccluded1 sets tfar = -inf)
    }
    record(hits, i, tri, t, u, v, tot);
  }
}

// Rays [begin, end) in packets of N consecutive rays (rtcIntersectN / rtcOccludedN, with the
// coherent or the incoherent context flag); the lanes past `end` of the last packet are invalid.
template <int N, typename RayHitN, typename IntersectFn, typename OccludedFn>
void trace_packets_of(RTCScene scene, const FrameMap& frame, const RayBatch& rays, HitBatch& hits, HitMode mode,
                      bool coherent, std::size_t begin, std::size_t end, TraceTotals& tot, IntersectFn intersect,
                      OccludedFn occluded) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  const TScale ts(frame.scale);
  for (std::size_t first = begin; first < end; first += N) {
    const int n = static_cast<int>(std::min<std::size_t>(N, end - first));
    alignas(64) int valid[N];
    alignas(64) RayHitN rh;
    for (int l = 0; l < N; ++l) {
      const std::size_t i = first + std::size_t(l < n ? l : 0);
      valid[l] = l < n ? -1 : 0;
      const Vec3f o = to_frame(Vec3(rays.ox[i], rays.oy[i], rays.oz[i]), frame);  // (check_rays: within reach)
      rh.ray.org_x[l] = o[0], rh.ray.org_y[l] = o[1], rh.ray.org_z[l] = o[2];
      rh.ray.dir_x[l] = rays.dx[i], rh.ray.dir_y[l] = rays.dy[i], rh.ray.dir_z[l] = rays.dz[i];
      rh.ray.tnear[l] = rays.tmin[i] * ts.to;
      rh.ray.tfar[l] = rays.tmax[i] * ts.to;
      rh.ray.time[l] = 0.0f;
      rh.ray.mask[l] = 0xffffffffu;
      rh.ray.id[l] = 0;
      rh.ray.flags[l] = 0;
      rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][l] = RTC_INVALID_GEOMETRY_ID;
    }
    if (mode == HitMode::Closest)
      intersect(valid, scene, &ctx, &rh);
    else
      occluded(valid, scene, &ctx, &rh.ray);
    for (int l = 0; l < n; ++l) {
      const std::size_t i = first + l;
      std::uint32_t tri = kNoTriangle;
      float t = 0, u = 0, v = 0;
      if (mode == HitMode::Closest) {
        if (rh.hit.geomID[l] != RTC_INVALID_GEOMETRY_ID)
          tri = rh.hit.primID[l], t = rh.ray.tfar[l] * ts.back, u = rh.hit.u[l], v = rh.hit.v[l];
      } else if (rh.ray.tfar[l] < 0.0f) {
        tri = kUnknownTriangle, t = rays.tmax[i];
      }
      record(hits, i, tri, t, u, v, tot);
    }
  }
}

}  // namespace

void EmbreeScene::check_rays(const RayBatch& rays) const {
  const FrameMap& frame = impl_->frame;
  for (std::size_t i = 0; i < rays.size(); ++i)
    if (!within_reach(rays, i, frame)) throw_out_of_reach(rays, i);
}

TraceTotals EmbreeScene::trace(const RayBatch& rays, HitBatch& hits, HitMode mode, unsigned threads) const {
  return trace_packets(rays, hits, mode, threads, 1);
}

TraceTotals EmbreeScene::trace_packets(const RayBatch& rays, HitBatch& hits, HitMode mode, unsigned threads,
                                       int width, bool coherent) const {
  if (width != 1 && width != 4 && width != 8 && width != 16)
    throw std::invalid_argument("Embree packets: width " + std::to_string(width) + " is not 1, 4, 8 or 16");
  const Impl& im = *impl_;
  const std::size_t n = rays.size();
  hits.resize(n);
  tbb::enumerable_thread_specific<TraceTotals> totals;
  constexpr std::size_t kTile = 64;  // rays per task, as the tracer
  auto body = [&](const tbb::blocked_range<std::size_t>& range) {
    TraceTotals& tot = totals.local();
    const std::size_t b = range.begin() * kTile, e = std::min(n, range.end() * kTile);
    switch (width) {
      case 1: trace_singles(im.scene, im.frame, rays, hits, mode, b, e, tot); break;
      case 4:
        trace_packets_of<4, RTCRayHit4>(im.scene, im.frame, rays, hits, mode, coherent, b, e, tot, rtcIntersect4, rtcOccluded4);
        break;
      case 8:
        trace_packets_of<8, RTCRayHit8>(im.scene, im.frame, rays, hits, mode, coherent, b, e, tot, rtcIntersect8, rtcOccluded8);
        break;
      default:
        trace_packets_of<16, RTCRayHit16>(im.scene, im.frame, rays, hits, mode, coherent, b, e, tot, rtcIntersect16,
                                          rtcOccluded16);
    }
  };
  const std::size_t tiles = (n + kTile - 1) / kTile;
  if (threads == 1) {
    body(tbb::blocked_range<std::size_t>(0, tiles));
  } else {
    tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : static_cast<int>(threads));
    arena.execute([&] { tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles, 1), body); });
  }
  TraceTotals sum;
  for (const TraceTotals& t : totals) sum.rays += t.rays, sum.hits += t.hits;
  return sum;
}

}  // namespace ptc::bvh
