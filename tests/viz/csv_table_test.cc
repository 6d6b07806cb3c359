#include "gipsi/viz/csv_table.h"

#include <cmath>
#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"
#include "gipsi/base/error.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

std::filesystem::path Write(const std::string& name, const std::string& text) {
  const auto dir = gipsi::testing::TempDir("gipsi_csv_", name);
  std::ofstream(dir / "t.csv") << text;
  return dir / "t.csv";
}

std::string Error(const std::filesystem::path& file) {
  try {
    (void)ReadCsv(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ReadCsv, ReadsColumnsByNameAsTheProbesWriteThem) {
  const auto file = Write("ok", "time,displacement_x, p\n0,1.5,-2e-3\n\n0.01,nan,+4\r\n");
  const CsvTable table = ReadCsv(file);
  ASSERT_EQ(table.names, (std::vector<std::string>{"time", "displacement_x", "p"}));
  EXPECT_EQ(table.num_rows(), 2u);
  EXPECT_EQ(table.Column("time"), (std::vector<double>{0, 0.01}));
  EXPECT_EQ(table.Column("p"), (std::vector<double>{-2e-3, 4}));
  EXPECT_TRUE(std::isnan(table.Column("displacement_x")[1]));
  EXPECT_EQ(table.Find("q"), -1);
  try {
    (void)table.Column("dispacement_x");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no column 'dispacement_x' (did you mean 'displacement_x'?); "
                                    "the columns are: time, displacement_x, p"));
  }
}

TEST(ReadCsv, NamesTheFileLineAndColumnOfBadInput) {
  EXPECT_THAT(Error(Write("fields", "a,b\n1,2\n3\n")),
              HasSubstr("t.csv: line 3: expected 2 comma-separated values (one per column of the "
                        "header), got 1"));
  EXPECT_THAT(Error(Write("number", "a,b\n1,x2\n")),
              HasSubstr("t.csv: line 2: column 'b': expected a number, got 'x2'"));
  EXPECT_THAT(Error(Write("empty", "")), HasSubstr("t.csv: empty file: expected a header line"));
  EXPECT_THAT(Error("/nonexistent/t.csv"),
              HasSubstr("/nonexistent/t.csv: cannot open the CSV file for reading"));
}

}  // namespace
}  // namespace gipsi::viz
