// Per-frame image quality of the thin client against the full-quality frame
// (Pasman & Jansen 2002, section 4.2). Pure functions, no GL, thread-safe.
//
// Definitions (docs/frontend.md), over the N = width * height * 3 RGB bytes
// of two RGBA8 frames (alpha ignored); s = the frontend's (simplified) frame,
// f = the reference (full-quality) frame:
//   MSE  = (1/N) sum (s_i - f_i)^2
//   VAR  = (1/N) sum (s_i - mean(s))^2          (variance of s, as in the paper)
//   SNR  = 10 log10(VAR / MSE) dB
//   PSNR = 10 log10(255^2 / MSE) dB
// Degenerate cases (IEEE infinities, never NaN):
//   MSE = 0, VAR > 0  -> SNR = +inf        (identical frames)
//   MSE = 0, VAR = 0  -> SNR = 0 dB        (identical uniform frames: the paper's
//                                           black screen "drops to 0 dB")
//   MSE > 0, VAR = 0  -> SNR = -inf        (uniform s, different f)
//   MSE = 0           -> PSNR = +inf
// Sums are exact (integers); MSE and VAR are then rounded once to double.
// Errors: frames of different or inconsistent sizes, or empty frames, are
// kInvalidArgument.
#pragma once

#include <cstddef>
#include <cstdint>

#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"

namespace thinlod::frontend {

struct FrameComparison {
  std::size_t samples = 0;  // N
  double mse = 0.0;
  double variance = 0.0;  // of the simplified frame
  double snrDb = 0.0;
  double psnrDb = 0.0;
};

Result<FrameComparison> compareFrames(const RgbaImage& simplified, const RgbaImage& reference);
// Same over raw RGBA8 buffers of `pixelCount` pixels each.
Result<FrameComparison> compareFrames(const std::uint8_t* simplified, const std::uint8_t* reference,
                                      std::size_t pixelCount);

Result<double> frameSnr(const RgbaImage& simplified, const RgbaImage& reference);
Result<double> framePsnr(const RgbaImage& simplified, const RgbaImage& reference);

// The formulas above applied to given moments (mse, variance >= 0).
double snrFromMoments(double variance, double mse);
double psnrFromMse(double mse);

}  // namespace thinlod::frontend
