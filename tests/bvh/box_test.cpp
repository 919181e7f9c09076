// Boxes: outward rounding (double -> float), one-ulp widening, containment of both the double
// and the float triangle, on hard values (zeros, negatives, powers of two, far offsets).
#include "bvh/box.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <span>

#include "test_util.h"

namespace ptc::bvh {
namespace {

TEST(Box, RoundingDirections) {
  for (double x : {0.0, -0.0, 1.0, -1.0, 0.1, -0.1, 1e-45, -1e-45, 1e-50, -1e-50, 3.4e38, -3.4e38, 1e39, -1e39,
                   16777217.0, -16777217.0, 1e7 + 0.3}) {
    EXPECT_LE(double(round_down(x)), x) << x;
    EXPECT_GE(double(round_up(x)), x) << x;
    // tight: the next float inwards is on the other side (or x is exactly representable)
    if (double(round_down(x)) != x) {
      EXPECT_GT(double(std::nextafter(round_down(x), kInf)), x) << x;
    }
    if (double(round_up(x)) != x) {
      EXPECT_LT(double(std::nextafter(round_up(x), -kInf)), x) << x;
    }
  }
  EXPECT_EQ(round_down(1.0), 1.0f);
  EXPECT_EQ(round_up(1.0), 1.0f);
  EXPECT_EQ(next_below(0.0f), -std::numeric_limits<float>::denorm_min());
  EXPECT_EQ(next_above(-0.0f), std::numeric_limits<float>::denorm_min());
  EXPECT_EQ(next_below(1.0f), std::nextafter(1.0f, 0.0f));
  EXPECT_EQ(next_above(-1.0f), std::nextafter(-1.0f, 0.0f));
}

TEST(Box, BoxesContainDoubleAndFloatTriangles) {
  std::mt19937 g(5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (double scale : {1e-3, 1.0, 1e3}) {
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e7, -1e7, 3e6)}) {
      std::vector<Vec3> pos;
      std::vector<Tri> tris;
      for (std::uint32_t t = 0; t < 2000; ++t) {
        for (int k = 0; k < 3; ++k) pos.push_back(offset + scale * Vec3(U(g), U(g), U(g)));
        tris.push_back({3 * t, 3 * t + 1, 3 * t + 2});
      }
      pos.push_back(Vec3(0, 0, 0));  // an exact zero corner: the widening must cross zero
      pos.push_back(Vec3(-0.0, 1, 2));
      pos.push_back(Vec3(1, -0.0, 0));
      tris.push_back({6000, 6001, 6002});
      for (const Vec3& origin : {Vec3(0, 0, 0), offset}) {
        const auto exact = triangle_boxes(pos, tris, origin);
        AlignedVector<Vec3f> fp;
        frame_positions(pos, origin, fp);
        const auto widened = triangle_boxes(fp, tris);
        const auto cent = triangle_centroids(fp, tris);
        std::vector<std::uint32_t> offsets{0}, idx;
        for (const Tri& t : tris) idx.insert(idx.end(), t.begin(), t.end()), offsets.push_back(std::uint32_t(idx.size()));
        AlignedVector<Box3f> groups;
        point_group_boxes(fp, offsets, idx, groups);
        for (std::size_t t = 0; t < tris.size(); ++t) {
          ASSERT_TRUE(widened[t].contains(exact[t])) << t;
          EXPECT_EQ(groups[t], widened[t]);
          Box3f c;
          c.extend(cent[t]);
          EXPECT_TRUE(widened[t].contains(c));
          for (std::uint32_t v : tris[t]) {
            Box3f f;
            f.extend(fp[v]);
            EXPECT_TRUE(exact[t].contains(f));  // the float corner is inside the outward-rounded box
            for (int a = 0; a < 3; ++a) {       // and the double corner too
              EXPECT_LE(double(exact[t].lo[a]), pos[v][a] - origin[a]);
              EXPECT_GE(double(exact[t].hi[a]), pos[v][a] - origin[a]);
              EXPECT_LE(double(widened[t].lo[a]), pos[v][a] - origin[a]);
              EXPECT_GE(double(widened[t].hi[a]), pos[v][a] - origin[a]);
            }
          }
        }
      }
    }
  }
}

