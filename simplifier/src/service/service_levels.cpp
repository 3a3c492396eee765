// Level bookkeeping of SimplifierService: how much accuracy a progressive-mesh
// level or a tessellation is credited with, and the curve samples sent to the
// backbone. Pure functions (service_internal.h).
#include <algorithm>
#include <cmath>

#include "service_internal.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/simplifier/impostor_level.h"

namespace thinlod::simplifier::service_detail {

double quantizationError(int bits) {
  const double steps = std::ldexp(1.0, bits) - 1.0;
  return 0.5 * std::sqrt(3.0) / steps;
}

DeliveredLevel deliveredLevel(double relativeError) {
  DeliveredLevel out;
  const double d = std::max(relativeError, 0.0);
  // A zero error (exact primitive) still asks for the finest bits.
  const double accuracy = d > 0.0 ? 1.0 / d : kExactRelativeAccuracy;
  out.positionBits = codec::positionBitsForAccuracy(accuracy, kQuantizationBudget);
  out.accuracy = 1.0 / (d + quantizationError(out.positionBits));
  return out;
}

std::string curveProducerFor(float attributeWeight, bool keepBoundary, bool skinSeams) {
  std::string producer = kCurveProducer;
  if (attributeWeight > 0.0f) producer += " attributes=" + std::to_string(attributeWeight);
  if (keepBoundary) producer += " keep_boundary=1";
  if (skinSeams) producer += " skin_seams=1";
  return producer;
}

std::uint32_t frameTriangles(const std::vector<std::uint8_t>& frame) {
  if (frame.size() < codec::kFrameHeaderBytes) return 0;
  return static_cast<std::uint32_t>(frame[12]) | (static_cast<std::uint32_t>(frame[13]) << 8) |
         (static_cast<std::uint32_t>(frame[14]) << 16) |
         (static_cast<std::uint32_t>(frame[15]) << 24);
}

PositionGrid gridOf(const IndexedMesh& whole) {
  PositionGrid grid;
  const Bounds bounds = whole.bounds();
  if (bounds.empty) return grid;
  const glm::vec3 extent = bounds.max - bounds.min;
  const float side = std::max({extent.x, extent.y, extent.z});
  if (!(side > 0.0f)) return grid;
  grid.origin = {bounds.min.x, bounds.min.y, bounds.min.z};
  // origin + range must not round below the maximum.
  grid.range = side * (1.0f + 1e-5f);
  return grid;
}

DeliveredLevel deliveredOnGrid(double relativeError, const PositionGrid& grid, double diameter) {
  if (!(grid.range > 0.0f) || !(diameter > 0.0)) return deliveredLevel(relativeError);
  DeliveredLevel out;
  out.positionBits = kRegionGridBits;
  const double d = std::max(relativeError, 0.0);
  out.accuracy = 1.0 / (d + double(grid.range) / diameter * quantizationError(kRegionGridBits));
  return out;
}

Result<protocol::SimplifyResult> encodedMeshResult(const IndexedMesh& mesh,
                                                   const DeliveredLevel& delivered,
                                                   const std::vector<anim::VertexSkin>& skin,
                                                   const PositionGrid& grid) {
  codec::MeshEncodeOptions encode;
  encode.positionBits = delivered.positionBits;
  encode.positionOrigin = grid.origin;
  encode.positionRange = grid.range;
  Result<std::vector<std::uint8_t>> frame =
      skin.empty() ? codec::encodeMesh(mesh, encode) : codec::encodeSkinnedMesh(mesh, skin, encode);
  if (!frame.ok()) return frame.status();
  protocol::SimplifyResult result;
  result.mesh = std::move(frame).value();
  result.triangleCount = frameTriangles(result.mesh);
  result.accuracy = delivered.accuracy;
  return result;
}

std::vector<LevelCredit> creditLevels(const std::vector<CurveLevel>& levels,
                                      double minRelativeError) {
  const std::vector<double> credits = creditedRelativeErrors(levels, minRelativeError);
  std::vector<LevelCredit> ladder(levels.size());
  for (std::size_t i = 0; i < levels.size(); ++i) {
    ladder[i].requestedTriangles = levels[i].requestedTriangles;
    ladder[i].triangles = levels[i].triangles;
    ladder[i].relativeError = credits[i];
  }
  return ladder;
}

std::size_t creditFor(const std::vector<LevelCredit>& ladder, std::size_t triangles) {
  std::size_t best = 0;
  for (std::size_t i = 0; i < ladder.size(); ++i) {
    if (ladder[i].triangles <= triangles) best = i;
  }
  return best;
}

std::vector<double> animatedLadderAccuracies(const MeshModel& model,
                                             const std::vector<double>& bounds,
                                             double motionBound, double skinningScale,
                                             double minRelativeError) {
  const double length = model.diameter;
  const double grown = length + 2.0 * motionBound;
  const double motionRatio = 2.0 * motionBound / length;
  const std::size_t n = std::min(bounds.size(), model.ladder.size());
  std::vector<double> accuracies(n);
  double worstFiner = 0.0;
  for (std::size_t i = n; i-- > 0;) {
    worstFiner = std::max({worstFiner, bounds[i], minRelativeError * length});
    const double rest = model.ladder[i].relativeError;
    const DeliveredLevel delivered = model.delivered(rest);
    const double quantization = std::max(0.0, 1.0 / delivered.accuracy - rest);
    const double measured = grown / (worstFiner + skinningScale * quantization * length);
    const double converted = anim::animatedRelativeAccuracy(delivered.accuracy, motionRatio);
    // NaN (a non-finite bound or scale) falls back to the conversion.
    accuracies[i] = measured > converted ? measured : converted;
    if (i + 1 < n) accuracies[i] = std::min(accuracies[i], accuracies[i + 1]);
  }
  return accuracies;
}

std::vector<AccuracySample> curveSamples(std::vector<AccuracySample> points, std::size_t count) {
  std::sort(points.begin(), points.end(), [](const AccuracySample& a, const AccuracySample& b) {
    return a.resources < b.resources || (a.resources == b.resources && a.accuracy > b.accuracy);
  });
  // Keep a point only if it buys more accuracy than every cheaper one: a
  // dominated level is never the cheapest way to reach an accuracy.
  std::vector<AccuracySample> front;
  for (const AccuracySample& p : points) {
    if (!std::isfinite(p.accuracy) || !(p.accuracy > 0.0)) continue;
    if (!front.empty() && (p.accuracy <= front.back().accuracy)) continue;
    if (!front.empty() && p.resources == front.back().resources) continue;
    front.push_back(p);
  }
  if (count == 0) return {};
  if (front.size() <= count) return front;
  if (count == 1) return {front.back()};
  std::vector<AccuracySample> picked;
  picked.reserve(count);
  const double last = static_cast<double>(front.size() - 1);
  for (std::size_t i = 0; i < count; ++i) {
    const auto index = static_cast<std::size_t>(
        std::llround(last * static_cast<double>(i) / static_cast<double>(count - 1)));
    if (picked.empty() || front[index].resources > picked.back().resources) {
      picked.push_back(front[index]);
    }
  }
  return picked;
}

}  // namespace thinlod::simplifier::service_detail
