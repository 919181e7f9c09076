// Internal: the tracer's packet path (TraceOptions::packets, tracer.h), included by
// tracer_avx2.cpp, tracer_avx512vl.cpp and tracer_avx512.cpp after tracer_kernel.h (it reuses
// that kernel's leaf tests and result store), so it exists in those variants only; with SSE2
// packets fall back to single rays. The AVX-512VL variant is this AVX2 code compiled for AVX-512
// on 256-bit vectors; the AVX-512 variant the same with per-lane leaf tests of 16 triangles.
//
// Eight consecutive rays of the batch make a packet, one ray per AVX2 lane. The single-ray
// set-up (validity, trace frame, reciprocals) runs for the eight at once, and so do the
// watertight test's constants (make_watertight_ray), at the packet's first leaf; both with the
// same float operations as for one ray. The rays are split
// into groups of one direction octant (so the same near and far box rows); a camera's rows make
// one group almost always. A group walks the 8-wide tree (TraceData::wide8) once:
//   - at an inner node, each of the eight children's boxes is tested against every active lane
//     with exactly the float operations of the single-ray slab test (rewritten here for one box
//     broadcast against eight rays; the single-ray test is eight boxes against one ray), so a
//     lane enters exactly the boxes its own ray would; a child is visited when any lane enters
//     it, with those lanes active; children are visited nearest first (the smallest entry distance among their lanes), the others
//     pushed with their lanes and per-lane entry distances;
//   - a popped entry keeps the lanes whose entry distance is not beyond their best hit (closest)
//     or that have no hit yet (any hit);
//   - a leaf is tested ray-parallel (each triangle against all lanes of one watertight axis
//     permutation, intersect_leaf_rays) when at least kRayParallel lanes of one permutation are
//     in it; the other lanes run the single-ray leaf test (eight triangles per AVX2 test). Both
//     do the single-ray test's float operations per (ray, triangle).
// So the node chain of a packet is walked once for up to eight rays, and the closest hit of
// every ray is its smallest (t, id), bit-identical to the single-ray path (a test checks it on
// every scene). Any hit reports some hit of the ray (not necessarily the one the single-ray path
// finds first); the same rays are occluded. Counters: per ray, the 8-wide nodes tested with the
// ray active and the triangles of the leaves tested for it.
#pragma once

#if !defined(PTC_TRACE_AVX2)
#error "bvh/tracer_packet.h belongs to the AVX2 and AVX-512 variants (tracer_avx2.cpp, tracer_avx512vl.cpp, tracer_avx512.cpp)"
#endif

namespace ptc::bvh::detail::PTC_TRACE_NS {
namespace {

constexpr int kLanes = 8;

struct alignas(32) PacketEntry {
  __m256 tn;            // per-lane entry distance of the box (+inf outside `mask`)
  std::uint32_t ref;    // as StackEntry
  std::uint32_t count;
  std::uint32_t mask;   // lanes that entered the box
};

// The slab-test constants of one octant group, one ray per lane: the single-ray kernel's
// 1/d x kNearScale and 1/d x kFarScale negated (the node test computes (o - b) * -inv).
struct PacketGroup {
  __m256 ox, oy, oz, ninx, niny, ninz, nifx, nify, nifz, tmin;
  std::ptrdiff_t nx, ny, nz, fx, fy, fz;
};

inline __m256 lane_mask(std::uint32_t m) {
  const __m256i bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  return _mm256_castsi256_ps(
      _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(static_cast<int>(m)), bits), bits));
}

inline float hmin8(__m256 x) {
  __m128 m = _mm_min_ps(_mm256_castps256_ps128(x), _mm256_extractf128_ps(x, 1));
  m = _mm_min_ps(m, _mm_movehl_ps(m, m));
  m = _mm_min_ss(m, _mm_shuffle_ps(m, m, 1));
  return _mm_cvtss_f32(m);
}

// Per lane, v0, v1 or v2 as the lane's axis kk is 0, 1 or 2.
inline __m256 pick_axis(__m256i kk, __m256 v0, __m256 v1, __m256 v2) {
  const __m256 is1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kk, _mm256_set1_epi32(1)));
  const __m256 is2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kk, _mm256_set1_epi32(2)));
  return _mm256_blendv_ps(_mm256_blendv_ps(v0, v1, is1), v2, is2);
}

// A lane's result on 32 bytes, so that the eight make an 8 x 8 matrix of 32-bit values (rows:
// lanes; columns: t, u, v, tri, nodes, tris and two unused), which store_results transposes.
struct alignas(32) LaneResult : Result {
  std::uint32_t unused[2] = {0, 0};
};
static_assert(sizeof(LaneResult) == 32 && offsetof(Result, t) == 0 && offsetof(Result, u) == 4 &&
              offsetof(Result, v) == 8 && offsetof(Result, tri) == 12 && offsetof(Result, tris) == 20);

