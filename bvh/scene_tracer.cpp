#include "bvh/scene_tracer.h"
#include "toolkit/core/stopwatch.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <utility>

namespace ptc::bvh {
namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

// The sub-mesh of the parts with is_static == want, its triangle id map (sub -> combined) and
// vertex map (combined -> sub, kNone for other parts' vertices).
struct SubMesh {
  Mesh mesh;
  std::vector<std::uint32_t> tri_ids, vertex_map;
};

SubMesh sub_mesh(const Mesh& m, const PartLayout& L, bool want) {
  SubMesh s;
  s.vertex_map.assign(m.vertex_count(), kNone);
  std::vector<Vec3> pos;
  std::vector<Tri> tris;
  const auto P = m.positions();
  const auto T = m.triangles();
  for (std::size_t p = 0; p < L.part_count(); ++p) {
    if (L.is_static[p] != want) continue;
    const std::size_t v0 = L.vertex_offsets[p], v1 = L.vertex_offsets[p + 1];
    for (std::size_t v = v0; v < v1; ++v) {
      s.vertex_map[v] = static_cast<std::uint32_t>(pos.size());
      pos.push_back(P[v]);
    }
    for (std::size_t t = L.triangle_offsets[p]; t < L.triangle_offsets[p + 1]; ++t) {
      Tri f = T[t];
      for (auto& c : f) {
        if (c < v0 || c >= v1)
          throw std::invalid_argument("SceneTracer: triangle " + std::to_string(t) + " of part " + std::to_string(p) +
                                      " uses vertex " + std::to_string(c) + " outside the part");
        c = s.vertex_map[c];
      }
      tris.push_back(f);
      s.tri_ids.push_back(static_cast<std::uint32_t>(t));
    }
  }
  s.mesh = Mesh(std::move(tris), std::move(pos));
  return s;
}

void map_ids(HitBatch& h, const std::vector<std::uint32_t>& ids) {
  for (auto& t : h.triangle)
    if (t != kNoTriangle) t = ids[t];
}

}  // namespace

PartLayout PartLayout::of(const Scene& scene) {
  PartLayout L;
  L.vertex_offsets.clear();
  L.triangle_offsets.clear();
  for (std::size_t p = 0; p <= scene.part_count(); ++p) {
    L.vertex_offsets.push_back(scene.vertex_offset(p));
    L.triangle_offsets.push_back(scene.triangle_offset(p));
    if (p < scene.part_count()) L.is_static.push_back(scene.is_static(p));
  }
  return L;
}

PartLayout PartLayout::single(const Mesh& mesh, bool is_static) {
  PartLayout L;
  L.vertex_offsets = {0, mesh.vertex_count()};
  L.triangle_offsets = {0, mesh.triangle_count()};
  L.is_static = {is_static};
  return L;
}

SceneConfig cluster_config(const SceneTracerConfig& cfg, const Vec3& origin) {
  SceneConfig c = cluster_scene_defaults();
  c.origin = cfg.origin ? *cfg.origin : origin;
  c.cluster_leaf = cfg.cluster_leaf;
  c.cluster_group_size = cfg.cluster_group_size;
  c.min_cluster_groups = cfg.min_cluster_groups;
  c.group_trees = cfg.group_trees;
  c.fallback_swelling = cfg.cluster_fallback;
  c.refit_growth = cfg.fallback_refit;
  c.fallback_area_weights = cfg.fallback_area_weights;
  c.fallback_area_eye = cfg.fallback_area_eye;
  return c;
}

std::uint32_t SceneTracer::cluster_group_size() const { return moving_cs_ ? moving_cs_->group_size() : 0u; }

