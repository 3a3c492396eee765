// frameSnr / framePsnr: the paper's formulas on hand-computed images, the
// documented degenerate cases, errors, and properties on random images
// (cross-checked with OpenImageIO's ImageBufAlgo::compare).
#include "thinlod/frontend/frame_metrics.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace thinlod::frontend {
namespace {

RgbaImage image(int w, int h, std::initializer_list<int> rgba) {
  RgbaImage out(w, h);
  std::size_t i = 0;
  for (int v : rgba) out.pixels.at(i++) = static_cast<std::uint8_t>(v);
  return out;
}

RgbaImage randomImage(int w, int h, std::mt19937& rng, int lo = 0, int hi = 255) {
  std::uniform_int_distribution<int> value(lo, hi);
  RgbaImage out(w, h);
  for (auto& byte : out.pixels) byte = static_cast<std::uint8_t>(value(rng));
  return out;
}

TEST(FrameMetrics, MatchesHandComputedValues) {
  // s bytes {10,20,30,40,50,60}, f bytes {10,20,30,40,50,66}: N = 6,
  // mean(s) = 35, VAR = 9100/6 - 35^2 = 1750/6, MSE = 6^2/6 = 6.
  const RgbaImage s = image(2, 1, {10, 20, 30, 255, 40, 50, 60, 255});
  const RgbaImage f = image(2, 1, {10, 20, 30, 255, 40, 50, 66, 255});
  auto c = compareFrames(s, f);
  ASSERT_TRUE(c.ok()) << c.status().toString();
  EXPECT_EQ(c->samples, 6u);
  EXPECT_DOUBLE_EQ(c->mse, 6.0);
  EXPECT_DOUBLE_EQ(c->variance, 1750.0 / 6.0);
  EXPECT_NEAR(c->snrDb, 10.0 * std::log10((1750.0 / 6.0) / 6.0), 1e-12);
  EXPECT_NEAR(c->snrDb, 16.8674, 1e-4);
  EXPECT_NEAR(c->psnrDb, 10.0 * std::log10(65025.0 / 6.0), 1e-12);
  EXPECT_NEAR(*frameSnr(s, f), c->snrDb, 0.0);
  EXPECT_NEAR(*framePsnr(s, f), c->psnrDb, 0.0);
}

TEST(FrameMetrics, VarianceIsOfTheSimplifiedFrame) {
  // Swapping the roles changes VAR (the paper's VAR is over s only) but not MSE.
  const RgbaImage uniform = image(1, 1, {100, 100, 100, 255});
  const RgbaImage varied = image(1, 1, {70, 100, 130, 255});
  auto a = compareFrames(uniform, varied);
  auto b = compareFrames(varied, uniform);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_DOUBLE_EQ(a->mse, b->mse);
  EXPECT_DOUBLE_EQ(a->variance, 0.0);
  EXPECT_DOUBLE_EQ(b->variance, 600.0);  // (30^2 + 0 + 30^2) / 3
  EXPECT_DOUBLE_EQ(b->snrDb, 0.0);       // VAR == MSE
}

TEST(FrameMetrics, AlphaIsIgnored) {
  const RgbaImage s = image(2, 1, {10, 20, 30, 0, 40, 50, 60, 17});
  const RgbaImage f = image(2, 1, {10, 20, 30, 255, 40, 50, 66, 99});
  const RgbaImage s2 = image(2, 1, {10, 20, 30, 255, 40, 50, 60, 255});
  EXPECT_DOUBLE_EQ(*frameSnr(s, f), *frameSnr(s2, f));
  EXPECT_DOUBLE_EQ(*framePsnr(s, f), *framePsnr(s2, f));
}

TEST(FrameMetrics, IdenticalFramesHaveInfiniteSnrAndPsnr) {
  std::mt19937 rng(7);
  const RgbaImage s = randomImage(16, 8, rng);
  auto c = compareFrames(s, s);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->mse, 0.0);
  EXPECT_GT(c->variance, 0.0);
  EXPECT_EQ(c->snrDb, std::numeric_limits<double>::infinity());
  EXPECT_EQ(c->psnrDb, std::numeric_limits<double>::infinity());
}

TEST(FrameMetrics, IdenticalBlankFramesAreZeroDecibels) {
  // The paper's black screen (all objects out of view): 0 dB, PSNR infinite.
  const RgbaImage black(32, 24);
  auto c = compareFrames(black, black);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->snrDb, 0.0);
  EXPECT_FALSE(std::isnan(c->snrDb));
  EXPECT_EQ(c->psnrDb, std::numeric_limits<double>::infinity());
}

TEST(FrameMetrics, UniformFrameAgainstDifferentReferenceIsMinusInfinity) {
  const RgbaImage black(4, 4);
  RgbaImage reference(4, 4);
  reference.pixels[0] = 255;
  auto c = compareFrames(black, reference);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->snrDb, -std::numeric_limits<double>::infinity());
  EXPECT_NEAR(c->psnrDb, 10.0 * std::log10(65025.0 / (65025.0 / 48.0)), 1e-12);
}

TEST(FrameMetrics, MomentFormulasCoverTheDegenerateCases) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(snrFromMoments(0.0, 0.0), 0.0);
  EXPECT_EQ(snrFromMoments(5.0, 0.0), inf);
  EXPECT_EQ(snrFromMoments(0.0, 5.0), -inf);
  EXPECT_NEAR(snrFromMoments(100.0, 1.0), 20.0, 1e-12);
  EXPECT_EQ(psnrFromMse(0.0), inf);
  EXPECT_NEAR(psnrFromMse(65025.0), 0.0, 1e-12);
}

