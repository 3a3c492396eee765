// The on-disk cache of a skinned ladder's bounds under a clip
// (animated_bound_cache.h): key, JSON (de)serialization (pure) and the thin
// file wrapper.
#include "thinlod/simplifier/animated_bound_cache.h"

#include <cmath>
#include <exception>
#include <nlohmann/json.hpp>
#include <string>
#include <system_error>

#include "curve_cache_files.h"
#include "qem_collapse.h"

namespace thinlod::simplifier {
namespace {

using Json = nlohmann::json;

constexpr const char* kFormatName = "thinlod-animated-bounds";

Status parseError(const std::string& message) {
  return Status(ErrorCode::kParseError, "animated bound cache: " + message);
}

void hashMatrix(curve_cache::KeyHasher& h, const glm::mat4& m) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) h.number(m[c][r]);
  }
}

void hashVectorKeys(curve_cache::KeyHasher& h, const std::vector<anim::VectorKey>& keys) {
  h.number(keys.size());
  for (const anim::VectorKey& k : keys) {
    h.number(k.time);
    h.number(k.value.x);
    h.number(k.value.y);
    h.number(k.value.z);
  }
}

}  // namespace

std::string animatedBoundCacheKey(const AnimatedLadderInputs& inputs) {
  curve_cache::KeyHasher h;
  h.text(kFormatName);
  h.number(kAnimatedBoundFormatVersion);
  h.text(inputs.producer);
  h.number(qem::kCollapseOrderVersion);
  h.mesh(inputs.full);
  h.number(inputs.skin.size());
  for (const anim::VertexSkin& s : inputs.skin) {
    h.number(s.boneA);
    h.number(s.boneB);
    h.number(s.weightB);
  }
  h.number(inputs.skeleton.bones.size());
  for (const anim::Bone& bone : inputs.skeleton.bones) {
    h.number(bone.parent);
    hashMatrix(h, bone.restLocal);
    hashMatrix(h, bone.inverseBind);
  }
  h.number(inputs.clip.duration);
  h.number(inputs.clip.channels.size());
  for (const anim::BoneChannel& channel : inputs.clip.channels) {
    h.number(channel.bone);
    hashVectorKeys(h, channel.positions);
    hashVectorKeys(h, channel.scales);
    h.number(channel.rotations.size());
    for (const anim::RotationKey& k : channel.rotations) {
      h.number(k.time);
      h.number(k.value.w);
      h.number(k.value.x);
      h.number(k.value.y);
      h.number(k.value.z);
    }
  }
  h.number(inputs.rungTriangles.size());
  for (const std::size_t n : inputs.rungTriangles) h.number(static_cast<std::uint64_t>(n));
  const AnimatedErrorOptions& o = inputs.options;
  h.number(o.t0);
  h.number(o.t1);
  h.number(static_cast<int>(o.wrap));
  h.number(static_cast<std::uint64_t>(o.initialPoses));
  h.number(static_cast<std::uint64_t>(o.maxPoses));
  h.number(static_cast<std::uint64_t>(o.motionSteps));
  h.number(o.relativeTolerance);
  h.number(o.absoluteTolerance);
  h.number(static_cast<std::uint64_t>(o.surface.samplesPerMesh));
  h.number(o.surface.seed);
  h.number(o.surface.includeVerticesAndEdges);
  return h.hex();
}

std::string serializeAnimatedBounds(const std::vector<double>& bounds, const std::string& key) {
  const Json document = {{"format", kFormatName},
                         {"version", kAnimatedBoundFormatVersion},
                         {"key", key},
                         {"bounds", bounds}};
  return document.dump(1);
}

Result<std::vector<double>> parseAnimatedBounds(const std::string& text,
                                                const std::string& expectedKey, std::size_t rungs) {
  const Json document = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (document.is_discarded() || !document.is_object()) return parseError("not a JSON object");
  try {
    THINLOD_RETURN_IF_ERROR(curve_cache::checkCacheHeader(
        document, kFormatName, kAnimatedBoundFormatVersion, expectedKey, "animated bound cache"));
    const Json& bounds = document.at("bounds");
    if (!bounds.is_array()) return parseError("bounds is not an array");
    if (bounds.size() != rungs) {
      return parseError(std::to_string(bounds.size()) + " bounds for " + std::to_string(rungs) +
                        " rungs");
    }
    std::vector<double> out;
    out.reserve(rungs);
    for (const Json& b : bounds) {
      if (!b.is_number())
        return parseError("bound " + std::to_string(out.size()) + " is not a number");
      const double value = b.get<double>();
      if (!std::isfinite(value) || value < 0.0) {
        return parseError("bound " + std::to_string(out.size()) + " is not finite and >= 0");
      }
      out.push_back(value);
    }
    return out;
  } catch (const std::exception& e) {
    return parseError(e.what());
  }
}

AnimatedBoundCache::AnimatedBoundCache(std::filesystem::path directory)
    : directory_(std::move(directory)) {}

std::filesystem::path AnimatedBoundCache::fileFor(const std::string& key) const {
  return directory_ / ("animated-" + key + ".json");
}

Result<std::vector<double>> AnimatedBoundCache::find(const AnimatedLadderInputs& inputs) {
  const std::string key = animatedBoundCacheKey(inputs);
  const std::filesystem::path path = fileFor(key);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return Status(ErrorCode::kNotFound, "animated bound cache: no " + path.string());
  }
  Result<std::string> text = curve_cache::readCacheFile(path);
  Result<std::vector<double>> stored =
      text.ok() ? parseAnimatedBounds(*text, key, inputs.rungTriangles.size())
                : Result<std::vector<double>>(text.status());
  if (stored.ok()) {
    ++stats_.hits;
  } else {
    ++stats_.rejected;
    lastRejection_ = path.string() + ": " + stored.status().toString();
  }
  return stored;
}

Result<std::vector<double>> AnimatedBoundCache::getOrMeasure(const AnimatedLadderInputs& inputs,
                                                             const Measure& measure) {
  Result<std::vector<double>> stored = find(inputs);
  if (stored.ok()) return stored;
  if (stored.status().code() == ErrorCode::kNotFound) ++stats_.misses;
  Result<std::vector<double>> measured = measure();
  if (!measured.ok()) return measured;
  const std::string key = animatedBoundCacheKey(inputs);
  const std::string text = serializeAnimatedBounds(*measured, key);
  // Never store what a reader would refuse (it would be measured forever).
  if (!parseAnimatedBounds(text, key, inputs.rungTriangles.size()).ok() ||
      !curve_cache::writeFileAtomically(fileFor(key), text).ok()) {
    ++stats_.writeFailures;
  }
  return measured;
}

}  // namespace thinlod::simplifier
