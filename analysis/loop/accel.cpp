#include "analysis/loop/accel.h"

#include <stdexcept>

#include "bvh/embree_peer.h"

namespace ptc::loop {

std::string_view to_string(AccelKind k) {
  switch (k) {
    case AccelKind::OursTriangles: return "ours_triangles";
    case AccelKind::OursClusters: return "ours_clusters";
    case AccelKind::EmbreeMedium: return "embree_medium";
    case AccelKind::EmbreeLow: return "embree_low";
    case AccelKind::EmbreeRefit: return "embree_refit";
  }
  return "?";
}

std::optional<AccelKind> parse_accel_kind(std::string_view s) {
  for (AccelKind k : kAllAccelKinds)
    if (to_string(k) == s) return k;
  return std::nullopt;
}

bool is_embree(AccelKind k) {
  return k == AccelKind::EmbreeMedium || k == AccelKind::EmbreeLow || k == AccelKind::EmbreeRefit;
}

UpdateTimes update_times_of(const bvh::StageTimes& t) {
  return {t.vertices_ms + t.boxes_ms,
          t.build_ms + t.collapse_ms + t.leaf_data_ms + t.refit_ms - t.overlap_ms + t.fallback_ms, t};
}

UpdateTimes SceneAccel::last_update() const { return update_times_of(tracer_.moving_times()); }

namespace {

// ours_triangles and ours_clusters: a bvh scene with data() and times().
template <class S>
class OursAccel final : public Accel {
 public:
  OursAccel(AccelKind kind, std::unique_ptr<S> scene) : kind_(kind), scene_(std::move(scene)) {}
  [[nodiscard]] std::string_view name() const override { return to_string(kind_); }
  void update(std::span<const Vec3> positions) override { scene_->update(positions); }
  [[nodiscard]] UpdateTimes last_update() const override { return update_times_of(scene_->times()); }
  bvh::TraceTotals trace(const bvh::RayBatch& rays, bvh::HitBatch& hits, const bvh::TraceOptions& opt) const override {
    return bvh::trace(scene_->data(), rays, hits, opt);
  }
  [[nodiscard]] Vec3 origin() const override { return scene_->data().origin; }
  [[nodiscard]] std::optional<double> sah_cost() const override {
    // A triangle BVH's binary SAH cost; none when it was refitted (its binary tree is the last build's).
    auto of = [](const bvh::TriangleScene& t) { return t.refitted() ? std::nullopt : std::optional<double>(t.bvh().cost); };
    if constexpr (requires { scene_->sah_cost(); }) {  // over the clusters (fixed group trees too),
      if (scene_->fallback_active()) return of(*scene_->fallback_scene());  // or the traced triangle BVH's
      return scene_->sah_cost();
    } else {
      return of(*scene_);
    }
  }
  [[nodiscard]] const S& scene() const { return *scene_; }

 private:
  AccelKind kind_;
  std::unique_ptr<S> scene_;
};

class EmbreeAccel final : public Accel {
 public:
  EmbreeAccel(AccelKind kind, const Mesh& mesh, const Vec3& origin, unsigned threads, bvh::StageClock clock,
              int packet_width)
      : kind_(kind), origin_(origin), threads_(threads), packet_width_(packet_width),
        scene_(mesh, origin,
               bvh::EmbreeConfig{kind == AccelKind::EmbreeMedium ? bvh::EmbreeMode::StaticMedium
                                 : kind == AccelKind::EmbreeLow  ? bvh::EmbreeMode::DynamicLow
                                                                 : bvh::EmbreeMode::DynamicRefit,
                                 threads, "", clock}) {}
  [[nodiscard]] std::string_view name() const override { return to_string(kind_); }
  void update(std::span<const Vec3> positions) override { scene_.update(positions); }
  [[nodiscard]] UpdateTimes last_update() const override {
    return {scene_.last_vertex_ms(), scene_.last_commit_ms(), {}};
  }
  bvh::TraceTotals trace(const bvh::RayBatch& rays, bvh::HitBatch& hits, const bvh::TraceOptions& opt) const override {
    // Packets: Embree's packets (rtcIntersect4/8/16), the peer of ours, with the options' hint
    // (TraceOptions::coherent: the coherent or the incoherent context flag).
    return scene_.trace_packets(rays, hits, opt.mode, threads_, opt.packets ? packet_width_ : 1, opt.coherent);
  }
  void check_rays(const bvh::RayBatch& rays) const override { scene_.check_rays(rays); }
  [[nodiscard]] Vec3 origin() const override { return origin_; }

 private:
  AccelKind kind_;
  Vec3 origin_;
  unsigned threads_;
  int packet_width_;
  bvh::EmbreeScene scene_;
};

}  // namespace

bvh::SceneConfig cluster_scene_config(const AccelSetup& s) {
  bvh::SceneConfig cfg = bvh::cluster_scene_defaults();
  cfg.origin = s.origin;
  cfg.cluster_leaf = s.cluster_leaf;
  cfg.leaf_format = s.leaf_format;
  cfg.cluster_group_size = s.cluster_group_size;
  cfg.min_cluster_groups = s.min_cluster_groups;
  cfg.group_trees = s.group_trees;
  cfg.clock = s.clock;
  cfg.builder = s.builder;
  cfg.fallback_swelling = s.cluster_fallback;
  cfg.refit_growth = s.fallback_refit;
  cfg.fallback_area_weights = s.fallback_area_weights;
  cfg.fallback_area_eye = s.fallback_area_eye;
  if (s.cluster_build) cfg.build = *s.cluster_build;
  return cfg;
}

std::unique_ptr<Accel> make_accel(AccelKind kind, const Mesh& mesh, const AccelSetup& s) {
  switch (kind) {
    case AccelKind::OursTriangles: {
      bvh::SceneConfig cfg = bvh::triangle_scene_defaults();
      cfg.origin = s.origin;
      cfg.clock = s.clock;
      cfg.builder = s.builder;
      if (s.triangle_build) cfg.build = *s.triangle_build;
      return std::make_unique<OursAccel<bvh::TriangleScene>>(kind, std::make_unique<bvh::TriangleScene>(mesh, cfg));
    }
    case AccelKind::OursClusters: {
      if (!s.clusters) throw std::invalid_argument("ours_clusters needs a clustering");
      return std::make_unique<OursAccel<bvh::ClusterScene>>(
          kind, std::make_unique<bvh::ClusterScene>(mesh, bvh::view_of(*s.clusters), cluster_scene_config(s)));
    }
    case AccelKind::EmbreeMedium:
    case AccelKind::EmbreeLow:
    case AccelKind::EmbreeRefit: return std::make_unique<EmbreeAccel>(kind, mesh, s.origin, s.threads, s.clock, s.embree_packet_width);
  }
  throw std::invalid_argument("unknown acceleration configuration");
}

const bvh::ClusterScene* cluster_scene_of(const Accel& a) {
  const auto* c = dynamic_cast<const OursAccel<bvh::ClusterScene>*>(&a);
  return c ? &c->scene() : nullptr;
}

const bvh::TriangleScene* triangle_scene_of(const Accel& a) {
  const auto* c = dynamic_cast<const OursAccel<bvh::TriangleScene>*>(&a);
  return c ? &c->scene() : nullptr;
}

}  // namespace ptc::loop
