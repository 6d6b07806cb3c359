#include "gipsi/viz/color_map.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

TEST(ColorMap, GreyIsLinearFromBlackToWhite) {
  const ColorMap grey = ColorMap::Named("grey");
  for (double s : {0.0, 0.25, 0.5, 0.9, 1.0}) {
    const Rgb c = grey.At(s);
    // Float interpolation of a double parameter: exact to float round-off.
    EXPECT_NEAR(c.r, s, 1e-6);
    EXPECT_EQ(c.r, c.g);
    EXPECT_EQ(c.g, c.b);
  }
}

TEST(ColorMap, MapsRangeEndsToMapEndsAndClamps) {
  const ColorMap viridis = ColorMap::Named("viridis");
  EXPECT_EQ(viridis.Map(-5, -5, 5), viridis.At(0));
  EXPECT_EQ(viridis.Map(5, -5, 5), viridis.At(1));
  EXPECT_EQ(viridis.Map(-50, -5, 5), viridis.At(0));
  EXPECT_EQ(viridis.Map(50, -5, 5), viridis.At(1));
  // Viridis runs from dark purple (#440154) to yellow (#fde725).
  EXPECT_NEAR(viridis.At(0).r, 0x44 / 255.0, 1e-6);
  EXPECT_NEAR(viridis.At(1).g, 0xe7 / 255.0, 1e-6);
  // An empty range gives the middle colour; NaN gives the NaN colour.
  EXPECT_EQ(viridis.Map(3, 1, 1), viridis.At(0.5));
  EXPECT_EQ(viridis.Map(std::nan(""), 0, 1), kNanColor);
}

TEST(ColorMap, CoolWarmIsBlueGreyRed) {
  const ColorMap map = ColorMap::Named("cool-warm");
  EXPECT_GT(map.At(0).b, map.At(0).r);
  EXPECT_GT(map.At(1).r, map.At(1).b);
  EXPECT_NEAR(map.At(0.5).r, 221 / 255.0, 1e-6);
  EXPECT_EQ(map.At(0.5).r, map.At(0.5).b);
}

TEST(ColorMap, UnknownNameListsTheNames) {
  try {
    (void)ColorMap::Named("virdis");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown colour map 'virdis' (did you mean 'viridis'?); "
                                    "expected one of: viridis, cool-warm, grey, rainbow"));
  }
}

}  // namespace
}  // namespace gipsi::viz
