#include "viz/legend.h"

#include <algorithm>
#include <cmath>
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
  const std::vector<Tick> tk = ticks(s, kTicks);
  std::vector<TextItem> items;
  items.push_back({s.title + (s.from.empty() ? "" : "  (range: " + s.from + ")"), l.bar_x0, 11, 14, -1,
                   {235, 235, 235}, true});
  const int bar_w = l.bar_x1 - l.bar_x0;
  auto tick_x = [&](double v) {
    return l.bar_x0 + static_cast<int>(std::lround((v - s.min) / (s.max - s.min) * (bar_w - 1)));
  };
  for (std::size_t i = 0; i < tk.size(); ++i) {
    const int x = tick_x(tk[i].value);
    const int align = x <= l.bar_x0 + 2 ? -1 : x >= l.bar_x1 - 3 ? 1 : 0;
    items.push_back({tk[i].text, x, 52, 13, align});
  }
  if (!note.empty()) items.push_back({note, l.bar_x0, 69, 12, -1, {200, 200, 200}});
  RgbImage img = r.text(width, l.height, items);
  for (int x = l.bar_x0; x < l.bar_x1; ++x) {
    const double v = s.min + (x - l.bar_x0 + 0.5) / bar_w * (s.max - s.min);
    const Rgb8 c = colour_of(s, v);
    for (int y = l.bar_y0; y < l.bar_y1; ++y) img.set(x, y, c);
  }
  for (const Tick& t : tk) {  // tick marks under the bar
    const int x = tick_x(t.value);
    for (int y = l.bar_y1; y < l.bar_y1 + 4; ++y) img.set(x, y, Rgb8{235, 235, 235});
  }
  return img;
}

}  // namespace ptc::viz
