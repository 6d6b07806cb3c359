// End-to-end tests of `gipsi cell`: the real binary paces a cell and writes a CSV trace.

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "apps/cli_test_util.h"

namespace gipsi {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using testing::Gipsi;
using testing::Result;

fs::path TempDir(const std::string& name) { return testing::TempDir("gipsi_cell_cli_", name); }

TEST(GipsiCell, WritesATraceWithEveryStateAndPrintsABeatTable) {
  const fs::path csv = TempDir("ttp") / "trace.csv";
  Result r = Gipsi(
      "cell TenTusscherPanfilov2006 --variant endo --bcl 500 --beats 2 --dt 0.02 "
      "--every 50 --out " +
      csv.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("TenTusscherPanfilov2006 (endo), 19 states"));
  EXPECT_THAT(r.output, HasSubstr("2 beats at bcl 500 ms, dt 0.02 ms, stimulus 52 uA/uF for 1 ms"));
  EXPECT_THAT(r.output, HasSubstr("APD90_ms"));
  std::ifstream in(csv);
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header,
            "t_ms,V_mV,Cai_mM,CaSR_mM,CaSS_mM,Nai_mM,Ki_mM,m,h,j,xr1,xr2,xs,r,s,d,f,f2,fCass,"
            "R_prime");
  // 1000 ms / 0.02 ms = 50 000 steps, written every 50: 1001 rows.
  std::size_t rows = 0, columns = 0;
  double t_last = -1, v_max = -1e9;
  while (std::getline(in, line)) {
    ++rows;
    std::stringstream fields(line);
    std::string field;
    columns = 0;
    while (std::getline(fields, field, ',')) {
      const double value = std::stod(field);
      if (columns == 0) t_last = value;
      if (columns == 1) v_max = std::max(v_max, value);
      ++columns;
    }
  }
  EXPECT_EQ(rows, 1001u);
  EXPECT_EQ(columns, 20u);
  EXPECT_DOUBLE_EQ(t_last, 1000.0);
  EXPECT_GT(v_max, 20.0);  // it fired
}

TEST(GipsiCell, PhenomenologicalModelWithParameters) {
  Result r = Gipsi(
      "cell MitchellSchaeffer --param tau_close=100 --param v_rest=-85 --dt 0.05 "
      "--apd 80");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("MitchellSchaeffer, 2 states"));
  EXPECT_THAT(r.output, HasSubstr("APD80_ms"));
  EXPECT_THAT(r.output, HasSubstr("   -85.000"));
}

TEST(GipsiCell, UnknownModelIsAnInputErrorListingTheModels) {
  Result r = Gipsi("cell LuoRudy");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output,
              HasSubstr("gipsi: error: command line: cell.model: unknown cell model 'LuoRudy'; "
                        "known: AlievPanfilov, FitzHughNagumo, MitchellSchaeffer, Nagumo, "
                        "TenTusscherPanfilov2006"));
}

TEST(GipsiCell, BadParametersAndVariantsAreInputErrors) {
  Result bad_key = Gipsi("cell TenTusscherPanfilov2006 --param gks=0.1");
  EXPECT_EQ(bad_key.code, 1);
  EXPECT_THAT(bad_key.output, HasSubstr("unknown key 'gks' (did you mean 'g_ks'?)"));
  Result bad_value = Gipsi("cell AlievPanfilov --param k=-1");
  EXPECT_EQ(bad_value.code, 1);
  EXPECT_THAT(bad_value.output, HasSubstr("cell.k: expected a positive number, got -1"));
  Result bad_variant = Gipsi("cell TenTusscherPanfilov2006 --variant mid");
  EXPECT_EQ(bad_variant.code, 1);
  EXPECT_THAT(bad_variant.output, HasSubstr("cell.variant: expected one of 'epi', 'endo', 'M'"));
  Result malformed = Gipsi("cell AlievPanfilov --param k");
  EXPECT_EQ(malformed.code, 1);
  EXPECT_THAT(malformed.output, HasSubstr("--param: expected key=value, got 'k'"));
}

TEST(GipsiCell, BadCommandLinesAreRejectedBeforeRunning) {
  EXPECT_NE(Gipsi("cell AlievPanfilov --bcl -5").code, 0);
  EXPECT_NE(Gipsi("cell").code, 0);
}

}  // namespace
}  // namespace gipsi
