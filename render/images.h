// Images as plain buffers (no VTK below viz/): 8-bit RGB pixels, row-major from the top-left
// pixel (the order of bvh::primary_rays), and the colour maps that turn per-pixel quantities
// (depth, normals, traversal cost) into colours. viz/png.h writes an RgbImage as a PNG.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace ptc {

using Rgb8 = std::array<std::uint8_t, 3>;

struct RgbImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< 3 * width * height bytes: R, G, B of pixel (x, y) at 3 * (y * width + x)

  RgbImage() = default;
  /// A width x height image filled with `fill`. Throws std::invalid_argument for a negative size.
  RgbImage(int w, int h, Rgb8 fill = {0, 0, 0});
  [[nodiscard]] std::size_t pixel_count() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
  [[nodiscard]] Rgb8 at(int x, int y) const;
  void set(int x, int y, Rgb8 c);
  void set(std::size_t pixel, Rgb8 c) { rgb[3 * pixel] = c[0], rgb[3 * pixel + 1] = c[1], rgb[3 * pixel + 2] = c[2]; }
};

/// [0, 1] -> 0..255, rounded to nearest; values outside [0, 1] are clamped and NaN gives 0 (the
/// caller's range, not this function, decides what is in range).
[[nodiscard]] std::uint8_t to_u8(double x);

/// The perceptually uniform "viridis" map (matplotlib, van der Walt & Smith 2015), sampled at 9
/// control points and interpolated linearly in sRGB: x in [0, 1] (clamped; NaN -> 0).
[[nodiscard]] Rgb8 viridis(double x);

/// The diverging "coolwarm" map (Moreland 2009; matplotlib's table at 9 control points,
/// interpolated linearly): blue at 0, light grey at 0.5, red at 1; x clamped, NaN -> 0.
[[nodiscard]] Rgb8 coolwarm(double x);

/// How a scalar image was mapped to colours (recorded in the manifest as the image's legend).
struct ColorLegend {
  std::string quantity;  ///< what a pixel holds ("nodes_visited", "depth", ...)
  std::string colormap;  ///< "viridis", "grey", ...
  double min = 0, max = 0;  ///< values mapped to the ends of the map
  std::string note;         ///< e.g. "background (missed rays): black"
};

/// Heatmap of per-pixel counts: value / max over the image through viridis (min = 0, so a
/// count's colour reads the same on every image of a run with the same max); pixels whose
/// `hit` is false (missed rays) still show their count (a miss can be expensive too).
/// `counts.size()` must be width * height (std::invalid_argument otherwise). With `range`
/// (MIN < MAX) the map runs from MIN to MAX instead, so images of frames, runs and BVHs compare;
/// counts outside take the end colours and the legend's note says how many pixels did.
[[nodiscard]] RgbImage cost_heatmap(std::span<const std::uint32_t> counts, int width, int height,
                                    ColorLegend& legend, const std::optional<std::pair<double, double>>& range = {});

/// A horizontal colour bar of the map (left = min, right = max), for a legend next to a heatmap.
[[nodiscard]] RgbImage viridis_bar(int width, int height);

}  // namespace ptc
