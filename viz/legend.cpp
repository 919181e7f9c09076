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
  // As many ticks (5, 3 or 2) as fit without their numbers touching (~7.5 px per character, at
  // least 8 px apart), placed as they are drawn: the first number starts at its tick, the last
  // ends at its tick, the others are centred on theirs (so the two last numbers of five evenly
  // spaced ticks are nearer than the spacing says), at the ticks' own fractions.
  const int bar_w0 = l.bar_x1 - l.bar_x0;
  const auto tick_at = [&](double fraction) { return l.bar_x0 + static_cast<int>(std::lround(fraction * (bar_w0 - 1))); };
  const auto fit = [&](const std::vector<Tick>& t) {
    double right_of_last = -1e300;
    for (const Tick& k : t) {
      const double x = tick_at(k.fraction), w = 7.5 * double(k.text.size());
      const double left = x <= l.bar_x0 + 2 ? x : x >= l.bar_x1 - 3 ? x - w : x - 0.5 * w;
      if (left - right_of_last < 8) return false;
      right_of_last = left + w;
    }
    return true;
  };
  std::vector<Tick> tk;
  for (int n : {5, 3, 2}) {
    tk = ticks(s, n);
    if (tk.size() < 2 || fit(tk)) break;
  }
  std::vector<TextItem> items;
  // The title with where the range came from; on a narrow legend that goes to the note line.
  const std::string range_from = s.from.empty() ? "" : "range: " + s.from;
  const bool fits = 8.5 * double(s.title.size() + range_from.size() + 4) <= l.bar_x1 - l.bar_x0;
  items.push_back({fits && !range_from.empty() ? s.title + "  (" + range_from + ")" : s.title, l.bar_x0, 11, 14, -1,
                   {235, 235, 235}, true});
  const std::string note_line = fits || range_from.empty() ? note : range_from + (note.empty() ? "" : "; " + note);
  const int bar_w = bar_w0;
  const auto& tick_x = tick_at;
  for (std::size_t i = 0; i < tk.size(); ++i) {
    const int x = tick_x(tk[i].fraction);
    const int align = x <= l.bar_x0 + 2 ? -1 : x >= l.bar_x1 - 3 ? 1 : 0;
    items.push_back({tk[i].text, x, 52, 13, align});
  }
  if (!note_line.empty()) items.push_back({note_line, l.bar_x0, 69, 12, -1, {200, 200, 200}});
  RgbImage img = r.text(width, l.height, items);
  for (int x = l.bar_x0; x < l.bar_x1; ++x) {
    const Rgb8 c = colour_of(s, s.value_at((x - l.bar_x0 + 0.5) / bar_w));
    for (int y = l.bar_y0; y < l.bar_y1; ++y) img.set(x, y, c);
  }
  for (const Tick& t : tk) {  // tick marks under the bar
    const int x = tick_x(t.fraction);
    for (int y = l.bar_y1; y < l.bar_y1 + 4; ++y) img.set(x, y, Rgb8{235, 235, 235});
  }
  return img;
}

}  // namespace ptc::viz