SceneTracer::SceneTracer(const Mesh& first, const PartLayout& L, const SceneTracerConfig& cfg) {
  const std::size_t np = L.part_count();
  if (np == 0 || L.vertex_offsets.size() != np + 1 || L.triangle_offsets.size() != np + 1 ||
      L.vertex_offsets.front() != 0 || L.triangle_offsets.front() != 0 ||
      L.vertex_offsets.back() != first.vertex_count() || L.triangle_offsets.back() != first.triangle_count() ||
      !std::is_sorted(L.vertex_offsets.begin(), L.vertex_offsets.end()) ||
      !std::is_sorted(L.triangle_offsets.begin(), L.triangle_offsets.end()))
    throw std::invalid_argument("SceneTracer: the part layout does not cover the mesh");
  if (cfg.clusters && cfg.clusters->triangle_count() != first.triangle_count())
    throw std::invalid_argument("SceneTracer: the clustering does not cover the mesh's triangles");
  combined_vertices_ = first.vertex_count();
  origin_ = cfg.origin ? *cfg.origin : first.referenced_bounds().center();
  SceneConfig tcfg = triangle_scene_defaults();
  tcfg.origin = origin_;
  const SceneConfig ccfg = cluster_config(cfg, origin_);

  const bool any_static = std::find(L.is_static.begin(), L.is_static.end(), true) != L.is_static.end();
  const bool any_moving = std::find(L.is_static.begin(), L.is_static.end(), false) != L.is_static.end();

  // The BVH of the parts with is_static == want; the cluster BVH when clusters are given and
  // (moving parts, or everything static: one BVH over the whole mesh as `ptc trace MESH
  // --clusters` always did).
  auto build = [&](bool want, std::vector<std::uint32_t>& ids, std::unique_ptr<TriangleScene>& ts,
                   std::unique_ptr<ClusterScene>* cs) {
    const bool whole = want ? !any_moving : !any_static;
    SubMesh s;
    const Mesh* m = &first;
    if (whole) {
      ids.clear();  // the identity (not stored: 53 MB at 13.3M triangles); trace() maps only a split
    } else {
      s = sub_mesh(first, L, want);
      ids = s.tri_ids;
      m = &s.mesh;
    }
    if (!cs || !cfg.clusters) {
      ts = std::make_unique<TriangleScene>(*m, tcfg);
      return;
    }
    if (whole) {
      SceneConfig c = ccfg;
      c.built_once = want;  // all static: never updated, so no per-frame state
      if (want) c.cluster_group_size = cfg.still_cluster_group_size;  // (default: the plain build)
      *cs = std::make_unique<ClusterScene>(*m, view_of(*cfg.clusters), c);
      return;
    }
    // The clusters of this sub-mesh, renumbered (monotone maps keep every list ascending).
    std::vector<std::uint32_t> sub_of_tri(first.triangle_count(), kNone);
    for (std::size_t k = 0; k < ids.size(); ++k) sub_of_tri[ids[k]] = static_cast<std::uint32_t>(k);
    Clustering c;
    const Clustering& g = *cfg.clusters;
    for (std::size_t k = 0; k < g.cluster_count(); ++k) {
      const auto tri = g.triangles_of(k);
      std::size_t inside = 0;
      for (auto t : tri) inside += t < sub_of_tri.size() && sub_of_tri[t] != kNone;
      if (inside == 0) continue;
      if (inside != tri.size())
        throw std::invalid_argument("SceneTracer: cluster " + std::to_string(k) + " mixes static and moving triangles");
      for (auto t : tri) c.triangle_order.push_back(sub_of_tri[t]);
      c.triangle_offsets.push_back(static_cast<std::uint32_t>(c.triangle_order.size()));
      for (auto v : g.vertices_of(k))
        if (v < s.vertex_map.size() && s.vertex_map[v] != kNone) c.vertices.push_back(s.vertex_map[v]);
      c.vertex_offsets.push_back(static_cast<std::uint32_t>(c.vertices.size()));
    }
    *cs = std::make_unique<ClusterScene>(*m, view_of(c), ccfg);
  };

  if (any_static) {
    Stopwatch t0;
    std::unique_ptr<ClusterScene> whole_cs;
    build(true, static_ids_, static_, any_moving ? nullptr : &whole_cs);
    static_n_ = any_moving ? static_ids_.size() : first.triangle_count();
    static_build_ms_ = t0.ms();
    if (whole_cs) {  // all static with clusters: the one BVH is the cluster BVH (built once)
      moving_cs_ = std::move(whole_cs);
      moving_ids_ = std::move(static_ids_);
      static_ids_.clear();
      moving_n_ = static_n_, static_n_ = 0;
      moving_setup_ms_ = static_build_ms_;
    }
  }
  if (any_moving) {
    Stopwatch t0;
    build(false, moving_ids_, moving_ts_, &moving_cs_);
    moving_n_ = any_static ? moving_ids_.size() : first.triangle_count();
    moving_setup_ms_ = t0.ms();
    for (std::size_t p = 0; p < np; ++p)
      if (!L.is_static[p] && L.vertex_offsets[p + 1] > L.vertex_offsets[p]) {
        if (!moving_vertex_ranges_.empty() &&
            moving_vertex_ranges_.back().first + moving_vertex_ranges_.back().count == L.vertex_offsets[p])
          moving_vertex_ranges_.back().count += L.vertex_offsets[p + 1] - L.vertex_offsets[p];
        else
          moving_vertex_ranges_.push_back({L.vertex_offsets[p], L.vertex_offsets[p + 1] - L.vertex_offsets[p]});
      }
    std::size_t n = 0;
    for (const auto& r : moving_vertex_ranges_) n += r.count;
    moving_pos_.resize(n);
  }
  all_static_ = !any_moving;
}

