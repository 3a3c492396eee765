// Live scoring: the frames the thin client actually showed, each kept with
// the pose it was drawn for, scored afterwards against the full-quality
// reference of that same pose (docs/frontend.md, "Live scoring").
//
// Why: in live mode the client never waits, so a frame may show
// representations planned for an older pose, or be drawn late. Rendering the
// reference inline would slow the client down and hide exactly that. So the
// replay keeps (frame, pose, image, held objects) and the references are
// rendered after the replay. A frame is always scored against the reference
// of the pose it was DRAWN for (ShownFrame::pose), never against the pose
// its representations answered nor the pose current when it was shown.
//
// Contract:
// - ShownFrameLog keeps copies of the images up to `maxBytes` of pixels;
//   frames beyond that are not kept (record() returns false, dropped()
//   counts them) so a long run cannot exhaust memory. Value type, not
//   thread-safe.
// - ReferenceSource renders the full-quality frame of a pose (GL in the
//   daemon, a fake in tests). scoreShownFrames() calls it once per kept
//   frame, in frame order, and returns one ShownFrameScore per kept frame.
// - Visibility is by world bounds against the pose's view volume (no
//   occlusion); objects of one LOD share a group (any level shown = shown).
// - Errors: a ReferenceSource failure or frames of mismatched sizes end the
//   scoring with that Status naming the frame.
// - Pure: no GL, files or clocks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <vector>

#include "thinlod/common/rgba_image.h"
#include "thinlod/common/status.h"
#include "thinlod/common/trace.h"

namespace thinlod::frontend {

// One drawable object of the scene for completeness checks.
struct ObjectExtent {
  std::uint64_t id = 0;
  std::uint64_t group = 0;  // objects of one LOD share it; otherwise unique per object
  glm::vec3 worldMin{0.0f};
  glm::vec3 worldMax{0.0f};
};

// Ids the frontend held (drew) in a frame, sorted ascending. Shared between
// frames until the held set changes.
using HeldObjects = std::shared_ptr<const std::vector<std::uint64_t>>;

// Whether the box [worldMin, worldMax] may be visible through `viewProjection`
// (clip space = viewProjection * world): false only when all 8 corners lie
// outside one clip plane (conservative: no occlusion, boxes near a frustum
// corner may count as visible).
bool boxMayBeVisible(const glm::vec3& worldMin, const glm::vec3& worldMax,
                     const glm::mat4& viewProjection);

struct Completeness {
  std::size_t visibleGroups = 0;  // groups with an object in the view volume
  std::size_t missingGroups = 0;  // of those, groups with no object held
};
// `held` sorted ascending (as HeldObjects); `objects` in any order.
Completeness frameCompleteness(const std::vector<ObjectExtent>& objects,
                               const std::vector<std::uint64_t>& held,
                               const glm::mat4& viewProjection);

struct ShownFrame {
  std::uint64_t frame = 0;
  Pose pose;                   // the pose the frame was drawn for
  std::int64_t shownAtNs = 0;  // clock time its readback finished
  RgbaImage image;             // what the client showed
  HeldObjects held;            // may be null: nothing held
};

class ShownFrameLog {
 public:
  explicit ShownFrameLog(std::size_t maxBytes) : maxBytes_(maxBytes) {}
  // Keeps a copy of `image`; false (and counted) when it would exceed maxBytes.
  bool record(std::uint64_t frame, const Pose& pose, std::int64_t shownAtNs, const RgbaImage& image,
              HeldObjects held);
  const std::vector<ShownFrame>& frames() const { return frames_; }
  std::vector<ShownFrame>& frames() { return frames_; }
  std::size_t dropped() const { return dropped_; }
  std::size_t bytes() const { return bytes_; }

 private:
  std::size_t maxBytes_;
  std::size_t bytes_ = 0;
  std::size_t dropped_ = 0;
  std::vector<ShownFrame> frames_;
};

class ReferenceSource {
 public:
  virtual ~ReferenceSource() = default;
  // Renders the full-quality frame for `pose` into `out` (same size as the
  // shown frames); returns its render time in ms. `viewProjection` receives
  // the camera used, for the completeness check.
  virtual Result<double> render(const Pose& pose, RgbaImage& out, glm::mat4& viewProjection) = 0;
};

struct ShownFrameScore {
  std::uint64_t frame = 0;
  double snrDb = 0.0;
  double psnrDb = 0.0;
  double referenceMs = 0.0;
  // The shown frame is one uniform colour while the reference is not.
  bool blank = false;
  Completeness completeness;
};

// Called after each frame is scored with the shown frame and its reference
// (e.g. to write them out); may be empty.
using ScoredFrameSink =
    std::function<void(const ShownFrame&, const RgbaImage& reference, const ShownFrameScore&)>;

Result<std::vector<ShownFrameScore>> scoreShownFrames(const std::vector<ShownFrame>& frames,
                                                      ReferenceSource& references,
                                                      const std::vector<ObjectExtent>& objects,
                                                      const ScoredFrameSink& sink = {});

// |a - b| per RGB channel, alpha 255 (for difference images). Sizes must match
// (kInvalidArgument otherwise).
Result<RgbaImage> differenceImage(const RgbaImage& a, const RgbaImage& b);

}  // namespace thinlod::frontend
