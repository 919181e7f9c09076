#include "viz/colour_scale.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace ptc::viz {

double ColourScale::fraction(double v) const {
  if (std::isnan(v)) return v;
  if (two_slope) return v < centre ? 0.5 * (v - min) / (centre - min) : 0.5 + 0.5 * (v - centre) / (max - centre);
  return (v - min) / (max - min);
}

double ColourScale::value_at(double f) const {
  if (two_slope) return f < 0.5 ? min + 2 * f * (centre - min) : centre + (2 * f - 1) * (max - centre);
  return min + f * (max - min);
}

ColourScale make_scale(std::string title, std::span<const double> values, bool diverging, double centre,
                       const std::optional<std::pair<double, double>>& fixed, bool from_zero, double floor) {
  ColourScale s;
  s.title = std::move(title);
  s.colormap = diverging ? "coolwarm" : "viridis";
  s.centre = centre;
  if (fixed) {
    if (!(std::isfinite(fixed->first) && std::isfinite(fixed->second) && fixed->first < fixed->second))
      throw std::invalid_argument("a range needs finite MIN < MAX");
    s.min = fixed->first, s.max = fixed->second;
    s.two_slope = diverging && s.min < centre && centre < s.max;
    s.from = "--range";
    return s;
  }
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double v : values)
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (diverging) {
    double d = lo > hi ? 1.0 : std::max(std::abs(hi - centre), std::abs(lo - centre));
    // No spread beyond rounding (a rigid motion's ratios are 1 to ~1e-16): no colours for noise.
    if (!(d > 1e-9 * std::max(1.0, std::abs(centre)))) d = 0.5;
    s.min = std::max(centre - d, floor), s.max = centre + d;
    if (!(s.min < centre)) s.min = centre - 0.5 * d;  // a floor at the centre: keep a lower half
    s.two_slope = true;
    return s;
  }
  if (lo > hi) {  // nothing finite
    s.min = 0, s.max = 1;
    return s;
  }
  if (from_zero && lo >= 0) lo = 0;
  // A spread below rounding, relative to the values (a mesh of 1e-6 units has areas of 1e-12 and
  // spreads far below 1): one value m, drawn on m -+ m / 2 (which keeps the sign of a positive or
  // negative quantity), or 0 .. 1 for m = 0.
  if (hi - lo > 1e-12 * std::max(std::abs(lo), std::abs(hi))) {
    s.min = lo, s.max = hi;
  } else {
    const double m = 0.5 * lo + 0.5 * hi;
    if (m == 0.0) s.min = 0.0, s.max = 1.0;
    else s.min = m - 0.5 * std::abs(m), s.max = m + 0.5 * std::abs(m);
  }
  return s;
}

double ColourScale::map_position(double v) const {
  if (std::isnan(v) || colormap != "coolwarm" || two_slope) return fraction(v);
  // A diverging range on one side of the centre: that side's part of the map, so that the centre
  // keeps the middle colour's meaning (a ratio range 1.2 .. 2 draws growth in reds, not 1.2 in
  // blue); values outside the range take its end colours.
  const double c = std::clamp(v, min, max);
  if (min >= centre && max > centre) return 0.5 + 0.5 * (c - centre) / (max - centre);
  if (max <= centre && min < centre) return 0.5 * (c - min) / (centre - min);
  return fraction(v);
}

Rgb8 colour_of(const ColourScale& s, double v) {
  if (std::isnan(v)) return kNanColour;
  const double x = s.map_position(v);
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
    double v = s.value_at(double(i) / (count - 1));
    if (i == count - 1) v = s.max;  // exactly, whatever the rounding of value_at
    if (s.integer) {
      v = std::round(v);
      if (v < s.min) v += 1;
      if (v > s.max) v -= 1;
      if (v < s.min || (!out.empty() && v <= out.back().value)) continue;
      out.push_back({v, s.fraction(v), fmt::format("{:.0f}", v)});
    } else {
      out.push_back({v, s.fraction(v), ""});
    }
  }
  if (!s.integer)  // 4 significant digits, more when a narrow range needs them to tell ticks apart
    for (int digits = 4; digits <= 15; ++digits) {
      for (Tick& t : out) t.text = fmt::format("{:.{}g}", t.value, digits);
      bool distinct = true;
      for (std::size_t i = 1; i < out.size(); ++i) distinct = distinct && out[i].text != out[i - 1].text;
      if (distinct) break;
    }
  return out;
}

}  // namespace ptc::viz
