#include "toolkit/anim/deformers.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "toolkit/core/error.h"

namespace ptc {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

template <class F>
void for_vertices(std::size_t n, F&& f) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

void check_out(std::span<Vec3> out, std::size_t n) {
  if (out.size() != n)
    throw std::invalid_argument(fmt::format("positions: output holds {} vertices, the source has {}", out.size(), n));
}

void check_time(double t) {
  if (!std::isfinite(t)) throw std::invalid_argument("positions: frame time is not finite");
}

// sin(x) / x without the 0/0 at 0.
double sinc(double x) {
  if (std::abs(x) < 1e-4) return 1.0 - x * x / 6.0;
  return std::sin(x) / x;
}

// 32-bit integer hash (Wang / Jenkins mix), for the deterministic per-triangle speed of explode.
std::uint32_t hash32(std::uint32_t x) {
  x = (x ^ 61u) ^ (x >> 16);
  x *= 9u;
  x ^= x >> 4;
  x *= 0x27d4eb2du;
  x ^= x >> 15;
  return x;
}

class Deformer final : public Animation {
 public:
  Deformer(Mesh rest, const DeformParams& p) : rest_(std::move(rest)), p_(p) {
    box_ = rest_.referenced_bounds();  // (the shape: an unused vertex far away would move the axis off it)
    c_ = box_.center();
    e_ = box_.extent();
    diag_ = e_.norm();
    if (p_.kind == DeformKind::Explode) build_soup();
  }

  const Mesh& rest() const override { return rest_; }
  std::size_t frame_count() const override { return 0; }
  std::string describe() const override {
    const char* ax = "xyz";
    return fmt::format("deformer {} (axis {}, direction {}, amplitude {}, period {}) of {} triangles, {} vertices",
                       to_string(p_.kind), ax[p_.axis], ax[p_.direction], p_.amplitude, p_.period,
                       rest_.triangle_count(), rest_.vertex_count());
  }

  void positions(double t, std::span<Vec3> out) override {
    check_time(t);
    const std::span<const Vec3> in = rest_.positions();
    check_out(out, in.size());
    const int a = p_.axis, b = p_.direction;
    const double s = std::sin(kTwoPi * t / p_.period);
    switch (p_.kind) {
      case DeformKind::Twist: {
        // Rotation about the axis line through c; the other two axes, in right-handed order.
        const int u = (a + 1) % 3, v = (a + 2) % 3;
        const double half = 0.5 * e_[a];
        const double amp = p_.amplitude * s;
        for_vertices(in.size(), [&](std::size_t i) {
          const Vec3& q = in[i];
          const double along = half > 0 ? (q[a] - c_[a]) / half : 0.0;
          const double ang = amp * along;
          if (ang == 0.0) {  // no rotation: the rest position itself (c + (q - c) may be an ulp off)
            out[i] = q;
            return;
          }
          const double cs = std::cos(ang), sn = std::sin(ang);
          const double x = q[u] - c_[u], y = q[v] - c_[v];
          Vec3 r = q;
          r[u] = c_[u] + cs * x - sn * y;
          r[v] = c_[v] + sn * x + cs * y;
          out[i] = r;
        });
        break;
      }
      case DeformKind::Bend: {
        const double k = e_[a] > 0 ? p_.amplitude * s / e_[a] : 0.0;
        if (k == 0.0) {
          for_vertices(in.size(), [&](std::size_t i) { out[i] = in[i]; });
          break;
        }
        for_vertices(in.size(), [&](std::size_t i) {
          const Vec3& q = in[i];
          const double x = q[a] - c_[a], w = q[b] - c_[b];
          const double th = k * x;
          const double st = std::sin(th), sh = std::sin(0.5 * th);
          Vec3 r = q;
          r[a] = c_[a] + x * sinc(th) - w * st;                     // sin(th)/k = x sinc(th)
          r[b] = c_[b] + w * std::cos(th) + 2.0 * sh * sh / k;     // (1 - cos th)/k
          out[i] = r;
        });
        break;
      }
      case DeformKind::Wave: {
        const double amp = p_.amplitude * diag_;
        const double len = p_.wavelength * e_[a];
        const double phase_t = t / p_.period;
        for_vertices(in.size(), [&](std::size_t i) {
          const Vec3& q = in[i];
          const double x = len > 0 ? (q[a] - box_.lo[a]) / len : 0.0;
          Vec3 r = q;
          r[b] += amp * std::sin(kTwoPi * (x - phase_t));
          out[i] = r;
        });
        break;
      }
      case DeformKind::Rigid: {
        const double ang = p_.amplitude * kTwoPi * t / p_.period;
        const Eigen::Matrix3d R = Eigen::AngleAxisd(ang, Vec3::Unit(a)).toRotationMatrix();
        const Vec3 move = p_.velocity * diag_ * t;
        if (ang == 0.0)  // a translation (or the rest pose at t = 0): exact, not c + (p - c) + move
          for_vertices(in.size(), [&](std::size_t i) { out[i] = in[i] + move; });
        else
          for_vertices(in.size(), [&](std::size_t i) { out[i] = c_ + R * (in[i] - c_) + move; });
        break;
      }
      case DeformKind::Explode: {
        const double dist = p_.amplitude * diag_ * t;
        if (vertex_triangle_.empty())
          for_vertices(in.size(), [&](std::size_t i) { out[i] = in[i] + dist * offset_[i / 3]; });
        else
          for_vertices(in.size(), [&](std::size_t i) { out[i] = in[i] + dist * offset_[vertex_triangle_[i]]; });
        break;
      }
    }
  }

