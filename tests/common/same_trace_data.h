// Two scenes' flat trace data compared byte for byte (the tests of scenes that must build the
// same BVH by different paths: thread counts, vertex orders, a scene built once).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "bvh/trace_data.h"

namespace ptc::bvh::test {

/// n objects at a and b, byte for byte (memcmp, whose pointers must not be null even for n = 0:
/// an empty scene's arrays have none).
template <class T>
bool same_bytes(const T* a, const T* b, std::size_t n) {
  return n == 0 || std::memcmp(a, b, n * sizeof(T)) == 0;
}

/// The flat data of two scenes, byte for byte: the 4-wide and 8-wide nodes, the leaf format, the
/// blocks or table groups, the lane ids and the leaf ranges, and the roots and depth.
inline void expect_same_data(const TraceData& d, const TraceData& w, const std::string& what) {
  ASSERT_EQ(d.wide.nodes.size(), w.wide.nodes.size()) << what;
  EXPECT_TRUE(same_bytes(d.wide.nodes.data(), w.wide.nodes.data(), w.wide.nodes.size())) << what;
  ASSERT_EQ(d.format, w.format) << what;
  ASSERT_EQ(d.blocks.size(), w.blocks.size()) << what;
  EXPECT_TRUE(same_bytes(d.blocks.data(), w.blocks.data(), w.blocks.size())) << what;
  ASSERT_EQ(d.tables.size(), w.tables.size()) << what;
  EXPECT_TRUE(same_bytes(d.tables.data(), w.tables.data(), w.tables.size())) << what;
  EXPECT_TRUE(std::equal(d.triangle_ids.begin(), d.triangle_ids.end(), w.triangle_ids.begin(), w.triangle_ids.end()))
      << what;
  ASSERT_EQ(d.ranges.size(), w.ranges.size()) << what;
  for (std::size_t i = 0; i < w.ranges.size(); ++i)
    ASSERT_TRUE(d.ranges[i].first_block == w.ranges[i].first_block && d.ranges[i].block_count == w.ranges[i].block_count &&
                d.ranges[i].triangle_count == w.ranges[i].triangle_count)
        << what << " range " << i;
  EXPECT_EQ(d.wide.root, w.wide.root) << what;
  ASSERT_EQ(d.wide8.nodes.size(), w.wide8.nodes.size()) << what;
  EXPECT_TRUE(same_bytes(d.wide8.nodes.data(), w.wide8.nodes.data(), w.wide8.nodes.size())) << what;
  EXPECT_EQ(d.wide8.root, w.wide8.root) << what;
  EXPECT_EQ(d.wide8.depth, w.wide8.depth) << what;
}

}  // namespace ptc::bvh::test
