// Estimated accuracy curves for mesh objects whose measured curve has not
// arrived yet (cold start: the backbone plans at once instead of waiting for
// the simplifier's measurements; docs/backbone.md "Startup").
//
// Contract:
// - Input: what the backbone knows without simplifying: the mesh's triangle
//   count. The curve is in relative accuracy (1 / error as a fraction of the
//   reference length L, core/relative_accuracy.h), resources = triangles:
//     r(a) = min(full, k a)   for a in [lowestAccuracy, fullMeshAbove)
//     r(a) = full             for a in [fullMeshAbove, kExactRelativeAccuracy]
//   (full mesh = exact), so r is non-decreasing, >= 1 and never above full.
// - Deliberately pessimistic about triangles: it should cost at least what
//   the simplifier's delivered curve costs at every accuracy, so a plan made
//   from it asks for at least the triangles the accuracy needs and does not
//   over-promise accuracy. Measured (thinlod-simplifier curve FILE --no-bytes
//   --json --levels 12 --samples 30000, every shared model): the delivered
//   staircase (each level credited the worst error of it and every finer
//   level, accuracy / 1.1 for the Draco quantization) needs k <= 31.8 for
//   a <= 50 (Stanford bunny; organic meshes 16-32, woody 3.2, fandisk 6.7);
//   k = 40 (the largest ratio of session 4's data) leaves 26 % over that.
//   Above a = 50 the horse's PM plateaus need up to 80 a, so the estimate
//   takes the full mesh there. tests/backbone_daemon/curve_estimate_test.cpp
//   checks the estimate against those measurements.
// - Budgets never depend on the estimate being right: a request asks for
//   ceil(r(a)) triangles, the simplifier delivers at most that many and
//   reports the accuracy it measured, and the frontend polygon cap counts the
//   delivered triangles (BackboneCore::finishPose).
// - Pure: no I/O. Errors: fullTriangles not finite or < 1, or options out of
//   range (kInvalidArgument).
#pragma once

#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/core/status.h"

namespace thinlod::backbone_daemon {

struct MeshCurveEstimate {
  double trianglesPerAccuracy = 40.0;  // k
  double fullMeshAbove = 50.0;         // relative accuracy from which the full mesh is assumed
  double lowestAccuracy = 1.0;         // domain start (error = the whole reference length)
};

Result<AccuracyCurve> estimatedMeshCurve(double fullTriangles,
                                         const MeshCurveEstimate& options = {});

}  // namespace thinlod::backbone_daemon