// The per-frame pass of a triangle scene: frame_positions, then triangle_boxes_and_centroids, in
// chunks on the caller's threads. The answers: to_frame per vertex, and triangle_boxes and
// triangle_centroids (one thread, the scalar centroid), bit for bit, at one, two and three
// threads, over 100,000 triangles with hard corners: signed zeros, subnormals, values near the
// float's largest (sums overflow to infinity alike), far offsets and repeated corners.
TEST(Box, FusedTrianglePassMatchesTheSeparateOnes) {
  std::mt19937 g(17);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::uniform_int_distribution<int> kind(0, 5);
  constexpr std::uint32_t T = 100000;
  std::vector<Vec3> pos;
  std::vector<Tri> tris;
  for (std::uint32_t t = 0; t < T; ++t) {
    const int k = kind(g);
    for (int c = 0; c < 3; ++c) {
      Vec3 p(U(g), U(g), U(g));
      if (k == 1) p *= 1e-41;                             // subnormal floats
      if (k == 2) p = Vec3(c == 0 ? -0.0 : 0.0, 0.0, -0.0);  // signed zeros, a point triangle
      if (k == 3) p *= 3e38;                              // the corners' sum overflows
      if (k == 4) p += Vec3(1e7, -1e7, 3e6);
      pos.push_back(p);
    }
    tris.push_back(k == 5 ? Tri{3 * t, 3 * t, 3 * t + 1} : Tri{3 * t, 3 * t + 1, 3 * t + 2});  // a repeated corner
  }
  const FrameMap origin{};
  AlignedVector<Vec3f> fp1;
  tbb::task_arena(1).execute([&] { frame_positions(pos, origin, fp1); });
  ASSERT_EQ(fp1.size(), pos.size());
  for (std::size_t v = 0; v < pos.size(); ++v) {
    const Vec3f e = to_frame(pos[v], origin);
    ASSERT_EQ(std::memcmp(&fp1[v], &e, sizeof(Vec3f)), 0) << v;
  }
  const auto boxes = triangle_boxes(fp1, tris);
  const auto cents = triangle_centroids(fp1, tris);
  tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 3);
  for (int threads : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    AlignedVector<Vec3f> fp;
    std::vector<Box3f> b(T);
    std::vector<Vec3f> c(T);
    tbb::task_arena(threads).execute([&] {
      frame_positions(pos, origin, fp);
      triangle_boxes_and_centroids(fp, tris, b, c);
    });
    ASSERT_EQ(std::memcmp(fp.data(), fp1.data(), fp1.size() * sizeof(Vec3f)), 0);
    for (std::uint32_t t = 0; t < T; ++t) {
      ASSERT_EQ(std::memcmp(&b[t], &boxes[t], sizeof(Box3f)), 0) << t;
      ASSERT_EQ(std::memcmp(&c[t], &cents[t], sizeof(Vec3f)), 0) << t;
    }
  }
}

TEST(Box, EmptyAndDegenerate) {
  Box3f e;
  EXPECT_TRUE(e.empty());
  EXPECT_EQ(e.surface_area(), 0.0);
  Box3f p;
  p.extend(Vec3f{1, 2, 3});
  EXPECT_FALSE(p.empty());
  EXPECT_EQ(p.surface_area(), 0.0);
  EXPECT_TRUE(p.contains(e));
  EXPECT_TRUE(union_of({}).empty());
  AlignedVector<Box3f> g;
  const std::vector<std::uint32_t> offs{0, 0};
  point_group_boxes(std::span<const Vec3f>(), offs, {}, g);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_TRUE(g[0].empty());
}

