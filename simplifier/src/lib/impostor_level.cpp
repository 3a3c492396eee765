// Impostor level choice and capture comparison (impostor_level.h).
#include "thinlod/simplifier/impostor_level.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

namespace thinlod::simplifier {

double impostorLevelTolerance(const ImpostorFraming& framing, double texelFraction) {
  if (!(texelFraction > 0.0) || !std::isfinite(texelFraction)) return 0.0;
  if (framing.textureSize <= 0 || !(framing.planeDistance > 0.0f)) return 0.0;
  const double texelAtPlane =
      std::min(framing.quad.width, framing.quad.height) / static_cast<double>(framing.textureSize);
  // Texels shrink towards the viewpoint: the nearest depth has the smallest.
  const double nearScale =
      std::max(0.0f, framing.nearDepth) / static_cast<double>(framing.planeDistance);
  const double tolerance = texelFraction * texelAtPlane * nearScale;
  return std::isfinite(tolerance) && tolerance > 0.0 ? tolerance : 0.0;
}

std::optional<std::size_t> chooseImpostorLevel(const std::vector<double>& relativeErrors,
                                               double diameter, double tolerance) {
  if (!(diameter > 0.0) || !std::isfinite(diameter)) return std::nullopt;
  if (!(tolerance > 0.0) || !std::isfinite(tolerance)) return std::nullopt;
  for (std::size_t i = 0; i < relativeErrors.size(); ++i) {
    const double e = relativeErrors[i];
    if (e >= 0.0 && std::isfinite(e) && e * diameter <= tolerance) return i;
  }
  return std::nullopt;
}

std::vector<double> creditedRelativeErrors(const std::vector<CurveLevel>& levels,
                                           double minRelativeError) {
  std::vector<double> credits(levels.size());
  double worstFiner = 0.0;
  for (std::size_t i = levels.size(); i-- > 0;) {
    worstFiner = std::max(worstFiner, std::max(levels[i].relativeMaxError, minRelativeError));
    credits[i] = worstFiner;
  }
  return credits;
}

Result<ImpostorTextureDifference> compareImpostorTextures(const RgbaImage& a, const RgbaImage& b) {
  if (!a.consistent() || !b.consistent()) {
    return Status(ErrorCode::kInvalidArgument, "compareImpostorTextures: inconsistent image");
  }
  if (a.width != b.width || a.height != b.height) {
    return Status(ErrorCode::kInvalidArgument,
                  "compareImpostorTextures: sizes differ (" + std::to_string(a.width) + "x" +
                      std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                      std::to_string(b.height) + ")");
  }
  ImpostorTextureDifference out;
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    const int d = std::abs(static_cast<int>(a.pixels[i]) - static_cast<int>(b.pixels[i]));
    out.maxAbs = std::max(out.maxAbs, d);
    sum += static_cast<std::uint64_t>(d);
  }
  for (std::size_t i = 3; i < a.pixels.size(); i += 4) {
    const bool ca = a.pixels[i] != 0;
    const bool cb = b.pixels[i] != 0;
    out.coverageMismatch += ca != cb;
    out.coveredEither += ca || cb;
  }
  if (!a.pixels.empty())
    out.meanAbs = static_cast<double>(sum) / static_cast<double>(a.pixels.size());
  return out;
}

}  // namespace thinlod::simplifier
