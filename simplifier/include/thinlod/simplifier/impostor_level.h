// Which progressive-mesh level an impostor is rendered from, and how far a
// capture from that level is from the full-resolution capture.
//
// Contract:
// - impostorLevelTolerance: the world error (metres) a level may have so that
//   its capture looks the same: `texelFraction` x the smallest texel footprint
//   on the object, s_near = min(quad width, height) / textureSize x nearDepth
//   / planeDistance (the texel at the object's nearest depth). 0 for a
//   degenerate framing or a fraction that is not positive and finite.
//   Why one texel (kImpostorLevelTexelFraction): the level's credited error
//   is a symmetric Hausdorff bound e, so every point of either surface is
//   within e of the other; projected at depth >= nearDepth it moves by at most
//   e / s_near texels. With e <= s_near a silhouette or crease moves by at
//   most one texel, so coverage can only flip in texels next to the full
//   mesh's silhouette (a one-texel band), well inside the two texels the
//   texture already loses (the 2 s term of the reported accuracy
//   D / (2 s + e)), which drops by at most a third (s_near <= s) and says so.
//   Half a texel was tried first: on the bunny (the ladder's max error is
//   1.17e-3 of the diagonal from 16.7k to 34k triangles, a fixed feature) and
//   the cow at 256 texels from 4 radii it admits no coarser level at all.
//   Shading (normals) is not bounded by e: its effect on colour is measured
//   (compareImpostorTextures, bench_impostor), not guaranteed.
// - chooseImpostorLevel: `relativeErrors[i]` is the credited error of level i
//   as a fraction of `diameter` (levels ordered coarse to fine; a measured
//   ladder's credits, see creditLevels in the service). Returns the first
//   (coarsest) i with relativeErrors[i] x diameter <= tolerance, or nullopt
//   (render the full mesh, error 0) when none qualifies or diameter /
//   tolerance are not positive and finite. NaN or negative errors never
//   qualify. Pure, O(levels).
// - creditedRelativeErrors: what a measured ladder credits each level with
//   (levels by increasing triangles): the worst measured max error at that
//   level or any finer one, floored at minRelativeError, so credits never
//   improve by coarsening (the service's creditLevels uses the same rule).
// - compareImpostorTextures: per-channel absolute differences of two images
//   of the same size (max and mean over all texels and the 4 channels) and
//   the texels whose coverage (alpha > 0) differs. kInvalidArgument for
//   inconsistent or differently sized images.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"
#include "thinlod/simplifier/impostor.h"
#include "thinlod/simplifier/mesh_curve.h"

namespace thinlod::simplifier {

inline constexpr double kImpostorLevelTexelFraction = 1.0;

double impostorLevelTolerance(const ImpostorFraming& framing,
                              double texelFraction = kImpostorLevelTexelFraction);

std::optional<std::size_t> chooseImpostorLevel(const std::vector<double>& relativeErrors,
                                               double diameter, double tolerance);

std::vector<double> creditedRelativeErrors(const std::vector<CurveLevel>& levels,
                                           double minRelativeError);

struct ImpostorTextureDifference {
  int maxAbs = 0;                    // 0..255 over R, G, B, A
  double meanAbs = 0.0;              // mean over every texel and channel
  std::size_t coverageMismatch = 0;  // texels covered in one image only
  std::size_t coveredEither = 0;     // texels covered in at least one image
};

Result<ImpostorTextureDifference> compareImpostorTextures(const RgbaImage& a, const RgbaImage& b);

}  // namespace thinlod::simplifier