  // Every kind but explode is a function of the rest position alone: renumbering the rest mesh
  // renumbers the output. Explode keeps each (soup) vertex's triangle.
  bool renumber_vertices_in_place(std::span<const std::uint32_t> to_old) override {
    if (to_old.size() != rest_.vertex_count())
      throw std::invalid_argument("renumber_vertices: " + std::to_string(to_old.size()) + " entries for " +
                                  std::to_string(rest_.vertex_count()) + " vertices");
    check_permutation(to_old);  // before anything changes
    std::vector<std::uint32_t> vt;
    if (p_.kind == DeformKind::Explode) {
      vt.resize(to_old.size());
      for (std::size_t i = 0; i < to_old.size(); ++i)
        vt[i] = vertex_triangle_.empty() ? to_old[i] / 3 : vertex_triangle_[to_old[i]];
    }
    rest_.renumber_vertices(to_old);  // in place (13.3M triangles: 160 MB not allocated); may throw, changing nothing
    if (p_.kind == DeformKind::Explode) vertex_triangle_ = std::move(vt);
    return true;
  }

 private:
  // Explode: one own vertex per triangle corner, and the per-triangle flight vector (unit
  // direction times the hashed speed factor).
  void build_soup() {
    const std::size_t T = rest_.triangle_count();
    std::vector<Tri> tris(T);
    std::vector<Vec3> pos(3 * T);
    offset_.resize(T);
    for (std::size_t t = 0; t < T; ++t) {
      const auto c = rest_.corners(t);
      for (int k = 0; k < 3; ++k) {
        tris[t][k] = static_cast<std::uint32_t>(3 * t + k);
        pos[3 * t + k] = c[k];
      }
      Vec3 dir = (c[1] - c[0]).cross(c[2] - c[0]);
      double n = dir.norm();
      if (!(n > 0) || !std::isfinite(n)) {
        dir = (c[0] + c[1] + c[2]) / 3.0 - c_;
        n = dir.norm();
        if (!(n > 0)) dir = Vec3::UnitY(), n = 1.0;
      }
      const double f = 0.5 + double(hash32(static_cast<std::uint32_t>(t))) / 4294967296.0;
      offset_[t] = dir / n * f;
    }
    rest_ = Mesh(std::move(tris), std::move(pos));
  }

  Mesh rest_;
  DeformParams p_;
  Box3 box_;
  Vec3 c_, e_;
  double diag_ = 0;
  std::vector<Vec3> offset_;
  std::vector<std::uint32_t> vertex_triangle_;  // explode after a renumbering: the triangle of each vertex
};

}  // namespace

DeformParams deform_preset(DeformKind kind) {
  DeformParams d;
  d.kind = kind;
  switch (kind) {
    case DeformKind::Twist: d.axis = 1, d.amplitude = std::numbers::pi / 2, d.period = 60; break;
    case DeformKind::Bend: d.axis = 1, d.direction = 2, d.amplitude = std::numbers::pi / 2, d.period = 60; break;
    case DeformKind::Wave: d.axis = 0, d.direction = 2, d.amplitude = 0.03, d.wavelength = 0.5, d.period = 30; break;
    case DeformKind::Rigid:
      d.axis = 1, d.amplitude = 1.0, d.period = 60, d.velocity = Vec3(0.005, 0.0, 0.0);
      break;
    case DeformKind::Explode: d.amplitude = 0.004; break;
  }
  return d;
}

std::optional<DeformKind> parse_deform_kind(std::string_view name) {
  if (name == "twist") return DeformKind::Twist;
  if (name == "bend") return DeformKind::Bend;
  if (name == "wave") return DeformKind::Wave;
  if (name == "rigid") return DeformKind::Rigid;
  if (name == "explode") return DeformKind::Explode;
  return std::nullopt;
}

std::string_view to_string(DeformKind kind) {
  switch (kind) {
    case DeformKind::Twist: return "twist";
    case DeformKind::Bend: return "bend";
    case DeformKind::Wave: return "wave";
    case DeformKind::Rigid: return "rigid";
    case DeformKind::Explode: return "explode";
  }
  return "?";
}

std::optional<int> parse_axis(std::string_view name) {
  if (name == "x") return 0;
  if (name == "y") return 1;
  if (name == "z") return 2;
  return std::nullopt;
}

std::string check(const DeformParams& p) {
  if (p.axis < 0 || p.axis > 2) return "axis must be x, y or z";
  const bool uses_direction = p.kind == DeformKind::Bend || p.kind == DeformKind::Wave;
  if (uses_direction && (p.direction < 0 || p.direction > 2)) return "direction must be x, y or z";
  if (uses_direction && p.direction == p.axis) return "direction must differ from axis";
  if (!std::isfinite(p.amplitude)) return "amplitude must be finite";
  if (p.kind != DeformKind::Explode && !(p.period > 0 && std::isfinite(p.period))) return "period must be > 0";
  if (p.kind == DeformKind::Wave && !(p.wavelength > 0 && std::isfinite(p.wavelength))) return "wavelength must be > 0";
  if (!p.velocity.allFinite()) return "velocity must be finite";
  return {};
}

AnimationPtr make_deformer(Mesh rest, const DeformParams& params) {
  if (const std::string why = check(params); !why.empty()) throw InputError("", "", "deformer", why);
  if (rest.empty()) throw InputError("", "", "deformer", "the mesh has no triangles");
  if (params.kind == DeformKind::Explode && rest.triangle_count() > 0xffffffffull / 3)
    throw InputError("", "", "deformer", "explode: too many triangles for 32-bit soup indices");
  for (std::size_t i = 0; i < rest.vertex_count(); ++i)
    if (!rest.position(i).allFinite())
      throw InputError("", "", "deformer", fmt::format("vertex {} has a non-finite coordinate", i));
  return std::make_unique<Deformer>(std::move(rest), params);
}

}  // namespace ptc