struct alignas(32) Packet {
  RayState ray[kLanes];            // the single-ray leaf state of a lane, made at its first leaf
  LaneResult res[kLanes];
  alignas(32) float tmax[kLanes];  // per lane: best hit so far (closest) or the ray's end
  std::uint32_t done = 0;          // any hit: lanes with a hit
  std::uint32_t ready = 0;         // lanes whose `ray` is made
  bool watertight = false;         // the eight lanes' watertight constants below are made
  __m256i nodes;                   // per lane: wide nodes tested with the lane active
  __m256 ox, oy, oz, dx, dy, dz;   // the rays in the trace frame
  alignas(32) float tmin[kLanes];
  // make_watertight_ray's constants per lane (the same float operations, eight lanes at once)
  alignas(32) float okx[kLanes], oky[kLanes], okz[kLanes], sx[kLanes], sy[kLanes], sz[kLanes];
  int kx[kLanes], ky[kLanes], kz[kLanes];
  std::uint32_t perm[6] = {};      // lanes per watertight axis permutation (kz, sign of d[kz])

  void make_watertight() {
    const __m256 sign = _mm256_set1_ps(-0.0f);
    const __m256 ax = _mm256_andnot_ps(sign, dx), ay = _mm256_andnot_ps(sign, dy), az = _mm256_andnot_ps(sign, dz);
    // kz: the dominant axis, the first of equals (abs(d[1]) > abs(d[kz]), then abs(d[2]) > abs(d[kz]))
    const __m256 y_wins = _mm256_cmp_ps(ay, ax, _CMP_GT_OQ);
    const __m256 z_wins = _mm256_cmp_ps(az, _mm256_blendv_ps(ax, ay, y_wins), _CMP_GT_OQ);
    const __m256 dkz = _mm256_blendv_ps(_mm256_blendv_ps(dx, dy, y_wins), dz, z_wins);
    // Per lane, in integer lanes: kz = 2 where z wins, else 1 where y wins, else 0; x = kz + 1 and
    // y = x + 1 (mod 3), swapped where d[kz] < 0 to keep the winding of the sheared triangle.
    const __m256i one = _mm256_set1_epi32(1), two = _mm256_set1_epi32(2);
    const __m256i yw = _mm256_castps_si256(y_wins), zw = _mm256_castps_si256(z_wins);
    const __m256i negw = _mm256_castps_si256(_mm256_cmp_ps(dkz, _mm256_setzero_ps(), _CMP_LT_OQ));
    const __m256i kzv = _mm256_blendv_epi8(_mm256_and_si256(yw, one), two, zw);
    const __m256i xv = _mm256_andnot_si256(zw, _mm256_add_epi32(kzv, one));  // (kz is 2 exactly where z wins)
    const __m256i yv = _mm256_andnot_si256(_mm256_cmpeq_epi32(xv, two), _mm256_add_epi32(xv, one));
    const __m256i kxv = _mm256_blendv_epi8(xv, yv, negw), kyv = _mm256_blendv_epi8(yv, xv, negw);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(kx), kxv);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(ky), kyv);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(kz), kzv);
    const __m256 n = _mm256_castsi256_ps(negw);
    for (int k = 0; k < 3; ++k) {  // the lanes of each permutation (kz, sign of d[kz])
      const __m256 on = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kzv, _mm256_set1_epi32(k)));
      perm[2 * k] = static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_andnot_ps(n, on)));
      perm[2 * k + 1] = static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_and_ps(n, on)));
    }
    _mm256_store_ps(sx, _mm256_div_ps(pick_axis(kxv, dx, dy, dz), dkz));
    _mm256_store_ps(sy, _mm256_div_ps(pick_axis(kyv, dx, dy, dz), dkz));
    _mm256_store_ps(sz, _mm256_div_ps(_mm256_set1_ps(1.0f), dkz));
    _mm256_store_ps(okx, pick_axis(kxv, ox, oy, oz));
    _mm256_store_ps(oky, pick_axis(kyv, ox, oy, oz));
    _mm256_store_ps(okz, _mm256_blendv_ps(_mm256_blendv_ps(ox, oy, y_wins), oz, z_wins));
    watertight = true;
  }

  // The state intersect_leaf reads (tracer_kernel.h: prepare_watertight's fields and tmin).
  RayState& leaf_state(int l) {
    if (!(ready >> l & 1)) {
      if (!watertight) make_watertight();
      RayState& r = ray[l];
      r.kx4 = 4 * kx[l], r.ky4 = 4 * ky[l], r.kz4 = 4 * kz[l];
      r.okx = _mm_set1_ps(okx[l]), r.oky = _mm_set1_ps(oky[l]), r.okz = _mm_set1_ps(okz[l]);
      r.sx = _mm_set1_ps(sx[l]), r.sy = _mm_set1_ps(sy[l]), r.sz = _mm_set1_ps(sz[l]);
      r.okx8 = _mm256_set1_ps(okx[l]), r.oky8 = _mm256_set1_ps(oky[l]), r.okz8 = _mm256_set1_ps(okz[l]);
      r.sx8 = _mm256_set1_ps(sx[l]), r.sy8 = _mm256_set1_ps(sy[l]), r.sz8 = _mm256_set1_ps(sz[l]);
#if defined(PTC_TRACE_AVX512)
      r.okx16 = _mm512_set1_ps(okx[l]), r.oky16 = _mm512_set1_ps(oky[l]), r.okz16 = _mm512_set1_ps(okz[l]);
      r.sx16 = _mm512_set1_ps(sx[l]), r.sy16 = _mm512_set1_ps(sy[l]), r.sz16 = _mm512_set1_ps(sz[l]);
#endif
      r.tmin = tmin[l];
      r.watertight_ready = true;
      ready |= 1u << l;
    }
    return ray[l];
  }
};

