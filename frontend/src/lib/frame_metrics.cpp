#include "thinlod/frontend/frame_metrics.h"

#include <cmath>
#include <limits>
#include <string>

namespace thinlod::frontend {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

}  // namespace

double snrFromMoments(double variance, double mse) {
  if (mse == 0.0) return variance == 0.0 ? 0.0 : kInfinity;
  if (variance == 0.0) return -kInfinity;
  return 10.0 * std::log10(variance / mse);
}

double psnrFromMse(double mse) {
  if (mse == 0.0) return kInfinity;
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

Result<FrameComparison> compareFrames(const std::uint8_t* simplified, const std::uint8_t* reference,
                                      std::size_t pixelCount) {
  if (pixelCount == 0) {
    return Status(ErrorCode::kInvalidArgument, "compareFrames: empty frames");
  }
  if (simplified == nullptr || reference == nullptr) {
    return Status(ErrorCode::kInvalidArgument, "compareFrames: null frame buffer");
  }
  // 16384^2 pixels * 3 * 255^2 < 2^64: the sums below cannot overflow for any
  // frame a render target can hold; larger inputs are refused.
  if (pixelCount > std::size_t{16384} * 16384) {
    return Status(ErrorCode::kInvalidArgument,
                  "compareFrames: " + std::to_string(pixelCount) + " pixels exceed 16384^2");
  }
  std::uint64_t sum = 0;
  std::uint64_t sumSquares = 0;
  std::uint64_t sumSquaredErrors = 0;
  for (std::size_t p = 0; p < pixelCount; ++p) {
    const std::uint8_t* s = simplified + p * 4;
    const std::uint8_t* f = reference + p * 4;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t sv = s[c];
      const std::int32_t d = static_cast<std::int32_t>(s[c]) - static_cast<std::int32_t>(f[c]);
      sum += sv;
      sumSquares += sv * sv;
      sumSquaredErrors += static_cast<std::uint32_t>(d * d);
    }
  }
  FrameComparison result;
  result.samples = pixelCount * 3;
  const auto n = static_cast<unsigned __int128>(result.samples);
  // N^2 VAR = N sum s^2 - (sum s)^2, exact in 128 bits.
  const unsigned __int128 varianceNumerator =
      n * sumSquares - static_cast<unsigned __int128>(sum) * sum;
  const double nDouble = static_cast<double>(result.samples);
  result.variance = static_cast<double>(varianceNumerator) / (nDouble * nDouble);
  result.mse = static_cast<double>(sumSquaredErrors) / nDouble;
  result.snrDb = snrFromMoments(result.variance, result.mse);
  result.psnrDb = psnrFromMse(result.mse);
  return result;
}

Result<FrameComparison> compareFrames(const RgbaImage& simplified, const RgbaImage& reference) {
  if (!simplified.consistent() || !reference.consistent()) {
    return Status(ErrorCode::kInvalidArgument,
                  "compareFrames: a frame's pixel buffer does not match its size");
  }
  if (simplified.width != reference.width || simplified.height != reference.height) {
    return Status(ErrorCode::kInvalidArgument,
                  "compareFrames: frame " + std::to_string(simplified.width) + "x" +
                      std::to_string(simplified.height) + " vs reference " +
                      std::to_string(reference.width) + "x" + std::to_string(reference.height));
  }
  return compareFrames(simplified.pixels.data(), reference.pixels.data(),
                       static_cast<std::size_t>(simplified.width) * simplified.height);
}

Result<double> frameSnr(const RgbaImage& simplified, const RgbaImage& reference) {
  auto comparison = compareFrames(simplified, reference);
  if (!comparison.ok()) return comparison.status();
  return comparison->snrDb;
}

Result<double> framePsnr(const RgbaImage& simplified, const RgbaImage& reference) {
  auto comparison = compareFrames(simplified, reference);
  if (!comparison.ok()) return comparison.status();
  return comparison->psnrDb;
}

}  // namespace thinlod::frontend
