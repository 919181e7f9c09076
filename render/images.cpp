#include "render/images.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ptc {

RgbImage::RgbImage(int w, int h, Rgb8 fill) : width(w), height(h) {
  if (w < 0 || h < 0) throw std::invalid_argument("RgbImage: negative size");
  rgb.resize(3 * pixel_count());
  for (std::size_t i = 0; i < pixel_count(); ++i) set(i, fill);
}

Rgb8 RgbImage::at(int x, int y) const {
  const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x));
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void RgbImage::set(int x, int y, Rgb8 c) {
  set(static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x), c);
}

std::uint8_t to_u8(double x) {
  if (!(x > 0.0)) return 0;  // also NaN
  if (x >= 1.0) return 255;
  return static_cast<std::uint8_t>(std::lround(255.0 * x));
}

namespace {

// A map given at 9 evenly spaced control points (0, 1/8, ..., 1), interpolated linearly in sRGB;
// x clamped to [0, 1], NaN -> 0.
Rgb8 sample_map(const double (&k)[9][3], double x) {
  if (!(x > 0.0)) x = 0.0;
  if (x > 1.0) x = 1.0;
  const double s = 8.0 * x;
  const int i = std::min(7, static_cast<int>(s));
  const double f = s - i;
  Rgb8 c;
  for (int a = 0; a < 3; ++a)
    c[a] = static_cast<std::uint8_t>(std::lround(k[i][a] + f * (k[i + 1][a] - k[i][a])));
  return c;
}

}  // namespace

Rgb8 viridis(double x) {
  // matplotlib's viridis at 0, 1/8, ..., 1 (#440154 #472d7b #3b528b #2c728e #21918c #28ae80
  // #5ec962 #addc30 #fde725).
  static constexpr double k[9][3] = {{68, 1, 84},    {71, 45, 123},  {59, 82, 139},  {44, 114, 142}, {33, 145, 140},
                                     {40, 174, 128}, {94, 201, 98},  {173, 220, 48}, {253, 231, 37}};
  return sample_map(k, x);
}

Rgb8 coolwarm(double x) {
  // matplotlib's coolwarm (Moreland 2009) at 0, 1/8, ..., 1.
  static constexpr double k[9][3] = {{59, 76, 192},   {98, 130, 234},  {141, 176, 254}, {184, 208, 249}, {221, 221, 221},
                                     {245, 196, 173}, {244, 154, 123}, {222, 96, 77},   {180, 4, 38}};
  return sample_map(k, x);
}

RgbImage cost_heatmap(std::span<const std::uint32_t> counts, int width, int height, ColorLegend& legend,
                      const std::optional<std::pair<double, double>>& range) {
  RgbImage img(width, height);
  if (counts.size() != img.pixel_count()) throw std::invalid_argument("cost_heatmap: counts do not match the image size");
  legend.colormap = "viridis";
  if (range) {
    if (!(range->first < range->second)) throw std::invalid_argument("cost_heatmap: the range needs MIN < MAX");
    legend.min = range->first;
    legend.max = range->second;
    std::size_t below = 0, above = 0;
    for (std::size_t i = 0; i < counts.size(); ++i) {
      below += counts[i] < range->first;
      above += counts[i] > range->second;
      img.set(i, viridis((double(counts[i]) - range->first) / (range->second - range->first)));
    }
    if (below) legend.note += "; " + std::to_string(below) + " pixels below the range drawn at the bottom colour";
    if (above) legend.note += "; " + std::to_string(above) + " pixels above the range drawn at the top colour";
    return img;
  }
  std::uint32_t mx = 0;
  for (std::uint32_t c : counts) mx = std::max(mx, c);
  legend.min = 0;
  legend.max = mx;
  for (std::size_t i = 0; i < counts.size(); ++i) img.set(i, viridis(mx ? double(counts[i]) / double(mx) : 0.0));
  return img;
}

RgbImage viridis_bar(int width, int height) {
  RgbImage img(width, height);
  for (int x = 0; x < width; ++x) {
    const Rgb8 c = viridis(width > 1 ? double(x) / double(width - 1) : 0.0);
    for (int y = 0; y < height; ++y) img.set(x, y, c);
  }
  return img;
}

}  // namespace ptc
