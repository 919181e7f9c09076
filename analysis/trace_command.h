// `ptc trace` and `ptc bench` as library calls (apps/ptc only parses the arguments).
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "analysis/images.h"
#include "analysis/peer_bench.h"
#include "analysis/trace_camera.h"
#include "analysis/trace_render.h"

namespace ptc {

/// Writes an image file (viz::write_png in the command; analysis itself never includes VTK).
/// Must replace the file atomically and throw on failure.
using ImageWriter = std::function<void(const std::filesystem::path&, const RgbImage&)>;

struct TraceCommandOptions {
  std::filesystem::path input;         ///< mesh file
  std::filesystem::path clusters;      ///< directory of `ptc cluster` (triangles.csv); empty: triangle BVH
  std::filesystem::path out_dir;       ///< images, trace.csv, manifest.json (required)
  CameraSpec camera;
  RenderConfig render;                 ///< size, shadows, AO, seed, light, threads (0 = all cores)
  std::vector<std::string> argv;       ///< recorded in the manifest
};

/// Reads the mesh (and clusters), builds the BVH, renders one view and writes
///   shaded.png, depth.png, normal.png, cost_nodes.png, cost_triangles.png, cost_legend.png,
///   ao.png (with AO), trace.csv (one row, columns in docs/tracing.md) and manifest.json
/// into `out_dir` atomically; prints a summary table to `out`. Bad input -> InputError.
void cmd_trace(const TraceCommandOptions& opt, const ImageWriter& write_image, std::ostream& out);

/// The column list of trace.csv (schema ptc-trace/1).
[[nodiscard]] std::vector<std::string> trace_csv_columns();

struct BenchCommandOptions {
  std::filesystem::path input;
  std::filesystem::path clusters;  ///< triangles.csv directory; empty: growth/Acc clustering with max_count
  std::filesystem::path out_dir;   ///< bench.csv, summary.csv, manifest.json (required)
  PeerBenchConfig config;
  std::vector<std::string> argv;
};
/// Runs the peer benchmark (analysis/peer_bench.h) and writes bench.csv (per frame and
/// configuration), summary.csv (medians and ratios) and manifest.json; prints the tables.
void cmd_bench(const BenchCommandOptions& opt, std::ostream& out);

}  // namespace ptc