// A leaf is tested ray-parallel (one triangle against the lanes) for the lanes of one watertight
// axis permutation when there are at least this many of them, else ray by ray. On the AMD host
// (2026-12-03) 4 beat 2, 3, 5 and 8 on the cluster BVH (leaves of 30-50 triangles). On the Intel
// host since (2026-12-05, docs/tracing.md, "The ray-parallel threshold on this host") 5-7 beat 4
// and 8 on every built-in scene with AVX2 and AVX-512: 6. On the AMD Zen 4 host (2026-12-06,
// docs/tracing.md, "The machine changed again") 8 was clearly faster on the cloth (primary rays
// 63 against 65-71 ms with AVX-512VL, the variant `auto` picks there) and within the noise of 6
// on the twist, the explode scene and the faerie (the Intel host's 8 had been 1-3% slower than
// its 6 on the twist): 8, so only full packets of one permutation.
constexpr int kRayParallel = 8;

#if defined(PTC_TRACE_AVX512)
// x in both 256-bit halves (as _mm512_broadcast_f32x8, whose GCC 12 header reads an uninitialised
// operand and warned at every use).
inline __m512 dup8(__m256 x) { return _mm512_insertf32x8(_mm512_castps256_ps512(x), x, 1); }
#endif

// One leaf against the lanes `lanes` (all of one axis permutation kx, ky, kz), one triangle
// against all lanes at a time: the single-ray test's float operations per (ray, triangle), so the
// same hits. Returns the lanes that found a hit (any hit: they are done).
// Not inlined: inside the walk GCC kept five of the lanes' constants and three corner rows of
// every triangle on the stack (a reload or a spill each), in its own function they stay in
// registers; a call per leaf costs less than that per triangle (cloth primary and shadow rays
// 1-4% faster, the twist unchanged).
template <bool AnyHit>
[[gnu::noinline]] std::uint32_t intersect_leaf_rays(const Flat& d, std::uint32_t ref, std::uint32_t count, Packet& p,
                                  std::uint32_t lanes, int kx4, int ky4, int kz4) {
  LeafRange one{ref, (count + 3) / 4, count};
  const LeafRange* ranges = &one;
  std::uint32_t nr = 1;
  if (count & kIndirectLeaf) ranges = d.ranges + ref, nr = count & ~kIndirectLeaf;
  const __m256 okx = _mm256_load_ps(p.okx), oky = _mm256_load_ps(p.oky), okz = _mm256_load_ps(p.okz);
  const __m256 sx = _mm256_load_ps(p.sx), sy = _mm256_load_ps(p.sy), sz = _mm256_load_ps(p.sz);
  const __m256 tmin = _mm256_load_ps(p.tmin);
  __m256 tmax = _mm256_load_ps(p.tmax);
  std::uint32_t found = 0;
  // The hits of triangle `id` among the lanes `m` (t, V, W, det of lane l at ft[l] ...): closest
  // keeps each lane's smallest (t, id), any hit the first.
  auto take = [&](std::uint32_t m, std::uint32_t id, const float* ft, const float* fv, const float* fw,
                  const float* fd) {
    for (; m; m &= m - 1) {
      const int l = ctz(m);
      Result& res = p.res[l];
      if constexpr (!AnyHit) {
        if (!(ft[l] < p.tmax[l] || (ft[l] == p.tmax[l] && id < res.tri))) continue;
      }
      res.t = ft[l], res.tri = id, res.u = fv[l] / fd[l], res.v = fw[l] / fd[l];
      p.tmax[l] = ft[l];
      found |= 1u << l;
    }
  };
#if defined(PTC_TRACE_AVX512)
  // Two triangles against the eight lanes in one 512-bit test (lanes 0-7: the first triangle,
  // 8-15: the second), taken in the order of the one-triangle test, so the same hits: a closest
  // hit of the second is checked against the lane's best after the first, an any-hit lane done
  // with the first leaves the second.
  const __m512 okx2 = dup8(okx), oky2 = dup8(oky);
  const __m512 okz2 = dup8(okz), sx2 = dup8(sx);
  const __m512 sy2 = dup8(sy), sz2 = dup8(sz);
  const __m512 tmin2 = dup8(tmin);
  // A triangle's corners: corner c's coordinate on axis a at c[k] + off[a] (blocks: rows 12
  // floats apart and axes 4 apart; table groups: a slot in rows 32 floats apart).
  struct Corners {
    const float* c[3];
  };
  Corners pend{};  // a triangle waiting for its partner (pend.c[0] null: none)
  std::uint32_t pend_id = kNoTriangle;
  int pend_ox = 0, pend_oy = 0, pend_oz = 0;
  // `both` false: the first triangle alone (lanes 8-15 not live; b may be a).
  auto test_pair = [&](const Corners& a, std::uint32_t id0, const Corners& b, std::uint32_t id1, bool both, int ox,
                       int oy, int oz) {
    auto at = [&](int k, int off, __m512 o) {
      return _mm512_sub_ps(_mm512_insertf32x8(_mm512_castps256_ps512(_mm256_broadcast_ss(a.c[k] + off)),
                                              _mm256_broadcast_ss(b.c[k] + off), 1),
                           o);
    };
    const __mmask16 live = static_cast<__mmask16>(lanes | (both ? lanes << 8 : 0u));
    const Pairs16 h = watertight16(at(0, ox, okx2), at(0, oy, oky2), at(0, oz, okz2), at(1, ox, okx2), at(1, oy, oky2),
                                   at(1, oz, okz2), at(2, ox, okx2), at(2, oy, oky2), at(2, oz, okz2), sx2, sy2, sz2,
                                   live);
    if (!h.valid) return;
    const __m512 tmax2 = dup8(tmax);
    const std::uint32_t m =
        h.valid & _mm512_cmp_ps_mask(h.t, tmin2, _CMP_GT_OQ) & _mm512_cmp_ps_mask(h.t, tmax2, _CMP_LE_OQ);
    if (!m) return;
    alignas(64) float ft[16], fv[16], fw[16], fd[16];
    _mm512_store_ps(ft, h.t), _mm512_store_ps(fv, h.V), _mm512_store_ps(fw, h.W), _mm512_store_ps(fd, h.det);
    take(m & 0xffu & lanes, id0, ft, fv, fw, fd);
    if constexpr (AnyHit) lanes &= ~found;
    take((m >> 8) & lanes, id1, ft + 8, fv + 8, fw + 8, fd + 8);
    if constexpr (AnyHit) lanes &= ~found;
    else tmax = _mm256_load_ps(p.tmax);
  };
  // A range's last triangle without a partner, alone. Pairs never span two ranges: an any-hit
  // packet done in one range is not charged the next one's triangles.
  auto test_last = [&] {
    if (!pend.c[0]) return;
    test_pair(pend, pend_id, pend, pend_id, false, pend_ox, pend_oy, pend_oz);
    pend.c[0] = nullptr;
  };
  // Triangle `id` with corners `t`: kept until its partner comes, then the pair tested; true
  // when an any-hit packet is done.
  auto add_pair = [&](const Corners& t, std::uint32_t id, int ox, int oy, int oz) {
    if (!pend.c[0]) {
      pend = t, pend_id = id, pend_ox = ox, pend_oy = oy, pend_oz = oz;
      return false;
    }
    test_pair(pend, pend_id, t, id, true, ox, oy, oz);
    pend.c[0] = nullptr;
    if constexpr (AnyHit) return lanes == 0;
    return false;
  };
#else
  // One triangle (corner c's coordinate on axis a at c_k + o_a) against the lanes; true when an
  // any-hit packet is done.
  auto test_one = [&](const float* c0, const float* c1, const float* c2, int ox, int oy, int oz, std::uint32_t id) {
    auto at = [&](const float* row, __m256 o) { return _mm256_sub_ps(_mm256_broadcast_ss(row), o); };
    const Pairs8 h = watertight8(at(c0 + ox, okx), at(c0 + oy, oky), at(c0 + oz, okz), at(c1 + ox, okx),
                                 at(c1 + oy, oky), at(c1 + oz, okz), at(c2 + ox, okx), at(c2 + oy, oky), at(c2 + oz, okz),
                                 sx, sy, sz, static_cast<int>(lanes));
    if (!h.valid_bits) return false;
    const __m256 in_range = _mm256_and_ps(_mm256_cmp_ps(h.t, tmin, _CMP_GT_OQ), _mm256_cmp_ps(h.t, tmax, _CMP_LE_OQ));
    const std::uint32_t m = static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_and_ps(h.valid, in_range))) & lanes;
    if (!m) return false;
    alignas(32) float ft[8], fv[8], fw[8], fd[8];
    _mm256_store_ps(ft, h.t), _mm256_store_ps(fv, h.V), _mm256_store_ps(fw, h.W), _mm256_store_ps(fd, h.det);
    take(m, id, ft, fv, fw, fd);
    if constexpr (AnyHit) {
      lanes &= ~found;
      return lanes == 0;
    } else {
      tmax = _mm256_load_ps(p.tmax);
      return false;
    }
  };
