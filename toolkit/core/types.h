// Basic value types shared by every layer.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products

namespace ptc {

/// A point or vector in 3D. Positions are stored in double: the hard cases (offsets of 1e7 with
/// features of 1e-3, scales of 1e-30) do not survive single precision. Layers that need floats
/// (the tracer, Embree) convert per frame.
using Vec3 = Eigen::Vector3d;

/// A triangle as three vertex indices into the mesh's position array.
using Tri = std::array<std::uint32_t, 3>;

/// Axis-aligned box in double precision. An empty box has lo = +inf, hi = -inf.
struct Box3 {
  Vec3 lo{Vec3::Constant(std::numeric_limits<double>::infinity())};
  Vec3 hi{Vec3::Constant(-std::numeric_limits<double>::infinity())};

  void extend(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void extend(const Box3& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  [[nodiscard]] bool empty() const { return !(lo.x() <= hi.x() && lo.y() <= hi.y() && lo.z() <= hi.z()); }
  [[nodiscard]] Vec3 extent() const { return empty() ? Vec3::Zero() : Vec3(hi - lo); }
  [[nodiscard]] Vec3 center() const { return 0.5 * (lo + hi); }
  /// Surface area 2(xy + yz + zx); 0 for an empty box.
  [[nodiscard]] double surface_area() const {
    const Vec3 e = extent();
    // A flat box whose other extents overflow (corners near +-1e308) has area inf, not inf x 0 = NaN.
    const auto face = [](double a, double b) { return a == 0.0 || b == 0.0 ? 0.0 : a * b; };
    return 2.0 * (face(e.x(), e.y()) + face(e.y(), e.z()) + face(e.z(), e.x()));
  }
};

}  // namespace ptc
