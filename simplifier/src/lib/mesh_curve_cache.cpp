// The on-disk cache of measured curves (see mesh_curve.h): key hashing and
// JSON (de)serialization (pure), and the thin file wrapper MeshCurveCache.
#include <cmath>
#include <cstdlib>
#include <exception>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "curve_cache_files.h"
#include "qem_collapse.h"
#include "thinlod/simplifier/mesh_curve.h"

namespace thinlod::simplifier {
namespace {

using Json = nlohmann::json;
using curve_cache::KeyHasher;
using curve_cache::writeFileAtomically;

constexpr const char* kFormatName = "thinlod-mesh-curves";

Json curveToJson(const AccuracyCurve& curve) {
  if (curve.empty()) return nullptr;
  Json triples = Json::array();
  for (const CurveTriple& t : curve.triples()) triples.push_back({t.A, t.R, t.K});
  return Json{{"maxAccuracy", curve.maxAccuracy()}, {"triples", triples}};
}

Status parseError(const std::string& message) {
  return Status(ErrorCode::kParseError, "mesh curve cache: " + message);
}

Result<AccuracyCurve> curveFromJson(const Json& value, const char* name) {
  if (value.is_null()) return AccuracyCurve();
  std::vector<CurveTriple> triples;
  for (const Json& t : value.at("triples")) {
    if (!t.is_array() || t.size() != 3) {
      return parseError(std::string(name) + ": a triple is not [A, R, K]");
    }
    triples.push_back({t[0].get<double>(), t[1].get<double>(), t[2].get<double>()});
  }
  Result<AccuracyCurve> curve =
      AccuracyCurve::fromTriples(triples, value.at("maxAccuracy").get<double>());
  if (!curve.ok()) return parseError(std::string(name) + ": " + curve.status().message());
  return curve;
}

// The stored curve must not promise more than its own stored levels: for
// every level, r(a_level) >= the cheapest level reaching at least a_level.
Status checkConservative(const AccuracyCurve& curve, const std::vector<AccuracySample>& samples,
                         const char* name) {
  if (curve.empty()) return parseError(std::string(name) + " curve is missing");
  for (const AccuracySample& s : samples) {
    double cheapest = s.resources;
    for (const AccuracySample& other : samples) {
      if (other.accuracy >= s.accuracy) cheapest = std::min(cheapest, other.resources);
    }
    // triples() -> fromTriples() rounds R + K A: allow a few ulps.
    const double r = curve.resourcesFor(s.accuracy);
    if (!(r >= cheapest * (1.0 - 1e-12) - 1e-9)) {
      return parseError(std::string(name) + " curve promises accuracy " +
                        std::to_string(s.accuracy) + " for " + std::to_string(r) +
                        ", measured cheapest " + std::to_string(cheapest));
    }
  }
  return Status();
}

}  // namespace

std::string meshCurveCacheKey(const IndexedMesh& original, const std::string& producer,
                              std::size_t minTriangles, std::size_t maxTriangles,
                              const MeshCurveOptions& options) {
  KeyHasher h;
  h.text(kFormatName);
  h.number(kMeshCurveFormatVersion);
  h.number(codec::kFrameVersion);  // encoded sizes depend on the frame layout
  h.text(producer);
  h.number(qem::kCollapseOrderVersion);  // the producer string names settings, not the order
  h.number(static_cast<std::uint64_t>(minTriangles));
  h.number(static_cast<std::uint64_t>(maxTriangles));
  h.number(options.levels);
  h.number(options.maxSegments);
  h.number(options.minRelativeError);
  h.number(static_cast<std::uint64_t>(options.error.samplesPerMesh));
  h.number(options.error.seed);
  h.number(options.error.includeVerticesAndEdges);
  h.number(options.measureEncodedBytes);
  h.number(options.textureCredit);
  h.number(options.quantizationBudgetFraction);
  h.number(options.encode.normalBits);
  h.number(options.encode.texcoordBits);
  h.number(options.encode.encodeSpeed);
  h.number(options.encode.decodeSpeed);
  h.mesh(original);
  return h.hex();
}

std::string serializeMeshCurves(const MeshCurves& curves, const std::string& key) {
  Json levels = Json::array();
  for (const CurveLevel& l : curves.levels) {
    levels.push_back({{"requestedTriangles", l.requestedTriangles},
                      {"triangles", l.triangles},
                      {"relativeMaxError", l.relativeMaxError},
                      {"relativeHausdorffError", l.relativeHausdorffError},
                      {"relativeTextureError", l.relativeTextureError},
                      {"relativeTextureMaxError", l.relativeTextureMaxError},
                      {"relativeMeanError", l.relativeMeanError},
                      {"accuracy", l.accuracy},
                      {"encodedBytes", l.encodedBytes},
                      {"positionBits", l.positionBits},
                      {"encodedAccuracy", l.encodedAccuracy}});
  }
  const Json document = {{"format", kFormatName},
                         {"version", kMeshCurveFormatVersion},
                         {"key", key},
                         {"levels", levels},
                         {"trianglesCurve", curveToJson(curves.triangles)},
                         {"bytesCurve", curveToJson(curves.bytes)}};
  return document.dump(1);
}

Result<MeshCurves> parseMeshCurves(const std::string& text, const std::string& expectedKey) {
  const Json document = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (document.is_discarded() || !document.is_object()) return parseError("not a JSON object");
  try {
    THINLOD_RETURN_IF_ERROR(
        curve_cache::checkCacheHeader(document, kFormatName, kMeshCurveFormatVersion, expectedKey, "mesh curve cache"));

    MeshCurves curves;
    std::vector<AccuracySample> triangleSamples;
    std::vector<AccuracySample> byteSamples;
    for (const Json& l : document.at("levels")) {
      CurveLevel level;
      level.requestedTriangles = l.at("requestedTriangles").get<std::size_t>();
      level.triangles = l.at("triangles").get<std::size_t>();
      level.relativeMaxError = curve_cache::nonNegativeField(l, "relativeMaxError");
      level.relativeHausdorffError = curve_cache::nonNegativeField(l, "relativeHausdorffError");
      level.relativeTextureError = curve_cache::nonNegativeField(l, "relativeTextureError");
      level.relativeTextureMaxError = curve_cache::nonNegativeField(l, "relativeTextureMaxError");
      level.relativeMeanError = curve_cache::nonNegativeField(l, "relativeMeanError");
      level.accuracy = curve_cache::nonNegativeField(l, "accuracy");
      level.encodedBytes = l.at("encodedBytes").get<std::size_t>();
      level.positionBits = l.at("positionBits").get<int>();
      level.encodedAccuracy = curve_cache::nonNegativeField(l, "encodedAccuracy");
      if (level.triangles == 0 || level.triangles > level.requestedTriangles ||
          !(level.accuracy > 0.0) ||
          (!curves.levels.empty() && level.triangles <= curves.levels.back().triangles)) {
        return parseError("level " + std::to_string(curves.levels.size()) + " is inconsistent");
      }
      triangleSamples.push_back({level.accuracy, static_cast<double>(level.triangles)});
      byteSamples.push_back({level.encodedAccuracy, static_cast<double>(level.encodedBytes)});
      curves.levels.push_back(level);
    }
    if (curves.levels.empty()) return parseError("no levels");

    Result<AccuracyCurve> triangles = curveFromJson(document.at("trianglesCurve"), "triangles");
    if (!triangles.ok()) return triangles.status();
    THINLOD_RETURN_IF_ERROR(checkConservative(*triangles, triangleSamples, "triangles"));
    curves.triangles = std::move(*triangles);
    Result<AccuracyCurve> bytes = curveFromJson(document.at("bytesCurve"), "bytes");
    if (!bytes.ok()) return bytes.status();
    if (!bytes->empty()) {
      THINLOD_RETURN_IF_ERROR(checkConservative(*bytes, byteSamples, "bytes"));
    }
    curves.bytes = std::move(*bytes);
    return curves;
  } catch (const std::exception& e) {
    return parseError(e.what());
  }
}

MeshCurveCache::MeshCurveCache(std::filesystem::path directory)
    : directory_(std::move(directory)) {}

std::filesystem::path MeshCurveCache::defaultDirectory() {
  const char* fromEnvironment = std::getenv("THINLOD_CACHE_DIR");
  if (fromEnvironment != nullptr && fromEnvironment[0] != '\0') return fromEnvironment;
  return std::filesystem::path("build") / "cache" / "curves";
}

std::filesystem::path MeshCurveCache::fileFor(const std::string& key) const {
  return directory_ / (key + ".json");
}

Result<MeshCurves> MeshCurveCache::getOrMeasure(const IndexedMesh& original,
                                                const std::string& producer,
                                                std::size_t minTriangles, std::size_t maxTriangles,
                                                const ExtractTriangles& extract,
                                                const MeshCurveOptions& options) {
  const std::string key =
      meshCurveCacheKey(original, producer, minTriangles, maxTriangles, options);
  const std::filesystem::path path = fileFor(key);
  Result<MeshCurves> stored = readStored(key);
  if (stored.ok()) {
    ++stats_.hits;
    return stored;
  }
  if (stored.status().code() == ErrorCode::kNotFound) {
    ++stats_.misses;
  } else {
    ++stats_.rejected;
  }
  Result<MeshCurves> measured =
      measureMeshCurves(original, minTriangles, maxTriangles, extract, options);
  if (!measured.ok()) return measured;
  if (!writeFileAtomically(path, serializeMeshCurves(*measured, key)).ok()) {
    ++stats_.writeFailures;
  }
  return measured;
}

Result<MeshCurves> MeshCurveCache::readStored(const std::string& key) {
  const std::filesystem::path path = fileFor(key);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    return Status(ErrorCode::kNotFound, "mesh curve cache: no " + path.string());
  Result<std::string> text = curve_cache::readCacheFile(path);
  if (!text.ok()) return text.status();
  return parseMeshCurves(*text, key);
}

Result<MeshCurves> MeshCurveCache::find(const IndexedMesh& original, const std::string& producer,
                                        const ProgressiveMesh& pm,
                                        const MeshCurveOptions& options) {
  const std::string key = meshCurveCacheKey(
      original, producer, std::max<std::size_t>(1, pm.minTriangles()), pm.maxTriangles(), options);
  Result<MeshCurves> stored = readStored(key);
  if (stored.ok()) {
    ++stats_.hits;
  } else if (stored.status().code() != ErrorCode::kNotFound) {
    ++stats_.rejected;
  }
  return stored;
}

Result<MeshCurves> MeshCurveCache::getOrMeasure(const IndexedMesh& original,
                                                const std::string& producer,
                                                const ProgressiveMesh& pm,
                                                const MeshCurveOptions& options) {
  return getOrMeasure(
      original, producer, std::max<std::size_t>(1, pm.minTriangles()), pm.maxTriangles(),
      [&pm](std::size_t n) { return pm.extract(n); }, options);
}

}  // namespace thinlod::simplifier