#endif
  // The triangles of blocks [0, nb) (ids from first_id, 4 a block); true when an any-hit packet
  // is done.
  auto test_blocks = [&](const TriBlock* blocks, const std::uint32_t* first_id, std::uint32_t nb) {
    for (std::uint32_t bk = 0; bk < nb; ++bk) {
      const float* blk = &blocks[bk].v[0][0][0];
      const std::uint32_t* ids = first_id + 4 * std::size_t(bk);
      for (int j = 0; j < 4; ++j) {
        const std::uint32_t id = ids[j];
        if (id == kNoTriangle) continue;
        const float* v = blk + j;
#if defined(PTC_TRACE_AVX512)
        if (add_pair({{v, v + 12, v + 24}}, id, kx4, ky4, kz4)) return true;
#else
        // (With the corner rows as `v + 12 * corner + axis` inline here the compiler kept nine
        // row pointers on the stack, three instructions a row.)
        if (test_one(v, v + 12, v + 24, kx4, ky4, kz4, id)) return true;
#endif
      }
    }
    return false;
  };
  // The triangles of a table group (ids[j] for triangle j < count): true when an any-hit packet
  // is done.
  auto test_group = [&](const TableGroup& tg, const std::uint32_t* ids) {
    const float* base = tg.v[0];
    const int ox = 8 * kx4, oy = 8 * ky4, oz = 8 * kz4;
    for (std::uint32_t j = 0; j < tg.count; ++j) {
      const float* c0 = base + tg.corner[0][j];
      const float* c1 = base + tg.corner[1][j];
      const float* c2 = base + tg.corner[2][j];
#if defined(PTC_TRACE_AVX512)
      if (add_pair({{c0, c1, c2}}, ids[j], ox, oy, oz)) return true;
#else
      if (test_one(c0, c1, c2, ox, oy, oz, ids[j])) return true;
#endif
    }
    return false;
  };
  // After a range or a table group: the last triangle without a partner; true when an any-hit
  // packet is done.
  auto end_run = [&] {
#if defined(PTC_TRACE_AVX512)
    test_last();
#endif
    if constexpr (AnyHit) return lanes == 0;
    return false;
  };
  for (std::uint32_t i = 0; i < nr; ++i) {
    const LeafRange lr = ranges[i];
    for (std::uint32_t mm = lanes; mm; mm &= mm - 1) p.res[ctz(mm)].tris += lr.triangle_count;
    if (!d.use_tables) {
      if (test_blocks(d.blocks + lr.first_block, d.ids + 4 * std::size_t(lr.first_block), lr.block_count) || end_run())
        return found;
      continue;
    }
    // Table groups (a direct leaf: its groups up to the last one), each triangle's corners read
    // from the group's rows through its slots (rows 32 floats apart).
    const bool direct = !(count & kIndirectLeaf);
    for (std::uint32_t g = lr.first_block; direct || g < lr.first_block + lr.block_count; ++g) {
      if (test_group(d.tables[g], d.ids + std::size_t{kTableSlots} * g) || end_run()) return found;
      if (direct && d.tables[g].last) break;
    }
  }
  return found;
}

