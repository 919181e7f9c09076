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
  // The note on as many lines as the width takes, broken at its "; " parts (then at spaces): a
  // narrow legend clipped it at the picture's edge. About 6 pixels a character at this size
  // (measured: 78 characters in 456 pixels), 6.5 taken; each further line adds 14 pixels.
  std::vector<std::string> lines;
  if (!note_line.empty()) {
    const std::size_t per_line = std::max<std::size_t>(12, static_cast<std::size_t>(double(width - l.bar_x0 - 4) / 6.5));
    std::vector<std::string> words;  // parts, and the words of a part too long for a line
    for (std::size_t at = 0;;) {
      const std::size_t semi = note_line.find("; ", at);
      std::string part = note_line.substr(at, semi == std::string::npos ? std::string::npos : semi + 1 - at);
      if (part.size() <= per_line) {
        words.push_back(part);
      } else {
        for (std::size_t b = 0; b < part.size();) {
          std::size_t e = part.find(' ', b);
          if (e == std::string::npos) e = part.size();
          words.push_back(part.substr(b, e - b));
          b = e + 1;
        }
      }
      if (semi == std::string::npos) break;
      at = semi + 2;
    }
    std::string cur;
    for (const std::string& w : words) {
      if (!cur.empty() && cur.size() + 1 + w.size() > per_line) lines.push_back(cur), cur.clear();
      cur += (cur.empty() ? "" : " ") + w;
    }
    if (!cur.empty()) lines.push_back(cur);
  }
  for (std::size_t i = 0; i < lines.size(); ++i)
    items.push_back({lines[i], l.bar_x0, 69 + 14 * static_cast<int>(i), 12, -1, {200, 200, 200}});
  const int height = l.height + 14 * static_cast<int>(lines.size() > 1 ? lines.size() - 1 : 0);
  RgbImage img = r.text(width, height, items);
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
