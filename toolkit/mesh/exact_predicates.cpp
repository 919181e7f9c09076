// The only CGAL kernel include besides the sphere code (CGAL headers are expensive).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "toolkit/mesh/mesh_report.h"

namespace ptc {

bool collinear_exact(const Vec3& a, const Vec3& b, const Vec3& c) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  return CGAL::collinear(K::Point_3(a.x(), a.y(), a.z()), K::Point_3(b.x(), b.y(), b.z()),
                         K::Point_3(c.x(), c.y(), c.z()));
}

}  // namespace ptc