// The walk of one octant group over the 8-wide nodes (those of the single-ray walk): per node,
// each of the eight children tested against the group's lanes.
template <bool AnyHit>
void traverse_packet(const Flat& d, const PacketGroup& g, std::uint32_t group, Packet& p, PacketEntry* stack) {
  if (d.empty) return;
  const WideNode8* const nodes = d.nodes;
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256i one = _mm256_set1_epi32(1);
  __m256 tmax = _mm256_load_ps(p.tmax);
  PacketEntry* sp = stack;
  std::uint32_t ref = d.root, cnt = 0, m = group;
  auto pop = [&] {
    while (sp != stack) {
      --sp;
      std::uint32_t mm = sp->mask;
      if constexpr (AnyHit)
        mm &= ~p.done;
      else
        mm &= static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_cmp_ps(sp->tn, tmax, _CMP_LE_OQ)));
      if (mm) {
        ref = sp->ref, cnt = sp->count, m = mm;
        return true;
      }
    }
    return false;
  };
  do {
    bool miss = false;
    while (cnt == 0) {
      const float* b = &nodes[ref].bounds[0][0];
      // The six rows this group reads, as pointers made per node and hidden from the optimiser:
      // with `b + g.nx + c` it hoisted the 48 loop-invariant offsets (plane and child) out of the
      // walk, kept them on the stack and reloaded one for every broadcast.
      const float* rnx = b + g.nx;
      const float* rny = b + g.ny;
      const float* rnz = b + g.nz;
      const float* rfx = b + g.fx;
      const float* rfy = b + g.fy;
      const float* rfz = b + g.fz;
      asm("" : "+r"(rnx), "+r"(rny), "+r"(rnz), "+r"(rfx), "+r"(rfy), "+r"(rfz));
      p.nodes = _mm256_add_epi32(p.nodes, _mm256_and_si256(_mm256_castps_si256(lane_mask(m)), one));
      __m256 tn[8];
      std::uint32_t lanes[8];
      unsigned any = 0;
#pragma GCC unroll 8
      for (int c = 0; c < 8; ++c) {
        // The single-ray kernel's operations (its comment explains the NaN rule), each slab
        // distance as (o - b) * -inv: the same value as its (b - o) * inv, rounding to nearest being
        // symmetric in sign, and NaN in the same cases (0 * inf). Only a zero's sign may differ;
        // the distances are only compared (and ordered), where the two zeros are equal, so every
        // lane enters the same boxes in the same order. The plane is the second operand, which
        // AVX-512VL takes from memory with an embedded broadcast (one instruction instead of two).
        const __m256 tnx = _mm256_mul_ps(_mm256_sub_ps(g.ox, _mm256_broadcast_ss(rnx + c)), g.ninx);
        const __m256 tny = _mm256_mul_ps(_mm256_sub_ps(g.oy, _mm256_broadcast_ss(rny + c)), g.niny);
        const __m256 tnz = _mm256_mul_ps(_mm256_sub_ps(g.oz, _mm256_broadcast_ss(rnz + c)), g.ninz);
        const __m256 tfx = _mm256_mul_ps(_mm256_sub_ps(g.ox, _mm256_broadcast_ss(rfx + c)), g.nifx);
        const __m256 tfy = _mm256_mul_ps(_mm256_sub_ps(g.oy, _mm256_broadcast_ss(rfy + c)), g.nify);
        const __m256 tfz = _mm256_mul_ps(_mm256_sub_ps(g.oz, _mm256_broadcast_ss(rfz + c)), g.nifz);
        tn[c] = _mm256_max_ps(_mm256_max_ps(tnx, tny), _mm256_max_ps(tnz, g.tmin));
        const __m256 tf = _mm256_min_ps(_mm256_min_ps(tfx, tfy), _mm256_min_ps(tfz, tmax));
        lanes[c] = static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_cmp_ps(tn[c], tf, _CMP_LE_OQ))) & m;
        any |= lanes[c] ? 1u << c : 0u;
      }
      if (!any) {
        miss = true;
        break;
      }
      const WideNode8& n = nodes[ref];
      if ((any & (any - 1)) == 0) {  // one child
        const int c = ctz(any);
        ref = n.child[c], cnt = n.count[c], m = lanes[c];
        continue;
      }
      int order[8], k = 0;
      for (unsigned a = any; a; a &= a - 1) order[k++] = ctz(a);
      if constexpr (!AnyHit) {  // (any hit pops by lanes alone, in slot order)
        float dist[8];
        for (int i = 0; i < k; ++i) {
          const int c = order[i];
          tn[c] = _mm256_blendv_ps(inf, tn[c], lane_mask(lanes[c]));
          dist[c] = hmin8(tn[c]);
        }
        for (int i = 1; i < k; ++i)  // insertion sort, descending distance
          for (int j = i; j > 0 && dist[order[j - 1]] < dist[order[j]]; --j) std::swap(order[j - 1], order[j]);
      }
      for (int i = 0; i < k - 1; ++i) {
        const int c = order[i];
        sp->tn = tn[c], sp->ref = n.child[c], sp->count = n.count[c], sp->mask = lanes[c];
        prefetch_child(d, n.child[c], n.count[c]);
        ++sp;
      }
      const int c = order[k - 1];
      ref = n.child[c], cnt = n.count[c], m = lanes[c];
    }
    if (!miss) {
      if (__builtin_popcount(m) >= kRayParallel) {
        if (!p.watertight) p.make_watertight();
        for (int c = 0; c < 6; ++c) {
          const std::uint32_t cl = m & p.perm[c];
          if (__builtin_popcount(cl) < kRayParallel) continue;
          const int l0 = ctz(cl);
          const std::uint32_t f = intersect_leaf_rays<AnyHit>(d, ref, cnt, p, cl, 4 * p.kx[l0], 4 * p.ky[l0], 4 * p.kz[l0]);
          if constexpr (AnyHit) p.done |= f;
          m &= ~cl;
        }
      }
      for (std::uint32_t mm = m; mm; mm &= mm - 1) {
        const int l = ctz(mm);
        if (intersect_leaf<AnyHit>(d, ref, cnt, p.leaf_state(l), p.tmax[l], p.res[l], p.res[l].tris) && AnyHit)
          p.done |= 1u << l;
      }
      if constexpr (AnyHit) {
        if ((group & ~p.done) == 0) return;  // every ray of the group is occluded
      } else {
        tmax = _mm256_load_ps(p.tmax);
      }
    }
  } while (pop());
}

