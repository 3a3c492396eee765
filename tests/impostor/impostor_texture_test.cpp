// bleedColorIntoTransparent: colour spreads into the transparent border, alpha stays (no GL).
#include <gtest/gtest.h>

#include <random>
#include <vector>

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

// The definition: every pass scans every texel (the implementation before
// the frontier version; kept here as the reference).
void bleedByFullScans(RgbaImage& image, int pixels) {
  const int w = image.width;
  const int h = image.height;
  std::vector<unsigned char> filled(static_cast<std::size_t>(w) * h);
  for (std::size_t i = 0; i < filled.size(); ++i) filled[i] = image.pixels[i * 4 + 3] != 0;
  std::vector<std::size_t> ring;
  for (int pass = 0; pass < pixels; ++pass) {
    ring.clear();
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        if (filled[i]) continue;
        int sum[3] = {0, 0, 0};
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx;
            const int ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            const std::size_t j = static_cast<std::size_t>(ny) * w + nx;
            if (!filled[j]) continue;
            for (int c = 0; c < 3; ++c) sum[c] += image.pixels[j * 4 + c];
            ++count;
          }
        }
        if (count == 0) continue;
        for (int c = 0; c < 3; ++c) {
          image.pixels[i * 4 + c] = static_cast<std::uint8_t>((sum[c] + count / 2) / count);
        }
        ring.push_back(i);
      }
    }
    if (ring.empty()) break;
    for (std::size_t i : ring) filled[i] = 1;
  }
}

// Property (fixed seed): random sizes, sparse to dense coverage, 0..6 rings,
// 1-texel-wide images included: identical to the full-scan definition.
TEST(ImpostorTexture, FrontierBleedEqualsFullScans) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 300; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 40);
    const int h = 1 + static_cast<int>(rng() % 40);
    RgbaImage image(w, h);
    const double density = std::uniform_real_distribution<double>(0.0, 0.6)(rng);
    std::bernoulli_distribution covered(density);
    for (std::size_t i = 0; i < image.pixels.size(); i += 4) {
      for (int c = 0; c < 3; ++c) image.pixels[i + c] = static_cast<std::uint8_t>(rng());
      image.pixels[i + 3] = covered(rng) ? static_cast<std::uint8_t>(1 + rng() % 255) : 0;
    }
    const int pixels = static_cast<int>(rng() % 7);
    RgbaImage expected = image;
    bleedByFullScans(expected, pixels);
    bleedColorIntoTransparent(image, pixels);
    ASSERT_EQ(image.pixels, expected.pixels) << trial << ": " << w << "x" << h << " " << pixels;
  }
}

}  // namespace
}  // namespace thinlod::simplifier
