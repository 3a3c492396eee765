// Pure measured-curve builder (see mesh_curve.h). File I/O lives in
// mesh_curve_cache.cpp.
#include "thinlod/simplifier/mesh_curve.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <optional>
#include <string>

#include "thinlod/common/core/parallel_for.h"
#include "thinlod/common/core/relative_accuracy.h"

namespace thinlod::simplifier {
namespace {

Status invalid(const std::string& message) {
  return Status(ErrorCode::kInvalidArgument, "measureMeshCurves: " + message);
}

Status checkOptions(const MeshCurveOptions& options) {
  if (options.levels < 2) return invalid("levels must be >= 2");
  if (options.maxSegments < 1) return invalid("maxSegments must be >= 1");
  if (options.threads < 0 || options.threads > 1024) return invalid("threads must be in 0..1024");
  if (!(options.minRelativeError > 0.0) || !std::isfinite(options.minRelativeError)) {
    return invalid("minRelativeError must be positive and finite");
  }
  if (!(options.quantizationBudgetFraction > 0.0) ||
      !std::isfinite(options.quantizationBudgetFraction)) {
    return invalid("quantizationBudgetFraction must be positive and finite");
  }
  return Status();
}

Result<CurveLevel> measureLevel(const IndexedMesh& original, double reference, std::size_t target,
                                const IndexedMesh& level, const MeshCurveOptions& options) {
  const std::string what = "extraction of " + std::to_string(target) + " triangles";
  const Status valid = level.validate(what);
  if (!valid.ok()) return Status(ErrorCode::kInternal, valid.message());
  if (level.triangleCount() == 0 || level.triangleCount() > target) {
    return Status(ErrorCode::kInternal,
                  what + " returned " + std::to_string(level.triangleCount()) + " triangles");
  }
  Result<SurfaceError> error = measureSurfaceError(original, level, options.error);
  if (!error.ok()) return error.status();

  CurveLevel out;
  out.requestedTriangles = target;
  out.triangles = level.triangleCount();
  out.relativeHausdorffError = relativeError(error->max(), reference);
  out.relativeMeanError = relativeError(error->mean(), reference);
  if (options.textureCredit && level.uvs.size() == level.positions.size() &&
      uvArea(original) > 0.0) {
    UvErrorOptions uv;
    uv.samples = options.error.samplesPerMesh;
    uv.seed = options.error.seed;
    Result<UvError> texture = measureUvError(original, level, uv);
    if (!texture.ok()) return texture.status();
    out.relativeTextureError = relativeError(texture->p95Displacement, reference);
    out.relativeTextureMaxError = relativeError(texture->maxDisplacement, reference);
  }
  out.relativeMaxError = std::max(out.relativeHausdorffError, out.relativeTextureError);
  const double d = std::max(out.relativeMaxError, options.minRelativeError);
  out.accuracy = 1.0 / d;
  if (options.measureEncodedBytes) {
    codec::MeshEncodeOptions encode = options.encode;
    encode.positionBits =
        codec::positionBitsForAccuracy(out.accuracy, options.quantizationBudgetFraction);
    Result<std::vector<std::uint8_t>> frame = codec::encodeMesh(level, encode);
    if (!frame.ok()) return frame.status();
    out.encodedBytes = frame->size();
    out.positionBits = encode.positionBits;
    out.encodedAccuracy =
        1.0 / (d + relativeError(codec::positionErrorBound(level, encode.positionBits), reference));
  }
  return out;
}

}  // namespace

std::vector<std::size_t> geometricLadder(std::size_t minTriangles, std::size_t maxTriangles,
                                         int levels) {
  std::vector<std::size_t> ladder;
  if (minTriangles == 0 || minTriangles > maxTriangles || levels < 1) return ladder;
  if (levels == 1) return {maxTriangles};
  const double ratio = static_cast<double>(maxTriangles) / static_cast<double>(minTriangles);
  for (int i = 0; i < levels; ++i) {
    const double t = static_cast<double>(i) / (levels - 1);
    std::size_t n = static_cast<std::size_t>(std::llround(minTriangles * std::pow(ratio, t)));
    if (i == 0) n = minTriangles;
    if (i == levels - 1) n = maxTriangles;
    n = std::clamp(n, minTriangles, maxTriangles);
    if (ladder.empty() || n > ladder.back()) ladder.push_back(n);
  }
  return ladder;
}

Result<MeshCurves> measureMeshCurves(const IndexedMesh& original, std::size_t minTriangles,
                                     std::size_t maxTriangles, const ExtractTriangles& extract,
                                     const MeshCurveOptions& options) {
  THINLOD_RETURN_IF_ERROR(checkOptions(options));
  THINLOD_RETURN_IF_ERROR(original.validate("measureMeshCurves: original"));
  if (original.triangleCount() == 0) return invalid("original mesh has no triangles");
  if (!extract) return invalid("no extraction function");
  if (minTriangles == 0 || minTriangles > maxTriangles) {
    return invalid("triangle range [" + std::to_string(minTriangles) + ", " +
                   std::to_string(maxTriangles) + "] is empty");
  }
  // The one reference length of relative accuracy (relative_accuracy.h).
  const double reference = referenceLength(referenceSphere(original));
  if (!(reference > 0.0)) return invalid("original mesh has a zero-size reference sphere");

  // Extract first, one after another; several requests can land on one
  // collapse state: measure it once.
  std::vector<std::size_t> targets;
  std::vector<IndexedMesh> extracted;
  for (std::size_t target : geometricLadder(minTriangles, maxTriangles, options.levels)) {
    IndexedMesh level = extract(target);
    if (!extracted.empty() && level.triangleCount() == extracted.back().triangleCount()) continue;
    targets.push_back(target);
    extracted.push_back(std::move(level));
  }
  // Then measure the levels on options.threads threads, the largest (the
  // slowest) first; each result goes to its own slot.
  const std::size_t total = extracted.size();
  std::vector<std::optional<Result<CurveLevel>>> measured(total);
  std::mutex reportMutex;
  std::size_t reported = 0;
  parallelFor(total, options.threads, [&](std::size_t k) {
    const std::size_t i = total - 1 - k;
    measured[i] = measureLevel(original, reference, targets[i], extracted[i], options);
    if (options.levelMeasured && measured[i]->ok()) {
      std::lock_guard<std::mutex> lock(reportMutex);
      options.levelMeasured(**measured[i], ++reported, total);
    }
  });
  MeshCurves curves;
  for (std::optional<Result<CurveLevel>>& level : measured) {
    if (!level->ok()) return level->status();
    curves.levels.push_back(std::move(**level));
  }

  std::vector<AccuracySample> triangleSamples;
  std::vector<AccuracySample> byteSamples;
  for (const CurveLevel& level : curves.levels) {
    triangleSamples.push_back({level.accuracy, static_cast<double>(level.triangles)});
    if (options.measureEncodedBytes) {
      byteSamples.push_back({level.encodedAccuracy, static_cast<double>(level.encodedBytes)});
    }
  }
  Result<AccuracyCurve> triangles =
      AccuracyCurve::fitConservative(std::move(triangleSamples), options.maxSegments);
  if (!triangles.ok()) return triangles.status();
  curves.triangles = std::move(*triangles);
  if (options.measureEncodedBytes) {
    Result<AccuracyCurve> bytes =
        AccuracyCurve::fitConservative(std::move(byteSamples), options.maxSegments);
    if (!bytes.ok()) return bytes.status();
    curves.bytes = std::move(*bytes);
  }
  return curves;
}

Result<MeshCurves> measureMeshCurves(const IndexedMesh& original, const ProgressiveMesh& pm,
                                     const MeshCurveOptions& options) {
  const std::size_t minTriangles = std::max<std::size_t>(1, pm.minTriangles());
  return measureMeshCurves(
      original, minTriangles, pm.maxTriangles(), [&pm](std::size_t n) { return pm.extract(n); },
      options);
}

}  // namespace thinlod::simplifier