// Eight floats of the batch from `first` (fewer at the end: the rest 0).
inline __m256 load_lanes(const float* a, std::size_t first, int n) {
  if (n == kLanes) return _mm256_loadu_ps(a + first);
  alignas(32) float v[kLanes] = {};
  for (int l = 0; l < n; ++l) v[l] = a[first + l];
  return _mm256_load_ps(v);
}
// Eight doubles of the batch minus `o`, times `scale`, rounded to float (to_frame's operations).
inline __m256 load_frame(const double* a, std::size_t first, int n, double o, double scale) {
  alignas(32) double v[kLanes];  // (zeroed only for a short packet: the compiler zeroed it for every packet)
  const double* src = a + first;
  if (n < kLanes) {
    for (int l = 0; l < kLanes; ++l) v[l] = l < n ? a[first + l] : 0.0;
    src = v;
  }
  const __m256d od = _mm256_set1_pd(o), sd = _mm256_set1_pd(scale);
  const __m128 lo = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(src), od), sd));
  const __m128 hi = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(src + 4), od), sd));
  return _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
}

// The sum of eight unsigned 32-bit lanes, in 64 bits (as the per-lane totals added one by one).
inline std::uint64_t hsum8(__m256i x) {
  const __m256i w = _mm256_add_epi64(_mm256_cvtepu32_epi64(_mm256_castsi256_si128(x)),
                                     _mm256_cvtepu32_epi64(_mm256_extracti128_si256(x, 1)));
  const __m128i v = _mm_add_epi64(_mm256_castsi256_si128(w), _mm256_extracti128_si256(w, 1));
  return static_cast<std::uint64_t>(_mm_cvtsi128_si64(v)) + static_cast<std::uint64_t>(_mm_extract_epi64(v, 1));
}

