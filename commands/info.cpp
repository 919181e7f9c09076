// `ptc info`: the mesh report as JSON (stable keys, schema "ptc-info/1") and as text.
#include "commands/commands.h"
#include "toolkit/clustering/cluster.h"

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>


#include "analysis/schema/json.h"
#include "bvh/threads.h"
#include "toolkit/core/memory.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/mesh_report.h"
#include "toolkit/core/strings.h"

#include <fmt/format.h>

namespace ptc {

namespace {

// Peak memory of the commands a mesh is given to, as measured on the armadillo subdivided to
// 208k .. 13.3M triangles (about half as many vertices as triangles; docs/scale.md, "Memory per
// triangle"): a fixed part (the program and its libraries) and bytes per triangle, within 15% of
// the measurements from 208k triangles on. Keys are the `ptc` commands as run there. MiB.
struct MemoryModel {
  const char* command;
  double base_mb, bytes_per_triangle;
  bool regions;  ///< a clustering that --regions N applies to (estimated for N = 8 and 32 too)
};
constexpr MemoryModel kMemoryModels[] = {
    {"cluster_growth", 32, 102, true},       // ptc cluster --method growth: 52 MiB at 208k, 1329 MiB at 13.3M
    {"cluster_contraction", 40, 142, true},  // ptc cluster --method contraction: 66 MiB at 208k, 1832 MiB at 13.3M
    {"trace", 40, 215, false},               // ptc trace MESH --clusters DIR --frame 0: 703 MiB at 3.3M
    {"bench", 60, 730, false},               // ptc bench MESH --frames 0:2 (Embree beside): 2397 MiB at 3.3M, 94-100 MiB at 52k
};

// Clustering in N regions on k = min(threads, N) threads (docs/clustering.md): the whole mesh's
// arrays, a vertex scratch per thread, and k regions at once, each at the one run's rate; never
// below the output stages' floor. bytes per triangle = max(floor, whole + k x per_thread +
// k / N x one_run). Fitted at 3.3M triangles (N = 8, 32; k = 1, 2); docs/scale.md.
constexpr double kRegionsWhole = 35, kRegionsPerThread = 4, kRegionsFloor = 60;

double regions_bytes_per_triangle(double one_run, double regions, double threads) {
  const double k = std::min(threads, regions);
  return std::max(kRegionsFloor, kRegionsWhole + k * kRegionsPerThread + k / regions * one_run);
}

nlohmann::json memory_estimate_json(std::size_t triangles) {
  nlohmann::json est, largest;
  const double machine = machine_memory_mb();
  // Below 2M triangles the contraction keeps the triangles' areas and normals
  // (detail::kLeanSavedBytesPerTriangle more; detail::lean_tables_for): measured 188 MiB at 832k against the lean model's 153.
  // `lean` and `full`: bytes a triangle from 2M triangles on and below; the peak at this mesh's
  // size, the largest mesh for the machine at the rate of its own size.
  auto add = [&](const std::string& command, double base_mb, double lean, double full) {
    const double lean_from = detail::kLeanContractionTriangles;
    est[command] = std::round(base_mb + double(triangles) * (double(triangles) < lean_from ? full : lean) / 1048576.0);
    if (machine > base_mb) {
      double n = (machine - base_mb) * 1048576.0 / lean;
      if (n < lean_from) n = (machine - base_mb) * 1048576.0 / full;
      largest[command] = static_cast<std::uint64_t>(n);
    }
  };
  const auto full = [](const MemoryModel& m) {
    return m.bytes_per_triangle + (std::string_view(m.command) == "cluster_contraction" ? detail::kLeanSavedBytesPerTriangle : 0.0);
  };
  for (const MemoryModel& m : kMemoryModels) add(m.command, m.base_mb, m.bytes_per_triangle, full(m));
  // With --regions 8 and 32 at this machine's default thread count (all cores).
  // The threads a run would take: --threads (ptc sets a process-wide limit from it), else all cores.
  const unsigned threads = static_cast<unsigned>(bvh::usable_threads());
  for (const MemoryModel& m : kMemoryModels)
    if (m.regions)
      for (const int n : {8, 32}) {
        const double k = static_cast<double>(threads);
        add(std::string(m.command) + "_regions_" + std::to_string(n), m.base_mb,
            regions_bytes_per_triangle(m.bytes_per_triangle, n, k), regions_bytes_per_triangle(full(m), n, k));
      }
  nlohmann::json j;
  j["peak_mb"] = est;
  j["machine_memory_mb"] = std::round(machine);
  j["threads"] = threads;
  j["largest_triangles_for_machine"] = largest;
  j["model"] = fmt::format(
      "peak MiB = base + triangles x bytes per triangle, measured on the armadillo subdivided (docs/scale.md); "
      "the contraction {} bytes per triangle more below {} triangles (it keeps the areas and normals there); "
      "with --regions N on k = min(threads, N) threads: bytes per triangle = max({}, {} + {} k + k / N x the one "
      "run's)",
      detail::kLeanSavedBytesPerTriangle, detail::kLeanContractionTriangles, kRegionsFloor, kRegionsWhole,
      kRegionsPerThread);
  return j;
}

nlohmann::json mesh_info_json(const std::filesystem::path& file, const ReadReport& read, const MeshReport& r, bool soup) {
  nlohmann::json j;
  j["schema"] = "ptc-info/1";
  j["file"] = file.string();
  j["format"] = to_string(read.format);
  j["binary"] = read.binary;
  j["faces_in_file"] = read.faces;
  j["polygons_triangulated"] = read.polygons;
  j["triangles_from_polygons"] = read.triangles_from_polygons;
  j["welded_vertices"] = read.welded_vertices;
  j["short_faces_skipped"] = read.short_faces;
  j["surplus_value_lines"] = read.surplus_lines;
  j["notes"] = read_notes(read);
  j["vertices"] = r.vertices;
  j["triangles"] = r.triangles;
  j["unreferenced_vertices"] = r.unreferenced_vertices;
  if (!r.bounds.empty()) {
    j["bbox_min"] = vec_json(r.bounds.lo);
    j["bbox_max"] = vec_json(r.bounds.hi);
    j["bbox_extent"] = vec_json(r.bounds.extent());
  }
  j["total_area"] = r.total_area;
  j["triangle_area"] = summary_json(r.triangle_area);
  j["edge_length"] = summary_json(r.edge_length);
  j["edges"] = r.edges;
  j["boundary_edges"] = r.boundary_edges;
  j["non_manifold_edges"] = r.non_manifold_edges;
  j["non_manifold_vertices"] = r.non_manifold_vertices;
  j["repeated_index_triangles"] = r.repeated_index_triangles;
  j["zero_area_triangles"] = r.zero_area_triangles;
  j["near_degenerate_triangles"] = r.near_degenerate_triangles;
  j["duplicate_vertices"] = r.duplicate_vertices;
  j["duplicate_triangles"] = r.duplicate_triangles;
  j["components"] = r.components;
  j["edge_components"] = r.edge_components;
  j["triangle_soup"] = soup;
  j["closed_manifold"] = r.closed_manifold();
  j["euler_characteristic"] = r.euler_characteristic();
  j["memory_estimate"] = memory_estimate_json(r.triangles);
  return j;
}

std::string mesh_info_text(const std::filesystem::path& file, const ReadReport& read, const MeshReport& r, bool soup) {
  std::string s;
  auto line = [&](std::string_view key, const std::string& value) { s += fmt::format("{:<26}{}\n", key, value); };
  auto summary = [](const Summary& x) {
    return fmt::format("min {:.6g}  mean {:.6g}  median {:.6g}  max {:.6g}", x.min, x.mean, x.p50, x.max);
  };
  line("file", file.string());
  line("format", fmt::format("{}{}", to_string(read.format), read.binary ? " (binary)" : ""));
  line("vertices", fmt::format("{} ({} unreferenced)", r.vertices, r.unreferenced_vertices));
  line("triangles", fmt::format("{} ({} from {} polygons)", r.triangles, read.triangles_from_polygons, read.polygons));
  if (read.welded_vertices) line("welded vertices", std::to_string(read.welded_vertices));
  for (const std::string& note : read_notes(read)) line("note", note);
  if (!r.bounds.empty()) {
    // (shortest round-trip digits: a small mesh far from the origin keeps its extent visible)
    line("bbox min", fmt::format("{} {} {}", r.bounds.lo.x(), r.bounds.lo.y(), r.bounds.lo.z()));
    line("bbox max", fmt::format("{} {} {}", r.bounds.hi.x(), r.bounds.hi.y(), r.bounds.hi.z()));
  }
  line("total area", std::isinf(r.total_area) ? std::string("inf (beyond double's range: areas are lengths squared)")
                                               : fmt::format("{:.9g}", r.total_area));
  line("triangle area", summary(r.triangle_area));
  line("edge length", summary(r.edge_length));
  line("edges", fmt::format("{} ({} boundary, {} non-manifold)", r.edges, r.boundary_edges, r.non_manifold_edges));
  line("non-manifold vertices", std::to_string(r.non_manifold_vertices));
  line("degenerate triangles",
       fmt::format("{} repeated index, {} zero area, {} near-degenerate (sine < 1e-12)", r.repeated_index_triangles,
                   r.zero_area_triangles, r.near_degenerate_triangles));
  line("duplicates", fmt::format("{}, {}", counted(r.duplicate_vertices, "vertex", "vertices"),
                                 counted(r.duplicate_triangles, "triangle")));
  line("components", fmt::format("{} (by vertex), {} (by edge)", r.components, r.edge_components));
  line("triangle soup", soup ? "yes (no vertex shared by two triangles: clustering joins coincident corners, --adjacency auto)"
                             : "no");
  line("closed manifold", r.closed_manifold() ? "yes" : "no");
  line("euler characteristic", std::to_string(r.euler_characteristic()));
  return s;
}

}  // namespace

void cmd_info(const InfoOptions& opt, std::ostream& out) {
  const LoadedMesh lm = read_mesh(opt.input);
  const MeshReport rep = analyze_mesh(lm.mesh);
  const bool soup = is_triangle_soup(lm.mesh);
  if (opt.json)
    out << dump_json(mesh_info_json(opt.input, lm.report, rep, soup));
  else
    out << mesh_info_text(opt.input, lm.report, rep, soup);
}

}  // namespace ptc
