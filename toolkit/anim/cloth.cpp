#include "toolkit/anim/cloth.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "toolkit/core/error.h"

namespace ptc {
namespace {

template <class F>
void parallel_range(std::size_t begin, std::size_t end, std::size_t grain, F&& f) {
  if (end - begin <= grain) {
    f(begin, end);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); });
}

bool in01(double x) { return x >= 0.0 && x <= 1.0; }

}  // namespace

std::string check(const ClothParams& p) {
  if (p.resolution < 2) return "resolution must be >= 2";
  if (p.resolution > 46341) return "resolution too large for 32-bit vertex indices";
  if (!(p.size > 0 && std::isfinite(p.size))) return "size must be > 0";
  if (!p.sphere_center.allFinite()) return "sphere centre must be finite";
  if (!(p.sphere_radius > 0 && std::isfinite(p.sphere_radius))) return "sphere radius must be > 0";
  if (!(p.drop >= 0 && std::isfinite(p.drop))) return "drop must be >= 0";
  if (!std::isfinite(p.offset)) return "offset must be finite";
  if (!(p.gravity >= 0 && std::isfinite(p.gravity))) return "gravity must be >= 0";
  if (!(p.fps > 0 && std::isfinite(p.fps))) return "fps must be > 0";
  if (p.substeps < 1 || p.substeps > 1000) return "substeps must be in 1..1000";
  if (p.iterations < 1 || p.iterations > 1000) return "iterations must be in 1..1000";
  if (!in01(p.stretch_stiffness) || !in01(p.shear_stiffness) || !in01(p.bend_stiffness))
    return "stiffnesses must be in [0, 1]";
  if (!(p.damping >= 0 && std::isfinite(p.damping))) return "damping must be >= 0";
  if (!in01(p.friction)) return "friction must be in [0, 1]";
  if (!(p.thickness >= 0 && std::isfinite(p.thickness))) return "thickness must be >= 0";
  return {};
}

ClothSimulation::ClothSimulation(const ClothParams& params) : p_(params) {
  if (const std::string why = check(p_); !why.empty()) throw InputError("", "", "cloth", why);
  const std::size_t n = static_cast<std::size_t>(p_.resolution);
  const double a = p_.size / double(n - 1);
  thickness_ = p_.thickness > 0 ? p_.thickness : a / 4;

  // Rest grid.
  std::vector<Vec3> pos(n * n);
  const Vec3 c0 = p_.sphere_center + Vec3(p_.offset, p_.sphere_radius + thickness_ + p_.drop, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      pos[i * n + j] = c0 + Vec3(-0.5 * p_.size + a * double(j), 0.0, -0.5 * p_.size + a * double(i));
  std::vector<Tri> tris;
  tris.reserve(2 * (n - 1) * (n - 1));
  auto id = [n](std::size_t i, std::size_t j) { return static_cast<std::uint32_t>(i * n + j); };
  for (std::size_t i = 0; i + 1 < n; ++i)
    for (std::size_t j = 0; j + 1 < n; ++j) {
      // Facing +y (counter-clockwise seen from above): z grows with i, x with j.
      tris.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      tris.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
    }
  rest_ = Mesh(std::move(tris), std::move(pos));

  // Constraints in colour classes. A class lists constraints whose particles are disjoint.
  auto add_group = [&](double k, auto&& fill) {
    const std::size_t b = constraints_.size();
    fill();
    if (constraints_.size() > b) groups_.push_back({b, constraints_.size(), k});
  };
  const double diag = a * std::sqrt(2.0);
  // Stretch: horizontal (i, j)-(i, j+1), classes by j parity; vertical by i parity.
  for (std::size_t par = 0; par < 2; ++par)
    add_group(p_.stretch_stiffness, [&] {
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = par; j + 1 < n; j += 2) constraints_.push_back({id(i, j), id(i, j + 1), a});
    });
  for (std::size_t par = 0; par < 2; ++par)
    add_group(p_.stretch_stiffness, [&] {
      for (std::size_t i = par; i + 1 < n; i += 2)
        for (std::size_t j = 0; j < n; ++j) constraints_.push_back({id(i, j), id(i + 1, j), a});
    });
  // Shear: diagonals (i, j)-(i+1, j+1), then anti-diagonals (i, j+1)-(i+1, j); a class takes the
  // rows i of one parity: in a row each particle ends exactly one diagonal of the direction.
  for (std::size_t par = 0; par < 2; ++par)
    add_group(p_.shear_stiffness, [&] {
      for (std::size_t i = par; i + 1 < n; i += 2)
        for (std::size_t j = 0; j + 1 < n; ++j) constraints_.push_back({id(i, j), id(i + 1, j + 1), diag});
    });
  for (std::size_t par = 0; par < 2; ++par)
    add_group(p_.shear_stiffness, [&] {
      for (std::size_t i = par; i + 1 < n; i += 2)
        for (std::size_t j = 0; j + 1 < n; ++j) constraints_.push_back({id(i, j + 1), id(i + 1, j), diag});
    });
  // Bending: (i, j)-(i, j+2), classes by j mod 4 in {0,1} / {2,3}; columns alike.
  if (p_.bend_stiffness > 0) {
    for (std::size_t cls = 0; cls < 2; ++cls)
      add_group(p_.bend_stiffness, [&] {
        for (std::size_t i = 0; i < n; ++i)
          for (std::size_t j = 0; j + 2 < n; ++j)
            if ((j / 2) % 2 == cls) constraints_.push_back({id(i, j), id(i, j + 2), 2 * a});
      });
    for (std::size_t cls = 0; cls < 2; ++cls)
      add_group(p_.bend_stiffness, [&] {
        for (std::size_t i = 0; i + 2 < n; ++i)
          if ((i / 2) % 2 == cls)
            for (std::size_t j = 0; j < n; ++j) constraints_.push_back({id(i, j), id(i + 2, j), 2 * a});
      });
  }
  reset();
}