// store_result for the eight lanes of a full packet at once: their results transposed (8 x 8),
// each column stored with one 256-bit store; the same values (a miss's t is 0; nodes from
// p.nodes) and the same totals.
inline void store_results(HitBatch& hits, std::size_t first, const Packet& p, bool counters, TraceTotals& tot) {
  __m256 r[kLanes];
  for (int l = 0; l < kLanes; ++l) r[l] = _mm256_load_ps(&p.res[l].t);
  // Rows (lanes) into columns. Within each 128-bit half: a0 = (t0 t1 u0 u1 | nodes0 nodes1 tris0
  // tris1), then b0 = (t0..t3 | nodes0..3), b1 = (u0..u3 | tris0..3), b2 = (v0..v3 | -), b3 =
  // (tri0..3 | -); the low halves of b0 and b4 make t of the eight lanes, the high halves of b1
  // and b5 their tris (their nodes are p.nodes).
  const __m256 a0 = _mm256_unpacklo_ps(r[0], r[1]), a1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 a2 = _mm256_unpacklo_ps(r[2], r[3]), a3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 a4 = _mm256_unpacklo_ps(r[4], r[5]), a5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 a6 = _mm256_unpacklo_ps(r[6], r[7]), a7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 b0 = _mm256_shuffle_ps(a0, a2, _MM_SHUFFLE(1, 0, 1, 0)), b1 = _mm256_shuffle_ps(a0, a2, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 b2 = _mm256_shuffle_ps(a1, a3, _MM_SHUFFLE(1, 0, 1, 0)), b3 = _mm256_shuffle_ps(a1, a3, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 b4 = _mm256_shuffle_ps(a4, a6, _MM_SHUFFLE(1, 0, 1, 0)), b5 = _mm256_shuffle_ps(a4, a6, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 b6 = _mm256_shuffle_ps(a5, a7, _MM_SHUFFLE(1, 0, 1, 0)), b7 = _mm256_shuffle_ps(a5, a7, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 t = _mm256_permute2f128_ps(b0, b4, 0x20), u = _mm256_permute2f128_ps(b1, b5, 0x20);
  const __m256 v = _mm256_permute2f128_ps(b2, b6, 0x20), tri = _mm256_permute2f128_ps(b3, b7, 0x20);
  const __m256i tris = _mm256_castps_si256(_mm256_permute2f128_ps(b1, b5, 0x31));
  const __m256 hit = _mm256_castsi256_ps(_mm256_xor_si256(
      _mm256_cmpeq_epi32(_mm256_castps_si256(tri), _mm256_set1_epi32(static_cast<int>(kNoTriangle))), _mm256_set1_epi32(-1)));
  _mm256_storeu_ps(hits.t.data() + first, _mm256_and_ps(t, hit));
  _mm256_storeu_ps(hits.u.data() + first, u);
  _mm256_storeu_ps(hits.v.data() + first, v);
  _mm256_storeu_ps(reinterpret_cast<float*>(hits.triangle.data() + first), tri);
  if (counters) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(hits.nodes_visited.data() + first), p.nodes);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(hits.triangles_tested.data() + first), tris);
  }
  tot.rays += kLanes;
  tot.hits += static_cast<std::uint64_t>(__builtin_popcount(static_cast<unsigned>(_mm256_movemask_ps(hit))));
  tot.nodes_visited += hsum8(p.nodes);
  tot.triangles_tested += hsum8(tris);
}

template <bool AnyHit>
void trace_packet(const TraceData& s, const Flat& f, const RayBatch& rays, HitBatch& hits, std::size_t first, int n,
                  bool counters, TraceTotals& tot, PacketEntry* stack) {
  // The single-ray set-up (tracer_kernel.h, setup), eight lanes at once: the same operations.
  const __m256 ox = load_frame(rays.ox.data(), first, n, s.origin.x(), s.scale);
  const __m256 oy = load_frame(rays.oy.data(), first, n, s.origin.y(), s.scale);
  const __m256 oz = load_frame(rays.oz.data(), first, n, s.origin.z(), s.scale);
  const __m256 sf = _mm256_set1_ps(static_cast<float>(s.scale));  // the frame's scale (exact)
  const __m256 dx = _mm256_mul_ps(load_lanes(rays.dx.data(), first, n), sf),
               dy = _mm256_mul_ps(load_lanes(rays.dy.data(), first, n), sf),
               dz = _mm256_mul_ps(load_lanes(rays.dz.data(), first, n), sf);
  const __m256 t0 = load_lanes(rays.tmin.data(), first, n), t1 = load_lanes(rays.tmax.data(), first, n);
  const __m256 big = _mm256_set1_ps(kBig), zero = _mm256_setzero_ps();
  auto finite = [&](__m256 x) {  // |x| <= max float (false for inf and NaN)
    const __m256 abs = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), x);
    return _mm256_cmp_ps(abs, big, _CMP_LE_OQ);
  };
  const __m256 tmax = _mm256_blendv_ps(big, t1, _mm256_cmp_ps(t1, big, _CMP_LT_OQ));  // tmax < big ? tmax : big
  __m256 ok = _mm256_and_ps(_mm256_and_ps(finite(dx), finite(dy)), finite(dz));
  ok = _mm256_and_ps(ok, _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(dx, zero, _CMP_NEQ_UQ), _mm256_cmp_ps(dy, zero, _CMP_NEQ_UQ)),
                                      _mm256_cmp_ps(dz, zero, _CMP_NEQ_UQ)));
  ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_and_ps(finite(ox), finite(oy)), finite(oz)));
  ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(t0, tmax, _CMP_LT_OQ), _mm256_cmp_ps(t0, zero, _CMP_GE_OQ)));
  const std::uint32_t valid = static_cast<std::uint32_t>(_mm256_movemask_ps(ok)) & ((1u << n) - 1u);
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 ix = _mm256_div_ps(one, dx), iy = _mm256_div_ps(one, dy), iz = _mm256_div_ps(one, dz);
  const std::uint32_t sx = static_cast<std::uint32_t>(_mm256_movemask_ps(ix));  // sign bits: the octant
  const std::uint32_t sy = static_cast<std::uint32_t>(_mm256_movemask_ps(iy));
  const std::uint32_t sz = static_cast<std::uint32_t>(_mm256_movemask_ps(iz));
  const __m256 ns = _mm256_set1_ps(kNearScale), fs = _mm256_set1_ps(kFarScale);
  PacketGroup g;
  g.ox = ox, g.oy = oy, g.oz = oz, g.tmin = t0;
  const __m256 sgn = _mm256_set1_ps(-0.0f);  // (the products' sign flipped: exact)
  auto neg = [&](__m256 x) { return _mm256_xor_ps(x, sgn); };
  g.ninx = neg(_mm256_mul_ps(ix, ns)), g.niny = neg(_mm256_mul_ps(iy, ns)), g.ninz = neg(_mm256_mul_ps(iz, ns));
  g.nifx = neg(_mm256_mul_ps(ix, fs)), g.nify = neg(_mm256_mul_ps(iy, fs)), g.nifz = neg(_mm256_mul_ps(iz, fs));

  Packet p;
  p.nodes = _mm256_setzero_si256();
  _mm256_store_ps(p.tmax, _mm256_and_ps(tmax, ok));
  _mm256_store_ps(p.tmin, t0);
  p.ox = ox, p.oy = oy, p.oz = oz, p.dx = dx, p.dy = dy, p.dz = dz;
  for (std::uint32_t todo = valid; todo;) {
    const int rep = ctz(todo);
    const int ax = sx >> rep & 1, ay = sy >> rep & 1, az = sz >> rep & 1;
    const std::uint32_t group = todo & (ax ? sx : ~sx) & (ay ? sy : ~sy) & (az ? sz : ~sz);
    todo &= ~group;
    g.nx = 8 * (0 + ax), g.ny = 8 * (2 + ay), g.nz = 8 * (4 + az);  // rows of eight floats (WideNode8)
    g.fx = 8 * (1 - ax), g.fy = 8 * (3 - ay), g.fz = 8 * (5 - az);
    traverse_packet<AnyHit>(f, g, group, p, stack);
  }
  if (n == kLanes) {
    store_results(hits, first, p, counters, tot);
    return;
  }
  alignas(32) std::uint32_t nodes[kLanes];
  _mm256_store_si256(reinterpret_cast<__m256i*>(nodes), p.nodes);
  for (int l = 0; l < n; ++l) {
    p.res[l].nodes = nodes[l];
    store_result(hits, first + l, p.res[l], counters, tot);
  }
}

