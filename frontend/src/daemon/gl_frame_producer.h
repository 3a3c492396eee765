// FrameProducer on an offscreen GL context: the FrontendRenderer draws what
// the backbone sent, the ReferenceRenderer draws the full-quality scene for
// the same camera (cameraFromPose) and lights, compareFrames gives SNR/PSNR.
// Owns the context; every call must come from the thread that created it.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "replay_loop.h"
#include "scene_setup.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/frontend/frontend_renderer.h"
#include "thinlod/frontend/reference_renderer.h"

namespace thinlod::frontend::daemon {

struct GlProducerOptions {
  int width = 640;
  int height = 480;
  render::Backend backend = render::Backend::kAuto;
  std::size_t uploadBytesPerFrame = FrontendRendererOptions{}.uploadBytesPerFrame;
};

class GlFrameProducer final : public FrameProducer {
 public:
  // `reference` may be empty (then measure() compares with a black frame).
  static Result<std::unique_ptr<GlFrameProducer>> create(const GlProducerOptions& options,
                                                         const render::Lighting& lighting,
                                                         std::vector<ReferenceItem> reference);
  ~GlFrameProducer() override;

  Status submit(SceneBatch batch) override;
  Result<ProducedFrame> renderFrame(std::uint64_t frame, const Pose& pose) override;
  Result<FrameQuality> measure(std::uint64_t frame, const Pose& pose) override;

  const RgbaImage& frame() const { return frame_; }
  const RgbaImage& referenceFrame() const { return referenceFrame_; }
  // "egl, llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string describe() const;

 private:
  GlFrameProducer() = default;

  GlProducerOptions options_;
  render::Lighting lighting_;
  std::vector<ReferenceItem> reference_;
  std::vector<ReferenceObject> drawList_;  // reused each measure()
  std::unique_ptr<render::OffscreenContext> context_;
  std::unique_ptr<FrontendRenderer> renderer_;
  std::unique_ptr<ReferenceRenderer> referenceRenderer_;
  RgbaImage frame_;
  RgbaImage referenceFrame_;
};

}  // namespace thinlod::frontend::daemon
