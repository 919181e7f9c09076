#include "analysis/schema/csv.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ptc {

namespace {
/// format_double's text, appended.
void append_double(std::string& out, double x) {
  if (std::isnan(x)) {
    out += "nan";
  } else if (std::isinf(x)) {
    out += x > 0 ? "inf" : "-inf";
  } else {
    char buf[64];
    const auto res = std::to_chars(buf, buf + sizeof buf, x);
    out.append(buf, res.ptr);
  }
}
}  // namespace

std::string format_double(double x) {
  std::string s;
  append_double(s, x);
  return s;
}

namespace {
void append_field(std::string& out, std::string_view s) {
  if (s.find_first_of(",\"\n\r") == std::string_view::npos) {
    out += s;
    return;
  }
  out += '"';
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
}
}  // namespace

CsvTable::CsvTable(std::vector<std::string> columns) : columns_(std::move(columns)) {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (i) text_ += ',';
    append_field(text_, columns_[i]);
  }
  text_ += '\n';
}

void CsvTable::add_row(std::vector<CsvValue> row) { add_row(std::span<const CsvValue>(row)); }

void CsvTable::add_row(std::span<const CsvValue> row) {
  if (row.size() != columns_.size())
    throw std::invalid_argument("CsvTable: row of " + std::to_string(row.size()) + " values for " +
                                std::to_string(columns_.size()) + " columns");
  for (std::size_t i = 0; i < row.size(); ++i) {
    if (i) text_ += ',';
    std::visit(
        [&](const auto& v) {
          using T = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<T, std::string>) {
            append_field(text_, v);
          } else if constexpr (std::is_same_v<T, double>) {
            append_double(text_, v);
          } else {
            char buf[24];
            const auto res = std::to_chars(buf, buf + sizeof buf, v);
            text_.append(buf, res.ptr);
          }
        },
        row[i]);
  }
  text_ += '\n';
  ++rows_;
}

std::size_t CsvText::column(std::string_view name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return i;
  throw std::invalid_argument("no column '" + std::string(name) + "'");
}

bool CsvText::has_column(std::string_view name) const {
  for (const auto& h : header)
    if (h == name) return true;
  return false;
}

double CsvText::number(std::size_t row, std::size_t col) const {
  const std::string& s = rows.at(row).at(col);
  if (s == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (s == "inf") return std::numeric_limits<double>::infinity();
  if (s == "-inf") return -std::numeric_limits<double>::infinity();
  double v = 0;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
  if (res.ec != std::errc() || res.ptr != s.data() + s.size())
    throw std::invalid_argument("row " + std::to_string(row + 1) + ", column '" + header.at(col) + "': '" + s +
                                "' is not a number");
  return v;
}

std::string CsvText::str() const {
  std::string out;
  auto line = [&](const std::vector<std::string>& f) {
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (i) out += ',';
      append_field(out, f[i]);
    }
    out += '\n';
  };
  line(header);
  for (const auto& r : rows) line(r);
  return out;
}

CsvText parse_csv(std::string_view text) {
  CsvText t;
  std::vector<std::string> fields(1);
  bool quoted = false, any = false;
  std::size_t line = 1, start_line = 1;
  auto end_row = [&] {
    if (t.header.empty() && t.rows.empty()) {
      t.header = std::move(fields);
    } else {
      if (fields.size() != t.header.size())
        throw std::invalid_argument("line " + std::to_string(start_line) + ": " + std::to_string(fields.size()) +
                                    " fields for " + std::to_string(t.header.size()) + " columns");
      t.rows.push_back(std::move(fields));
    }
    fields.assign(1, std::string());
    any = false;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (!any) start_line = line, any = true;
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') fields.back() += '"', ++i;
      else if (c == '"') quoted = false;
      else {
        if (c == '\n') ++line;
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      ++line;
      end_row();
    } else {
      fields.back() += c;
    }
  }
  if (quoted) throw std::invalid_argument("line " + std::to_string(start_line) + ": a quoted field is not closed");
  if (any) end_row();
  return t;
}

}  // namespace ptc
