// On-disk cache of measured hybrid ladders (measureHybridLevels, the slow
// part of a hybrid curve: 45-90 s for a 96,000-triangle model), in the same
// directory as the mesh curves (MeshCurveCache, mesh_curve.h).
//
// Contract:
// - Key (32 hex digits) over everything the ladder depends on: the format
//   name and kHybridCurveFormatVersion, kHybridGraphVersion, the mesh bytes
//   (positions, normals, uvs, colours, indices), every HybridOptions field
//   (kappa, tau, enablePoints, sampleDistanceTolerance, octreeMaxDepth), the
//   ladder length and the measurement's SurfaceErrorOptions (samples, seed,
//   vertices and edges). Credits are not stored: the caller derives them
//   from the measured errors (the service's creditHybridLevels).
// - The file holds the rungs (cut threshold, units, triangles, points) and
//   each rung's measured error. It is untrusted: parseHybridLevels refuses
//   (kParseError; kVersionMismatch for another version) anything but a JSON
//   object of the right format and key whose rungs are exactly
//   hybridLadderSteps(graph, levels) of the graph rebuilt from the same mesh
//   (so counts, finiteness, increasing units and decreasing thresholds are
//   checked by equality with what the graph gives) and whose measured errors
//   are finite, >= 0 and at most the rung's guaranteed bound (threshold +
//   1e-6 of the graph's diagonal for rounding: a sampled distance cannot
//   exceed it). Files are read through readFileBounded (16 MiB).
// - getOrMeasure: a valid file is returned (hits); a missing one is
//   measured (misses), a refused one measured again (rejected, the reason in
//   lastRejection()); the measurement is written atomically (temporary +
//   rename; distinct processes race benignly). A failed write is counted,
//   the result still returned. Not thread-safe across one instance.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"
#include "thinlod/simplifier/hybrid_graph.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::simplifier {

// 1: first version (rungs with measured errors, no credits).
inline constexpr int kHybridCurveFormatVersion = 1;

std::string hybridCurveCacheKey(const IndexedMesh& original, const HybridOptions& options,
                                int levels, const SurfaceErrorOptions& error);

// Pure (de)serialization; `key` is stored and checked.
std::string serializeHybridLevels(const std::vector<HybridMeasuredLevel>& levels,
                                  const std::string& key);
Result<std::vector<HybridMeasuredLevel>> parseHybridLevels(const std::string& json,
                                                           const std::string& expectedKey,
                                                           const HybridGraph& graph, int levels);
// The checks of parseHybridLevels on decoded rungs (also applied to a fresh
// measurement before it is written).
Status validateHybridLevels(const std::vector<HybridMeasuredLevel>& measured,
                            const HybridGraph& graph, int levels);

class HybridCurveCache {
 public:
  struct Stats {
    int hits = 0;
    int misses = 0;         // no file: measured
    int rejected = 0;       // file present but refused: measured again
    int writeFailures = 0;  // result still returned
  };

  explicit HybridCurveCache(std::filesystem::path directory);

  // `graph` must be buildHybridGraph(original, options).
  Result<std::vector<HybridMeasuredLevel>> getOrMeasure(const IndexedMesh& original,
                                                        const HybridGraph& graph,
                                                        const HybridOptions& options, int levels,
                                                        const SurfaceErrorOptions& error);

  // "hybrid-<key>.json" in the directory.
  std::filesystem::path fileFor(const std::string& key) const;
  const std::filesystem::path& directory() const { return directory_; }
  const Stats& stats() const { return stats_; }
  // Why the last refused file was refused (empty before any).
  const std::string& lastRejection() const { return lastRejection_; }

 private:
  std::filesystem::path directory_;
  Stats stats_;
  std::string lastRejection_;
};

}  // namespace thinlod::simplifier
