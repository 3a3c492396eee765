// Frame-time cost constants of a renderer (Gobbetti & Bouvier 1999, "Time-
// critical multiresolution scene rendering", section 4.1) and their fit.
//
// Contract:
// - Units: seconds. The model of one frame with objects j, each drawn with
//   T_j triangles covering P_j pixels, is
//     t_frame = t_init + t_final + sum_j (t_setup + max(T_j * t_tri, P_j * t_pix)).
//   (The paper's text lost its symbols; this is derived from its definitions:
//   per-object setup, then whichever of triangle processing and pixel fill is
//   the bottleneck, plus fixed initialisation and finalisation.) A software
//   rasteriser does not overlap the two stages; `additive` replaces the max()
//   by a sum: t_setup + T_j * t_tri + P_j * t_pix (bench_calibrate fits both
//   and keeps the better R^2).
// - fitFrameCostConstants: non-negative least squares of that model over
//   measured frames. The max() is handled by alternating regime assignment
//   (each object triangle- or fill-bound under the current constants) with an
//   exact NNLS of the then linear model (all subsets of the 4 unknowns); the
//   additive model is that NNLS directly. Only
//   the sum t_init + t_final is identifiable from frame times: the fit returns
//   it in initSeconds + finalSeconds split by `initShare` (measure the split
//   separately, e.g. by timing the clear). Errors (kInvalidArgument): NaN/Inf
//   or negative inputs, fewer samples than unknowns, a design that cannot
//   separate the constants (e.g. every frame has the same object count).
// - formatFrameCostToml / parseFrameCostToml: a small versioned text file
//   ("version = 1", one "key = number" line per constant, "additive = 0|1"). The parser takes
//   untrusted text: bounded (64 KiB), every key known and present once, every
//   value finite and >= 0; errors name the line; then validateFrameCostConstants.
// - validateFrameCostConstants: every constant finite, >= 0 and at most its
//   plausibility limit below (larger values are no renderer's: corrupt or
//   hostile input, e.g. from a frontend's Hello). validateCalibratedFrameCost
//   also needs t_tri > 0: a model in which triangles cost nothing cannot
//   trade detail for time (what a frame-time budget needs).
// - loadFrameCostFile: the thin file wrapper (kNotFound, kResourceExhausted
//   above 64 KiB, the parse error, then validateCalibratedFrameCost; every
//   message starts with the path). Everything else is pure: no I/O, no globals.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod {

struct FrameCostConstants {
  double initSeconds = 0.0;      // t_init: clear, state set-up per frame
  double finalSeconds = 0.0;     // t_final: finish, swap or readback per frame
  double setupSeconds = 0.0;     // t_setup: per object (state, material, draw call)
  double triangleSeconds = 0.0;  // t_tri: per triangle
  double pixelSeconds = 0.0;     // t_pix: per covered pixel
  bool additive = false;         // false: max(triangles, pixels); true: their sum
};
// Plausibility limits of validateFrameCostConstants (seconds).
inline constexpr double kMaxFrameFixedSeconds = 1.0;   // t_init, t_final each
inline constexpr double kMaxObjectSetupSeconds = 0.1;  // t_setup
inline constexpr double kMaxTriangleSeconds = 1e-3;    // t_tri
inline constexpr double kMaxPixelSeconds = 1e-3;       // t_pix
inline constexpr std::size_t kMaxFrameCostFileBytes = 64 * 1024;

Status validateFrameCostConstants(const FrameCostConstants& constants);
Status validateCalibratedFrameCost(const FrameCostConstants& constants);

// One drawn object of a measured frame.
struct DrawnObjectLoad {
  double triangles = 0.0;
  double coveredPixels = 0.0;
};

// One measured frame.
struct FrameTimeSample {
  std::vector<DrawnObjectLoad> objects;
  double seconds = 0.0;
};

struct FrameCostFit {
  FrameCostConstants constants;
  double rSquared = 0.0;      // 1 - SSE / SST of the max() model over the samples
  double rmsSeconds = 0.0;    // root mean square residual
  int iterations = 0;         // regime-assignment rounds
  double fillBoundShare = 0;  // share of objects assigned to the fill-bound regime
};

Result<FrameCostFit> fitFrameCostConstants(const std::vector<FrameTimeSample>& samples,
                                           double initShare = 0.5, bool additive = false);

// Predicted time of one frame under the model above.
double predictFrameSeconds(const FrameCostConstants& constants,
                           const std::vector<DrawnObjectLoad>& objects);

std::string formatFrameCostToml(const FrameCostConstants& constants, const std::string& comment);
Result<FrameCostConstants> parseFrameCostToml(const std::string& text);
Result<FrameCostConstants> loadFrameCostFile(const std::string& path);

}  // namespace thinlod
