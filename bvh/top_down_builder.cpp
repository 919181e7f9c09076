#include "bvh/top_down_builder.h"

#include <cassert>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ptc::bvh {

void check_input(const BuildInput& in, const BuildConfig& cfg) {
  assert(in.centroids.size() == in.boxes.size());
  assert(in.weights.empty() || in.weights.size() == in.boxes.size());
  assert(cfg.max_leaf_size >= 1);
  assert(cfg.bins >= 2 && cfg.bins <= 256);
  assert(cfg.cost.traversal > 0.0 && cfg.cost.intersection > 0.0);
  (void)in, (void)cfg;
}

void check_area_weights(const BuildConfig& cfg) {
  for (int a = 0; a < 3; ++a)
    if (!(std::isfinite(cfg.area_weights[a]) && cfg.area_weights[a] > 0.0f))
      throw std::invalid_argument("BVH build: the area weight of axis " + std::string(1, "xyz"[a]) + " is " +
                                  std::to_string(cfg.area_weights[a]) + " (each must be finite and above 0)");
}

void check_area_eye(const BuildConfig& cfg) {
  if (cfg.area_eye)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite((*cfg.area_eye)[a]))
        throw std::invalid_argument("BVH build: the rays' point (area_eye) is not finite on axis " + std::string(1, "xyz"[a]));
}

void check_no_nan(const BuildInput& in) {
  for (std::size_t i = 0; i < in.boxes.size(); ++i)
    for (int a = 0; a < 3; ++a)
      if (std::isnan(in.boxes[i].lo[a]) || std::isnan(in.boxes[i].hi[a]) || std::isnan(in.centroids[i][a]))
        throw std::invalid_argument("BVH build: the box or centroid of primitive " + std::to_string(i) + " holds NaN");
}

}  // namespace ptc::bvh
