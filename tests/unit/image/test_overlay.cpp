// The overlays' scale bar (issue 21): a round length (1, 2 or 5 x 10^k m) that fits a quarter of
// the picture, drawn to the pixel, with its unit.
#include <gtest/gtest.h>

#include "tomodem/image/outputs.hpp"

using namespace tomodem::image;

TEST(OverlayScaleBar, RoundLengthInAQuarterOfTheWidth) {
  struct Row { double mpp; int width; double length_m; int pixels; const char* label; };
  // By hand: room = width/4 x mpp; the largest of 1, 2, 5 x 10^k below it; pixels = length / mpp.
  const Row rows[] = {
      {1e-6, 400, 100e-6, 100, "100 um"},    // room 100 um exactly: the bar takes it
      {2.5e-6, 300, 100e-6, 40, "100 um"},   // room 187.5 um
      {1e-5, 256, 500e-6, 50, "500 um"},     // room 640 um
      {1e-5, 450, 1e-3, 100, "1 mm"},        // room 1.125 mm: the unit changes to mm
      {3e-9, 1000, 500e-9, 167, "500 nm"},   // room 750 nm; 166.7 px rounds to 167
      {4e-3, 1000, 1.0, 250, "1 m"},
  };
  for (const Row& r : rows) {
    const ScaleBar b = scale_bar(r.mpp, r.width);
    EXPECT_NEAR(b.length_m / r.length_m, 1.0, 1e-12) << r.label;
    EXPECT_EQ(b.pixels, r.pixels) << r.label;
    EXPECT_EQ(b.label, r.label);
    EXPECT_LE(b.pixels, r.width / 4 + 1) << r.label;
  }
}

TEST(OverlayScaleBar, NoPictureIsAnError) {
  EXPECT_ANY_THROW(scale_bar(0.0, 100));
  EXPECT_ANY_THROW(scale_bar(1e-6, 0));
}
