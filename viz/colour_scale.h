// Colour scales of the heatmaps: a metric's values to colours through viridis (sequential) or
// coolwarm (diverging about a centre, symmetric), with the range the user fixed (--range MIN:MAX,
// so that frames, runs and BVHs compare by eye) or the range of the values (over a whole frame
// series when the caller collects it). Values outside the range take the end colours and are
// counted (the legend says how many); NaN takes kNanColour. Also the compositing of pictures
// into panels. No VTK here; legend_strip() (legend.h) draws the scale with its numbers.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "render/images.h"

namespace ptc::viz {

/// Colour of values that are not numbers (a cluster whose reference had a zero box, ...).
inline constexpr Rgb8 kNanColour = {110, 110, 110};

struct ColourScale {
  std::string title;           ///< the metric's name as in the CSVs ("box_area_ratio", "nodes_visited")
  std::string colormap = "viridis";  ///< "viridis" or "coolwarm"
  double min = 0, max = 1;     ///< values drawn at the two ends
  bool integer = false;        ///< label the ticks as integers (counters)
  std::string from;            ///< where the range came from: "--range", "values of frame 3", "values of frames 0:60"
  /// Diverging scales map [min, centre] to the lower half of the map and [centre, max] to the
  /// upper half (matplotlib's TwoSlopeNorm), so the centre keeps the middle colour when the range
  /// is not symmetric (ratios, which stop at 0). Linear when false.
  bool two_slope = false;
  double centre = 0;
  /// Where v falls on the map, 0 .. 1 (outside for values outside the range; NaN for NaN).
  [[nodiscard]] double fraction(double v) const;
  /// The value at fraction f of the map (the inverse of fraction()).
  [[nodiscard]] double value_at(double f) const;
  /// Where v's colour lies on the colour map, 0 .. 1: fraction(v), except for a diverging range
  /// that lies on one side of the centre, drawn with that side's half of the map only (the
  /// centre's colour keeps meaning the centre).
  [[nodiscard]] double map_position(double v) const;
};

/// The scale for `values` (NaN ignored): `fixed` when given; else sequential: [min, max] of the
/// values (0 .. max for non-negative counters when `from_zero`), diverging: centre -+ the largest
/// distance of a value from the centre, but never below `floor` (0 for ratios), two-slope about
/// the centre. A constant or empty set widens to a non-empty range, as does a spread below
/// rounding (1e-9 of the centre's size for diverging scales: a rigid motion's ratios are 1 to
/// ~1e-16, not a picture; 1e-12 of the values' size for sequential ones, whatever their units):
/// diverging centre -+ 0.5, sequential m -+ |m| / 2 for the one value m (its sign kept: no
/// negative legend for an area), 0 .. 1 for m = 0 or nothing finite. A
/// fixed diverging range is two-slope when it contains the centre; else it is laid out linearly
/// and coloured with the half of the map on its side of the centre (map_position).
[[nodiscard]] ColourScale make_scale(std::string title, std::span<const double> values, bool diverging, double centre,
                                     const std::optional<std::pair<double, double>>& fixed, bool from_zero = false,
                                     double floor = -std::numeric_limits<double>::infinity());

/// The colour of v on the scale (NaN -> kNanColour; outside the range: the end colour).
[[nodiscard]] Rgb8 colour_of(const ColourScale& s, double v);

/// How many of `values` fall below min and above max (NaN counted apart).
struct OutOfRange {
  std::size_t below = 0, above = 0, nan = 0;
};
[[nodiscard]] OutOfRange out_of_range(const ColourScale& s, std::span<const double> values);

/// Images side by side (top-aligned, `gap` pixels of `fill` between them and below shorter
/// ones) and one above the other (left-aligned).
[[nodiscard]] RgbImage hstack(std::span<const RgbImage> images, int gap, Rgb8 fill);
[[nodiscard]] RgbImage vstack(std::span<const RgbImage> images, int gap, Rgb8 fill);

/// Ticks for a legend: `count` values at even fractions of the map (value_at) with their text
/// ("{:.4g}"); on an integer scale the values are rounded to integers (duplicates dropped) and
/// written as integers; `fraction` is each tick's own position.
struct Tick {
  double value = 0, fraction = 0;
  std::string text;
};
[[nodiscard]] std::vector<Tick> ticks(const ColourScale& s, int count);

}  // namespace ptc::viz