void ClothSimulation::reset() {
  const auto r = rest_.positions();
  x_.assign(r.begin(), r.end());
  v_.assign(x_.size(), Vec3::Zero());
  pred_.assign(x_.size(), Vec3::Zero());
  prev_frame_.assign(r.begin(), r.end());
  frame_ = 0;
}

void ClothSimulation::project_collisions(std::size_t begin, std::size_t end) {
  const double R = p_.sphere_radius + thickness_;
  const double floor_y = p_.sphere_center.y() - p_.sphere_radius + thickness_;
  for (std::size_t i = begin; i < end; ++i) {
    Vec3& q = pred_[i];
    const Vec3 d = q - p_.sphere_center;
    const double len2 = d.squaredNorm();
    if (len2 < R * R) {
      const double len = std::sqrt(len2);
      // A particle exactly at the centre is pushed straight up (any direction is as good).
      q = len > 0 ? Vec3(p_.sphere_center + d * (R / len)) : Vec3(p_.sphere_center + Vec3(0, R, 0));
    }
    if (p_.floor && q.y() < floor_y) q.y() = floor_y;
  }
}

void ClothSimulation::substep(double h) {
  const std::size_t N = x_.size();
  const Vec3 g(0.0, -p_.gravity, 0.0);
  const double keep = std::max(0.0, 1.0 - p_.damping * h);
  parallel_range(0, N, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      v_[i] = (v_[i] + h * g) * keep;
      pred_[i] = x_[i] + h * v_[i];
    }
  });
  for (int it = 0; it < p_.iterations; ++it) {
    for (const Group& grp : groups_) {
      const double k = grp.stiffness;
      if (k == 0) continue;
      parallel_range(grp.begin, grp.end, 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t c = b; c < e; ++c) {
          const Constraint& con = constraints_[c];
          Vec3& p = pred_[con.i];
          Vec3& q = pred_[con.j];
          const Vec3 d = q - p;
          const double len = d.norm();
          if (!(len > 0)) continue;  // coincident particles: no direction to correct along
          const Vec3 corr = (0.5 * k * (len - con.rest) / len) * d;
          p += corr;
          q -= corr;
        }
      });
    }
    parallel_range(0, N, 4096, [&](std::size_t b, std::size_t e) { project_collisions(b, e); });
  }
  // Velocity update and contact friction.
  const double R = p_.sphere_radius + thickness_;
  const double floor_y = p_.sphere_center.y() - p_.sphere_radius + thickness_;
  const double contact_eps = 1e-9 * (1.0 + R);
  parallel_range(0, N, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      Vec3 v = (pred_[i] - x_[i]) / h;
      Vec3 nrm = Vec3::Zero();
      const Vec3 d = pred_[i] - p_.sphere_center;
      if (d.norm() <= R + contact_eps)
        nrm = d.normalized();
      else if (p_.floor && pred_[i].y() <= floor_y + contact_eps)
        nrm = Vec3::UnitY();
      if (nrm.squaredNorm() > 0) {
        double vn = v.dot(nrm);
        const Vec3 vt = v - vn * nrm;
        vn = std::max(vn, 0.0);  // no velocity into the obstacle
        v = vn * nrm + (1.0 - p_.friction) * vt;
      }
      v_[i] = v;
      x_[i] = pred_[i];
    }
  });
}

void ClothSimulation::step_frame() {
  std::copy(x_.begin(), x_.end(), prev_frame_.begin());
  const double h = 1.0 / (p_.fps * p_.substeps);
  for (int s = 0; s < p_.substeps; ++s) substep(h);
  ++frame_;
}

void ClothSimulation::positions(double frame, std::span<Vec3> out) {
  if (!std::isfinite(frame) || frame < 0)
    throw std::invalid_argument("positions: cloth frame time must be finite and >= 0");
  if (out.size() != x_.size())
    throw std::invalid_argument(
        fmt::format("positions: output holds {} vertices, the source has {}", out.size(), x_.size()));
  const auto target = static_cast<std::int64_t>(std::ceil(frame));
  if (target < frame_) reset();
  while (frame_ < target) step_frame();
  const double f = frame - double(target - 1);  // weight of the current frame, in (0, 1]
  if (target == 0 || f >= 1.0) {
    std::copy(x_.begin(), x_.end(), out.begin());
    return;
  }
  parallel_range(0, x_.size(), 8192, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) out[i] = prev_frame_[i] + f * (x_[i] - prev_frame_[i]);
  });
}

double ClothSimulation::energy() const {
  const double floor_y = p_.sphere_center.y() - p_.sphere_radius;
  double e = 0;
  for (std::size_t i = 0; i < x_.size(); ++i) e += 0.5 * v_[i].squaredNorm() + p_.gravity * (x_[i].y() - floor_y);
  return e;
}

std::string ClothSimulation::describe() const {
  return fmt::format("cloth {}x{} ({} triangles) on a sphere of radius {}, {} substeps x {} iterations at {} fps",
                     p_.resolution, p_.resolution, rest_.triangle_count(), p_.sphere_radius, p_.substeps,
                     p_.iterations, p_.fps);
}

}  // namespace ptc