TEST(FrameMetrics, SizeMismatchIsRejected) {
  auto c = compareFrames(RgbaImage(4, 4), RgbaImage(4, 5));
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(c.status().message().find("4x5"), std::string::npos);
}

TEST(FrameMetrics, InconsistentBufferIsRejected) {
  RgbaImage broken(4, 4);
  broken.pixels.resize(10);
  EXPECT_EQ(compareFrames(broken, broken).status().code(), ErrorCode::kInvalidArgument);
}

TEST(FrameMetrics, EmptyFramesAreRejected) {
  EXPECT_EQ(compareFrames(RgbaImage(), RgbaImage()).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(compareFrames(nullptr, nullptr, 4).status().code(), ErrorCode::kInvalidArgument);
}

// Two-pass long-double computation straight from the paper's definitions.
void naiveMoments(const RgbaImage& s, const RgbaImage& f, long double& mse, long double& var) {
  long double mean = 0, n = 0;
  for (std::size_t i = 0; i < s.pixels.size(); ++i) {
    if (i % 4 == 3) continue;
    mean += s.pixels[i];
    n += 1;
  }
  mean /= n;
  mse = 0;
  var = 0;
  for (std::size_t i = 0; i < s.pixels.size(); ++i) {
    if (i % 4 == 3) continue;
    const long double d = static_cast<long double>(s.pixels[i]) - f.pixels[i];
    mse += d * d;
    var += (s.pixels[i] - mean) * (s.pixels[i] - mean);
  }
  mse /= n;
  var /= n;
}

TEST(FrameMetrics, AgreesWithTwoPassDefinitionOnRandomFrames) {
  std::mt19937 rng(2002);
  for (int trial = 0; trial < 20; ++trial) {
    std::uniform_int_distribution<int> size(1, 90);
    const int w = size(rng);
    const int h = size(rng);
    const RgbaImage s = randomImage(w, h, rng);
    const RgbaImage f = randomImage(w, h, rng);
    long double mse = 0, var = 0;
    naiveMoments(s, f, mse, var);
    auto c = compareFrames(s, f);
    ASSERT_TRUE(c.ok());
    EXPECT_NEAR(c->mse, static_cast<double>(mse), 1e-9 * static_cast<double>(mse));
    EXPECT_NEAR(c->variance, static_cast<double>(var), 1e-9 * static_cast<double>(var) + 1e-12);
    EXPECT_NEAR(c->snrDb, 10.0 * std::log10(static_cast<double>(var / mse)), 1e-9);
  }
}

TEST(FrameMetrics, ShiftingBothFramesChangesNothing) {
  // MSE depends on differences only and VAR is shift-invariant.
  std::mt19937 rng(35);
  const RgbaImage s = randomImage(40, 30, rng, 0, 200);
  const RgbaImage f = randomImage(40, 30, rng, 0, 200);
  RgbaImage s2 = s, f2 = f;
  for (std::size_t i = 0; i < s.pixels.size(); ++i) {
    s2.pixels[i] = static_cast<std::uint8_t>(s.pixels[i] + 55);
    f2.pixels[i] = static_cast<std::uint8_t>(f.pixels[i] + 55);
  }
  auto a = compareFrames(s, f);
  auto b = compareFrames(s2, f2);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_DOUBLE_EQ(a->mse, b->mse);
  EXPECT_DOUBLE_EQ(a->variance, b->variance);
  EXPECT_DOUBLE_EQ(a->snrDb, b->snrDb);
}

// OpenImageIO over the RGB channels only: rms_error^2 * 255^2 is our MSE and
// its PSNR is ours.
OIIO::ImageBuf toImageBuf(const RgbaImage& image) {
  OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::UINT8);
  OIIO::ImageBuf buffer(spec);
  buffer.set_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, image.pixels.data());
  return buffer;
}

TEST(FrameMetrics, PsnrAgreesWithOpenImageIoOnRandomFrames) {
  std::mt19937 rng(480);
  for (int trial = 0; trial < 5; ++trial) {
    const RgbaImage s = randomImage(64, 48, rng);
    RgbaImage f = s;
    std::normal_distribution<double> noise(0.0, 4.0 + 8.0 * trial);
    for (auto& byte : f.pixels) {
      byte = static_cast<std::uint8_t>(std::clamp(byte + std::lround(noise(rng)), 0L, 255L));
    }
    OIIO::ROI rgb = OIIO::get_roi(toImageBuf(s).spec());
    rgb.chbegin = 0;
    rgb.chend = 3;
    const OIIO::ImageBufAlgo::CompareResults oiio =
        OIIO::ImageBufAlgo::compare(toImageBuf(s), toImageBuf(f), 1.0f, 1.0f, rgb);
    ASSERT_FALSE(oiio.error);
    auto c = compareFrames(s, f);
    ASSERT_TRUE(c.ok());
    EXPECT_NEAR(c->mse, oiio.rms_error * oiio.rms_error * 255.0 * 255.0, 1e-5 * c->mse);
    EXPECT_NEAR(c->psnrDb, oiio.PSNR, 1e-4);
  }
}

}  // namespace
}  // namespace thinlod::frontend
