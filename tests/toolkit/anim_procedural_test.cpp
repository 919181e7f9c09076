// Procedural deformers and subdivision carrying an animation, against independent answers:
// hand-written formulas (Rodrigues rotation, Barr's bend in its (R - w) form), exact identities
// at zero amplitude, edge lengths under rigid motion, per-triangle areas under explode, and
// per-frame subdivision (a separate Subdivider per frame, and midpoints computed by hand).
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/subdivided.h"
#include "toolkit/anim/cloth.h"

#include <gtest/gtest.h>

#include <oneapi/tbb/global_control.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"
#include "toolkit/mesh/topology.h"

namespace ptc {
namespace {

constexpr double kPi = std::numbers::pi;

// A closed random-ish surface: a UV sphere, squashed and offset, so the box is not a cube and
// the centre is not the origin.
Mesh uv_sphere(int rings, int segs, const Vec3& offset, const Vec3& scale) {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  p.push_back(offset + Vec3(0, scale.y(), 0));
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segs; ++j) {
      const double th = kPi * i / rings, ph = 2 * kPi * j / segs;
      p.push_back(offset + Vec3(scale.x() * std::sin(th) * std::cos(ph), scale.y() * std::cos(th),
                                scale.z() * std::sin(th) * std::sin(ph)));
    }
  p.push_back(offset + Vec3(0, -scale.y(), 0));
  const auto S = static_cast<std::uint32_t>(segs);
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(1 + (i - 1) * segs + (j % segs)); };
  for (int j = 0; j < segs; ++j) t.push_back({0, id(1, j + 1), id(1, j)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segs; ++j) {
      t.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      t.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  const auto last = static_cast<std::uint32_t>(p.size() - 1);
  for (int j = 0; j < segs; ++j) t.push_back({last, id(rings - 1, j), id(rings - 1, j + 1)});
  (void)S;
  return Mesh(std::move(t), std::move(p));
}

Mesh test_mesh() { return uv_sphere(12, 16, Vec3(3.0, -2.0, 7.5), Vec3(1.0, 2.5, 0.6)); }

std::vector<Vec3> frame(Animation& a, double t) {
  std::vector<Vec3> out(a.rest().vertex_count());
  a.positions(t, out);
  return out;
}

double area(const Vec3& a, const Vec3& b, const Vec3& c) { return 0.5 * (b - a).cross(c - a).norm(); }

// ---------------------------------------------------------------------------------------------
// Bad input first

TEST(Deformers, RejectsBadParametersAndMeshes) {
  DeformParams p;
  p.period = 0;
  EXPECT_THROW((void)make_deformer(test_mesh(), p), InputError);
  p = {};
  p.kind = DeformKind::Bend;
  p.axis = p.direction = 1;
  EXPECT_THROW((void)make_deformer(test_mesh(), p), InputError);
  p = {};
  p.amplitude = std::nan("");
  EXPECT_THROW((void)make_deformer(test_mesh(), p), InputError);
  p = {};
  p.kind = DeformKind::Wave;
  p.direction = 0;
  p.wavelength = -1;
  EXPECT_THROW((void)make_deformer(test_mesh(), p), InputError);
  EXPECT_THROW((void)make_deformer(Mesh(), DeformParams{}), InputError);
  Mesh nan_mesh({{0, 1, 2}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, std::nan(""), 0)});
  EXPECT_THROW((void)make_deformer(nan_mesh, DeformParams{}), InputError);

  auto d = make_deformer(test_mesh(), DeformParams{});
  std::vector<Vec3> wrong(d->rest().vertex_count() + 1);
  EXPECT_THROW(d->positions(0, wrong), std::invalid_argument);
  std::vector<Vec3> ok(d->rest().vertex_count());
  EXPECT_THROW(d->positions(std::nan(""), ok), std::invalid_argument);
  EXPECT_THROW(d->positions(INFINITY, ok), std::invalid_argument);
}

TEST(Deformers, ParseNames) {
  EXPECT_EQ(parse_deform_kind("explode"), DeformKind::Explode);
  EXPECT_EQ(parse_deform_kind("Twist"), std::nullopt);
  EXPECT_EQ(parse_axis("z"), 2);
  EXPECT_EQ(parse_axis("w"), std::nullopt);
  for (auto k : {DeformKind::Twist, DeformKind::Bend, DeformKind::Wave, DeformKind::Rigid, DeformKind::Explode})
    EXPECT_EQ(parse_deform_kind(to_string(k)), k);
}

// ---------------------------------------------------------------------------------------------
// Identity at zero amplitude (bit-exact), and at frame 0 for the oscillating kinds

TEST(Deformers, ZeroAmplitudeIsIdentity) {
  // Also a mesh whose rest positions are not exactly c + (p - c) (c its box centre): far from the
  // origin, with a third of a unit in it (the armadillo's frame 0 was 3.5e-15 off its rest pose).
  for (const Mesh& m : {test_mesh(), uv_sphere(9, 13, Vec3(1000.0 / 3.0, -0.1, 77.7), Vec3(0.3, 5.0 / 3.0, 2.2))}) {
  for (auto k : {DeformKind::Twist, DeformKind::Bend, DeformKind::Wave, DeformKind::Rigid, DeformKind::Explode}) {
    for (int axis = 0; axis < 3; ++axis) {
      DeformParams p;
      p.kind = k;
      p.axis = axis;
      p.direction = (axis + 1) % 3;
      p.amplitude = 0;
      auto d = make_deformer(m, p);
      for (double t : {0.0, 1.0, 13.7, 1e6}) {
        const auto f = frame(*d, t);
        const auto r = d->rest().positions();
        for (std::size_t i = 0; i < f.size(); ++i)
          ASSERT_EQ(f[i], r[i]) << to_string(k) << " axis " << axis << " t " << t << " vertex " << i;
      }
    }
  }
  // Twist and bend oscillate as sin(2 pi t / period), rigid turns by amplitude 2 pi t / period:
  // frame 0 is the rest pose, bit for bit.
  for (auto k : {DeformKind::Twist, DeformKind::Bend, DeformKind::Rigid}) {
    DeformParams p;
    p.kind = k;
    p.direction = 0;
    p.amplitude = 1.3;
    if (k == DeformKind::Rigid) p.velocity = Vec3(0.1, 0.02, 0.0);
    auto d = make_deformer(m, p);
    const auto f = frame(*d, 0.0);
    for (std::size_t i = 0; i < f.size(); ++i) ASSERT_EQ(f[i], m.position(i)) << to_string(k);
  }
  // A rigid motion without rotation is a translation: every vertex moved by the same vector.
  DeformParams p;
  p.kind = DeformKind::Rigid;
  p.amplitude = 0.0;
  p.velocity = Vec3(0.1, -0.3, 0.05);
  auto d = make_deformer(m, p);
  const auto f = frame(*d, 7.0);
  const Vec3 move = p.velocity * m.bounds().extent().norm() * 7.0;
  for (std::size_t i = 0; i < f.size(); ++i) ASSERT_EQ(f[i], m.position(i) + move);
  }
}

TEST(Deformers, FlatMeshAlongTheAxisDoesNotDivideByZero) {
  // Every vertex at y = 4: the box has zero extent along y.
  Mesh flat({{0, 1, 2}, {0, 2, 3}}, {Vec3(0, 4, 0), Vec3(1, 4, 0), Vec3(1, 4, 1), Vec3(0, 4, 1)});
  for (auto k : {DeformKind::Twist, DeformKind::Bend, DeformKind::Wave}) {
    DeformParams p;
    p.kind = k;
    p.axis = 1;
    p.direction = 0;
    auto d = make_deformer(flat, p);
    for (const Vec3& q : frame(*d, 7.0)) EXPECT_TRUE(q.allFinite()) << to_string(k);
  }
}

// ---------------------------------------------------------------------------------------------
// Against hand-written formulas

TEST(Deformers, TwistMatchesRodriguesRotation) {
  const Mesh m = test_mesh();
  DeformParams p;
  p.kind = DeformKind::Twist;
  p.axis = 1;
  p.amplitude = 0.9;
  p.period = 40;
  auto d = make_deformer(m, p);
  const double t = 7.0;
  const auto f = frame(*d, t);
  const Box3 b = m.bounds();
  const Vec3 c = b.center();
  for (std::size_t i = 0; i < f.size(); ++i) {
    const Vec3 q = m.position(i);
    const double u = (q.y() - c.y()) / (0.5 * (b.hi.y() - b.lo.y()));
    const double ang = 0.9 * std::sin(2 * kPi * t / 40) * u;
    // Rodrigues about k = +y through c: v cos + (k x v) sin + k (k.v)(1 - cos)
    const Vec3 v = q - c, k = Vec3::UnitY();
    const Vec3 expect = c + v * std::cos(ang) + k.cross(v) * std::sin(ang) + k * k.dot(v) * (1 - std::cos(ang));
    ASSERT_LT((f[i] - expect).norm(), 1e-12 * (1 + c.norm())) << i;
  }
}

TEST(Deformers, BendMatchesBarrFormula) {
  const Mesh m = test_mesh();
  for (double amp : {1e-9, 0.4, kPi}) {
    DeformParams p;
    p.kind = DeformKind::Bend;
    p.axis = 1;
    p.direction = 2;
    p.amplitude = amp;
    p.period = 40;
    auto d = make_deformer(m, p);
    const double t = 10;  // s(t) = 1
    const auto f = frame(*d, t);
    const Box3 b = m.bounds();
    const Vec3 c = b.center();
    const double k = amp / (b.hi.y() - b.lo.y()), R = 1 / k;
    for (std::size_t i = 0; i < f.size(); ++i) {
      const Vec3 q = m.position(i);
      const double x = q.y() - c.y(), w = q.z() - c.z(), th = k * x;
      // Barr's bend in its direct form (cancels badly for tiny k, hence the looser bound there).
      const Vec3 expect(q.x(), c.y() + (R - w) * std::sin(th), c.z() + R - (R - w) * std::cos(th));
      const double tol = amp < 1e-6 ? 1e-6 : 1e-11;
      ASSERT_LT((f[i] - expect).norm(), tol) << "amp " << amp << " vertex " << i;
    }
  }
}

TEST(Deformers, WaveMatchesFormula) {
  const Mesh m = test_mesh();
  DeformParams p;
  p.kind = DeformKind::Wave;
  p.axis = 0;
  p.direction = 1;
  p.amplitude = 0.05;
  p.wavelength = 0.3;
  p.period = 25;
  auto d = make_deformer(m, p);
  const Box3 b = m.bounds();
  const double diag = b.extent().norm(), L = 0.3 * (b.hi.x() - b.lo.x());
  for (double t : {0.0, 3.5, 30.0}) {
    const auto f = frame(*d, t);
    for (std::size_t i = 0; i < f.size(); ++i) {
      const Vec3 q = m.position(i);
      const Vec3 expect = q + Vec3(0, 0.05 * diag * std::sin(2 * kPi * ((q.x() - b.lo.x()) / L - t / 25)), 0);
      ASSERT_LT((f[i] - expect).norm(), 1e-12 * 10) << i;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Rigid motion: every edge length unchanged to rounding; the motion is the one asked for

TEST(Deformers, RigidMotionKeepsEveryEdgeLength) {
  // Far from the origin and tiny: offsets of 1e5, features of 1e-3.
  for (const Mesh& m : {test_mesh(), uv_sphere(10, 12, Vec3(1e5, -2e5, 3e5), Vec3(1e-3, 2e-3, 5e-4))}) {
    const EdgeMap edges = EdgeMap::build(m.triangles(), m.vertex_count());
    for (int axis = 0; axis < 3; ++axis) {
      DeformParams p;
      p.kind = DeformKind::Rigid;
      p.axis = axis;
      p.amplitude = 1.0;
      p.period = 17;
      p.velocity = Vec3(0.3, -0.1, 0.05);
      auto d = make_deformer(m, p);
      for (double t : {0.5, 4.25, 100.0}) {
        const auto f = frame(*d, t);
        // Rounding bound: a few ulps of the largest coordinate magnitude (the rotation runs on
        // p - c, the result is added back to c + move, each rounding to ulp(|coordinate|)).
        double mag = 0;
        for (const Vec3& q : f) mag = std::max(mag, q.cwiseAbs().maxCoeff());
        for (const Vec3& q : m.positions()) mag = std::max(mag, q.cwiseAbs().maxCoeff());
        const double tol = 16 * std::numeric_limits<double>::epsilon() * mag;
        double worst = 0;
        for (const Edge& e : edges.edges()) {
          const double l0 = (m.position(e.v0) - m.position(e.v1)).norm();
          const double l1 = (f[e.v0] - f[e.v1]).norm();
          worst = std::max(worst, std::abs(l1 - l0));
        }
        EXPECT_LE(worst, tol) << "axis " << axis << " t " << t;
        // The rotation is real: the centroid moved by velocity * diag * t, and a vertex off the
        // axis turned by 2 pi t / period about it.
        const Vec3 c = m.bounds().center();
        const double ang = 2 * kPi * t / 17;
        const Vec3 move = p.velocity * m.bounds().extent().norm() * t;
        const Vec3 v = m.position(5) - c, k = Vec3::Unit(axis);
        const Vec3 expect = c + move + v * std::cos(ang) + k.cross(v) * std::sin(ang) + k * k.dot(v) * (1 - std::cos(ang));
        EXPECT_LT((f[5] - expect).norm(), 1e-9 * (1 + c.norm())) << "axis " << axis << " t " << t;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Explode: a soup with the same triangles, each translated rigidly along its normal

TEST(Deformers, ExplodeKeepsTriangleCountAndAreas) {
  const Mesh m = test_mesh();
  DeformParams p;
  p.kind = DeformKind::Explode;
  p.amplitude = 0.01;
  auto d = make_deformer(m, p);
  const Mesh& soup = d->rest();
  ASSERT_EQ(soup.triangle_count(), m.triangle_count());
  ASSERT_EQ(soup.vertex_count(), 3 * m.triangle_count());
  const double diag = m.bounds().extent().norm();
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(soup.triangle(t)[k], 3 * t + k);
      ASSERT_EQ(soup.position(3 * t + k), m.corners(t)[k]);  // same corners, same order
    }
  for (double t : {1.0, 25.0, 500.0}) {
    const auto f = frame(*d, t);
    for (std::size_t tri = 0; tri < m.triangle_count(); ++tri) {
      const auto c = m.corners(tri);
      const Vec3 a = f[3 * tri], b = f[3 * tri + 1], e = f[3 * tri + 2];
      const double a0 = area(c[0], c[1], c[2]);
      ASSERT_NEAR(area(a, b, e), a0, 1e-9 * (a0 + diag * diag * 1e-6)) << tri;
      // One translation for the three corners, along the unit normal, by 0.5..1.5 x 0.01 diag t.
      const Vec3 move = a - c[0];
      ASSERT_LT((b - c[1] - move).norm(), 1e-9 * (1 + move.norm()));
      ASSERT_LT((e - c[2] - move).norm(), 1e-9 * (1 + move.norm()));
      const Vec3 n = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
      ASSERT_GT(move.normalized().dot(n), 1 - 1e-9);
      const double dist = move.norm() / (0.01 * diag * t);
      ASSERT_GE(dist, 0.5 - 1e-9);
      ASSERT_LT(dist, 1.5);
    }
  }
}

TEST(Deformers, ExplodeOfDegenerateTriangleStaysFinite) {
  // A zero-area triangle (three collinear corners) next to a normal one.
  Mesh m({{0, 1, 2}, {0, 1, 3}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(0, 1, 0)});
  DeformParams p;
  p.kind = DeformKind::Explode;
  auto d = make_deformer(m, p);
  for (const Vec3& q : frame(*d, 3.0)) EXPECT_TRUE(q.allFinite());
}

TEST(Deformers, SameResultOnOneThreadAndAll) {
  const Mesh big = subdivide(test_mesh(), SubdivisionScheme::Midpoint, 3);  // > grain size
  for (auto k : {DeformKind::Twist, DeformKind::Bend, DeformKind::Wave, DeformKind::Rigid, DeformKind::Explode}) {
    DeformParams p;
    p.kind = k;
    p.direction = 2;
    auto d = make_deformer(big, p);
    const auto all = frame(*d, 11.0);
    std::vector<Vec3> one;
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
      one = frame(*d, 11.0);
    }
    ASSERT_EQ(all, one) << to_string(k);
  }
}

// ---------------------------------------------------------------------------------------------
// Subdivision carrying an animation equals subdividing each frame separately

TEST(Subdivided, CarriedAnimationMatchesPerFrameSubdivision) {
  const Mesh m = test_mesh();
  for (auto scheme : {SubdivisionScheme::Midpoint, SubdivisionScheme::Loop}) {
    for (int levels : {0, 1, 2}) {
      DeformParams p;
      p.kind = DeformKind::Twist;
      p.amplitude = 1.1;
      SubdividedAnimation carried(make_deformer(m, p), scheme, levels);
      auto plain = make_deformer(m, p);
      ASSERT_EQ(carried.rest().triangle_count(), m.triangle_count() << (2 * levels));
      EXPECT_FALSE(carried.is_static());
      EXPECT_EQ(carried.frame_count(), 0u);
      for (double t : {0.0, 4.5, 9.0, 2.0}) {
        const auto f = frame(carried, t);
        const Mesh per_frame = subdivide(m.with_positions(frame(*plain, t)), scheme, levels);
        ASSERT_EQ(f.size(), per_frame.vertex_count());
        for (std::size_t i = 0; i < f.size(); ++i)
          ASSERT_EQ(f[i], per_frame.position(i)) << to_string(scheme) << " levels " << levels << " t " << t << " v " << i;
        const auto tr = carried.rest().triangles();
        const auto tp = per_frame.triangles();
        ASSERT_TRUE(std::equal(tr.begin(), tr.end(), tp.begin(), tp.end()));
      }
    }
  }
}

TEST(Subdivided, MidpointEqualsHandComputedMidpointsOfEachFrame) {
  // Independent of the Subdivider: one midpoint level, child 4t + 3 = (m0, m1, m2) of the
  // parent's frame positions, so its corners are the midpoints of the parent's sides.
  ClothParams cp;
  cp.resolution = 6;
  SubdividedAnimation carried(std::make_unique<ClothSimulation>(cp), SubdivisionScheme::Midpoint, 1);
  ClothSimulation plain(cp);
  for (double t : {0.0, 3.0, 7.0}) {
    const auto f = frame(carried, t);
    const auto g = frame(plain, t);
    const Mesh& r = carried.rest();
    for (std::size_t tri = 0; tri < plain.rest().triangle_count(); ++tri) {
      const Tri& P = plain.rest().triangle(tri);
      const Tri& C = r.triangle(4 * tri + 3);
      for (int k = 0; k < 3; ++k) {
        const Vec3 mid = 0.5 * (g[P[k]] + g[P[(k + 1) % 3]]);
        ASSERT_LT((f[C[k]] - mid).norm(), 1e-15 * (1 + mid.norm())) << "t " << t << " tri " << tri;
      }
    }
  }
}

TEST(Subdivided, LoopOnNonManifoldSourceIsAnInputError) {
  // Three triangles on one edge.
  Mesh book({{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1)});
  EXPECT_THROW(SubdividedAnimation(make_deformer(book, DeformParams{}), SubdivisionScheme::Loop, 1), InputError);
  EXPECT_NO_THROW(SubdividedAnimation(make_deformer(book, DeformParams{}), SubdivisionScheme::Midpoint, 1));
}

}  // namespace
}  // namespace ptc
