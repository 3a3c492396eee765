// Measured accuracy curves of a progressive mesh (Pasman & Jansen 2002,
// sections 3.1-3.2: QSlim + Metro measurements fitted by a few (A, R, K)).
//
// Contract:
// - A geometric ladder of triangle counts from minTriangles to maxTriangles
//   is extracted; at each level d = symmetric Hausdorff max
//   (measureSurfaceError) / L, L = referenceLength(referenceSphere(original))
//   (core/relative_accuracy.h: the one reference length), floored at
//   minRelativeError because the full mesh has d = 0 and a curve needs a
//   finite domain; a = 1/d.
// - Textured meshes (uvs with a non-zero uv area, textureCredit): d is
//   max(Hausdorff max, texel displacement p95) / L, the texel displacement
//   of measureUvError (how far from its place on the original a texel is
//   drawn; surface_error.h). The 95th percentile, not the max: the max is
//   set by a few samples where a simplified chart border cuts a corner of
//   its chart and a texel comes from the neighbouring chart of the atlas
//   (duck.dae at 50%: p95 0.65%, max 5.3% of the diagonal; meshopt_simplify
//   0.18 p95 0.64%, max 44%), which an atlas' gutter hides and no
//   collapse order avoids entirely. docs/simplifier.md "UV error".
// - triangles curve: resources = extracted triangle count against a.
//   bytes curve: resources = Draco-encoded frame size (encodeMesh, position
//   bits from positionBitsForAccuracy(a)) against the accuracy of what the
//   client decodes, bounded by 1 / (d + quantization bound / L)
//   (Hausdorff triangle inequality: moving vertices by <= q moves the
//   surface by <= q).
// - Both curves come from AccuracyCurve::fitConservative: for every a the
//   curve's resources >= the cheapest measured level reaching >= a, so it
//   never promises more accuracy for a resource than was measured.
// - Levels are extracted one after another (the extraction function need
//   not be thread-safe) and measured on options.threads threads (the same
//   curves for any count).
// - measureMeshCurves is pure (no I/O). MeshCurveCache is its thin file
//   wrapper: one JSON file per key (hash of the mesh bytes, producer tag,
//   options, ladder and kMeshCurveFormatVersion) in a directory; files that
//   fail to parse, have another version or key, or whose curves fail
//   AccuracyCurve::fromTriples or are not conservative w.r.t. their own
//   levels are ignored, recomputed and overwritten. Not thread-safe across
//   one instance; distinct processes race benignly (atomic rename).
// - Errors: invalid mesh / options (kInvalidArgument), extraction returning
//   an invalid or empty mesh (kInternal), measurement and fit errors passed on.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::simplifier {

// 2: relative errors refer to the reference sphere's diameter (version 1
// files used the bbox diagonal; they are rejected and measured again).
// 3: levels carry the Hausdorff and texture errors apart; d of a textured
// mesh includes the texture term.
inline constexpr int kMeshCurveFormatVersion = 3;

struct CurveLevel {
  std::size_t requestedTriangles = 0;
  std::size_t triangles = 0;             // what the extraction returned
  double relativeMaxError = 0.0;         // measured d, before the floor: max of the next two
  double relativeHausdorffError = 0.0;   // Hausdorff max / L
  double relativeTextureError = 0.0;     // texel displacement p95 / L (0: untextured)
  double relativeTextureMaxError = 0.0;  // its max / L, reported only
  double relativeMeanError = 0.0;        // Hausdorff mean / L
  double accuracy = 0.0;                 // 1 / max(d, floor)
  std::size_t encodedBytes = 0;          // 0 when not measured
  int positionBits = 0;
  double encodedAccuracy = 0.0;  // 1 / (max(d, floor) + quantization / L)
};

