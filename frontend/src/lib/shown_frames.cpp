#include "thinlod/frontend/shown_frames.h"

#include <algorithm>
#include <glm/vec4.hpp>
#include <string>
#include <unordered_set>
#include <utility>

#include "thinlod/frontend/frame_metrics.h"

namespace thinlod::frontend {
namespace {

// Every pixel's RGB equals the first pixel's (alpha ignored, as in the metrics).
bool uniformRgb(const RgbaImage& image) {
  const std::uint8_t* p = image.pixels.data();
  for (std::size_t i = 4; i + 3 < image.pixels.size(); i += 4) {
    if (p[i] != p[0] || p[i + 1] != p[1] || p[i + 2] != p[2]) return false;
  }
  return true;
}

}  // namespace

bool boxMayBeVisible(const glm::vec3& lo, const glm::vec3& hi, const glm::mat4& viewProjection) {
  // Per clip plane (-w <= x, y, z <= w), count the corners outside it.
  int outside[6] = {0, 0, 0, 0, 0, 0};
  for (int corner = 0; corner < 8; ++corner) {
    const glm::vec4 p((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y,
                      (corner & 4) ? hi.z : lo.z, 1.0f);
    const glm::vec4 c = viewProjection * p;
    outside[0] += c.x < -c.w;
    outside[1] += c.x > c.w;
    outside[2] += c.y < -c.w;
    outside[3] += c.y > c.w;
    outside[4] += c.z < -c.w;
    outside[5] += c.z > c.w;
  }
  return std::none_of(std::begin(outside), std::end(outside), [](int n) { return n == 8; });
}

Completeness frameCompleteness(const std::vector<ObjectExtent>& objects,
                               const std::vector<std::uint64_t>& held,
                               const glm::mat4& viewProjection) {
  std::unordered_set<std::uint64_t> visible;
  std::unordered_set<std::uint64_t> shown;
  for (const ObjectExtent& object : objects) {
    if (std::binary_search(held.begin(), held.end(), object.id)) shown.insert(object.group);
    if (boxMayBeVisible(object.worldMin, object.worldMax, viewProjection)) {
      visible.insert(object.group);
    }
  }
  Completeness result;
  result.visibleGroups = visible.size();
  for (std::uint64_t group : visible) result.missingGroups += shown.count(group) == 0;
  return result;
}

bool ShownFrameLog::record(std::uint64_t frame, const Pose& pose, std::int64_t shownAtNs,
                           const RgbaImage& image, HeldObjects held) {
  if (bytes_ + image.pixels.size() > maxBytes_) {
    ++dropped_;
    return false;
  }
  bytes_ += image.pixels.size();
  frames_.push_back(ShownFrame{frame, pose, shownAtNs, image, std::move(held)});
  return true;
}

Result<std::vector<ShownFrameScore>> scoreShownFrames(const std::vector<ShownFrame>& frames,
                                                      ReferenceSource& references,
                                                      const std::vector<ObjectExtent>& objects,
                                                      const ScoredFrameSink& sink) {
  static const std::vector<std::uint64_t> kNothingHeld;
  std::vector<ShownFrameScore> scores;
  scores.reserve(frames.size());
  RgbaImage reference;
  for (const ShownFrame& shown : frames) {
    glm::mat4 viewProjection(1.0f);
    // The reference of the pose this frame was drawn for.
    Result<double> renderMs = references.render(shown.pose, reference, viewProjection);
    if (!renderMs.ok()) {
      return Status(renderMs.status().code(), "reference of shown frame " +
                                                  std::to_string(shown.frame) + ": " +
                                                  renderMs.status().message());
    }
    Result<FrameComparison> comparison = compareFrames(shown.image, reference);
    if (!comparison.ok()) {
      return Status(comparison.status().code(), "shown frame " + std::to_string(shown.frame) +
                                                    ": " + comparison.status().message());
    }
    ShownFrameScore score;
    score.frame = shown.frame;
    score.snrDb = comparison->snrDb;
    score.psnrDb = comparison->psnrDb;
    score.referenceMs = *renderMs;
    score.blank = comparison->variance == 0.0 && !uniformRgb(reference);
    score.completeness = frameCompleteness(
        objects, shown.held != nullptr ? *shown.held : kNothingHeld, viewProjection);
    if (sink) sink(shown, reference, score);
    scores.push_back(score);
  }
  return scores;
}

Result<RgbaImage> differenceImage(const RgbaImage& a, const RgbaImage& b) {
  if (!a.consistent() || !b.consistent() || a.width != b.width || a.height != b.height) {
    return Status(ErrorCode::kInvalidArgument,
                  "differenceImage: sizes differ or are inconsistent (" + std::to_string(a.width) +
                      "x" + std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                      std::to_string(b.height) + ")");
  }
  RgbaImage out(a.width, a.height);
  for (std::size_t i = 0; i < a.pixels.size(); i += 4) {
    for (int c = 0; c < 3; ++c) {
      const int d = int(a.pixels[i + c]) - int(b.pixels[i + c]);
      out.pixels[i + c] = static_cast<std::uint8_t>(d < 0 ? -d : d);
    }
    out.pixels[i + 3] = 255;
  }
  return out;
}

}  // namespace thinlod::frontend
