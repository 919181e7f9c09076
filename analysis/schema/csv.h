// Tidy CSV: one row per observation, one column per variable, units in column names
// (`build_ms`, `radius_rel_err`). Doubles are written in the shortest form that reads back
// bit-identical, so a CSV is as precise as the run that wrote it.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace ptc {

using CsvValue = std::variant<std::int64_t, std::uint64_t, double, std::string>;

class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> columns);
  /// Appends a row; its size must equal the column count (std::invalid_argument otherwise).
  void add_row(std::vector<CsvValue> row);
  [[nodiscard]] const std::vector<std::string>& columns() const { return columns_; }
  [[nodiscard]] std::size_t rows() const { return rows_.size(); }
  /// RFC 4180 text: fields with commas, quotes or newlines are quoted; "\n" line ends;
  /// non-finite doubles are written as nan / inf / -inf.
  [[nodiscard]] std::string str() const;

 private:
  std::vector<std::string> columns_;
  std::vector<std::vector<CsvValue>> rows_;
};

/// Shortest round-trip decimal form of a double ("nan", "inf", "-inf" for non-finite).
[[nodiscard]] std::string format_double(double x);

}  // namespace ptc
