#include "viz/legend.h"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace ptc::viz {

LegendLayout legend_layout(int width) {
  width = std::max(width, kMinLegendWidth);
  LegendLayout l;
  l.width = width;
  l.height = 78;
  l.bar_x0 = 24, l.bar_x1 = width - 24;
  l.bar_y0 = 24, l.bar_y1 = 40;
  return l;
}

RgbImage legend_strip(Renderer& r, const ColourScale& s, int width, const std::string& note) {
  width = std::max(width, kMinLegendWidth);
  const LegendLayout l = legend_layout(width);
  constexpr int kTicks = 5;
  const std::vector<std::string> ticks = tick_labels(s, kTicks);
  std::vector<TextItem> items;
  items.push_back({s.title + (s.from.empty() ? "" : "  (range: " + s.from + ")"), l.bar_x0, 11, 14, -1,
                   {235, 235, 235}, true});
  const int bar_w = l.bar_x1 - l.bar_x0;
  for (int i = 0; i < kTicks; ++i) {
    const int x = l.bar_x0 + (bar_w - 1) * i / (kTicks - 1);
    items.push_back({ticks[i], x, 52, 13, i == 0 ? -1 : i == kTicks - 1 ? 1 : 0});
  }
  if (!note.empty()) items.push_back({note, l.bar_x0, 69, 12, -1, {200, 200, 200}});
  RgbImage img = r.text(width, l.height, items);
  for (int x = l.bar_x0; x < l.bar_x1; ++x) {
    const double v = s.min + (x - l.bar_x0 + 0.5) / bar_w * (s.max - s.min);
    const Rgb8 c = colour_of(s, v);
    for (int y = l.bar_y0; y < l.bar_y1; ++y) img.set(x, y, c);
  }
  for (int i = 0; i < kTicks; ++i) {  // tick marks under the bar
    const int x = l.bar_x0 + (bar_w - 1) * i / (kTicks - 1);
    for (int y = l.bar_y1; y < l.bar_y1 + 4; ++y) img.set(x, y, Rgb8{235, 235, 235});
  }
  return img;
}

}  // namespace ptc::viz
