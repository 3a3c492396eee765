#include "thinlod/frontend/shown_frames.h"

#include <algorithm>
#include <string>
#include <unordered_map>
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

glm::vec4 coverageColor(std::size_t index) {
  const std::size_t id = index + 1;
  return glm::vec4(static_cast<float>(id & 0xff) / 255.0f,
                   static_cast<float>((id >> 8) & 0xff) / 255.0f,
                   static_cast<float>((id >> 16) & 0xff) / 255.0f, 1.0f);
}

Result<std::vector<std::uint32_t>> coverageFromIdImage(const RgbaImage& ids,
                                                       std::size_t objectCount) {
  if (!ids.consistent()) {
    return Status(ErrorCode::kInvalidArgument, "coverageFromIdImage: inconsistent image");
  }
  std::vector<std::uint32_t> covered(objectCount, 0);
  for (std::size_t i = 0; i + 3 < ids.pixels.size(); i += 4) {
    const std::size_t id = std::size_t{ids.pixels[i]} | (std::size_t{ids.pixels[i + 1]} << 8) |
                           (std::size_t{ids.pixels[i + 2]} << 16);
    if (id == 0) continue;
    if (id > objectCount) {
      return Status(ErrorCode::kInvalidArgument, "coverageFromIdImage: colour " +
                                                     std::to_string(id) + " names no object (" +
                                                     std::to_string(objectCount) + " objects)");
    }
    ++covered[id - 1];
  }
  return covered;
}

Result<Completeness> frameCompleteness(const std::vector<ObjectExtent>& objects,
                                       const std::vector<std::uint32_t>& covered,
                                       const std::vector<std::uint64_t>& held,
                                       std::uint32_t minPixels) {
  if (covered.size() != objects.size()) {
    return Status(ErrorCode::kInvalidArgument,
                  "frameCompleteness: " + std::to_string(covered.size()) + " coverage counts for " +
                      std::to_string(objects.size()) + " objects");
  }
  std::unordered_map<std::uint64_t, std::uint64_t> pixels;  // group -> covered pixels
  std::unordered_set<std::uint64_t> shown;
  for (std::size_t k = 0; k < objects.size(); ++k) {
    pixels[objects[k].group] += covered[k];
    if (std::binary_search(held.begin(), held.end(), objects[k].id)) {
      shown.insert(objects[k].group);
    }
  }
  Completeness result;
  for (const auto& [group, count] : pixels) {
    if (count < std::max<std::uint32_t>(minPixels, 1)) continue;
    ++result.visibleGroups;
    result.missingGroups += shown.count(group) == 0;
  }
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

Result<FrameQuality> scoreFrame(const RgbaImage& shown, const RgbaImage& reference,
                                const std::vector<ObjectExtent>& objects,
                                const std::vector<std::uint32_t>& covered,
                                const std::vector<std::uint64_t>& held, std::uint32_t minPixels) {
  Result<FrameComparison> comparison = compareFrames(shown, reference);
  if (!comparison.ok()) return comparison.status();
  FrameQuality quality;
  quality.snrDb = comparison->snrDb;
  quality.psnrDb = comparison->psnrDb;
  quality.blank = comparison->variance == 0.0 && !uniformRgb(reference) ? 1 : 0;
  if (!covered.empty()) {
    Result<Completeness> completeness = frameCompleteness(objects, covered, held, minPixels);
    if (!completeness.ok()) return completeness.status();
    quality.visibleObjects = static_cast<long>(completeness->visibleGroups);
    quality.missingObjects = static_cast<long>(completeness->missingGroups);
  }
  return quality;
}

Result<std::vector<FrameScore>> scoreShownFrames(const std::vector<ShownFrame>& frames,
                                                 ReferenceSource& references,
                                                 const std::vector<ObjectExtent>& objects,
                                                 std::uint32_t minPixels,
                                                 const ScoredFrameSink& sink) {
  static const std::vector<std::uint64_t> kNothingHeld;
  std::vector<FrameScore> scores;
  scores.reserve(frames.size());
  RgbaImage reference;
  std::vector<std::uint32_t> covered;
  for (const ShownFrame& shown : frames) {
    covered.clear();
    // The reference of the pose this frame was drawn for.
    Result<double> renderMs = references.render(shown.pose, reference, covered);
    if (!renderMs.ok()) {
      return Status(renderMs.status().code(), "reference of shown frame " +
                                                  std::to_string(shown.frame) + ": " +
                                                  renderMs.status().message());
    }
    Result<FrameQuality> quality =
        scoreFrame(shown.image, reference, objects, covered,
                   shown.held != nullptr ? *shown.held : kNothingHeld, minPixels);
    if (!quality.ok()) {
      return Status(quality.status().code(), "shown frame " + std::to_string(shown.frame) + ": " +
                                                 quality.status().message());
    }
    FrameScore score;
    score.frame = shown.frame;
    score.quality = *quality;
    score.quality.referenceMs = *renderMs;
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
