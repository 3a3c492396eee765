#include "curve_estimate.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "thinlod/common/mesh/primitives.h"

namespace thinlod::backbone_daemon {

Result<AccuracyCurve> estimatedMeshCurve(double fullTriangles, const MeshCurveEstimate& o) {
  if (!std::isfinite(fullTriangles) || fullTriangles < 1.0)
    return Status(ErrorCode::kInvalidArgument, "curve estimate: the mesh needs >= 1 triangle");
  if (!std::isfinite(o.trianglesPerAccuracy) || o.trianglesPerAccuracy <= 0.0 ||
      !std::isfinite(o.lowestAccuracy) || o.lowestAccuracy <= 0.0 ||
      !std::isfinite(o.fullMeshAbove) || o.fullMeshAbove <= o.lowestAccuracy ||
      o.fullMeshAbove >= kExactRelativeAccuracy)
    return Status(
        ErrorCode::kInvalidArgument,
        "curve estimate: need k > 0 and 0 < lowest accuracy < full-mesh accuracy < exact");
  const double k = o.trianglesPerAccuracy;
  std::vector<CurveSegment> segments;
  const double start = o.lowestAccuracy;
  if (k * start >= fullTriangles) {
    // Even the coarsest accuracy costs the whole mesh: one flat piece.
    segments.push_back({start, fullTriangles, 0.0});
  } else {
    segments.push_back({start, k * start, k});
    // Where k a reaches the full mesh (if before fullMeshAbove), the line
    // turns flat; otherwise the curve jumps up to the full mesh there.
    const double reachesFull = fullTriangles / k;
    segments.push_back({std::min(reachesFull, o.fullMeshAbove), fullTriangles, 0.0});
  }
  return AccuracyCurve::fromSegments(std::move(segments), kExactRelativeAccuracy);
}

}  // namespace thinlod::backbone_daemon