struct MeshCurveOptions {
  int levels = 12;                 // ladder rungs (duplicates after rounding merge)
  int maxSegments = 6;             // per fitted curve (see error-validation.md)
  double minRelativeError = 1e-4;  // floor on d: accuracy at most 10^4
  SurfaceErrorOptions error{};
  bool measureEncodedBytes = true;
  // Textured meshes: d includes the texel displacement (above); its samples
  // and seed are error's.
  bool textureCredit = true;
  double quantizationBudgetFraction = 0.1;  // see positionBitsForAccuracy
  codec::MeshEncodeOptions encode{};        // positionBits is chosen per level
  // Levels measured at once (parallelFor; 0: one per hardware thread). Each
  // level is an independent measurement with the same seed, so the curves
  // are the same for any count (the cache key leaves it out).
  int threads = 1;
  // Called after each level's measurement (progress of long measurements),
  // one call at a time, from the thread that measured it; `measured` counts
  // the levels done so far of `total`. Not in the cache key.
  std::function<void(const CurveLevel& level, std::size_t measured, std::size_t total)>
      levelMeasured;
};


struct MeshCurves {
  std::vector<CurveLevel> levels;  // increasing triangle counts
  AccuracyCurve triangles;
  AccuracyCurve bytes;  // empty unless measureEncodedBytes
};

// Returns a mesh with at most `targetTriangles` triangles of the same object.
using ExtractTriangles = std::function<IndexedMesh(std::size_t targetTriangles)>;

// `levels` counts spaced geometrically from min to max (both included),
// rounded, deduplicated, increasing. Empty if min == 0 or min > max.
std::vector<std::size_t> geometricLadder(std::size_t minTriangles, std::size_t maxTriangles,
                                         int levels);

Result<MeshCurves> measureMeshCurves(const IndexedMesh& original, std::size_t minTriangles,
                                     std::size_t maxTriangles, const ExtractTriangles& extract,
                                     const MeshCurveOptions& options = {});
// The ladder spans [max(1, pm.minTriangles()), pm.maxTriangles()].
Result<MeshCurves> measureMeshCurves(const IndexedMesh& original, const ProgressiveMesh& pm,
                                     const MeshCurveOptions& options = {});

// Pure (de)serialization of the cache file; `key` is stored and checked.
std::string serializeMeshCurves(const MeshCurves& curves, const std::string& key);
Result<MeshCurves> parseMeshCurves(const std::string& json, const std::string& expectedKey);
// 32 hex digits over everything that determines the result. `producer` names
// the simplifier and its settings (e.g. "qem boundaries=1 flips=1").
std::string meshCurveCacheKey(const IndexedMesh& original, const std::string& producer,
                              std::size_t minTriangles, std::size_t maxTriangles,
                              const MeshCurveOptions& options);

class MeshCurveCache {
 public:
  struct Stats {
    int hits = 0;
    int misses = 0;         // no file: measured
    int rejected = 0;       // file present but corrupt / stale: measured again
    int writeFailures = 0;  // result still returned
  };

  explicit MeshCurveCache(std::filesystem::path directory);
  // $THINLOD_CACHE_DIR if set and non-empty, else "build/cache/curves"
  // (relative to the working directory).
  static std::filesystem::path defaultDirectory();

  Result<MeshCurves> getOrMeasure(const IndexedMesh& original, const std::string& producer,
                                  std::size_t minTriangles, std::size_t maxTriangles,
                                  const ExtractTriangles& extract,
                                  const MeshCurveOptions& options = {});
  Result<MeshCurves> getOrMeasure(const IndexedMesh& original, const std::string& producer,
                                  const ProgressiveMesh& pm, const MeshCurveOptions& options = {});
  // The stored curves only, never measuring: kNotFound when there is no
  // valid file (a corrupt or stale one counts as rejected). Ladder = pm's.
  Result<MeshCurves> find(const IndexedMesh& original, const std::string& producer,
                          const ProgressiveMesh& pm, const MeshCurveOptions& options = {});

  std::filesystem::path fileFor(const std::string& key) const;
  const std::filesystem::path& directory() const { return directory_; }
  const Stats& stats() const { return stats_; }

 private:
  // The parsed file for `key`; kNotFound (no file) or its parse error.
  Result<MeshCurves> readStored(const std::string& key);

  std::filesystem::path directory_;
  Stats stats_;
};

}  // namespace thinlod::simplifier
