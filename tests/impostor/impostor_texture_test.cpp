// bleedColorIntoTransparent: colour spreads into the transparent border, alpha stays (no GL).
#include <gtest/gtest.h>

#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

RgbaImage dot5x5() {  // one opaque red texel in the middle
  RgbaImage image(5, 5);
  std::uint8_t* p = image.at(2, 2);
  p[0] = 200;
  p[3] = 255;
  return image;
}

TEST(ImpostorTexture, OneRingTakesNeighbourColourAndKeepsAlpha) {
  RgbaImage image = dot5x5();
  bleedColorIntoTransparent(image, 1);
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 5; ++x) {
      const std::uint8_t* p = image.at(x, y);
      const bool centre = x == 2 && y == 2;
      const bool ring = !centre && x >= 1 && x <= 3 && y >= 1 && y <= 3;
      EXPECT_EQ(p[3], centre ? 255 : 0) << x << "," << y;
      EXPECT_EQ(p[0], (centre || ring) ? 200 : 0) << x << "," << y;
      EXPECT_EQ(p[1], 0);
    }
  }
}

TEST(ImpostorTexture, RingsGrowOnePixelPerPass) {
  RgbaImage image = dot5x5();
  bleedColorIntoTransparent(image, 2);
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 5; ++x) {
      EXPECT_EQ(image.at(x, y)[0], 200) << x << "," << y;
      EXPECT_EQ(image.at(x, y)[3], (x == 2 && y == 2) ? 255 : 0);
    }
  }
}

TEST(ImpostorTexture, MixedNeighboursAverage) {
  RgbaImage image(3, 1);
  image.pixels = {100, 0, 0, 255, 0, 0, 0, 0, 0, 50, 0, 255};
  bleedColorIntoTransparent(image, 1);
  EXPECT_EQ(image.at(1, 0)[0], 50);  // (100 + 0) / 2
  EXPECT_EQ(image.at(1, 0)[1], 25);  // (0 + 50) / 2
  EXPECT_EQ(image.at(1, 0)[3], 0);
}

TEST(ImpostorTexture, ZeroPassesAndEmptyImagesAreNoOps) {
  RgbaImage image = dot5x5();
  const RgbaImage before = image;
  bleedColorIntoTransparent(image, 0);
  EXPECT_EQ(image.pixels, before.pixels);
  RgbaImage empty;
  bleedColorIntoTransparent(empty, 3);
  EXPECT_TRUE(empty.pixels.empty());
}

}  // namespace
}  // namespace thinlod::simplifier
