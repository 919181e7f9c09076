// The exact (full-sweep) SAH builder: the quality reference the binned builder is measured
// against. One of the two builders behind sah_builder.h (which states the split rule both follow).
#pragma once

#include "bvh/build_config.h"

namespace ptc::bvh {

/// Exact SAH: at every node every axis is sorted by centroid (ties by primitive id) and all
/// |P| - 1 split positions are evaluated. O(n log^2 n); the quality reference.
[[nodiscard]] Bvh build_sweep_sah(const BuildInput& in, const BuildConfig& cfg = {});

}  // namespace ptc::bvh
