#include "analysis/experiments/study.h"

#include <oneapi/tbb/global_control.h>

#include <stdexcept>

#include "bvh/cluster_scene.h"
#include "analysis/loop/frame_loop.h"
#include "bvh/vertex_order.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/stopwatch.h"

namespace ptc::study {

std::optional<ClusterConfig> clustering_config(std::string_view name, const ClusterConfig& base) {
  ClusterConfig c = base;
  if (name == "acc_growth") c.method = ClusterMethod::Growth, c.objective = ObjectiveKind::Acc;
  else if (name == "acc_contraction") c.method = ClusterMethod::Contraction, c.objective = ObjectiveKind::Acc;
  else if (name == "naive") c.method = ClusterMethod::Contraction, c.objective = ObjectiveKind::Naive;
  else if (name == "gwh01") c.method = ClusterMethod::Contraction, c.objective = ObjectiveKind::Gwh01;
  else if (name == "meshopt") c.method = ClusterMethod::Meshopt;
  else if (name == "sah_split") c.method = ClusterMethod::SahSplit;
  else return std::nullopt;
  return c;
}

Prepared prepare(const Mesh& rest, const ConfigSpec& spec, const StudySetup& setup, const loop::AccelSetup& base) {
  Prepared p;
  p.spec = spec;
  p.mesh = rest;
  loop::AccelSetup as = base;
  if (spec.kind == loop::AccelKind::OursClusters) {
    if (spec.given) {
      p.clustering = *spec.given;
    } else {
      if (!spec.cluster) throw std::invalid_argument("configuration '" + spec.name + "' has no clustering");
      Stopwatch sw;
      // Ctrl-C stops a long clustering at its next progress step (the clustering loops run on
      // this thread, so the exception leaves no task behind).
      p.clustering = cluster_mesh(rest, *spec.cluster, [](double) { throw_if_cancelled(); });
      p.cluster_ms = sw.ms();
    }
    p.has_clusters = true;
  }
  throw_if_cancelled();
  Stopwatch sw;
  if (p.has_clusters && setup.vertex_order == bvh::VertexOrder::Clusters) {
    // The method's precomputation (as in `ptc bench`): each cluster's vertices consecutive, so
    // the cluster path converts and boxes in one pass. The study loop hands this configuration
    // its positions in that order (an untimed gather, as a renumbered frame source would).
    const std::size_t one_part[] = {0, rest.vertex_count()};
    p.to_old = bvh::cluster_vertex_order(rest, bvh::view_of(p.clustering), one_part, loop::cluster_scene_config(as));
    p.clustering = renumber_vertices(p.clustering, inverse_permutation(p.to_old));
    p.mesh = renumber_vertices(rest, p.to_old);
  }
  if (p.has_clusters &&
      (spec.cluster ? resolve_adjacency(p.mesh, spec.cluster->adjacency) : adjacency_on(p.mesh, spec.given_adjacency)) ==
          ClusterAdjacency::Positions)
    p.adjacency = adjacency_triangles(p.mesh, ClusterAdjacency::Positions);
  if (p.has_clusters) as.clusters = &p.clustering;
  p.accel = loop::make_accel(spec.kind, p.mesh, as);
  p.setup_ms = sw.ms();
  return p;
}

loop::AccelSetup accel_setup(const StudySetup& setup, const Vec3& origin) {
  loop::AccelSetup as;
  as.origin = origin;
  as.cluster_leaf = setup.cluster_leaf;
  as.leaf_format = bvh::LeafFormatChoice::Blocks;
  as.cluster_group_size = setup.cluster_group_size;
  as.min_cluster_groups = setup.min_cluster_groups;
  as.group_trees = setup.group_trees;
  as.threads = setup.threads;
  return as;
}

StudyRays study_rays(const Mesh& rest, const StudySetup& setup) {
  StudyRays r;
  const Box3 b = rest.referenced_bounds();
  r.origin = b.center();
  r.camera = make_camera(setup.camera, rest.referenced_bounds(), setup.width, setup.height);
  r.primary = camera_rays(r.camera, setup.width, setup.height);
  return r;
}

Passes trace_passes(Prepared& p, const StudyRays& rays, const Vec3& light, const PassOptions& opt) {
  Passes out;
  bvh::TraceOptions t;
  t.threads = opt.threads;
  t.counters = false;
  const loop::Accel& a = *p.accel;
  const bool counted = opt.counters && !loop::is_embree(p.spec.kind);
  bvh::HitBatch& hits = p.hits;
  hits.resize(rays.primary.size());  // allocated and touched outside the timed trace
  if (!p.rays_checked) a.check_rays(rays.primary), p.rays_checked = true;  // (likewise; once: the same rays every frame)
  Stopwatch sw;
  const bvh::TraceTotals tp = a.trace(rays.primary, hits, t);  // timed alone (argument order is unspecified)
  out.primary.add(tp, sw.ms());
  if (counted) {
    bvh::TraceOptions c = t;
    c.counters = true;
    bvh::HitBatch h2;
    const bvh::TraceTotals tc = a.trace(rays.primary, h2, c);
    out.primary.nodes_visited = tc.nodes_visited, out.primary.triangles_tested = tc.triangles_tested;
  }
  if (!opt.shadows && opt.ao_samples <= 0) return out;
  const SurfaceHits s = surface_hits(p.mesh, rays.primary, hits);
  const RayFrame frame{p.mesh.referenced_bounds(), a.origin()};
  const TraceTarget target = target_of(a);
  const TraceTarget counting = with_counters(target);  // the untimed counted passes
  if (opt.shadows) {
    out.shadow = trace_shadows(target, s, light, frame, opt.threads).stats;
    if (counted) {
      const PassStats c = trace_shadows(counting, s, light, frame, opt.threads).stats;
      out.shadow.nodes_visited = c.nodes_visited, out.shadow.triangles_tested = c.triangles_tested;
    }
  }
  if (opt.ao_samples > 0) {
    AoConfig ao;
    ao.samples = opt.ao_samples;
    out.ao = trace_ao(target, s, ao, frame, opt.threads).stats;
    if (counted) {
      const PassStats c = trace_ao(counting, s, ao, frame, opt.threads).stats;
      out.ao.nodes_visited = c.nodes_visited, out.ao.triangles_tested = c.triangles_tested;
    }
  }
  return out;
}

namespace {

// A prepared configuration as the one frame loop sees it: update() puts the frame's positions
// into the configuration's mesh in its own vertex order (a gather: the untimed part, as a
// renumbered frame source would) and updates the structure, whose own stage clock times it.
class InOrder final : public loop::Accel {
 public:
  explicit InOrder(Prepared& p) : p_(p) {}
  [[nodiscard]] std::string_view name() const override { return p_.accel->name(); }
  void update(std::span<const Vec3> positions) override {
    auto dst = p_.mesh.positions();
    if (p_.to_old.empty()) std::copy(positions.begin(), positions.end(), dst.begin());
    else
      for (std::size_t v = 0; v < dst.size(); ++v) dst[v] = positions[p_.to_old[v]];
    p_.accel->update(dst);
  }
  [[nodiscard]] loop::UpdateTimes last_update() const override { return p_.accel->last_update(); }
  bvh::TraceTotals trace(const bvh::RayBatch& rays, bvh::HitBatch& hits, const bvh::TraceOptions& opt) const override {
    return p_.accel->trace(rays, hits, opt);
  }
  void check_rays(const bvh::RayBatch& rays) const override { p_.accel->check_rays(rays); }
  [[nodiscard]] Vec3 origin() const override { return p_.accel->origin(); }
  [[nodiscard]] std::optional<double> sah_cost() const override { return p_.accel->sah_cost(); }

