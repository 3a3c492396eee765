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
//   frame, in frame order, and returns one FrameScore per kept frame.
// - Visibility is by coverage of the reference: an object group is visible
//   when it covers at least minPixels pixels of the pose's reference (an id
//   render: occlusion included); objects of one LOD share a group (any level
//   held = shown).
// - Errors: a ReferenceSource failure or frames of mismatched sizes end the
//   scoring with that Status naming the frame.
// - Pure: no GL, files or clocks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <glm/vec4.hpp>
#include <memory>
#include <vector>

#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/core/trace.h"
#include "thinlod/frontend/frame_record.h"

namespace thinlod::frontend {

// One drawable object of the scene for completeness checks.
struct ObjectExtent {
  std::uint64_t id = 0;
  std::uint64_t group = 0;  // objects of one LOD share it; otherwise unique per object
};

// Ids the frontend held (drew) in a frame, sorted ascending. Shared between
// frames until the held set changes.
using HeldObjects = std::shared_ptr<const std::vector<std::uint64_t>>;

// The flat colour object `index` is drawn with in a coverage (id) render of
// the reference: index + 1 in the RGB bytes (R low byte), alpha 1; black (0)
// is the background. Exact in RGBA8: each component is k / 255.
// Distinct for index < kMaxCoverageObjects (2^24 - 1); callers check.
constexpr std::size_t kMaxCoverageObjects = (std::size_t{1} << 24) - 1;
glm::vec4 coverageColor(std::size_t index);
// Pixels per object of a coverage render (objectCount entries). A colour
// naming no object (> objectCount) is kInvalidArgument.
Result<std::vector<std::uint32_t>> coverageFromIdImage(const RgbaImage& ids,
                                                       std::size_t objectCount);

struct Completeness {
  std::size_t visibleGroups = 0;  // groups covering at least minPixels of the reference
  std::size_t missingGroups = 0;  // of those, groups with no object held
};
// `covered[k]` = pixels of objects[k] in the reference (occlusion included);
// a group is visible when its objects cover at least `minPixels` together.
// `held` sorted ascending (as HeldObjects). covered.size() must equal
// objects.size() (else kInvalidArgument).
Result<Completeness> frameCompleteness(const std::vector<ObjectExtent>& objects,
                                       const std::vector<std::uint32_t>& covered,
                                       const std::vector<std::uint64_t>& held,
                                       std::uint32_t minPixels);

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
  // shown frames) and the pixels each object covers in it into `covered`
  // (one entry per ObjectExtent, or empty when not measured); returns the
  // render time in ms.
  virtual Result<double> render(const Pose& pose, RgbaImage& out,
                                std::vector<std::uint32_t>& covered) = 0;
};

// Called after each frame is scored with the shown frame and its reference
// (e.g. to write them out); may be empty.
using ScoredFrameSink =
    std::function<void(const ShownFrame&, const RgbaImage& reference, const FrameScore&)>;

// The one scoring of a shown frame against the reference of its pose, inline
// (lockstep) and deferred (scoreShownFrames) alike: SNR, PSNR, blank and
// completeness (referenceMs is the caller's). blank: 1 when the shown frame is
// uniform (zero variance) while the reference is not one uniform colour.
// Completeness (visible / missing objects) stays -1 when `covered` is empty.
// Errors: sizes that differ (compareFrames), covered.size() != objects.size().
Result<FrameQuality> scoreFrame(const RgbaImage& shown, const RgbaImage& reference,
                                const std::vector<ObjectExtent>& objects,
                                const std::vector<std::uint32_t>& covered,
                                const std::vector<std::uint64_t>& held, std::uint32_t minPixels);

// One FrameScore per kept frame (frame_record.h: the record's quality whole),
// each scored by scoreFrame.
Result<std::vector<FrameScore>> scoreShownFrames(const std::vector<ShownFrame>& frames,
                                                 ReferenceSource& references,
                                                 const std::vector<ObjectExtent>& objects,
                                                 std::uint32_t minPixels,
                                                 const ScoredFrameSink& sink = {});

// |a - b| per RGB channel, alpha 255 (for difference images). Sizes must match
// (kInvalidArgument otherwise).
Result<RgbaImage> differenceImage(const RgbaImage& a, const RgbaImage& b);

}  // namespace thinlod::frontend
