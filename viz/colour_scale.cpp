#include "viz/colour_scale.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace ptc::viz {

ColourScale make_scale(std::string title, std::span<const double> values, bool diverging, double centre,
                       const std::optional<std::pair<double, double>>& fixed, bool from_zero) {
  ColourScale s;
  s.title = std::move(title);
  s.colormap = diverging ? "coolwarm" : "viridis";
  if (fixed) {
    if (!(std::isfinite(fixed->first) && std::isfinite(fixed->second) && fixed->first < fixed->second))
      throw std::invalid_argument("a range needs finite MIN < MAX");
    s.min = fixed->first, s.max = fixed->second;
    s.from = "--range";
    return s;
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double v : values)
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (lo > hi) {  // nothing finite
    s.min = diverging ? centre - 1 : 0, s.max = diverging ? centre + 1 : 1;
    return s;
  }
  if (diverging) {
    const double d = std::max(std::abs(hi - centre), std::abs(lo - centre));
    s.min = centre - (d > 0 ? d : 0.5), s.max = centre + (d > 0 ? d : 0.5);
    return s;
  }
  if (from_zero && lo >= 0) lo = 0;
  if (hi > lo) s.min = lo, s.max = hi;
  else s.min = lo - 0.5, s.max = hi + 0.5;
  return s;
}

Rgb8 colour_of(const ColourScale& s, double v) {
  if (std::isnan(v)) return kNanColour;
  const double x = (v - s.min) / (s.max - s.min);
  return s.colormap == "coolwarm" ? coolwarm(x) : viridis(x);
}

OutOfRange out_of_range(const ColourScale& s, std::span<const double> values) {
  OutOfRange o;
  for (double v : values) {
    if (std::isnan(v)) ++o.nan;
    else if (v < s.min) ++o.below;
    else if (v > s.max) ++o.above;
  }
  return o;
}

RgbImage hstack(std::span<const RgbImage> images, int gap, Rgb8 fill) {
  int w = 0, h = 0;
  for (std::size_t i = 0; i < images.size(); ++i) w += images[i].width + (i ? gap : 0), h = std::max(h, images[i].height);
  RgbImage out(w, h, fill);
  int x0 = 0;
  for (const RgbImage& img : images) {
    for (int y = 0; y < img.height; ++y)
      std::copy_n(img.rgb.begin() + 3 * static_cast<std::ptrdiff_t>(y) * img.width, 3 * img.width,
                  out.rgb.begin() + 3 * (static_cast<std::ptrdiff_t>(y) * w + x0));
    x0 += img.width + gap;
  }
  return out;
}

RgbImage vstack(std::span<const RgbImage> images, int gap, Rgb8 fill) {
  int w = 0, h = 0;
  for (std::size_t i = 0; i < images.size(); ++i) h += images[i].height + (i ? gap : 0), w = std::max(w, images[i].width);
  RgbImage out(w, h, fill);
  int y0 = 0;
  for (const RgbImage& img : images) {
    for (int y = 0; y < img.height; ++y)
      std::copy_n(img.rgb.begin() + 3 * static_cast<std::ptrdiff_t>(y) * img.width, 3 * img.width,
                  out.rgb.begin() + 3 * static_cast<std::ptrdiff_t>(y0 + y) * w);
    y0 += img.height + gap;
  }
  return out;
}

std::vector<Tick> ticks(const ColourScale& s, int count) {
  if (count < 2) throw std::invalid_argument("at least two ticks");
  std::vector<Tick> out;
  for (int i = 0; i < count; ++i) {
    double v = s.min + (s.max - s.min) * i / (count - 1);
    if (s.integer) {
      v = std::round(v);
      if (v < s.min) v += 1;
      if (v > s.max) v -= 1;
      if (v < s.min || (!out.empty() && v <= out.back().value)) continue;
      out.push_back({v, fmt::format("{:.0f}", v)});
    } else {
      out.push_back({v, fmt::format("{:.4g}", v)});
    }
  }
  return out;
}

}  // namespace ptc::viz
