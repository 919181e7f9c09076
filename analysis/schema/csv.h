// Tidy CSV: one row per observation, one column per variable, units in column names
// (`build_ms`, `radius_rel_err`). Doubles are written in the shortest form that reads back
// bit-identical, so a CSV is as precise as the run that wrote it.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace ptc {

using CsvValue = std::variant<std::int64_t, std::uint64_t, double, std::string>;

class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> columns);
  /// Appends a row; its size must equal the column count (std::invalid_argument otherwise). The
  /// row is written into the text at once (a table of 13M rows holds its text only: 16 bytes a
  /// row for triangles.csv instead of the 120 of the values).
  void add_row(std::vector<CsvValue> row);
  /// The same from a row built in place (no vector per row): `values` of column-count size.
  void add_row(std::span<const CsvValue> values);
  [[nodiscard]] const std::vector<std::string>& columns() const { return columns_; }
  [[nodiscard]] std::size_t rows() const { return rows_; }
  /// Room for `bytes` of text in all (a table of millions of rows then grows without copies).
  void reserve(std::size_t bytes) { text_.reserve(bytes); }
  /// RFC 4180 text: fields with commas, quotes or newlines are quoted; "\n" line ends;
  /// non-finite doubles are written as nan / inf / -inf.
  [[nodiscard]] const std::string& str() const { return text_; }
  /// Empties the text written so far, keeping its room (a caller that streams the table hands
  /// str() to its file, then clears it; the next rows start an empty text).
  void clear_text() { text_.clear(); }

 private:
  std::vector<std::string> columns_;
  std::size_t rows_ = 0;
  std::string text_;
};

/// Shortest round-trip decimal form of a double ("nan", "inf", "-inf" for non-finite).
[[nodiscard]] std::string format_double(double x);

/// A CSV read back as text: what `ptc merge` and the derived tables of the experiments work on,
/// so that a single run, a shard and a merge of shards derive their summaries from the same
/// cells. Fields are kept verbatim (written back unchanged by str()).
struct CsvText {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  /// Index of a column; std::invalid_argument naming it when there is none.
  [[nodiscard]] std::size_t column(std::string_view name) const;
  [[nodiscard]] bool has_column(std::string_view name) const;
  /// The cell as a double (nan/inf/-inf as written by format_double); std::invalid_argument
  /// naming the row and column when it is not a number.
  [[nodiscard]] double number(std::size_t row, std::size_t col) const;
  /// The same quoting rules as CsvTable::str().
  [[nodiscard]] std::string str() const;
};

/// Parses RFC 4180 text (quoted fields, "\n" or "\r\n" line ends; a final line end optional).
/// std::invalid_argument "line L: ..." for an unterminated quote or a row whose field count
/// differs from the header's; an empty text has no header.
[[nodiscard]] CsvText parse_csv(std::string_view text);

}  // namespace ptc
