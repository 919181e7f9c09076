// The part of a triangle inside an axis-aligned box: the geometric primitive of the end-point
// overlap metric (EPO, Aila, Karras & Laine 2013, "On quality metrics of bounding volume
// hierarchies": the area of geometry outside a node's subtree that lies inside the node).
//
// The triangle is clipped against the six planes of the closed box (Sutherland & Hodgman 1974),
// in double precision, in a frame centred at the box (coordinates relative to the box centre, so
// that a far-away scene keeps its precision); the area of the convex polygon left is half the
// norm of the sum of its fan's cross products. A triangle lying in a face plane of the box
// counts as inside (the box is closed). Cost: at most 9 vertices per plane, a few hundred flops.
#pragma once

#include "toolkit/core/types.h"

namespace ptc {

/// Area of triangle (a, b, c) inside the closed box `box` (0 for an empty box, a triangle that
/// misses it, or a degenerate triangle). Finite inputs.
[[nodiscard]] double clipped_area(const Vec3& a, const Vec3& b, const Vec3& c, const Box3& box);

}  // namespace ptc
