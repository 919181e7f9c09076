// CSV as the tests read it: RFC 4180 fields (quotes allowed) and rows as column -> value maps.
#pragma once

#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace ptc::test {

/// A column whose values differ between two runs of the same command by nature: times and rates
/// (`_ms`, `_s`, `mrays_per_s`, `ns_per_sphere*`, speed-ups), memory (`_mb`) and the thread count
/// (all cores by default). Everything else must repeat exactly.
inline bool run_dependent_column(const std::string& c) {
  if (c == "threads") return true;
  auto ends = [&](const std::string& s) { return c.size() >= s.size() && c.compare(c.size() - s.size(), s.size(), s) == 0; };
  return ends("_ms") || ends("_s") || ends("_mb") || c.find("mrays_per_s") != std::string::npos ||
         c.rfind("ns_per_sphere", 0) == 0 || c.find("speedup") != std::string::npos ||
         c.find("speed_vs") != std::string::npos;
}

/// The fields of one line.
inline std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> f(1);
  bool q = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char ch = line[i];
    if (q) {
      if (ch == '"' && i + 1 < line.size() && line[i + 1] == '"') f.back() += '"', ++i;
      else if (ch == '"') q = false;
      else f.back() += ch;
    } else if (ch == '"') {
      q = true;
    } else if (ch == ',') {
      f.emplace_back();
    } else {
      f.back() += ch;
    }
  }
  return f;
}

/// Every line's fields (the header first).
inline std::vector<std::vector<std::string>> csv_table(const std::string& text) {
  std::vector<std::vector<std::string>> t;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) t.push_back(csv_fields(l));
  return t;
}

/// The data rows as column -> value (columns from the header line).
inline std::vector<std::map<std::string, std::string>> csv_rows(const std::string& text) {
  const auto t = csv_table(text);
  std::vector<std::map<std::string, std::string>> out;
  for (std::size_t r = 1; r < t.size(); ++r) {
    std::map<std::string, std::string> m;
    for (std::size_t c = 0; c < t[0].size() && c < t[r].size(); ++c) m[t[0][c]] = t[r][c];
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace ptc::test