 private:
  Prepared& p_;
};

}  // namespace

void run_study(Scene& scene, std::vector<Prepared>& configs, const StudySetup& setup,
               const std::function<void(const StudyFrame&, std::size_t, Prepared&)>& measure) {
  if (setup.frames.first < 0 || setup.frames.count() < 1) throw std::invalid_argument("frames must be a range A:B, 0 <= A <= B");
  oneapi::tbb::global_control limit(oneapi::tbb::global_control::max_allowed_parallelism, setup.threads);
  std::vector<InOrder> wrapped;
  wrapped.reserve(configs.size());
  std::vector<loop::Accel*> accels;
  for (Prepared& p : configs) accels.push_back(&wrapped.emplace_back(p));
  bvh::AlignedVector<Vec3> pos(scene.rest().positions().begin(), scene.rest().positions().end());
  const std::size_t frames = static_cast<std::size_t>(setup.frames.count());
  const std::size_t steps = frames * std::max<std::size_t>(configs.size(), 1);
  loop::LoopOptions lo;
  lo.frames = setup.frames;
  lo.fresh_positions = false;  // every configuration gathers its own copy (InOrder)
  loop::run_frame_loop(scene, pos, accels, lo, [&](const loop::FrameRecord& r, loop::Accel&, std::span<const Vec3>) {
    StudyFrame sf;
    sf.index = r.index;
    sf.frame = r.frame;
    sf.warmup = r.index == 0 && frames > 1;
    sf.times = r.times;
    measure(sf, r.accel, configs[r.accel]);
    if (setup.progress) setup.progress(double(std::size_t(r.index) * configs.size() + r.accel + 1) / double(steps));
  });
}

}  // namespace ptc::study
