// Tables with a schema (analysis/schema/table.h): the header and the values from one visitor.
#include <gtest/gtest.h>

#include <stdexcept>

#include "analysis/schema/table.h"

namespace ptc {
namespace {

struct Row {
  std::int64_t frame = 0;
  std::string config;
  double ms = 0;
  std::size_t hits = 0;
  bool ok = false;
};

void visit(const Row& r, Columns& col) {
  col("frame", r.frame);
  col("config", r.config);
  col("trace_ms", r.ms);
  col("hits", r.hits);
  col("ok", r.ok);
}

TEST(Table, HeaderAndValuesFromOneVisitor) {
  const std::vector<Row> rows{{0, "a", 1.5, 3, true}, {1, "b,c", 0.25, 0, false}};
  const Table t = tabulate(Schema{"ptc-test", 3}, rows, visit);
  EXPECT_EQ(t.schema.id(), "ptc-test/3");
  EXPECT_EQ(t.csv.columns(), (std::vector<std::string>{"frame", "config", "trace_ms", "hits", "ok"}));
  EXPECT_EQ(t.csv.str(), "frame,config,trace_ms,hits,ok\n0,a,1.5,3,1\n1,\"b,c\",0.25,0,0\n");
  // No rows: the header alone, from a default row.
  EXPECT_EQ(tabulate(Schema{"ptc-test", 3}, std::vector<Row>{}, visit).csv.str(), "frame,config,trace_ms,hits,ok\n");
}

TEST(Table, AVisitorThatChangesItsColumnsIsAnError) {
  const std::vector<Row> rows{{0, "a", 1, 1, true}, {1, "", 1, 1, true}};
  // A column only for some rows: the row does not match the header.
  auto conditional = [](const Row& r, Columns& col) {
    col("frame", r.frame);
    if (!r.config.empty()) col("config", r.config);
  };
  EXPECT_THROW((void)tabulate(Schema{"x", 1}, rows, conditional), std::logic_error);
  auto reordered = [](const Row& r, Columns& col) {
    if (r.frame == 0) {
      col("frame", r.frame);
      col("hits", r.hits);
    } else {
      col("hits", r.hits);
      col("frame", r.frame);
    }
  };
  EXPECT_THROW((void)tabulate(Schema{"x", 1}, rows, reordered), std::logic_error);
}

}  // namespace
}  // namespace ptc
