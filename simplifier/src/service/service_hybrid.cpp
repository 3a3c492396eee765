// Hybrid (triangles + disc points) SimplifyRequests of SimplifierService
// (service.h): one HybridGraph per (mesh, kappa), cuts by object-space error,
// encodeHybrid frames, curves in primitive units (docs/hybrid.md, "Service").
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "service_internal.h"
#include "thinlod/common/codec/encoding.h"

namespace thinlod::simplifier {

using namespace service_detail;

namespace service_detail {

std::vector<AccuracySample> hybridCurvePoints(const std::vector<HybridCurveStep>& steps,
                                              double referenceLength, double minRelativeError) {
  std::vector<AccuracySample> points;
  points.reserve(steps.size());
  for (const HybridCurveStep& step : steps) {
    const double d = std::max(step.error / referenceLength, minRelativeError);
    points.push_back(AccuracySample{deliveredLevel(d).accuracy, step.units});
  }
  return points;
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
    Result<HybridGraph> graph = buildHybridGraph(*model.original, hybridOptions);
    if (!graph.ok()) return graph.status();
    ++stats.hybridGraphBuilds;
    auto hybrid = std::make_unique<MeshModel::Hybrid>();
    hybrid->graph = std::move(graph).value();
    hybrid->steps = hybrid->graph.unitsVersusError();
    found = model.hybrids.emplace(kappa, std::move(hybrid)).first;
  }
  const MeshModel::Hybrid& hybrid = *found->second;
  const double length = model.diameter;
  const double floor = options.curve.minRelativeError;
  auto relative = [&](double error) { return std::max(error / length, floor); };

  // Steps: increasing error, decreasing units. Pick the coarsest step that
  // still meets the target (the first step, the input, when none does).
  double error = 0.0;
  for (const HybridCurveStep& step : hybrid.steps) {
    const bool meets =
        request.target == protocol::SimplifyRequest::Target::kTriangles
            ? true
            : deliveredLevel(relative(step.error)).accuracy >= request.targetAccuracy;
    if (!meets) break;
    error = step.error;
    if (request.target == protocol::SimplifyRequest::Target::kTriangles &&
        step.units <= static_cast<double>(request.targetTriangles)) {
      break;
    }
  }
  HybridCut cut(hybrid.graph);
  cut.adaptToError(error);
  const DeliveredLevel delivered = deliveredLevel(relative(cut.errorBound()));
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
    result.curve =
        curveSamples(hybridCurvePoints(hybrid.steps, length, floor), request.curvePoints);
  }
  return result;
}

}  // namespace thinlod::simplifier