void trace_range_packet_impl(const TraceData& scene, const RayBatch& rays, HitBatch& hits, std::size_t begin,
                             std::size_t end, HitMode mode, bool counters, TraceTotals& tot) {
  const Flat f = flat_of(scene);
  std::vector<PacketEntry> stack(stack_size(scene));
  for (std::size_t i = begin; i < end; i += kLanes) {
    const int n = static_cast<int>(std::min<std::size_t>(kLanes, end - i));
    if (mode == HitMode::Closest)
      trace_packet<false>(scene, f, rays, hits, i, n, counters, tot, stack.data());
    else
      trace_packet<true>(scene, f, rays, hits, i, n, counters, tot, stack.data());
  }
}

}  // namespace
}  // namespace ptc::bvh::detail::PTC_TRACE_NS

// The variant's entry point (detail::trace_range_packet_avx2, ..._avx512; tracer_isa.h).
namespace ptc::bvh::detail {
void PTC_TRACE_CAT(trace_range_packet_, PTC_TRACE_NS)(const TraceData& s, const RayBatch& r, HitBatch& h,
                                                      std::size_t b, std::size_t e, HitMode m, bool c,
                                                      TraceTotals& t) {
  PTC_TRACE_NS::trace_range_packet_impl(s, r, h, b, e, m, c, t);
}
}  // namespace ptc::bvh::detail
