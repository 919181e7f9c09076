#include "analysis/experiments/trace.h"

namespace ptc {

Table trace_table(const std::vector<TraceRow>& rows) {
  return tabulate(Schema{"ptc-trace", 5}, rows, [](const TraceRow& r, Columns& col) {
    const auto per_ray = [&](std::uint64_t total) { return r.stats.rays ? double(total) / double(r.stats.rays) : 0.0; };
    col("mesh", r.mesh);
    col("bvh", r.bvh);
    col("triangles", r.triangles);
    col("clusters", r.clusters);
    col("width", r.width);
    col("height", r.height);
    col("threads", r.threads);
    col("frame", r.frame);
    col("pass", r.pass);
    col("rays", r.stats.rays);
    col("hits", r.stats.hits);
    col("trace_ms", r.stats.trace_ms);
    col("mrays_per_s", r.stats.mrays_per_s());
    col("nodes_visited", r.stats.nodes_visited);
    col("triangles_tested", r.stats.triangles_tested);
    col("nodes_per_ray", per_ray(r.stats.nodes_visited));
    col("triangles_per_ray", per_ray(r.stats.triangles_tested));
    col("ao_samples", r.ao_samples);
    col("setup_ms", r.setup_ms);
    col("static_build_ms", r.static_build_ms);
    col("update_ms", r.update_ms);
    col("build_ms", r.build_ms);
    col("vertices_ms", r.stages.vertices_ms);
    col("boxes_ms", r.stages.boxes_ms);
    col("sah_build_ms", r.stages.build_ms);
    col("collapse_ms", r.stages.collapse_ms);
    col("leaf_data_ms", r.stages.leaf_data_ms);
    col("refit_ms", r.stages.refit_ms);
    col("overlap_ms", r.stages.overlap_ms);
    col("static_triangles", r.static_triangles);
    col("moving_triangles", r.moving_triangles);
    col("rss_mb", r.rss_mb);
    col("peak_rss_mb", r.peak_rss_mb);
  });
}

}  // namespace ptc
