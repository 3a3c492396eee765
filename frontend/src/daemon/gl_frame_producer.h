// FrameProducer on an offscreen GL context: the FrontendRenderer draws what
// the backbone sent, the ReferenceRenderer draws the full-quality scene for
// the same camera (cameraFromPose) and lights, compareFrames gives SNR/PSNR.
// With deferred measurement (keepShown/scoreKept) the frames shown are kept in
// a ShownFrameLog and scored after the replay on the same context, so the
// reference never runs while the client is replaying.
// Owns the context; every call must come from the thread that created it.
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "replay_loop.h"
#include "scene_setup.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/frontend/frontend_renderer.h"
#include "thinlod/frontend/reference_renderer.h"
#include "thinlod/frontend/shown_frames.h"

namespace thinlod::frontend::daemon {

// The defaults of the daemon's options (daemon_options.h binds them here).
struct GlProducerOptions {
  int width = 640;
  int height = 480;
  render::Backend backend = render::Backend::kAuto;
  std::size_t uploadBytesPerFrame = FrontendRendererOptions{}.uploadBytesPerFrame;
  std::size_t maxKeptBytes = std::size_t{4} << 30;  // deferred measurement: pixels kept
  // Completeness: an object group covering fewer pixels is not visible.
  std::uint32_t visibleMinPixels = 16;
};

class GlFrameProducer final : public FrameProducer {
 public:
  // `reference` may be empty (then measure() compares with a black frame).
  static Result<std::unique_ptr<GlFrameProducer>> create(const GlProducerOptions& options,
                                                         const render::Lighting& lighting,
                                                         std::vector<ReferenceItem> reference,
                                                         std::vector<ObjectExtent> extents = {});
  ~GlFrameProducer() override;

  Status submit(SceneBatch batch) override;
  Result<ProducedFrame> renderFrame(std::uint64_t frame, const Pose& pose) override;
  Result<FrameQuality> measure(std::uint64_t frame, const Pose& pose) override;
  bool keepShown(std::uint64_t frame, const Pose& pose, std::int64_t shownAtNs) override;
  Result<std::vector<FrameScore>> scoreKept() override;
  // Called for every frame scoreKept() scores (after which frame() is that
  // shown frame and referenceFrame() its reference).
  void setScoredSink(std::function<void(std::uint64_t frame)> sink) {
    scoredSink_ = std::move(sink);
  }
  std::size_t keptBytes() const { return std::max(kept_.bytes(), keptPeakBytes_); }

  const RgbaImage& frame() const { return frame_; }
  // What the frontend holds (and drew in the last renderFrame).
  const FrontendScene& scene() const { return renderer_->scene(); }
  const RgbaImage& referenceFrame() const { return referenceFrame_; }
  // "egl, llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string describe() const;

 private:
  GlFrameProducer() : kept_(0) {}
  class References;
  // The full-quality frame of `pose` into referenceFrame_ and, with extents,
  // the pixels each object covers in it (a flat-colour id pass) into `covered`.
  Result<double> renderReference(const Pose& pose, std::vector<std::uint32_t>& covered);
  HeldObjects heldNow();

  GlProducerOptions options_;
  render::Lighting lighting_;
  std::vector<ReferenceItem> reference_;
  std::vector<ReferenceObject> drawList_;  // reused each measure()
  std::vector<ObjectExtent> extents_;
  std::vector<ReferenceObject> coverageList_;           // the reference in coverage colours, unlit
  std::vector<std::vector<glm::mat4>> referenceBones_;  // per reference item: this frame's pose
  RgbaImage coverageFrame_;
  std::vector<std::uint32_t> covered_;
  ShownFrameLog kept_;
  HeldObjects held_;
  std::vector<protocol::HeldRepresentation> lastHeld_;  // as last reported (ProducedFrame::held)
  std::uint64_t heldPlan_ = 0;
  std::size_t heldCount_ = 0;
  std::size_t keptPeakBytes_ = 0;
  std::function<void(std::uint64_t)> scoredSink_;
  std::unique_ptr<render::OffscreenContext> context_;
  std::unique_ptr<FrontendRenderer> renderer_;
  std::unique_ptr<ReferenceRenderer> referenceRenderer_;
  RgbaImage frame_;
  RgbaImage referenceFrame_;
};

}  // namespace thinlod::frontend::daemon