// The fused per-frame box update (boxes and centres in one pass, 16-byte loads) equals the
// plain one and Box3f::center() bit for bit: empty groups, single vertices, groups that end
// with the last vertex of the array (where a 16-byte load would read past the end), negative
// and zero coordinates, and reused output vectors of another size.
TEST(Box, FusedGroupBoxesEqualThePlainOnes) {
  std::mt19937 g(11);
  std::uniform_real_distribution<float> U(-5.0f, 5.0f);
  std::vector<Vec3f> fp(101);
  for (Vec3f& p : fp) p = {U(g), U(g), U(g)};
  fp[7] = {0.0f, -0.0f, 0.0f};
  const auto last = static_cast<std::uint32_t>(fp.size() - 1);
  const std::vector<std::uint32_t> offsets{0, 0, 1, 4, 4, 9, 11, 12};
  const std::vector<std::uint32_t> indices{last, 7, 3, last, 1, 2, 3, 4, 5, 50, last, last};
  AlignedVector<Box3f> plain, fused(3);
  AlignedVector<Vec3f> centers(1);
  point_group_boxes(fp, offsets, indices, plain);
  point_group_boxes(fp, offsets, indices, fused, centers);
  ASSERT_EQ(fused.size(), offsets.size() - 1);
  ASSERT_EQ(centers.size(), fused.size());
  const auto want_centers = box_centers(plain);
  for (std::size_t i = 0; i < fused.size(); ++i) {
    EXPECT_EQ(fused[i], plain[i]) << i;
    for (int a = 0; a < 3; ++a) {
      if (plain[i].empty()) continue;  // (the centre of the empty box is NaN)
      EXPECT_EQ(centers[i][a], want_centers[i][a]) << i;
    }
  }
  EXPECT_TRUE(fused[0].empty());
  EXPECT_TRUE(fused[3].empty());
  // Independent check: every group's box contains its points and is at most one ulp loose.
  for (std::size_t gi = 0; gi + 1 < offsets.size(); ++gi)
    for (std::uint32_t i = offsets[gi]; i < offsets[gi + 1]; ++i)
      for (int a = 0; a < 3; ++a) {
        EXPECT_LT(fused[gi].lo[a], fp[indices[i]][a]);
        EXPECT_GT(fused[gi].hi[a], fp[indices[i]][a]);
      }
}

// The group boxes made from the doubles (each point converted where it is read, groups on the
// caller's threads) equal those of the float overload over frame_positions, bit for bit, with
// their centres: a far origin and a scale, zeros of both signs on one axis (the widening maps
// both alike, whatever the order of min and max), repeated and empty groups, and more groups
// than one chunk, at one and two threads.
TEST(Box, GroupBoxesFromDoublesEqualThoseOverTheFramePositions) {
  std::mt19937 g(23);
  std::uniform_real_distribution<double> U(-3.0, 3.0);
  const FrameMap frame(Vec3(0.0, -2.5e6, 1e7), 0.125);  // (x about 0: zeros in the frame)
  std::vector<Vec3> pos(500);
  for (Vec3& p : pos) p = frame.origin + Vec3(U(g), U(g), U(g));
  pos[3].x() = 0.0;   // +0 in the frame
  pos[4].x() = -0.0;  // -0 in the frame
  std::vector<std::uint32_t> offsets{0}, indices;
  std::uniform_int_distribution<std::uint32_t> V(0, static_cast<std::uint32_t>(pos.size() - 1)), N(0, 9);
  for (int k = 0; k < 3000; ++k) {  // (3000 groups: three chunks of 1024)
    const std::uint32_t n = k % 97 == 0 ? 0 : N(g);
    for (std::uint32_t i = 0; i < n; ++i) indices.push_back(k % 5 == 0 ? (i % 2 ? 3u : 4u) : V(g));
    offsets.push_back(static_cast<std::uint32_t>(indices.size()));
  }
  AlignedVector<Vec3f> fp;
  frame_positions(pos, frame, fp);
  AlignedVector<Box3f> want, got;
  AlignedVector<Vec3f> want_c, got_c;
  point_group_boxes(fp, offsets, indices, want, want_c);
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    point_group_boxes(pos, frame, offsets, indices, got, got_c);
    ASSERT_EQ(got.size(), want.size());
    ASSERT_EQ(got_c.size(), want.size());
    for (std::size_t i = 0; i < want.size(); ++i) {
      ASSERT_EQ(std::memcmp(&got[i], &want[i], sizeof(Box3f)), 0) << "group " << i << " threads " << threads;
      ASSERT_EQ(std::memcmp(&got_c[i], &want_c[i], sizeof(Vec3f)), 0) << "group " << i << " threads " << threads;
    }
  }
  EXPECT_TRUE(got[0].empty());
}

// A vertex beyond the float range is named with its coordinates in %g form (they were printed with
// %f: a 768-byte line of digits for 1e300).
TEST(Box, NotFiniteVertexIsNamedShortly) {
  const std::vector<Vec3> pos = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1e300, -1e300, 0.5)};
  try {
    throw_not_finite(pos, FrameMap());
    FAIL() << "no error";
  } catch (const FrameRangeError& e) {
    EXPECT_EQ(std::string(e.what()),
              "vertex 2: position (1e+300, -1e+300, 0.5) is not finite in single precision (NaN, infinite, or beyond "
              "the float range in the trace frame)");
  }
}

}  // namespace
}  // namespace ptc::bvh
