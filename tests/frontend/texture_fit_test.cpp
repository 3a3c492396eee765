// Fitting textures into array-texture layers: pass-through, padding, shrinking.
#include "texture_fit.h"

#include <gtest/gtest.h>

#include "frontend_test_util.h"

namespace thinlod::frontend::detail {
namespace {

using testing::solidImage;

TEST(TextureFit, ExactSizeIsUsedAsIs) {
  const FittedTexture fitted = fitTextureToLayer(*solidImage(16, 16, 1, 2, 3), 16);
  EXPECT_TRUE(fitted.useSource);
  EXPECT_EQ(fitted.uvScale, glm::vec2(1.0f));
}

TEST(TextureFit, SmallerTextureIsPaddedByReplicatingTheRightColumnAndTopRow) {
  RgbaImage image(3, 2);  // texel (x, y) = (10x, 10y, 7, 255)
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 3; ++x) {
      std::uint8_t* p = image.at(x, y);
      p[0] = static_cast<std::uint8_t>(10 * x);
      p[1] = static_cast<std::uint8_t>(10 * y);
      p[2] = 7;
      p[3] = 255;
    }
  }
  const FittedTexture fitted = fitTextureToLayer(image, 8);
  EXPECT_FALSE(fitted.useSource);
  EXPECT_FLOAT_EQ(fitted.uvScale.x, 3.0f / 8.0f);
  EXPECT_FLOAT_EQ(fitted.uvScale.y, 2.0f / 8.0f);
  ASSERT_EQ(fitted.image.width, 4);
  ASSERT_EQ(fitted.image.height, 3);
  // Row 0 repeats the image's top row; rows 1-2 are the image; column 3 repeats column 2.
  EXPECT_EQ(fitted.image.at(1, 0)[1], 0);
  EXPECT_EQ(fitted.image.at(1, 1)[1], 0);
  EXPECT_EQ(fitted.image.at(1, 2)[1], 10);
  EXPECT_EQ(fitted.image.at(3, 2)[0], 20);
  EXPECT_EQ(fitted.image.at(3, 0)[0], 20);
}

TEST(TextureFit, LargerTextureShrinksToTheLayer) {
  const FittedTexture fitted = fitTextureToLayer(*solidImage(32, 64, 40, 50, 60), 16);
  ASSERT_EQ(fitted.image.width, 16);
  ASSERT_EQ(fitted.image.height, 16);
  EXPECT_EQ(fitted.uvScale, glm::vec2(1.0f));
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      const std::uint8_t* p = fitted.image.at(x, y);
      ASSERT_TRUE(p[0] == 40 && p[1] == 50 && p[2] == 60 && p[3] == 255);
    }
  }
}

TEST(TextureFit, WideTextureShrinksOneAxisAndPadsTheOther) {
  const FittedTexture fitted = fitTextureToLayer(*solidImage(40, 4, 1, 1, 1), 16);
  EXPECT_EQ(fitted.image.width, 16);
  EXPECT_EQ(fitted.image.height, 5);  // 4 rows + one replicated top row
  EXPECT_FLOAT_EQ(fitted.uvScale.x, 1.0f);
  EXPECT_FLOAT_EQ(fitted.uvScale.y, 0.25f);
}

TEST(TextureFit, ShrinkWeightsColourByAlpha) {
  // A transparent texel must not darken its opaque neighbour.
  RgbaImage image(2, 1);
  const std::uint8_t texels[8] = {200, 100, 0, 255, 0, 0, 0, 0};
  std::copy(texels, texels + 8, image.pixels.begin());
  const RgbaImage small = shrinkImage(image, 1, 1);
  EXPECT_EQ(small.at(0, 0)[0], 200);
  EXPECT_EQ(small.at(0, 0)[1], 100);
  EXPECT_EQ(small.at(0, 0)[3], 128);
}

TEST(TextureFit, ShrinkOfFullyTransparentIsTransparentBlack) {
  const RgbaImage small = shrinkImage(*solidImage(4, 4, 90, 90, 90, 0), 2, 2);
  EXPECT_EQ(small.at(1, 1)[0], 0);
  EXPECT_EQ(small.at(1, 1)[3], 0);
}

// Repeating (mesh) textures fill the whole layer, so the layer's repeat wrap tiles them.
TEST(TextureFit, RepeatingTextureFillsTheLayerAndWrapsAtItsEdges) {
  EXPECT_TRUE(fitRepeatingTextureToLayer(*solidImage(16, 16, 1, 2, 3), 16).useSource);
  RgbaImage stripes(2, 1);  // left texel red, right texel blue
  stripes.at(0, 0)[0] = 200;
  stripes.at(0, 0)[3] = 255;
  stripes.at(1, 0)[2] = 200;
  stripes.at(1, 0)[3] = 255;
  const FittedTexture fitted = fitRepeatingTextureToLayer(stripes, 8);
  EXPECT_FALSE(fitted.useSource);
  EXPECT_EQ(fitted.uvScale, glm::vec2(1.0f));
  ASSERT_EQ(fitted.image.width, 8);
  ASSERT_EQ(fitted.image.height, 8);
  // Texel centres of the source land at layer x = 1.5 and 5.5: pure there.
  EXPECT_NEAR(fitted.image.at(1, 3)[0], 175, 1);  // 7/8 red, 1/8 wrapped-around blue
  EXPECT_NEAR(fitted.image.at(5, 3)[2], 175, 1);
  // The left edge blends with the right texel (wrap), not with itself (clamp).
  EXPECT_NEAR(fitted.image.at(0, 3)[0], 125, 1);
  EXPECT_NEAR(fitted.image.at(0, 3)[2], 75, 1);
  // Larger textures shrink to the layer first (box filter), then fill it.
  const FittedTexture big = fitRepeatingTextureToLayer(*solidImage(32, 8, 9, 8, 7), 16);
  ASSERT_EQ(big.image.width, 16);
  ASSERT_EQ(big.image.height, 16);
  EXPECT_EQ(big.image.at(3, 11)[0], 9);
  EXPECT_EQ(big.image.at(3, 11)[2], 7);
}

}  // namespace
}  // namespace thinlod::frontend::detail
