// On-disk cache of a skinned mesh's ladder bounds under a clip: one
// deformedLevelBound (skinned_level.h) per rung of its progressive mesh,
// measured once per mesh, skin, skeleton, clip, ladder and options (seconds
// of work per figure; docs/animation.md, "Measured accuracy under motion").
//
// Contract:
// - animatedBoundCacheKey hashes everything the bounds depend on: the full
//   mesh, its skin, the skeleton (parents, rest and inverse-bind matrices),
//   the clip (duration and every key), the producer and collapse order of
//   the progressive mesh, the rungs' requested triangle counts and every
//   AnimatedErrorOptions field. Field by field: no padding byte is hashed.
// - getOrMeasure (and find, which never measures) returns the stored bounds
//   when the file
//   "animated-<key>.json" parses: its header (format, version, key), one
//   finite bound >= 0 per rung, no more; otherwise it calls `measure`, checks
//   its result the same way, stores it by atomic rename and returns it. A
//   refused file (corrupt, stale, another version) is measured again and
//   overwritten; a failed write still returns the measurement.
// - Files are untrusted: bounded read (16 MiB), every field checked.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/core/status.h"
#include "thinlod/simplifier/skinned_level.h"

namespace thinlod::simplifier {

inline constexpr int kAnimatedBoundFormatVersion = 1;

struct AnimatedLadderInputs {
  const IndexedMesh& full;
  const std::vector<anim::VertexSkin>& skin;  // skeleton bones, one per full vertex
  const anim::Skeleton& skeleton;
  const anim::AnimationClip& clip;
  std::string producer;                    // the progressive mesh's curve producer
  std::vector<std::size_t> rungTriangles;  // requested triangles, one per rung
  AnimatedErrorOptions options;
};

std::string animatedBoundCacheKey(const AnimatedLadderInputs& inputs);

// The stored text of `bounds` and its parse (kParseError / kVersionMismatch
// with the reason). Pure.
std::string serializeAnimatedBounds(const std::vector<double>& bounds, const std::string& key);
Result<std::vector<double>> parseAnimatedBounds(const std::string& text,
                                                const std::string& expectedKey, std::size_t rungs);

class AnimatedBoundCache {
 public:
  struct Stats {
    int hits = 0;
    int misses = 0;         // no file: measured
    int rejected = 0;       // file present but refused: measured again
    int writeFailures = 0;  // result still returned
  };
  using Measure = std::function<Result<std::vector<double>>()>;

  explicit AnimatedBoundCache(std::filesystem::path directory);

  Result<std::vector<double>> getOrMeasure(const AnimatedLadderInputs& inputs,
                                           const Measure& measure);
  // The stored bounds only, never measuring: kNotFound without a file, the
  // parse error for a refused one (counted as rejected).
  Result<std::vector<double>> find(const AnimatedLadderInputs& inputs);

  std::filesystem::path fileFor(const std::string& key) const;
  const Stats& stats() const { return stats_; }
  const std::string& lastRejection() const { return lastRejection_; }

 private:
  std::filesystem::path directory_;
  Stats stats_;
  std::string lastRejection_;
};

}  // namespace thinlod::simplifier
