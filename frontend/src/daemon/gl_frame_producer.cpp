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
    std::vector<ReferenceItem> reference, std::vector<ObjectExtent> extents) {
  std::unique_ptr<GlFrameProducer> producer(new GlFrameProducer());
  producer->options_ = options;
  producer->extents_ = std::move(extents);
  producer->kept_ = ShownFrameLog(options.maxKeptBytes);
  producer->lighting_ = lighting;
  producer->reference_ = std::move(reference);
  // Opaque first in scene order, blended ones after (sorted per frame).
  std::stable_partition(producer->reference_.begin(), producer->reference_.end(),
                        [](const ReferenceItem& item) { return !item.blended; });
  if (producer->extents_.size() > kMaxCoverageObjects) {
    return Status(ErrorCode::kInvalidArgument,
                  "completeness: " + std::to_string(producer->extents_.size()) +
                      " objects exceed the coverage colours (" +
                      std::to_string(kMaxCoverageObjects) + ")");
  }
  if (!producer->extents_.empty()) {
    for (const ReferenceItem& item : producer->reference_) {
      if (item.extent >= producer->extents_.size()) {
        return Status(ErrorCode::kInvalidArgument, "reference item names no object extent");
      }
      ReferenceObject flat;
      flat.mesh = item.object.mesh;
      flat.transform = item.object.transform;
      flat.material.diffuse = coverageColor(item.extent);
      flat.material.lit = false;
      flat.material.doubleSided = item.object.material.doubleSided;
      flat.skin = item.object.skin;
      producer->coverageList_.push_back(std::move(flat));
    }
  }

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
  Result<FrameReport> report = renderer_->renderFrame(*camera, lighting_, frame_, pose.time);
  if (!report.ok()) {
    return Status(report.status().code(),
                  "frame " + std::to_string(frame) + ": " + report.status().message());
  }
  ProducedFrame produced;
  produced.triangles = report->triangles;
  produced.points = report->discs;
  produced.appliedPlan = report->appliedPlan;
  produced.earlyPolygons = report->earlyPolygons;
  produced.committedBatches = report->committedBatches;
  produced.droppedBatches = report->droppedBatches;
  produced.droppedPlans = report->droppedPlans;
  produced.lastUploadError = report->lastUploadError;
  produced.renderMs = report->timing.totalMs;
  produced.drawCalls = report->drawCalls;
  produced.uploadedBytes = report->uploadedBytes;
  produced.skinnedObjects = report->skinnedObjects;
  produced.deformedVertices = report->deformedVertices;
  std::vector<protocol::HeldRepresentation> held = heldRepresentations(renderer_->scene());
  if (held != lastHeld_) {
    lastHeld_ = held;
    produced.held = std::move(held);
  }
  return produced;
}

Result<double> GlFrameProducer::renderReference(const Pose& pose,
                                                std::vector<std::uint32_t>& covered) {
  Result<render::Camera> camera = cameraFromPose(pose, options_.width, options_.height);
  if (!camera.ok()) return camera.status();
  // Animated objects at the pose's time (the backbone's clock: pose time).
  referenceBones_.resize(reference_.size());
  for (std::size_t i = 0; i < reference_.size(); ++i) {
    const scene::SkinnedAnimation* animation = reference_[i].animation;
    if (animation == nullptr) continue;
    referenceBones_[i] = anim::paletteMatricesAt(
        animation->skeleton, animation->clip, animation->palette,
        pose.time + double(reference_[i].animationOffset), anim::ClipWrap::kLoop);
    reference_[i].object.bones = &referenceBones_[i];
    if (i < coverageList_.size()) coverageList_[i].bones = &referenceBones_[i];
  }
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
  if (!report.ok()) return report.status();
  covered.clear();
  if (!coverageList_.empty()) {
    // Which objects the reference shows, and how much of each (depth-tested,
    // so occluded objects cover nothing). Not included in the reference's time.
    Result<ReferenceReport> ids =
        referenceRenderer_->render(coverageList_, *camera, lighting_, coverageFrame_);
    if (!ids.ok()) return ids.status();
    Result<std::vector<std::uint32_t>> counts =
        coverageFromIdImage(coverageFrame_, extents_.size());
    if (!counts.ok()) return counts.status();
    covered = std::move(counts).value();
  }
  return report->renderMs;
}

HeldObjects GlFrameProducer::heldNow() {
  const FrontendScene& scene = renderer_->scene();
  // Every commit applies a plan, so (plan, count) changes whenever the held set does.
  if (held_ == nullptr || scene.lastAppliedPlan() != heldPlan_ ||
      scene.objects().size() != heldCount_) {
    auto ids = std::make_shared<std::vector<std::uint64_t>>();
    ids->reserve(scene.objects().size());
    for (const auto& [id, object] : scene.objects()) ids->push_back(id);  // map: ascending
    held_ = std::move(ids);
    heldPlan_ = scene.lastAppliedPlan();
    heldCount_ = scene.objects().size();
  }
  return held_;
}

Result<FrameQuality> GlFrameProducer::measure(std::uint64_t frame, const Pose& pose) {
  Result<double> renderMs = renderReference(pose, covered_);
  if (!renderMs.ok()) {
    return Status(renderMs.status().code(),
                  "reference frame " + std::to_string(frame) + ": " + renderMs.status().message());
  }
  static const std::vector<std::uint64_t> kNothingHeld;
  Result<FrameQuality> quality =
      scoreFrame(frame_, referenceFrame_, extents_, covered_,
                 covered_.empty() ? kNothingHeld : *heldNow(), options_.visibleMinPixels);
  if (!quality.ok()) return quality.status();
  quality->referenceMs = *renderMs;
  return quality;
}

bool GlFrameProducer::keepShown(std::uint64_t frame, const Pose& pose, std::int64_t shownAtNs) {
  return kept_.record(frame, pose, shownAtNs, frame_, heldNow());
}

// The reference renderer as a ReferenceSource for scoreShownFrames.
class GlFrameProducer::References final : public ReferenceSource {
 public:
  explicit References(GlFrameProducer& producer) : producer_(producer) {}
  Result<double> render(const Pose& pose, RgbaImage& out,
                        std::vector<std::uint32_t>& covered) override {
    Result<double> ms = producer_.renderReference(pose, covered);
    if (ms.ok()) out = producer_.referenceFrame_;
    return ms;
  }

 private:
  GlFrameProducer& producer_;
};

Result<std::vector<FrameScore>> GlFrameProducer::scoreKept() {
  References references(*this);
  const ScoredFrameSink sink = [this](const ShownFrame& shown, const RgbaImage&,
                                      const FrameScore&) {
    if (!scoredSink_) return;
    frame_ = shown.image;  // referenceFrame_ already holds its reference
    scoredSink_(shown.frame);
  };
  Result<std::vector<FrameScore>> scores =
      scoreShownFrames(kept_.frames(), references, extents_, options_.visibleMinPixels, sink);
  keptPeakBytes_ = kept_.bytes();
  kept_ = ShownFrameLog(0);  // the images are no longer needed
  return scores;
}

std::string GlFrameProducer::describe() const {
  return std::string(render::backendName(context_->backend())) + ", " + context_->rendererName();
}

}  // namespace thinlod::frontend::daemon
