// Hybrid (triangles + disc points) SimplifyRequests of SimplifierService
// (service.h): one HybridGraph per (mesh, kappa) with its measured ladder,
// cuts at its rungs, encodeHybrid frames, curves in primitive units
// (docs/hybrid.md, "Service" and "Measured curve").
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include "service_internal.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/simplifier/impostor_level.h"

namespace thinlod::simplifier {

using namespace service_detail;

namespace service_detail {

std::vector<AccuracySample> hybridCurvePoints(const std::vector<HybridRung>& rungs) {
  std::vector<AccuracySample> points;
  points.reserve(rungs.size());
  for (const HybridRung& rung : rungs) {
    points.push_back(AccuracySample{deliveredLevel(rung.relativeError).accuracy, rung.units});
  }
  return points;
}

std::vector<HybridRung> creditHybridLevels(const std::vector<HybridMeasuredLevel>& levels,
                                           double referenceLength, double minRelativeError) {
  // The mesh ladder's rule, on the same CurveLevel fields it reads.
  std::vector<CurveLevel> asMesh(levels.size());
  for (std::size_t i = 0; i < levels.size(); ++i) {
    asMesh[i].relativeMaxError = levels[i].measuredError / referenceLength;
  }
  const std::vector<double> credits = creditedRelativeErrors(asMesh, minRelativeError);
  std::vector<HybridRung> rungs(levels.size());
  for (std::size_t i = 0; i < levels.size(); ++i) {
    rungs[i] = HybridRung{levels[i].step.error, levels[i].step.units, credits[i]};
  }
  return rungs;
}

}  // namespace service_detail

Result<protocol::SimplifyResult> SimplifierService::Impl::simplifyHybrid(
    const protocol::SimplifyRequest& request, MeshModel& model) {
  const double kappa = request.kappa > 0.0 ? request.kappa : options.hybridKappa;
  if (!(kappa >= 1.0) || !(kappa <= protocol::kMaxKappa) || !(options.hybridTau > 0.0)) {
    return Status(ErrorCode::kInvalidArgument, "hybrid: kappa " + std::to_string(kappa) +
                                                   " / tau " + std::to_string(options.hybridTau) +
                                                   " out of range");
  }
  auto found = model.hybrids.find(kappa);
  if (found == model.hybrids.end()) {
    HybridOptions hybridOptions;
    hybridOptions.kappa = kappa;
    hybridOptions.tau = options.hybridTau;
    const auto started = std::chrono::steady_clock::now();
    Result<HybridGraph> graph = buildHybridGraph(*model.original, hybridOptions);
    if (!graph.ok()) return graph.status();
    ++stats.hybridGraphBuilds;
    auto hybrid = std::make_unique<MeshModel::Hybrid>();
    hybrid->graph = std::move(graph).value();
    // Measured like a mesh curve (same ladder length, same sampling): the
    // scheduler compares the two kinds on measured error, not a measured
    // error against a guaranteed bound (docs/hybrid.md, "Measured curve").
    // The measurement, not the graph, is the slow part: it is kept on disk.
    Result<std::vector<HybridMeasuredLevel>> levels = Status(ErrorCode::kInternal, "not measured");
    bool fromDisk = false;
    if (hybridCurveCache) {
      const HybridCurveCache::Stats before = hybridCurveCache->stats();
      levels = hybridCurveCache->getOrMeasure(*model.original, hybrid->graph, hybridOptions,
                                              options.curve.levels, options.curve.error);
      const HybridCurveCache::Stats& after = hybridCurveCache->stats();
      fromDisk = after.hits > before.hits;
      if (after.rejected > before.rejected) {
        progress("event=hybrid_curve_cache_rejected reason=\"" + hybridCurveCache->lastRejection() +
                 "\"");
      }
      if (after.writeFailures > before.writeFailures) {
        progress("event=hybrid_curve_cache_write_failed dir=\"" + options.curveCacheDir + "\"");
      }
    } else {
      levels = measureHybridLevels(*model.original, hybrid->graph, options.curve.levels,
                                   options.curve.error);
    }
    if (!levels.ok()) return levels.status();
    ++(fromDisk ? stats.hybridCurvesFromDisk : stats.hybridCurvesMeasured);
    hybrid->rungs = creditHybridLevels(*levels, model.diameter, options.curve.minRelativeError);
    progress(
        std::string(fromDisk ? "event=hybrid_curve_from_disk" : "event=hybrid_curve_measured") +
        " triangles=" + std::to_string(model.original->triangleCount()) + " kappa=" +
        std::to_string(kappa) + " rungs=" + std::to_string(hybrid->rungs.size()) + " ms=" +
        std::to_string(std::llround(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
                .count())));
    found = model.hybrids.emplace(kappa, std::move(hybrid)).first;
  }
  const MeshModel::Hybrid& hybrid = *found->second;
  // Rungs: increasing units (the last one the input). Accuracy target: the
  // coarsest rung credited with at least it (the input when none is). Unit
  // target: the finest rung with at most that many units (the coarsest when
  // none has).
  std::size_t pick = hybrid.rungs.size() - 1;
  if (request.target == protocol::SimplifyRequest::Target::kTriangles) {
    pick = 0;
    for (std::size_t i = 0; i < hybrid.rungs.size(); ++i) {
      if (hybrid.rungs[i].units <= static_cast<double>(request.targetTriangles)) pick = i;
    }
  } else {
    for (std::size_t i = 0; i < hybrid.rungs.size(); ++i) {
      if (deliveredLevel(hybrid.rungs[i].relativeError).accuracy >= request.targetAccuracy) {
        pick = i;
        break;
      }
    }
  }
  const HybridRung& rung = hybrid.rungs[pick];
  HybridCut cut(hybrid.graph);
  cut.adaptToError(rung.error);
  const DeliveredLevel delivered = deliveredLevel(rung.relativeError);
  codec::MeshEncodeOptions encode;
  encode.positionBits = delivered.positionBits;
  const HybridGeometry geometry = hybridGeometry(cut);
  Result<std::vector<std::uint8_t>> frame = codec::encodeHybrid(geometry, encode);
  if (!frame.ok()) return frame.status();

  protocol::SimplifyResult result;
  result.kind = protocol::RepresentationKind::kHybrid;
  result.mesh = std::move(frame).value();
  // What the frame carries (encodeMesh drops degenerate triangles).
  const auto u32At = [&](std::size_t offset) {
    return static_cast<std::uint32_t>(result.mesh[offset]) |
           static_cast<std::uint32_t>(result.mesh[offset + 1]) << 8 |
           static_cast<std::uint32_t>(result.mesh[offset + 2]) << 16 |
           static_cast<std::uint32_t>(result.mesh[offset + 3]) << 24;
  };
  result.pointCount = u32At(8);
  result.triangleCount = u32At(12);
  result.kappa = kappa;
  result.accuracy = delivered.accuracy;
  if (request.curvePoints > 0) {
    result.curve = curveSamples(hybridCurvePoints(hybrid.rungs), request.curvePoints);
  }
  return result;
}

}  // namespace thinlod::simplifier
