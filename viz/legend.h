// The legend under a heatmap: the metric's name and range source on the first line, the colour
// bar (drawn here pixel by pixel with the scale's own colours, so the bar is exactly the map of
// the picture above), tick marks and their numbers (VTK text) under it, and a note line (values
// outside the range, NaN).
#pragma once

#include <string>

#include "viz/colour_scale.h"
#include "viz/renderer.h"

namespace ptc::viz {

/// Layout of legend_strip (pixels from the strip's top-left corner), for tests and callers.
inline constexpr int kMinLegendWidth = 240;

struct LegendLayout {
  int width = 0;   ///< max(asked width, kMinLegendWidth): narrower pictures get a wider legend
  int height = 0;
  int bar_x0 = 0, bar_x1 = 0;  ///< bar columns [bar_x0, bar_x1): x maps to min + (x - x0 + 0.5) / (x1 - x0) (max - min)
  int bar_y0 = 0, bar_y1 = 0;  ///< bar rows [bar_y0, bar_y1)
};
[[nodiscard]] LegendLayout legend_layout(int width);

/// A legend max(`width`, kMinLegendWidth) pixels wide. `note`: e.g.
/// "312 pixels above 120 drawn at the top colour". Its height is legend_layout's, plus 14 pixels
/// for each further line the note takes where it does not fit on one (broken at "; ", then at
/// spaces).
[[nodiscard]] RgbImage legend_strip(Renderer& r, const ColourScale& s, int width, const std::string& note = "");

}  // namespace ptc::viz
