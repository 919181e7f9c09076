// validate() accepts real trees and rejects each kind of corruption (so it can fail).
#include "bvh/validate.h"

#include <gtest/gtest.h>

#include "bvh/sah_builder.h"
#include "test_util.h"

namespace ptc::bvh {
namespace {

struct Fixture {
  Mesh mesh = test::load_mesh("bunny00.off");
  std::vector<Box3f> boxes = triangle_boxes(mesh.positions(), mesh.triangles());
  std::vector<Vec3f> cent = triangle_centroids(mesh.positions(), mesh.triangles());
  Bvh bvh = build_binned_sah({boxes, cent, {}}, {});
};

std::uint32_t first_inner(const Bvh& b) {
  for (std::uint32_t i = 0; i < b.nodes.size(); ++i)
    if (!b.nodes[i].is_leaf() && i > 0) return i;
  return 0;
}
std::uint32_t first_leaf(const Bvh& b) {
  for (std::uint32_t i = 0; i < b.nodes.size(); ++i)
    if (b.nodes[i].is_leaf()) return i;
  return 0;
}

TEST(Validate, AcceptsBuiltTrees) {
  Fixture f;
  ASSERT_GT(f.mesh.triangle_count(), 1000u);
  EXPECT_TRUE(validate(f.bvh, f.boxes).empty()) << test::joined(validate(f.bvh, f.boxes));
}

TEST(Validate, RejectsEachCorruption) {
  Fixture f;
  auto rejects = [&](const char* what, auto corrupt) {
    Bvh b = f.bvh;
    corrupt(b);
    const auto issues = validate(b, f.boxes);
    EXPECT_FALSE(issues.empty()) << what;
    if (!issues.empty()) std::cout << "  " << what << ": " << issues.front() << "\n";
  };
  rejects("duplicate primitive", [](Bvh& b) { b.prim_order[1] = b.prim_order[0]; });
  rejects("primitive id out of range", [](Bvh& b) { b.prim_order[3] = 0xfffffff0u; });
  rejects("missing primitive", [](Bvh& b) { b.prim_order.pop_back(); });
  rejects("child box sticks out", [](Bvh& b) { b.nodes[1].bounds.hi[0] = b.nodes[0].bounds.hi[0] + 1.0f; });
  rejects("leaf box too small", [](Bvh& b) {
    BvhNode& l = b.nodes[first_leaf(b)];
    l.bounds.lo[1] = l.bounds.hi[1];
  });
  rejects("shrunk by one ulp", [](Bvh& b) {
    BvhNode& l = b.nodes[first_leaf(b)];
    l.bounds.hi[2] = std::nextafter(l.bounds.hi[2], -kInf);
  });
  rejects("cycle", [](Bvh& b) { b.nodes[first_inner(b)].index = 0; });
  rejects("second child out of range", [](Bvh& b) { b.nodes[0].index = static_cast<std::uint32_t>(b.nodes.size()); });
  rejects("leaf range past the end", [](Bvh& b) { b.nodes[first_leaf(b)].count = 0x7fffffffu; });
  rejects("overlapping leaves", [](Bvh& b) {
    BvhNode& l = b.nodes[first_leaf(b)];
    l.count += 1;  // steals the first primitive of the next leaf
  });
  rejects("primitive in no leaf", [](Bvh& b) {
    BvhNode& l = b.nodes[first_leaf(b)];
    if (l.count > 1) {
      l.count -= 1;
    } else {
      l.index += 1;
    }
  });
  rejects("unreachable node", [](Bvh& b) { b.nodes.push_back(b.nodes.back()); });
  rejects("wrong cost", [](Bvh& b) { b.cost *= 1.001; });
  rejects("no nodes for primitives", [](Bvh& b) { b.nodes.clear(); });
}

TEST(Validate, CostCheckUsesWeightsAndModel) {
  Fixture f;
  std::vector<std::uint32_t> w(f.boxes.size(), 3);
  BuildConfig cfg;
  cfg.cost = {2.0, 0.5};
  const Bvh b = build_binned_sah({f.boxes, f.cent, w}, cfg);
  ValidateOptions opt;
  opt.weights = w;
  opt.model = cfg.cost;
  EXPECT_TRUE(validate(b, f.boxes, opt).empty());
  opt.weights = {};  // the wrong weights: the recomputed cost differs
  EXPECT_FALSE(validate(b, f.boxes, opt).empty());
}

}  // namespace
}  // namespace ptc::bvh
