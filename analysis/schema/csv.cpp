#include "analysis/schema/csv.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace ptc {

std::string format_double(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, res.ptr);
}

CsvTable::CsvTable(std::vector<std::string> columns) : columns_(std::move(columns)) {}

void CsvTable::add_row(std::vector<CsvValue> row) {
  if (row.size() != columns_.size())
    throw std::invalid_argument("CsvTable: row of " + std::to_string(row.size()) + " values for " +
                                std::to_string(columns_.size()) + " columns");
  rows_.push_back(std::move(row));
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

std::string CsvTable::str() const {
  std::string out;
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (i) out += ',';
    append_field(out, columns_[i]);
  }
  out += '\n';
  for (const auto& row : rows_) {
    for (std::size_t i = 0; i < row.size(); ++i) {
      if (i) out += ',';
      std::visit(
          [&](const auto& v) {
            using T = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<T, std::string>)
              append_field(out, v);
            else if constexpr (std::is_same_v<T, double>)
              out += format_double(v);
            else
              out += std::to_string(v);
          },
          row[i]);
    }
    out += '\n';
  }
  return out;
}

}  // namespace ptc
