// The on-disk cache of measured hybrid ladders (hybrid_curve_cache.h): key,
// JSON (de)serialization and validation (pure), and the thin file wrapper.
#include "thinlod/simplifier/hybrid_curve_cache.h"

#include <cmath>
#include <exception>
#include <nlohmann/json.hpp>
#include <string>
#include <system_error>

#include "curve_cache_files.h"

namespace thinlod::simplifier {
namespace {

using Json = nlohmann::json;

constexpr const char* kFormatName = "thinlod-hybrid-curves";

Status parseError(const std::string& message) {
  return Status(ErrorCode::kParseError, "hybrid curve cache: " + message);
}

std::string rungText(std::size_t i) { return "rung " + std::to_string(i); }

}  // namespace

std::string hybridCurveCacheKey(const IndexedMesh& original, const HybridOptions& options,
                                int levels, const SurfaceErrorOptions& error) {
  curve_cache::KeyHasher h;
  h.text(kFormatName);
  h.number(kHybridCurveFormatVersion);
  h.number(kHybridGraphVersion);
  h.number(options.kappa);
  h.number(options.tau);
  h.number(options.enablePoints);
  h.number(options.sampleDistanceTolerance);
  h.number(options.octreeMaxDepth);
  h.number(levels);
  h.number(static_cast<std::uint64_t>(error.samplesPerMesh));
  h.number(error.seed);
  h.number(error.includeVerticesAndEdges);
  h.mesh(original);
  return h.hex();
}

std::string serializeHybridLevels(const std::vector<HybridMeasuredLevel>& levels,
                                  const std::string& key) {
  Json rungs = Json::array();
  for (const HybridMeasuredLevel& l : levels) {
    rungs.push_back({{"error", l.step.error},
                     {"units", l.step.units},
                     {"triangles", l.step.triangles},
                     {"points", l.step.points},
                     {"measuredError", l.measuredError}});
  }
  const Json document = {{"format", kFormatName},
                         {"version", kHybridCurveFormatVersion},
                         {"key", key},
                         {"rungs", rungs}};
  return document.dump(1);
}

Status validateHybridLevels(const std::vector<HybridMeasuredLevel>& measured,
                            const HybridGraph& graph, int levels) {
  // The rungs are a pure function of the graph: equality checks counts,
  // finiteness, increasing units, decreasing thresholds and the input rung.
  const std::vector<HybridCurveStep> expected = hybridLadderSteps(graph, levels);
  if (expected.empty()) return parseError("the graph has no ladder");
  if (measured.size() != expected.size()) {
    return parseError(std::to_string(measured.size()) + " rungs, the graph gives " +
                      std::to_string(expected.size()));
  }
  // A sampled distance never exceeds the guaranteed bound (docs/hybrid.md,
  // "Verification"); the slack covers float rounding, as in the tests.
  const double slack = 1e-6 * graph.diagonal();
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const HybridCurveStep& s = measured[i].step;
    const HybridCurveStep& e = expected[i];
    if (s.error != e.error || s.units != e.units || s.triangles != e.triangles ||
        s.points != e.points) {
      return parseError(rungText(i) + " (error " + std::to_string(s.error) + ", units " +
                        std::to_string(s.units) + ") is not the graph's (error " +
                        std::to_string(e.error) + ", units " + std::to_string(e.units) + ")");
    }
    const double m = measured[i].measuredError;
    if (!std::isfinite(m) || m < 0.0 || m > e.error + slack) {
      return parseError(rungText(i) + ": measured error " + std::to_string(m) +
                        " is not in [0, bound " + std::to_string(e.error) + "]");
    }
  }
  return Status();
}

Result<std::vector<HybridMeasuredLevel>> parseHybridLevels(const std::string& text,
                                                           const std::string& expectedKey,
                                                           const HybridGraph& graph, int levels) {
  const Json document = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (document.is_discarded() || !document.is_object()) return parseError("not a JSON object");
  try {
    THINLOD_RETURN_IF_ERROR(
        curve_cache::checkCacheHeader(document, kFormatName, kHybridCurveFormatVersion, expectedKey, "hybrid curve cache"));
    const Json& rungs = document.at("rungs");
    if (!rungs.is_array()) return parseError("rungs is not an array");
    // geometricLadder gives at most `levels` targets, plus the input.
    if (levels < 1 || rungs.size() > static_cast<std::size_t>(levels) + 1) {
      return parseError(std::to_string(rungs.size()) + " rungs for a ladder of " +
                        std::to_string(levels));
    }
    std::vector<HybridMeasuredLevel> out;
    out.reserve(rungs.size());
    for (const Json& r : rungs) {
      if (!r.is_object()) return parseError(rungText(out.size()) + " is not an object");
      HybridMeasuredLevel level;
      level.step.error = curve_cache::nonNegativeField(r, "error");
      level.step.units = curve_cache::nonNegativeField(r, "units");
      if (!r.at("triangles").is_number_unsigned() || !r.at("points").is_number_unsigned()) {
        return parseError(rungText(out.size()) + ": counts are not unsigned integers");
      }
      level.step.triangles = r.at("triangles").get<std::size_t>();
      level.step.points = r.at("points").get<std::size_t>();
      level.measuredError = curve_cache::nonNegativeField(r, "measuredError");
      out.push_back(level);
    }
    THINLOD_RETURN_IF_ERROR(validateHybridLevels(out, graph, levels));
    return out;
  } catch (const std::exception& e) {
    return parseError(e.what());
  }
}

HybridCurveCache::HybridCurveCache(std::filesystem::path directory)
    : directory_(std::move(directory)) {}

std::filesystem::path HybridCurveCache::fileFor(const std::string& key) const {
  return directory_ / ("hybrid-" + key + ".json");
}

Result<std::vector<HybridMeasuredLevel>> HybridCurveCache::getOrMeasure(
    const IndexedMesh& original, const HybridGraph& graph, const HybridOptions& options, int levels,
    const SurfaceErrorOptions& error) {
  const std::string key = hybridCurveCacheKey(original, options, levels, error);
  const std::filesystem::path path = fileFor(key);
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    Result<std::string> text = curve_cache::readCacheFile(path);
    Result<std::vector<HybridMeasuredLevel>> stored =
        text.ok() ? parseHybridLevels(*text, key, graph, levels)
                  : Result<std::vector<HybridMeasuredLevel>>(text.status());
    if (stored.ok()) {
      ++stats_.hits;
      return stored;
    }
    ++stats_.rejected;
    lastRejection_ = path.string() + ": " + stored.status().toString();
  } else {
    ++stats_.misses;
  }
  Result<std::vector<HybridMeasuredLevel>> measured =
      measureHybridLevels(original, graph, levels, error);
  if (!measured.ok()) return measured;
  // Never store what a reader would refuse (it would be measured forever).
  if (!validateHybridLevels(*measured, graph, levels).ok() ||
      !curve_cache::writeFileAtomically(path, serializeHybridLevels(*measured, key)).ok()) {
    ++stats_.writeFailures;
  }
  return measured;
}

}  // namespace thinlod::simplifier
