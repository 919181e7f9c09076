#include "analysis/trace_deform.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ptc {

const char* to_string(Deformation d) {
  switch (d) {
    case Deformation::None: return "none";
    case Deformation::Twist: return "twist";
    case Deformation::Wave: return "wave";
  }
  return "?";
}

std::optional<Deformation> parse_deformation(std::string_view s) {
  if (s == "none") return Deformation::None;
  if (s == "twist") return Deformation::Twist;
  if (s == "wave") return Deformation::Wave;
  return std::nullopt;
}

void deform(std::span<const Vec3> rest, const Box3& bounds, Deformation kind, int frame, std::span<Vec3> out) {
  if (out.size() != rest.size()) throw std::invalid_argument("deform: output size differs from the rest pose");
  if (frame < 0) throw std::invalid_argument("deform: negative frame");
  const double a = std::sin(2.0 * M_PI * double(frame % kDeformPeriod) / kDeformPeriod);
  const Vec3 c = bounds.center(), e = bounds.extent();
  if (kind == Deformation::None || a == 0.0 || bounds.empty()) {
    std::copy(rest.begin(), rest.end(), out.begin());
    return;
  }
  if (kind == Deformation::Twist) {
    const double h = e.y() > 0 ? e.y() : 1.0;
    for (std::size_t v = 0; v < rest.size(); ++v) {
      const Vec3& p = rest[v];
      const double ang = 0.6 * a * (p.y() - bounds.lo.y()) / h;
      const double cs = std::cos(ang), sn = std::sin(ang);
      const double x = p.x() - c.x(), z = p.z() - c.z();
      out[v] = Vec3(c.x() + cs * x + sn * z, p.y(), c.z() - sn * x + cs * z);
    }
    return;
  }
  const double w = e.x() > 0 ? e.x() : 1.0;
  const double amp = 0.05 * e.norm() * a;
  const double phase = double(frame % kDeformPeriod) / kDeformPeriod;
  for (std::size_t v = 0; v < rest.size(); ++v) {
    const Vec3& p = rest[v];
    out[v] = Vec3(p.x(), p.y(), p.z() + amp * std::sin(2.0 * M_PI * (2.0 * (p.x() - bounds.lo.x()) / w + phase)));
  }
}

}  // namespace ptc
