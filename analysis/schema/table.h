// Tables with a schema: a name and a version ("ptc-bench/1"), and named columns defined together
// with their values by ONE visitor per row type, so a column list can never drift from its
// values (style.md point 15):
//
//   void visit(const BenchRow& r, Columns& col) {
//     col("frame", r.frame);
//     col("config", r.config);
//     col("trace_ms", r.trace_ms);
//   }
//   const Table t = tabulate(kBenchSchema, rows, visit);   // t.csv.str(), t.schema.id()
//
// The header comes from visiting a default-constructed row, and every row must yield the same
// names in the same order (checked: std::logic_error otherwise). Units go into column names
// (`build_ms`, `mrays_per_s`); every column is documented in docs/ next to its schema name.
// A change of columns is a change of the schema's version.
#pragma once

#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "analysis/schema/csv.h"

namespace ptc {

struct Schema {
  std::string name;  ///< "ptc-bench"
  int version = 1;
  [[nodiscard]] std::string id() const { return name + "/" + std::to_string(version); }
};

/// What a row visitor writes into: the header names (first pass) or one row's values.
class Columns {
 public:
  /// The header pass: names are collected.
  Columns() = default;
  /// A row pass: names must repeat the header in order.
  explicit Columns(const std::vector<std::string>& header) : header_(&header) {}

  void operator()(std::string_view name, CsvValue value) {
    if (!header_) {
      names_.emplace_back(name);
      return;
    }
    if (values_.size() >= header_->size() || (*header_)[values_.size()] != name)
      throw std::logic_error("table row visitor: column '" + std::string(name) + "' out of order");
    values_.push_back(std::move(value));
  }
  template <class T>
    requires std::is_integral_v<T> && std::is_signed_v<T> && (!std::is_same_v<T, bool>)
  void operator()(std::string_view name, T v) { (*this)(name, CsvValue(static_cast<std::int64_t>(v))); }
  template <class T>
    requires std::is_integral_v<T> && std::is_unsigned_v<T> && (!std::is_same_v<T, bool>)
  void operator()(std::string_view name, T v) { (*this)(name, CsvValue(static_cast<std::uint64_t>(v))); }
  void operator()(std::string_view name, bool v) { (*this)(name, CsvValue(std::int64_t(v ? 1 : 0))); }
  void operator()(std::string_view name, double v) { (*this)(name, CsvValue(v)); }
  void operator()(std::string_view name, const char* v) { (*this)(name, CsvValue(std::string(v))); }
  void operator()(std::string_view name, const std::string& v) { (*this)(name, CsvValue(v)); }

  [[nodiscard]] std::vector<std::string> take_names() { return std::move(names_); }
  /// The row's values (complete: as many as the header has columns); clear() starts the next
  /// row in the same storage.
  [[nodiscard]] std::span<const CsvValue> values() const {
    if (header_ && values_.size() != header_->size())
      throw std::logic_error("table row visitor: a row has fewer columns than the header");
    return values_;
  }
  void clear() { values_.clear(); }

 private:
  const std::vector<std::string>* header_ = nullptr;
  std::vector<std::string> names_;
  std::vector<CsvValue> values_;
};

struct Table {
  Schema schema;
  CsvTable csv;
};

/// The header of a row type's table.
template <class Row, class Visit>
[[nodiscard]] std::vector<std::string> columns_of(Visit&& visit) {
  Columns c;
  visit(Row{}, c);
  return c.take_names();
}

/// `n` rows made one at a time by `row_at(i)` (a table of millions of rows needs no vector of
/// them), columns from `visit` (see the file comment). `reserve_bytes`: room for the text, when
/// the caller can bound it.
template <class Row, class RowAt, class Visit>
[[nodiscard]] Table tabulate_each(Schema schema, std::size_t n, RowAt&& row_at, Visit&& visit,
                                  std::size_t reserve_bytes = 0) {
  const std::vector<std::string> header = columns_of<Row>(visit);
  Table t{std::move(schema), CsvTable(header)};
  t.csv.reserve(reserve_bytes);
  Columns c(header);  // one row's storage for all rows
  for (std::size_t i = 0; i < n; ++i) {
    c.clear();
    visit(static_cast<const Row&>(row_at(i)), c);
    t.csv.add_row(c.values());
  }
  return t;
}
/// The block size of the tables written as they are made (stream_each, analysis/metrics's writers).
inline constexpr std::size_t kCsvBlockBytes = std::size_t{1} << 20;
/// tabulate_each's text handed to `sink(std::string_view)` in blocks of about 1 MiB instead of
/// kept as one string (a table of a million rows never holds its text whole). The same bytes in
/// the same order; returns the schema's id.
template <class Row, class RowAt, class Visit, class Sink>
std::string stream_each(const Schema& schema, std::size_t n, RowAt&& row_at, Visit&& visit, Sink&& sink) {
  constexpr std::size_t kBlock = kCsvBlockBytes;
  const std::vector<std::string> header = columns_of<Row>(visit);
  CsvTable csv(header);
  csv.reserve(kBlock + 4096);
  Columns c(header);
  for (std::size_t i = 0; i < n; ++i) {
    c.clear();
    visit(static_cast<const Row&>(row_at(i)), c);
    csv.add_row(c.values());
    if (csv.str().size() >= kBlock) {
      sink(std::string_view(csv.str()));
      csv.clear_text();
    }
  }
  sink(std::string_view(csv.str()));
  return schema.id();
}
/// One row per element of `rows`.
template <class Row, class Visit>
[[nodiscard]] Table tabulate(Schema schema, std::span<const Row> rows, Visit&& visit) {
  return tabulate_each<Row>(
      std::move(schema), rows.size(), [&](std::size_t i) -> const Row& { return rows[i]; }, std::forward<Visit>(visit));
}
template <class Row, class Visit>
[[nodiscard]] Table tabulate(Schema schema, const std::vector<Row>& rows, Visit&& visit) {
  return tabulate(std::move(schema), std::span<const Row>(rows), std::forward<Visit>(visit));
}

}  // namespace ptc
