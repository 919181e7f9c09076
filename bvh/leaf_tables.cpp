#include "bvh/leaf_tables.h"

#include "bvh/box_simd.h"

#include <emmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace ptc::bvh {

namespace {

constexpr std::size_t kLookAhead = 64;          // triangles a group chooses from (make_table_layout)
constexpr std::size_t kClustersPerTask = 1024;  // the fill's chunks, as fill_blocks_and_cluster_boxes'

struct Lane {
  std::uint32_t id;
  std::uint32_t v[3];
};

// One cluster's groups appended to `out`.
void group_cluster(std::vector<Lane>& rest, std::uint32_t sentinel, TableLayout& out) {
  std::size_t placed = 0;  // rest[0, placed) are placed; the others keep their order
  while (placed < rest.size()) {
    std::uint32_t slots[kTableSlots];
    int nslots = 0, ntris = 0;
    std::uint32_t ids[kTableSlots];
    std::uint8_t corner[3][kTableSlots];
    auto slot_of = [&](std::uint32_t v) {
      for (int s = 0; s < nslots; ++s)
        if (slots[s] == v) return s;
      return -1;
    };
    while (ntris < kTableSlots && placed < rest.size()) {
      std::size_t best = rest.size();
      int best_new = 4;
      const std::size_t end = std::min(rest.size(), placed + kLookAhead);
      for (std::size_t i = placed; i < end && best_new > 0; ++i) {
        const Lane& t = rest[i];
        int added = 0;
        for (int k = 0; k < 3; ++k) {
          bool seen = slot_of(t.v[k]) >= 0;
          for (int j = 0; j < k && !seen; ++j) seen = t.v[j] == t.v[k];  // a corner repeated in the triangle
          added += seen ? 0 : 1;
        }
        if (nslots + added <= kTableSlots && added < best_new) best = i, best_new = added;
      }
      if (best == rest.size()) break;  // none fits
      const Lane t = rest[best];
      std::rotate(rest.begin() + static_cast<std::ptrdiff_t>(placed), rest.begin() + static_cast<std::ptrdiff_t>(best),
                  rest.begin() + static_cast<std::ptrdiff_t>(best) + 1);  // keeps the others' order
      ++placed;
      for (int k = 0; k < 3; ++k) {
        int s = slot_of(t.v[k]);
        if (s < 0) s = nslots, slots[nslots++] = t.v[k];
        corner[k][ntris] = static_cast<std::uint8_t>(s);
      }
      ids[ntris++] = t.id;
    }
    const auto pad = static_cast<std::uint8_t>(nslots < kTableSlots ? nslots : 0);  // a NaN slot if there is one
    for (int s = 0; s < kTableSlots; ++s) out.slot_vertices.push_back(s < nslots ? slots[s] : sentinel);
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < kTableSlots; ++l) out.corner_slots.push_back(l < ntris ? corner[k][l] : pad);
    for (int l = 0; l < kTableSlots; ++l) out.triangle_ids.push_back(l < ntris ? ids[l] : kNoTriangle);
    out.triangle_count.push_back(static_cast<std::uint8_t>(ntris));
  }
}

}  // namespace

TableLayout make_table_layout(std::span<const LeafRange> ranges, std::span<const std::uint32_t> lane_ids,
                              std::span<const std::uint32_t> corners, std::uint32_t sentinel) {
  if (corners.size() != 3 * lane_ids.size() || lane_ids.size() % 4 != 0)
    throw std::invalid_argument("make_table_layout: " + std::to_string(lane_ids.size()) + " lanes and " +
                                std::to_string(corners.size()) + " corner indices (4 lanes and 12 corners a block)");
  TableLayout out;
  out.group_offsets.reserve(ranges.size() + 1);
  out.group_offsets.push_back(0);
  std::vector<Lane> lanes;
  for (const LeafRange& r : ranges) {
    if ((std::size_t{r.first_block} + r.block_count) * 4 > lane_ids.size())
      throw std::invalid_argument("make_table_layout: a cluster's blocks beyond the lanes");
    lanes.clear();
    for (std::size_t b = r.first_block; b < std::size_t{r.first_block} + r.block_count; ++b)
      for (int l = 0; l < 4; ++l) {
        const std::uint32_t id = lane_ids[4 * b + l];
        if (id == kNoTriangle) continue;
        lanes.push_back({id, {corners[12 * b + l], corners[12 * b + 4 + l], corners[12 * b + 8 + l]}});
      }
    group_cluster(lanes, sentinel, out);
    out.group_offsets.push_back(static_cast<std::uint32_t>(out.group_count()));
  }
  return out;
}

void fill_tables_and_cluster_boxes(const TableLayout& layout, const float* fp, std::span<VertexTable> tables,
                                   Box3f* cluster_boxes, Vec3f* centres) {
  if (tables.size() != layout.group_count())
    throw std::invalid_argument("fill_tables_and_cluster_boxes: " + std::to_string(tables.size()) + " tables for " +
                                std::to_string(layout.group_count()) + " groups");
  const std::size_t C = layout.group_offsets.empty() ? 0 : layout.group_offsets.size() - 1;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, C, kClustersPerTask), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c < r.end(); ++c) {
      __m128 lo[3], hi[3];
      for (int a = 0; a < 3; ++a) lo[a] = _mm_set1_ps(kInf), hi[a] = _mm_set1_ps(-kInf);
      for (std::size_t g = layout.group_offsets[c]; g < layout.group_offsets[c + 1]; ++g) {
        const std::uint32_t* sv = layout.slot_vertices.data() + kTableSlots * g;
        VertexTable& t = tables[g];
        for (int q = 0; q < kTableSlots; q += 4) {
          // Four slots' (x y z .) by 16-byte loads (add_sentinel's extra element keeps the last in
          // the array), transposed to rows; the NaN sentinel's lanes drop out of the min and max
          // (_mm_min_ps(x, acc) returns acc for a NaN x).
          __m128 r0 = _mm_loadu_ps(fp + 3 * std::size_t{sv[q]}), r1 = _mm_loadu_ps(fp + 3 * std::size_t{sv[q + 1]});
          __m128 r2 = _mm_loadu_ps(fp + 3 * std::size_t{sv[q + 2]}), r3 = _mm_loadu_ps(fp + 3 * std::size_t{sv[q + 3]});
          _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
          _mm_stream_ps(&t.v[0][q], r0), _mm_stream_ps(&t.v[1][q], r1), _mm_stream_ps(&t.v[2][q], r2);
          lo[0] = _mm_min_ps(r0, lo[0]), lo[1] = _mm_min_ps(r1, lo[1]), lo[2] = _mm_min_ps(r2, lo[2]);
          hi[0] = _mm_max_ps(r0, hi[0]), hi[1] = _mm_max_ps(r1, hi[1]), hi[2] = _mm_max_ps(r2, hi[2]);
        }
      }
      if (cluster_boxes && centres) simd::fold_rows_store_widened(lo, hi, cluster_boxes[c], centres[c]);
    }
    _mm_sfence();
  });
}

}  // namespace ptc::bvh