const TraceData& SceneTracer::moving_data() const {
  if (moving_cs_) return moving_cs_->data();
  if (moving_ts_) return moving_ts_->data();
  throw std::logic_error("SceneTracer: no moving BVH");
}

void SceneTracer::update(std::span<const Vec3> p) {
  if (p.size() != combined_vertices_)
    throw std::invalid_argument("SceneTracer::update: " + std::to_string(p.size()) + " positions for " +
                                std::to_string(combined_vertices_) + " vertices");
  if (all_static_) return;
  std::span<const Vec3> sub = p;
  if (!(moving_vertex_ranges_.size() == 1 && moving_vertex_ranges_[0].count == p.size())) {
    std::size_t k = 0;
    for (const auto& r : moving_vertex_ranges_) {
      std::copy_n(p.begin() + static_cast<std::ptrdiff_t>(r.first), r.count, moving_pos_.begin() + static_cast<std::ptrdiff_t>(k));
      k += r.count;
    }
    sub = moving_pos_;
  }
  if (moving_cs_) {
    moving_cs_->update(sub);
    moving_times_ = moving_cs_->times();
  } else {
    moving_ts_->update(sub);
    moving_times_ = moving_ts_->times();
  }
}

TraceTotals SceneTracer::trace(const RayBatch& rays, HitBatch& hits, const TraceOptions& opt) const {
  const bool has_moving = moving_cs_ || moving_ts_;
  if (!static_ || !has_moving) {  // one BVH (its ids are the combined ids: identity map)
    const TraceData& d = static_ ? static_->data() : moving_data();
    return bvh::trace(d, rays, hits, opt);
  }
  TraceTotals a = bvh::trace(static_->data(), rays, hits, opt);
  // The second traversal only needs what can still win: closest hit up to the first one's t
  // (inclusive: (tmin, tmax] keeps a hit at equal t, whose id then decides); any hit only for
  // rays the first did not stop (a zero direction never hits).
  scratch_rays_ = rays;
  const bool closest = opt.mode == HitMode::Closest;
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (hits.triangle[i] == kNoTriangle) continue;
    if (closest)
      scratch_rays_.tmax[i] = std::min(scratch_rays_.tmax[i], hits.t[i]);
    else
      scratch_rays_.dx[i] = scratch_rays_.dy[i] = scratch_rays_.dz[i] = 0.0f;
  }
  const TraceTotals b = bvh::trace(moving_data(), scratch_rays_, scratch_, opt);
  map_ids(hits, static_ids_);
  map_ids(scratch_, moving_ids_);
  std::uint64_t n_hits = 0;
  for (std::size_t i = 0; i < hits.size(); ++i) {
    const std::uint32_t ta = hits.triangle[i], tb = scratch_.triangle[i];
    bool take_b = false;
    if (tb != kNoTriangle) {
      if (ta == kNoTriangle)
        take_b = true;
      else if (closest)
        take_b = scratch_.t[i] < hits.t[i] || (scratch_.t[i] == hits.t[i] && tb < ta);
    }
    if (take_b) {
      hits.t[i] = scratch_.t[i], hits.u[i] = scratch_.u[i], hits.v[i] = scratch_.v[i];
      hits.triangle[i] = tb;
    }
    n_hits += hits.triangle[i] != kNoTriangle;
  }
  if (opt.counters && scratch_.nodes_visited.size() == hits.size())
    for (std::size_t i = 0; i < hits.size(); ++i) {
      hits.nodes_visited[i] += scratch_.nodes_visited[i];
      hits.triangles_tested[i] += scratch_.triangles_tested[i];
    }
  a.hits = n_hits;
  a.nodes_visited += b.nodes_visited;
  a.triangles_tested += b.triangles_tested;
  return a;
}

std::vector<std::uint32_t> renumber_by_clusters(Scene& scene, Clustering& clusters, const SceneConfig& cfg) {
  std::vector<std::uint32_t> to_old = cluster_vertex_order(scene.rest(), view_of(clusters), scene.vertex_offsets(), cfg);
  clusters = renumber_vertices(std::move(clusters), inverse_permutation(to_old));  // (no copy)
  scene.renumber_vertices(to_old);
  return to_old;
}

}  // namespace ptc::bvh
