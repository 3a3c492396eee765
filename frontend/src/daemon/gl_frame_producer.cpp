#include "gl_frame_producer.h"

#include <algorithm>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <limits>
#include <utility>

#include "thinlod/frontend/frame_metrics.h"
#include "thinlod/frontend/view_camera.h"

namespace thinlod::frontend::daemon {

Result<std::unique_ptr<GlFrameProducer>> GlFrameProducer::create(
    const GlProducerOptions& options, const render::Lighting& lighting,
    std::vector<ReferenceItem> reference) {
  std::unique_ptr<GlFrameProducer> producer(new GlFrameProducer());
  producer->options_ = options;
  producer->lighting_ = lighting;
  producer->reference_ = std::move(reference);
  // Opaque first in scene order, blended ones after (sorted per frame).
  std::stable_partition(producer->reference_.begin(), producer->reference_.end(),
                        [](const ReferenceItem& item) { return !item.blended; });

  Result<std::unique_ptr<render::OffscreenContext>> context =
      render::createOffscreenContext(options.backend, options.width, options.height);
  if (!context.ok()) return context.status();
  producer->context_ = std::move(context).value();

  FrontendRendererOptions rendererOptions;
  rendererOptions.width = options.width;
  rendererOptions.height = options.height;
  rendererOptions.uploadBytesPerFrame = options.uploadBytesPerFrame;
  Result<std::unique_ptr<FrontendRenderer>> renderer =
      FrontendRenderer::create(*producer->context_, rendererOptions);
  if (!renderer.ok()) return renderer.status();
  producer->renderer_ = std::move(renderer).value();
  // Shader compiles now, before the first frame is timed.
  THINLOD_RETURN_IF_ERROR(producer->renderer_->warmUp(lighting));

  ReferenceRendererOptions referenceOptions;
  referenceOptions.width = options.width;
  referenceOptions.height = options.height;
  referenceOptions.clearColor = rendererOptions.clearColor;
  referenceOptions.linearFilter = rendererOptions.linearFilter;
  Result<std::unique_ptr<ReferenceRenderer>> referenceRenderer =
      ReferenceRenderer::create(*producer->context_, referenceOptions);
  if (!referenceRenderer.ok()) return referenceRenderer.status();
  producer->referenceRenderer_ = std::move(referenceRenderer).value();
  return producer;
}

GlFrameProducer::~GlFrameProducer() {
  // Renderers free GL objects: the context must be current while they go.
  if (context_ != nullptr) (void)context_->makeCurrent();
  referenceRenderer_.reset();
  renderer_.reset();
  context_.reset();
}

Status GlFrameProducer::submit(SceneBatch batch) { return renderer_->submit(std::move(batch)); }

Result<ProducedFrame> GlFrameProducer::renderFrame(std::uint64_t frame, const Pose& pose) {
  Result<render::Camera> camera = cameraFromPose(pose, options_.width, options_.height);
  if (!camera.ok()) {
    return Status(camera.status().code(),
                  "frame " + std::to_string(frame) + ": " + camera.status().message());
  }
  Result<FrameReport> report = renderer_->renderFrame(*camera, lighting_, frame_);
  if (!report.ok()) {
    return Status(report.status().code(),
                  "frame " + std::to_string(frame) + ": " + report.status().message());
  }
  ProducedFrame produced;
  produced.triangles = report->triangles;
  produced.appliedPlan = report->appliedPlan;
  produced.committedBatches = report->committedBatches;
  produced.droppedBatches = report->droppedBatches;
  produced.droppedPlans = report->droppedPlans;
  produced.lastUploadError = report->lastUploadError;
  produced.renderMs = report->timing.totalMs;
  produced.drawCalls = report->drawCalls;
  produced.uploadedBytes = report->uploadedBytes;
  return produced;
}

Result<FrameQuality> GlFrameProducer::measure(std::uint64_t frame, const Pose& pose) {
  Result<render::Camera> camera = cameraFromPose(pose, options_.width, options_.height);
  if (!camera.ok()) return camera.status();
  drawList_.clear();
  for (const ReferenceItem& item : reference_) drawList_.push_back(item.object);
  const auto firstBlended =
      std::find_if(reference_.begin(), reference_.end(), [](const auto& i) { return i.blended; });
  if (firstBlended != reference_.end()) {
    // Back to front by distance of the object's centre from the eye.
    const glm::vec3 eye = glm::vec3(glm::inverse(camera->view)[3]);
    const auto offset = firstBlended - reference_.begin();
    std::vector<std::pair<float, std::size_t>> order;
    for (auto i = static_cast<std::size_t>(offset); i < reference_.size(); ++i) {
      order.emplace_back(glm::distance(eye, reference_[i].worldCentre), i);
    }
    std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a > b; });
    for (std::size_t k = 0; k < order.size(); ++k) {
      drawList_[static_cast<std::size_t>(offset) + k] = reference_[order[k].second].object;
    }
  }
  Result<ReferenceReport> report =
      referenceRenderer_->render(drawList_, *camera, lighting_, referenceFrame_);
  if (!report.ok()) {
    return Status(report.status().code(),
                  "reference frame " + std::to_string(frame) + ": " + report.status().message());
  }
  Result<FrameComparison> comparison = compareFrames(frame_, referenceFrame_);
  if (!comparison.ok()) return comparison.status();
  FrameQuality quality;
  quality.snrDb = comparison->snrDb;
  quality.psnrDb = comparison->psnrDb;
  quality.referenceMs = report->renderMs;
  return quality;
}

std::string GlFrameProducer::describe() const {
  return std::string(render::backendName(context_->backend())) + ", " + context_->rendererName();
}

}  // namespace thinlod::frontend::daemon
