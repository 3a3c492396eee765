#include "backbone_core.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <limits>
#include <utility>

#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/mesh/primitives.h"

namespace thinlod::backbone_daemon {
namespace {

// How far one pose may move the backbone's clock, and how many poses in a
// row beyond that make a jump real (see beginPose).
constexpr std::int64_t kMaxPoseTimeStepNs = 60'000'000'000LL;
constexpr int kPosesBeforeJump = 10;

using backbone::OptionKind;

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kMaxCurveSegments = 16;

// `curve` with every accuracy a replaced by anim::animatedRelativeAccuracy(a,
// ratio), fitted conservatively through its knots: the staircase of the
// mapped knots never credits more than the curve did between them.
Result<AccuracyCurve> animatedCurve(const AccuracyCurve& curve, double ratio) {
  std::vector<AccuracySample> knots;
  for (const CurveSegment& segment : curve.segments())
    knots.push_back({anim::animatedRelativeAccuracy(segment.start, ratio), segment.value});
  knots.push_back({anim::animatedRelativeAccuracy(curve.maxAccuracy(), ratio),
                   curve.resourcesFor(curve.maxAccuracy())});
  return AccuracyCurve::fitConservative(std::move(knots), kMaxCurveSegments);
}
// Bytes per triangle are only learned from meshes at least this large (the
// frame overhead dominates smaller ones).
constexpr double kMinTrianglesToLearnBytes = 64.0;

Status invalid(const std::string& message) { return Status(ErrorCode::kInvalidArgument, message); }

// A region object's mesh levels keep its borders (SimplifyRequest::keepBoundary):
// independent per-region levels then meet without cracks (docs/regions.md).
bool keepsBoundary(const ObjectRecord& record, protocol::RepresentationKind kind) {
  return kind == protocol::RepresentationKind::kMesh && !record.cluster &&
         record.object != nullptr && record.object->regionCount > 0;
}

bool isMeshKind(OptionKind kind) {
  return kind == OptionKind::kOriginalMesh || kind == OptionKind::kSimplifiedMesh ||
         kind == OptionKind::kHybrid;
}

protocol::ConicRange everywhereOnWire() {
  protocol::ConicRange range;
  range.distanceMin = 0.0f;
  range.distanceMax = std::numeric_limits<float>::infinity();
  range.direction = glm::vec3(0.0f, 0.0f, 1.0f);
  range.halfAngle = 3.14159265f;
  return range;
}

double payloadBytes(const protocol::Representation& rep) {
  return static_cast<double>(rep.mesh.size() + rep.texture.data.size()) + kOperationOverheadBytes;
}

std::string idText(std::uint64_t id) { return std::to_string(id); }

backbone::SchedulerOptions schedulerOptions(const CoreOptions& o) {
  backbone::SchedulerOptions options;
  options.config = o.config;
  options.timeCritical = o.timeCritical;
  return options;
}

}  // namespace

Status validateCoreOptions(const CoreOptions& o) {
  if (!(o.hybridKappa == 0.0 || (o.hybridKappa > 1.0 && o.hybridKappa <= protocol::kMaxKappa)))
    return invalid("hybrid kappa " + std::to_string(o.hybridKappa) + ": 0 (off) or in (1, " +
                   std::to_string(protocol::kMaxKappa) + "]");
  THINLOD_RETURN_IF_ERROR(backbone::validateConfig(o.config));
  THINLOD_RETURN_IF_ERROR(backbone::validateBudget(o.budget));
  Result<std::unique_ptr<backbone::Scheduler>> scheduler =
      backbone::makeScheduler(o.scheduler, schedulerOptions(o));
  if (!scheduler.ok()) return invalid(scheduler.status().message());
  THINLOD_RETURN_IF_ERROR((*scheduler)->accepts(o.budget));
  if (o.defaultFrameCost) {
    const Status usable = validateCalibratedFrameCost(*o.defaultFrameCost);
    if (!usable.ok()) return invalid("default frame cost: " + usable.message());
  }
  if (o.textureSize < 8 || o.textureSize > 4096)
    return invalid("texture size " + std::to_string(o.textureSize) + ": expected 8..4096");
  if (o.textureCodec == protocol::TextureCodec::kNone)
    return invalid("impostor texture codec must not be none");
  for (double radii : {o.simpleImpostorRadii, o.meshedImpostorRadii}) {
    if (!std::isfinite(radii) || radii < 0.0)
      return invalid("impostor radii must be finite and >= 0 (0 disables the kind)");
    if (radii > 0.0 && radii < 1.1)
      return invalid("impostors need the viewer outside the object: radii >= 1.1");
  }
  if (!std::isfinite(o.meshedImpostorTriangles) || o.meshedImpostorTriangles < 1.0)
    return invalid("meshed impostor triangles must be >= 1");
  if (o.curvePoints < 2 || o.curvePoints > protocol::kMaxCurveSamples)
    return invalid("curve points must be in 2.." + std::to_string(protocol::kMaxCurveSamples));
  if (o.curveRequestTriangles < 1 || o.curveRequestTriangles > protocol::kMaxTriangleCount)
    return invalid("curve request triangles out of range");
  if (!std::isfinite(o.linkBurstBytes) || o.linkBurstBytes < 0.0 || o.linkBurstBytes > 4.0e9)
    return invalid("link burst must be in [0, 4e9] bytes (0: automatic)");
  if (!o.linkSchedule.empty() && !o.budget.maxLinkBytesPerSecond)
    return invalid("a link schedule needs a link budget (--budget-link) for the time before its "
                   "first step");
  for (std::size_t i = 0; i < o.linkSchedule.size(); ++i) {
    const LinkStep& step = o.linkSchedule[i];
    if (!std::isfinite(step.timeSeconds) || step.timeSeconds < 0.0 ||
        (i > 0 && step.timeSeconds <= o.linkSchedule[i - 1].timeSeconds) ||
        !std::isfinite(step.bytesPerSecond) || step.bytesPerSecond < 1.0 ||
        step.bytesPerSecond > 1e11)
      return invalid("link schedule step " + std::to_string(i + 1) +
                     ": times >= 0 and increasing, rates in [1, 1e11] bytes/s");
  }
  if (!std::isfinite(o.defaultAspect) || o.defaultAspect <= 0.0)
    return invalid("default aspect must be > 0");
  if (o.firstRequestId == 0 || o.firstRequestId >= (std::uint64_t(1) << 62))
    return invalid("first request id must be in [1, 2^62)");
  return Status();
}

BackboneCore::BackboneCore(scene::Scene scene, std::string scenePath, CoreOptions options)
    : sceneGraph_(std::move(scene)),
      scenePath_(std::move(scenePath)),
      options_(std::move(options)),
      lastShaperNs_(std::numeric_limits<std::int64_t>::min()) {}

BackboneCore::~BackboneCore() = default;

Result<std::unique_ptr<BackboneCore>> BackboneCore::create(scene::Scene scene,
                                                           std::string scenePath,
                                                           CoreOptions options) {
  THINLOD_RETURN_IF_ERROR(validateCoreOptions(options));
  std::unique_ptr<BackboneCore> core(
      new BackboneCore(std::move(scene), std::move(scenePath), std::move(options)));
  THINLOD_RETURN_IF_ERROR(core->initialize());
  return core;
}

const char* BackboneCore::schedulerName() const { return scheduler_->name(); }

Status BackboneCore::admitFrontend(const protocol::Hello& hello) const {
  if (hello.role != protocol::Role::kFrontend) return Status();
  THINLOD_RETURN_IF_ERROR(protocol::checkSameScene("backbone", sceneGraph_.fingerprint, scenePath_,
                                                   "frontend", hello.sceneFingerprint,
                                                   hello.sceneFile));
  THINLOD_RETURN_IF_ERROR(checkHeld(hello.held));
  return frameCostFor(hello).status();
}

Status BackboneCore::checkHeld(const std::vector<protocol::HeldRepresentation>& held) const {
  if (held.size() > protocol::kMaxHeldRepresentations)
    return invalid("Hello.held lists " + std::to_string(held.size()) + " representations, limit " +
                   std::to_string(protocol::kMaxHeldRepresentations));
  for (const protocol::HeldRepresentation& h : held)
    if (objectById_.count(h.objectId) == 0)
      return invalid("Hello.held names object " + idText(h.objectId) +
                     ", which the backbone's scene does not have");
  return Status();
}

const char* frameCostSourceName(FrameCostSource source) {
  switch (source) {
    case FrameCostSource::kUnused:
      return "unused";
    case FrameCostSource::kFrontend:
      return "frontend";
    case FrameCostSource::kBackboneDefault:
      return "backbone-default";
  }
  return "invalid";
}

Result<SessionFrameCost> BackboneCore::frameCostFor(const protocol::Hello& hello) const {
  SessionFrameCost session;
  if (!options_.budget.maxFrameSeconds) return session;
  if (hello.frameCost) {
    // The decoder checked them already; the core does not rely on its caller.
    const Status usable = validateCalibratedFrameCost(*hello.frameCost);
    if (!usable.ok()) return invalid("the frontend's frame cost: " + usable.message());
    session.source = FrameCostSource::kFrontend;
    session.constants = *hello.frameCost;
    return session;
  }
  if (options_.defaultFrameCost) {
    session.source = FrameCostSource::kBackboneDefault;
    session.constants = *options_.defaultFrameCost;
    return session;
  }
  return invalid(
      "the backbone plans a frame-time budget (--budget-frame-ms) and has no default frame cost "
      "(--frame-cost): the frontend must send its calibrated constants (thinlod-frontend "
      "--frame-cost FILE, written by bench_calibrate)");
}

Status BackboneCore::startFrontendSession(const protocol::Hello& hello) {
  resetFrontend();
  Result<SessionFrameCost> session = frameCostFor(hello);
  if (!session.ok()) return session.status();
  if (session->source != FrameCostSource::kUnused) {
    CoreOptions withCosts = options_;
    withCosts.timeCritical.costs = session->constants;
    Result<std::unique_ptr<backbone::Scheduler>> scheduler =
        backbone::makeScheduler(options_.scheduler, schedulerOptions(withCosts));
    if (!scheduler.ok()) return scheduler.status();
    scheduler_ = std::move(scheduler).value();
  }
  sessionFrameCost_ = *session;
  THINLOD_RETURN_IF_ERROR(checkHeld(hello.held));
  heldForeign_ = 0;
  heldTakenBack_ = 0;
  for (const protocol::HeldRepresentation& h : hello.held) {
    const std::uint32_t object = objectById_.at(h.objectId);
    const backbone::SceneObject& o = scene_.objects[object];
    if (o.optionCount == 0) continue;
    // The option of the held kind (its first option if this backbone has
    // none of that kind: the units count all the same).
    std::uint32_t option = o.firstOption;
    for (std::uint32_t k = o.firstOption; k < o.firstOption + o.optionCount; ++k) {
      if (optionStates_[k].wireKind == h.kind) {
        option = k;
        break;
      }
    }
    backbone::RepresentationCopy copy;
    copy.present = true;
    copy.id = h.representationId;
    // Credited with nothing: the scheduler never keeps it for accuracy
    // (valid nowhere; the smallest positive accuracy, as copies need > 0).
    copy.relativeAccuracy = std::numeric_limits<double>::min();
    copy.triangles = double(h.triangleCount);
    if (h.kind == protocol::RepresentationKind::kHybrid && options_.hybridKappa > 0.0)
      copy.triangles += double(h.pointCount) / options_.hybridKappa;
    copy.encodedBytes = 0.0;
    copy.validity = ConicRange::nowhere();
    if (mirror_.adopt(object, option, copy)) {
      ++heldTakenBack_;
    } else {
      // Its id may be another process's: a foreign copy goes by none.
      scene_.options[option].atFrontend.id = 0;
      ++heldForeign_;
    }
  }
  return Status();
}

Status BackboneCore::initialize() {
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(sceneGraph_);
  if (!objects.ok()) return objects.status();
  sceneObjects_ = std::move(objects).value();
  Result<ConvertedScene> converted = convertScene(sceneGraph_, sceneObjects_);
  if (!converted.ok()) return converted.status();
  converted_ = std::move(converted).value();
  scene_ = std::move(converted_.scheduling);
  converted_.scheduling = backbone::SchedulingScene();
  for (std::uint32_t k = 0; k < converted_.records.size(); ++k)
    objectById_[converted_.records[k].id] = k;

  // Until a frontend session says otherwise: the default frame cost.
  CoreOptions initial = options_;
  if (options_.defaultFrameCost) initial.timeCritical.costs = *options_.defaultFrameCost;
  Result<std::unique_ptr<backbone::Scheduler>> scheduler =
      backbone::makeScheduler(options_.scheduler, schedulerOptions(initial));
  if (!scheduler.ok()) return scheduler.status();
  scheduler_ = std::move(scheduler).value();
  if (options_.budget.maxFrameSeconds && options_.defaultFrameCost)
    sessionFrameCost_ = {FrameCostSource::kBackboneDefault, *options_.defaultFrameCost};

  const std::size_t count = converted_.records.size();
  meshBytesPerTriangle_.assign(count, kDefaultMeshBytesPerTriangle);
  meshBytesLearned_.assign(count, false);
  const double texels = double(options_.textureSize) * double(options_.textureSize);
  // Prior texel count across the quad (see docs/backbone.md): the quad spans
  // about the object's world box diagonal, detail below two texels is lost
  // and the rendered level adds at most half a texel.
  const double texelsPerDiagonal = double(options_.textureSize) / 3.5;

  animationOf_.assign(count, nullptr);
  animationOffsetOf_.assign(count, 0.0f);
  motionRatio_.assign(count, 0.0);
  for (std::uint32_t k = 0; k < count; ++k) {
    const ObjectRecord& record = converted_.records[k];
    backbone::SceneObject& object = scene_.objects[k];
    object.firstOption = static_cast<std::uint32_t>(scene_.options.size());
    if (!record.cluster && record.object != nullptr && record.object->shape != nullptr) {
      animationOf_[k] = record.object->shape->geometry.animation.get();
      animationOffsetOf_[k] = record.object->shape->geometry.animationOffset;
    }
    if (animationOf_[k] != nullptr) {
      // Its leaf sphere encloses every pose (scene_objects.h); its
      // accuracies, measured against the bind mesh, shrink by the motion.
      const double length = referenceLength(referenceSphere(*record.object->fullMesh));
      motionRatio_[k] = 2.0 * animationOf_[k]->motionBound / length;
    }
    // A skinned object moves: only its meshes, which the frontend deforms
    // with each frame's bone poses, show it. An impostor would freeze one
    // pose, a Hybrid's points are not skinned.
    const bool animated = animationOf_[k] != nullptr;

    // Simplified mesh (unless the scene's imposter nodes leave only impostors:
    // a cluster of several objects, an LOD level of one kind; docs/backbone.md
    // "Imposter nodes").
    if (record.mesh.offered) {
      OptionState state;
      state.object = k;
      state.wireKind = protocol::RepresentationKind::kMesh;
      backbone::RepresentationOption option;
      option.kind = OptionKind::kSimplifiedMesh;
      if (record.primitive) {
        Result<AccuracyCurve> curve =
            primitiveAccuracyCurve(record.object->shape->geometry.primitive);
        if (!curve.ok())
          return Status(curve.status().code(),
                        "object " + idText(record.id) + ": " + curve.status().message());
        state.baseTriangles = curve->scaledAccuracy(1.0 / (1.0 + kQuantizationShare));
        state.measuredCurve = true;
      } else {
        // Until the simplifier's curve arrives: the pessimistic estimate.
        Result<AccuracyCurve> estimate =
            estimatedMeshCurve(std::max(1.0, record.fullTriangles), options_.curveEstimate);
        if (!estimate.ok())
          return Status(estimate.status().code(),
                        "object " + idText(record.id) + ": " + estimate.status().message());
        state.baseTriangles = std::move(estimate).value();
        if (motionRatio_[k] > 0.0) {
          Result<AccuracyCurve> moving = animatedCurve(state.baseTriangles, motionRatio_[k]);
          if (!moving.ok()) return moving.status();
          state.baseTriangles = std::move(moving).value();
        }
        state.estimatedCurve = true;
        queueStartupRequest(k, static_cast<std::uint32_t>(scene_.options.size()), false);
      }
      if (record.mesh.range) option.validity = *record.mesh.range;
      scene_.options.push_back(std::move(option));
      optionStates_.push_back(std::move(state));
      rebuildCurves(static_cast<std::uint32_t>(scene_.options.size() - 1));
    }

    // Hybrid (behind CoreOptions::hybridKappa): like the simplified mesh, in
    // primitive units, exact full mesh until its own curve arrives. Not for
    // a textured object: hybrids carry no uvs (docs/hybrid.md) and their
    // curve credits geometry only, so a hybrid would drop the texture while
    // claiming the accuracy of a textured copy.
    const bool textured = record.object != nullptr && scene::isTextured(*record.object);
    if (options_.hybridKappa > 0.0 && !record.primitive && record.mesh.offered && !animated &&
        !textured) {
      OptionState state;
      state.object = k;
      state.wireKind = protocol::RepresentationKind::kHybrid;
      state.baseTriangles = AccuracyCurve::point(kExactRelativeAccuracy, record.fullTriangles);
      backbone::RepresentationOption option;
      option.kind = OptionKind::kHybrid;
      scene_.options.push_back(std::move(option));
      optionStates_.push_back(std::move(state));
      const auto index = static_cast<std::uint32_t>(scene_.options.size() - 1);
      rebuildCurves(index);
      queueStartupRequest(k, index, false);
    }

    // Impostors: usable from `radii` bounding radii on, every direction; a
    // kind the scene names in an LOD level with a range: in that range; one
    // an imposter node names: even when `radii` switches the default off
    // (then everywhere: its copies' own validity cones still bound them).
    auto addImpostor = [&](OptionKind kind, protocol::RepresentationKind wireKind, double radii,
                           double triangles, const KindOffer& offer) -> Status {
      if (!offer.offered || animated) return Status();
      if (!(radii > 0.0) && !offer.explicitNode) return Status();
      Result<ConicRange> validity = ConicRange();
      if (offer.range) {
        validity = *offer.range;
      } else if (radii > 0.0) {
        validity = ConicRange::make(record.bounds.center, radii * record.bounds.radius, kInf,
                                    {0.0, 0.0, 1.0}, kPi);
      }
      if (!validity.ok()) return validity.status();
      OptionState state;
      state.object = k;
      state.wireKind = wireKind;
      // a = L / (3.5 texels), a texel = worldBoxDiagonal / texelsPerDiagonal.
      state.textureAccuracy = record.worldBoxDiagonal > 0.0
                                  ? texelsPerDiagonal * (record.diameter / record.worldBoxDiagonal)
                                  : texelsPerDiagonal;
      state.estimatedTriangles = triangles;
      state.estimatedBytes = kDefaultTextureBytesPerTexel * texels + kMeshFrameOverheadBytes +
                             3.0 * triangles + kOperationOverheadBytes;
      backbone::RepresentationOption option;
      option.kind = kind;
      option.validity = *validity;
      scene_.options.push_back(std::move(option));
      optionStates_.push_back(std::move(state));
      rebuildCurves(static_cast<std::uint32_t>(scene_.options.size() - 1));
      return Status();
    };
    THINLOD_RETURN_IF_ERROR(
        addImpostor(OptionKind::kMeshedImpostor, protocol::RepresentationKind::kMeshedImpostor,
                    options_.meshedImpostorRadii, options_.meshedImpostorTriangles,
                    record.meshedImpostor));
    THINLOD_RETURN_IF_ERROR(addImpostor(OptionKind::kSimpleImpostor,
                                        protocol::RepresentationKind::kSimpleImpostor,
                                        options_.simpleImpostorRadii, 2.0, record.simpleImpostor));
    object.optionCount = static_cast<std::uint32_t>(scene_.options.size()) - object.firstOption;
    if (object.optionCount == 0)
      return invalid("object " + idText(record.id) +
                     ": the scene and the options leave it no representation kind");
  }
  // ImpostorRequests carry no scene path: the simplifier renders from the
  // scene it loaded last. Without a mesh curve request, make it load ours.
  if (ledger_.openCount() == 0 && !scene_.objects.empty()) {
    // The warm-up names a scene object (a cluster's id is the backbone's).
    for (std::uint32_t k = 0; k < count; ++k) {
      if (converted_.records[k].cluster) continue;
      queueStartupRequest(k, 0, true);
      break;
    }
  }
  backbone::updateSubtreeVersions(scene_);
  dirty_ = false;
  return backbone::validateScene(scene_);
}

void BackboneCore::queueStartupRequest(std::uint32_t object, std::uint32_t option, bool warmup) {
  if (!options_.startupRequests) return;
  const ObjectRecord& record = converted_.records[object];
  LedgerRequest request;
  request.id = planner_.allocateRequestId();
  request.purpose = warmup ? RequestPurpose::kWarmup : RequestPurpose::kCurve;
  request.object = object;
  request.option = option;
  request.targetTriangles = static_cast<std::uint32_t>(std::clamp<double>(
      record.fullTriangles, 1.0, warmup ? 12.0 : double(options_.curveRequestTriangles)));
  protocol::SimplifyRequest message;
  message.requestId = request.id;
  message.objectId = record.id;
  message.sourcePath = scenePath_;
  message.sceneFingerprint = sceneGraph_.fingerprint;
  message.target = protocol::SimplifyRequest::Target::kTriangles;
  message.targetTriangles = request.targetTriangles;
  message.curvePoints = warmup ? 0 : options_.curvePoints;
  // (The mesh option queues its request before its state exists: index == size.)
  if (!warmup && option < optionStates_.size() &&
      optionStates_[option].wireKind == protocol::RepresentationKind::kHybrid) {
    message.representation = protocol::RepresentationKind::kHybrid;
    message.kappa = options_.hybridKappa;
  }
  message.keepBoundary = keepsBoundary(record, message.representation);
  // Fresh ids from the planner's counter are never known to the ledger.
  if (!ledger_.ask(request).ok()) return;
  if (!warmup) {
    ++curvesWanted_;
    curveRequestOfOption_[option] = request.id;
  }
  if (!warmup && options_.deferCurveRequests) {
    heldCurves_.push_back({record.fullTriangles, OutgoingRequest{request.id, std::move(message)}});
  } else {
    queued_.push_back({request.id, std::move(message)});
  }
}

void BackboneCore::rebuildCurves(std::uint32_t index) {
  OptionState& state = optionStates_[index];
  backbone::RepresentationOption& option = scene_.options[index];
  if (isMeshKind(option.kind)) {
    option.relativeTriangles = state.calibration == 1.0
                                   ? state.baseTriangles
                                   : state.baseTriangles.scaledAccuracy(state.calibration);
    option.relativeLinkBytes =
        option.relativeTriangles.affineResources(kOperationOverheadBytes + kMeshFrameOverheadBytes,
                        meshBytesPerTriangle_[state.object]);
  } else {
    const double accuracy = state.textureAccuracy * state.parallaxFactor;
    option.relativeTriangles = AccuracyCurve::point(accuracy, state.estimatedTriangles);
    option.relativeLinkBytes = AccuracyCurve::point(accuracy, state.estimatedBytes);
  }
  touchObject(state.object);
}

void BackboneCore::touchObject(std::uint32_t object) {
  ++scene_.nodes[converted_.records[object].leafNode].contentVersion;
  dirty_ = true;
}

Status BackboneCore::setGenerationDelay(double seconds) {
  backbone::SchedulerConfig config = options_.config;
  config.generationDelay = seconds;
  THINLOD_RETURN_IF_ERROR(scheduler_->setConfig(config));
  options_.config = config;
  return Status();
}

double BackboneCore::timeoutSeconds() const {
  const backbone::SchedulerConfig& c = options_.config;
  return c.linkDelay + c.generationDelay + c.plannedLifetime;
}

// ---------------------------------------------------------------- requests

std::vector<OutgoingRequest> BackboneCore::takeRequests() {
  std::vector<OutgoingRequest> out;
  out.swap(queued_);
  // A held curve request goes when the viewer's requests are all answered
  // (none queued here, none open in the ledger) and the last released curve
  // is in: at most one measurement at a time, smallest mesh first.
  if (posesPlanned_ > 0 && out.empty() && ledger_.openCount(RequestPurpose::kPlan) == 0 &&
      releaseHeldCurve()) {
    out.swap(queued_);
  }
  return out;
}

bool BackboneCore::curveRequestOpen() const {
  return releasedCurve_ != 0 && ledger_.open(releasedCurve_) != nullptr;
}

bool BackboneCore::releaseHeldCurve() {
  if (heldCurves_.empty() || posesPlanned_ == 0 || curveRequestOpen()) return false;
  auto smallest = std::min_element(heldCurves_.begin(), heldCurves_.end(),
                                   [](const auto& a, const auto& b) { return a.first < b.first; });
  releasedCurve_ = smallest->second.requestId;
  queued_.push_back(std::move(smallest->second));
  heldCurves_.erase(smallest);
  return true;
}

std::vector<std::uint64_t> BackboneCore::takeCancellations() {
  std::vector<std::uint64_t> out;
  out.swap(cancellations_);
  return out;
}

void BackboneCore::requestSubmitted(std::uint64_t requestId) { ledger_.submitted(requestId); }

void BackboneCore::requestNotSubmitted(std::uint64_t requestId) {
  const LedgerRequest* request = ledger_.open(requestId);
  if (request == nullptr) return;
  const LedgerRequest copy = *request;
  ledger_.close(requestId, RequestState::kFailed);
  withdraw(copy);
}

void BackboneCore::withdraw(const LedgerRequest& request) {
  if (request.state == RequestState::kInFlight) cancellations_.push_back(request.id);
  queued_.erase(std::remove_if(queued_.begin(), queued_.end(),
                               [&](const OutgoingRequest& r) { return r.requestId == request.id; }),
                queued_.end());
  heldCurves_.erase(
      std::remove_if(heldCurves_.begin(), heldCurves_.end(),
                     [&](const auto& held) { return held.second.requestId == request.id; }),
      heldCurves_.end());
  planner_.releaseLinkReservation(request.id);
}

namespace {

bool curveMeasuredKind(protocol::RepresentationKind kind) {
  return kind == protocol::RepresentationKind::kMesh ||
         kind == protocol::RepresentationKind::kHybrid;
}

}  // namespace

Status BackboneCore::checkSameLayout(const BackboneCore& other) const {
  if (other.sceneGraph_.fingerprint != sceneGraph_.fingerprint ||
      other.scenePath_ != scenePath_ || other.optionStates_.size() != optionStates_.size() ||
      other.scene_.options.size() != scene_.options.size())
    return invalid("the other core holds another scene or option layout");
  for (std::size_t i = 0; i < optionStates_.size(); ++i) {
    if (other.optionStates_[i].object != optionStates_[i].object ||
        other.optionStates_[i].wireKind != optionStates_[i].wireKind)
      return invalid("the other core's option " + std::to_string(i) + " differs");
  }
  return Status();
}

Result<std::size_t> BackboneCore::adoptMeasuredCurves(const BackboneCore& other) {
  THINLOD_RETURN_IF_ERROR(checkSameLayout(other));
  std::size_t adopted = 0;
  for (std::uint32_t i = 0; i < optionStates_.size(); ++i) {
    OptionState& mine = optionStates_[i];
    const OptionState& theirs = other.optionStates_[i];
    if (!curveMeasuredKind(mine.wireKind)) continue;
    if (mine.measuredCurve && theirs.measuredCurve && theirs.calibration < mine.calibration) {
      // What the simplifier really delivered, learned by the other session
      // (the same curve: analytic, or measured for the same mesh).
      mine.calibration = theirs.calibration;
      rebuildCurves(i);
      continue;
    }
    if (mine.measuredCurve || !theirs.measuredCurve) continue;
    mine.baseTriangles = theirs.baseTriangles;
    mine.calibration = theirs.calibration;
    mine.measuredCurve = true;
    mine.estimatedCurve = false;
    if (other.meshBytesLearned_[mine.object]) {
      meshBytesPerTriangle_[mine.object] =
          meshBytesLearned_[mine.object]
              ? std::max(meshBytesPerTriangle_[mine.object],
                         other.meshBytesPerTriangle_[mine.object])
              : other.meshBytesPerTriangle_[mine.object];
      meshBytesLearned_[mine.object] = true;
    }
    rebuildCurves(i);
    ++adopted;
    const auto asked = curveRequestOfOption_.find(i);
    if (asked == curveRequestOfOption_.end()) continue;
    if (const LedgerRequest* open = ledger_.open(asked->second)) {
      const LedgerRequest request = *open;
      ledger_.close(request.id, RequestState::kRetried);
      withdraw(request);
    }
  }
  return adopted;
}

Result<std::size_t> BackboneCore::adoptGeneratedCopies(const BackboneCore& other) {
  THINLOD_RETURN_IF_ERROR(checkSameLayout(other));
  std::size_t adopted = 0;
  for (std::uint32_t i = 0; i < optionStates_.size(); ++i) {
    if (scene_.options[i].atBackbone.present) continue;
    // The other core's stock copy, else the one its frontend holds (then a
    // restarted frontend's Hello finds its copies here under their ids).
    // Any kind: a copy's validity range and credited accuracy are world
    // properties (an impostor's cone is where its accuracy holds), and this
    // core's scheduler checks them against its own viewer as for its own
    // copies.
    const protocol::Representation* stock = other.mirror_.generatedPayload(i);
    const protocol::Representation* payload = stock ? stock : other.mirror_.frontendPayload(i);
    if (payload == nullptr) continue;
    const backbone::RepresentationOption& theirs = other.scene_.options[i];
    storeBackboneCopy(i, stock ? theirs.atBackbone : theirs.atFrontend, *payload);
    ++adopted;
  }
  return adopted;
}

std::size_t BackboneCore::curvesPending() const {
  return ledger_.openCount(RequestPurpose::kCurve) + ledger_.openCount(RequestPurpose::kWarmup);
}

std::vector<std::uint64_t> BackboneCore::objectsWithEstimatedCurve() const {
  std::vector<std::uint64_t> ids;
  for (const OptionState& state : optionStates_) {
    if (state.wireKind == protocol::RepresentationKind::kMesh && state.estimatedCurve)
      ids.push_back(converted_.records[state.object].id);
  }
  return ids;
}

std::vector<std::uint64_t> BackboneCore::objectsWithoutMeasuredCurve() const {
  std::vector<std::uint64_t> ids;
  for (const OptionState& state : optionStates_) {
    if (state.wireKind == protocol::RepresentationKind::kMesh && !state.measuredCurve)
      ids.push_back(converted_.records[state.object].id);
  }
  return ids;
}

std::size_t BackboneCore::awaitedResults() const {
  return ledger_.openPlanRequestsOfPose(poseCounter_);
}

Status BackboneCore::issueRequest(const backbone::RepresentationRequest& r) {
  if (r.object >= converted_.records.size() || r.option >= scene_.options.size())
    return Status(ErrorCode::kInternal,
                  "plan request " + idText(r.requestId) + " names no object/option of the scene");
  const ObjectRecord& record = converted_.records[r.object];
  const backbone::RepresentationOption& option = scene_.options[r.option];
  const OptionState& state = optionStates_[r.option];

  LedgerRequest request;
  request.id = r.requestId;
  request.purpose = RequestPurpose::kPlan;
  request.object = r.object;
  request.option = r.option;
  request.kind = state.wireKind;
  request.viewRegion = r.viewRegion;
  request.pose = poseCounter_;
  std::variant<protocol::SimplifyRequest, protocol::ImpostorRequest> message;

  if (isMeshKind(option.kind)) {
    const double wanted = std::ceil(r.expectedTriangles * (1.0 - 1e-12));
    request.targetTriangles = static_cast<std::uint32_t>(
        std::clamp(std::isfinite(wanted) ? wanted : 1.0, 1.0, double(protocol::kMaxTriangleCount)));
    request.requestedAccuracy = r.relativeAccuracy;
    protocol::SimplifyRequest simplify;
    simplify.objectId = record.id;
    simplify.sourcePath = scenePath_;
    simplify.sceneFingerprint = sceneGraph_.fingerprint;
    simplify.target = protocol::SimplifyRequest::Target::kTriangles;
    simplify.targetTriangles = request.targetTriangles;
    if (state.wireKind == protocol::RepresentationKind::kHybrid) {
      simplify.representation = protocol::RepresentationKind::kHybrid;
      simplify.kappa = options_.hybridKappa;
    }
    simplify.keepBoundary = keepsBoundary(record, simplify.representation);
    message = std::move(simplify);
  } else {
    request.impostor = true;
    // The angular error the planned accuracy allows at the region's
    // distance: the impostor's validity cone is where its parallax error
    // stays below it. A fixed accuracy caps every target, so nothing more
    // is needed (a looser bound gives a wider cone, a longer life). Under a
    // budget the target may rise later: deliver what the option promises.
    const double distance = backbone::conversionDistance(
        r.viewRegion.center, r.viewRegion.radius, record.bounds, options_.config.minimalDistance);
    double absolute = absoluteAccuracy(r.relativeAccuracy, distance, record.diameter);
    if (options_.budget.fixedAccuracy)
      absolute = std::min(absolute, *options_.budget.fixedAccuracy);
    if (!std::isfinite(absolute) || absolute <= 0.0) absolute = 1.0;
    request.requestedAccuracy = absolute * record.diameter / distance;
    protocol::ImpostorRequest impostor;
    impostor.sceneFingerprint = sceneGraph_.fingerprint;
    impostor.objectIds = record.members;
    impostor.eye = glm::vec3(r.viewRegion.center);
    impostor.orientation = pose_.orientation;
    impostor.fovY = pose_.fovY;
    impostor.textureWidth = options_.textureSize;
    impostor.textureHeight = options_.textureSize;
    impostor.kind = state.wireKind;
    impostor.accuracyBound = std::clamp(1.0 / absolute, 1e-7, 1.0);
    impostor.textureCodec = options_.textureCodec;
    const KindOffer& offer =
        option.kind == OptionKind::kSimpleImpostor ? record.simpleImpostor : record.meshedImpostor;
    impostor.frameCenter = offer.frameCenter;
    impostor.frameWidth = offer.frameSize.x;
    impostor.frameHeight = offer.frameSize.y;
    message = std::move(impostor);
  }
  // The scheduler asks again for an option whose request is open (the same
  // target under its new id, or another one): the new request replaces the
  // old, whose reply would carry an id the scheduler no longer awaits.
  Result<std::optional<LedgerRequest>> asked = ledger_.ask(request);
  if (!asked.ok()) return Status(ErrorCode::kInternal, "plan request: " + asked.status().message());
  if (asked->has_value()) withdraw(**asked);
  std::visit([&](auto& m) { m.requestId = request.id; }, message);
  queued_.push_back({request.id, std::move(message)});
  return Status();
}

Result<LedgerRequest> BackboneCore::claim(std::uint64_t id, const char* what) {
  Result<LedgerRequest> claimed = ledger_.claim(id);
  if (!claimed.ok())
    return Status(claimed.status().code(), std::string(what) + ": " + claimed.status().message());
  return claimed;
}

void BackboneCore::refuse(const LedgerRequest& request, const Status& replyStatus) {
  const bool timedOut =
      replyStatus.code() == ErrorCode::kTimeout || replyStatus.code() == ErrorCode::kUnavailable;
  ledger_.reclassify(request.id, timedOut ? RequestState::kTimedOut : RequestState::kFailed);
  planner_.releaseLinkReservation(request.id);
}

void BackboneCore::learnMeshBytes(std::uint32_t object, double meshBytes, double triangles) {
  if (triangles < kMinTrianglesToLearnBytes) return;
  const double perTriangle = std::max(0.1, (meshBytes - kMeshFrameOverheadBytes) / triangles);
  double& current = meshBytesPerTriangle_[object];
  // The first measurement replaces the default; later ones only raise it
  // (an estimate below the truth would let the link budget overflow).
  if (meshBytesLearned_[object] && !(perTriangle > current * 1.02)) return;
  current = perTriangle;
  meshBytesLearned_[object] = true;
  const backbone::SceneObject& o = scene_.objects[object];
  for (std::uint32_t k = o.firstOption; k < o.firstOption + o.optionCount; ++k)
    if (isMeshKind(scene_.options[k].kind)) rebuildCurves(k);
}

void BackboneCore::storeBackboneCopy(std::uint32_t option, backbone::RepresentationCopy copy,
                                     protocol::Representation payload) {
  mirror_.storeGenerated(option, copy, std::move(payload));
  touchObject(optionStates_[option].object);
}

Status BackboneCore::onSimplifyResult(const protocol::SimplifyResult& result) {
  Result<LedgerRequest> claimed = claim(result.requestId, "SimplifyResult");
  if (!claimed.ok()) return claimed.status();
  const Status used = useSimplifyResult(*claimed, result);
  if (!used.ok()) refuse(*claimed, result.status);
  return used;
}

Status BackboneCore::useSimplifyResult(const LedgerRequest& request,
                                       const protocol::SimplifyResult& result) {
  const ObjectRecord& record = converted_.records[request.object];
  const std::string where =
      "SimplifyResult " + idText(result.requestId) + " (object " + idText(record.id) + ")";
  if (request.impostor) return invalid(where + ": answers an ImpostorRequest");
  if (result.objectId != record.id)
    return invalid(where + ": carries object id " + idText(result.objectId));
  if (!result.status.ok())
    return Status(result.status.code(), where + ": simplifier error: " + result.status.message());
  if (result.mesh.empty()) return invalid(where + ": no mesh");
  const protocol::RepresentationKind wanted = request.purpose == RequestPurpose::kWarmup
                                                  ? protocol::RepresentationKind::kMesh
                                                  : optionStates_[request.option].wireKind;
  if (result.kind != wanted)
    return invalid(where + std::string(": kind ") + protocol::representationKindName(result.kind) +
                   ", requested " + protocol::representationKindName(wanted));
  const bool hybrid = wanted == protocol::RepresentationKind::kHybrid;
  if (hybrid && std::fabs(result.kappa - options_.hybridKappa) > 1e-9 * options_.hybridKappa)
    return invalid(where + ": kappa " + std::to_string(result.kappa) + ", requested " +
                   std::to_string(options_.hybridKappa));
  // Primitive units: triangles, or triangles + points / kappa for a hybrid.
  const double units =
      hybrid ? double(result.triangleCount) + double(result.pointCount) / options_.hybridKappa
             : double(result.triangleCount);
  if (!(units > 0.0) || result.triangleCount > protocol::kMaxTriangleCount)
    return invalid(where + ": triangle count " + std::to_string(result.triangleCount));
  if (!std::isfinite(result.accuracy) || result.accuracy <= 0.0)
    return invalid(where + ": accuracy must be finite and > 0");

  if (request.purpose == RequestPurpose::kWarmup) return Status();  // the scene is loaded
  OptionState& state = optionStates_[request.option];
  // What a level keeps while its object moves: measured by the simplifier
  // under the clip (motionIncluded), else the bind-pose accuracy converted by
  // the motion bound (the same as the bind-pose one when static).
  const double motionRatio = result.motionIncluded ? 0.0 : motionRatio_[request.object];
  if (request.purpose == RequestPurpose::kCurve) {
    if (result.curve.empty()) return invalid(where + ": no curve samples");
    std::vector<AccuracySample> samples;
    samples.reserve(result.curve.size());
    for (std::size_t i = 0; i < result.curve.size(); ++i) {
      const AccuracySample& s = result.curve[i];
      if (!std::isfinite(s.accuracy) || s.accuracy <= 0.0 || !std::isfinite(s.resources) ||
          s.resources < 0.0 || s.resources > double(protocol::kMaxTriangleCount))
        return invalid(where + ": curve[" + std::to_string(i) + "] is not a finite sample");
      samples.push_back({anim::animatedRelativeAccuracy(s.accuracy, motionRatio), s.resources});
    }
    Result<AccuracyCurve> fitted = AccuracyCurve::fitConservative(samples, kMaxCurveSegments);
    if (!fitted.ok()) return invalid(where + ": curve: " + fitted.status().message());
    learnMeshBytes(request.object, double(result.mesh.size()), units);
    // The measured curve replaces the estimate (and any calibration learned
    // against the estimate) in the scheduling scene.
    state.baseTriangles = std::move(fitted).value();
    state.calibration = 1.0;
    state.measuredCurve = true;
    state.estimatedCurve = false;
    rebuildCurves(request.option);
    return Status();
  }

  learnMeshBytes(request.object, double(result.mesh.size()), units);
  const double relative = anim::animatedRelativeAccuracy(result.accuracy, motionRatio);
  if (request.requestedAccuracy > 0.0 && relative < request.requestedAccuracy * 0.99) {
    // Delivered less than the curve promised: shift the curve so the same
    // triangles are credited with what they reached.
    state.calibration = std::max(0.05, state.calibration * relative / request.requestedAccuracy);
    rebuildCurves(request.option);
  }
  protocol::Representation rep;
  rep.representationId = request.id;
  rep.kind = wanted;
  rep.pointCount = hybrid ? result.pointCount : 0;
  rep.mesh = result.mesh;
  rep.transform = record.object->objectToWorld;
  rep.validity = everywhereOnWire();
  rep.accuracy = relative;
  rep.triangleCount = result.triangleCount;
  // Hybrid triangles carry no uvs (docs/hybrid.md): only mesh copies are textured.
  if (!hybrid && request.object < objectTexture_.size())
    rep.textureId = objectTexture_[request.object];
  backbone::RepresentationCopy copy;
  copy.present = true;
  copy.id = request.id;
  copy.relativeAccuracy = relative;
  copy.triangles = units;
  copy.encodedBytes = payloadBytes(rep);
  storeBackboneCopy(request.option, copy, std::move(rep));
  return Status();
}

Status BackboneCore::onImpostorResult(const protocol::ImpostorResult& result) {
  Result<LedgerRequest> claimed = claim(result.requestId, "ImpostorResult");
  if (!claimed.ok()) return claimed.status();
  const Status used = useImpostorResult(*claimed, result);
  if (!used.ok()) refuse(*claimed, result.status);
  return used;
}

Status BackboneCore::useImpostorResult(const LedgerRequest& request,
                                       const protocol::ImpostorResult& result) {
  const ObjectRecord& record = converted_.records[request.object];
  const std::string where =
      "ImpostorResult " + idText(result.requestId) + " (object " + idText(record.id) + ")";
  if (!request.impostor) return invalid(where + ": answers a SimplifyRequest");
  if (result.objectIds != record.members)
    return invalid(where + ": object ids do not match the request");
  if (!result.status.ok())
    return Status(result.status.code(), where + ": simplifier error: " + result.status.message());
  const protocol::Representation& rep = result.representation;
  if (rep.kind != request.kind)
    return invalid(where + std::string(": kind ") + protocol::representationKindName(rep.kind) +
                   ", requested " + protocol::representationKindName(request.kind));
  if (rep.texture.codec == protocol::TextureCodec::kNone || rep.texture.data.empty())
    return invalid(where + ": no texture");
  if (rep.triangleCount == 0 || rep.triangleCount > protocol::kMaxTriangleCount)
    return invalid(where + ": triangle count " + std::to_string(rep.triangleCount));
  if (!std::isfinite(rep.accuracy) || rep.accuracy <= 0.0)
    return invalid(where + ": accuracy must be finite and > 0");
  const protocol::ConicRange& v = rep.validity;
  Result<ConicRange> validity = ConicRange::make(glm::dvec3(v.center), v.distanceMin, v.distanceMax,
                                                 glm::dvec3(v.direction), v.halfAngle);
  if (!validity.ok()) return invalid(where + ": validity: " + validity.status().message());
  if (validity->isEmpty()) return invalid(where + ": empty validity range");

  OptionState& state = optionStates_[request.option];
  const double textureRelative = rep.accuracy;
  const double bytes = payloadBytes(rep);
  const double oldAccuracy = state.textureAccuracy * state.parallaxFactor;
  const double oldTriangles = state.estimatedTriangles;
  const double oldBytes = state.estimatedBytes;
  if (!state.learned) {
    state.textureAccuracy = textureRelative;
    state.estimatedTriangles = rep.triangleCount;
    state.estimatedBytes = bytes;
    state.learned = true;
  } else {
    state.textureAccuracy = std::min(state.textureAccuracy, textureRelative);
    state.estimatedTriangles = std::max(state.estimatedTriangles, double(rep.triangleCount));
    state.estimatedBytes = std::max(state.estimatedBytes, bytes);
  }
  // A cone that does not hold the region it was made for: ask for less
  // accuracy next time (a looser bound gives a wider cone).
  if (!validity->containsSphere(request.viewRegion.center, request.viewRegion.radius))
    state.parallaxFactor = std::max(0.02, state.parallaxFactor * 0.7);
  if (state.textureAccuracy * state.parallaxFactor != oldAccuracy ||
      state.estimatedTriangles != oldTriangles || state.estimatedBytes != oldBytes)
    rebuildCurves(request.option);

  protocol::Representation stored = rep;
  stored.representationId = request.id;
  backbone::RepresentationCopy copy;
  copy.present = true;
  copy.id = request.id;
  copy.relativeAccuracy = request.requestedAccuracy > 0.0
                              ? std::min(textureRelative, request.requestedAccuracy)
                              : textureRelative;
  copy.triangles = rep.triangleCount;
  copy.encodedBytes = bytes;
  copy.validity = *validity;
  storeBackboneCopy(request.option, copy, std::move(stored));
  return Status();
}

// ------------------------------------------------------------------- poses

backbone::Budget BackboneCore::budgetAtPose() const {
  backbone::Budget budget = options_.budget;
  if (!options_.linkSchedule.empty()) {
    // The shaper's clock (finishPose): pose time, never backwards.
    const std::int64_t nowNs = std::max(lastShaperNs_, poseTimeNs_);
    budget.maxLinkBytesPerSecond =
        linkRateAt(options_.linkSchedule, double(nowNs) * 1e-9, options_.budget.maxLinkBytesPerSecond);
  }
  // An explicit --link-burst is the shaper's bucket: the scheduler may plan up
  // to it (Budget::linkBurstBytes). The default bucket (at least 64 KiB) is
  // slack for the shaper only; the scheduler keeps its one-lifetime window.
  if (budget.maxLinkBytesPerSecond && options_.linkBurstBytes > 0.0)
    budget.linkBurstBytes = options_.linkBurstBytes;
  return budget;
}

double BackboneCore::poseLinkReserve() const {
  return poseLinkReserve(budgetAtPose().maxLinkBytesPerSecond);
}

double BackboneCore::poseLinkReserve(std::optional<double> rate) const {
  if (!rate || !(poseIntervalSeconds_ > 0.0)) return 0.0;
  double bytesPerPose = 0.0;
  for (std::uint32_t k = 0; k < animationOf_.size(); ++k) {
    if (animationOf_[k] == nullptr || !(mirror_.trianglesOf(k) > 0.0)) continue;
    bytesPerPose += bonePoseBytes(animationOf_[k]->palette.bones.size());
  }
  // Decision (docs/animation.md, "Served"): poses get at most half the link
  // in planning. Above that the shaper defers some of them (the frontend
  // keeps its last pose), rather than the plan starving geometry entirely.
  return std::min(bytesPerPose / poseIntervalSeconds_, 0.5 * *rate);
}

backbone::Budget BackboneCore::schedulingBudget() const {
  backbone::Budget budget = budgetAtPose();
  const double reserve = poseLinkReserve(budget.maxLinkBytesPerSecond);
  if (budget.maxLinkBytesPerSecond && reserve > 0.0) *budget.maxLinkBytesPerSecond -= reserve;
  return budget;
}

Status BackboneCore::runPlan() {
  if (dirty_) {
    backbone::updateSubtreeVersions(scene_);
    dirty_ = false;
    THINLOD_RETURN_IF_ERROR(backbone::validateScene(scene_));
  }
  Result<backbone::Plan> planned = scheduler_->plan(scene_, viewer_, schedulingBudget(), planner_);
  if (!planned.ok()) return planned.status();
  plan_ = std::move(planned).value();
  ++plansThisPose_;
  ++posesPlanned_;
  requestsThisPose_ += static_cast<std::uint32_t>(plan_->requests.size());
  schedulingMicrosecondsThisPose_ += plan_->row.schedulingMicroseconds;
  const double now = viewer_.timeSeconds;
  for (const backbone::ObjectDecision& d : plan_->decisions)
    if (d.action == backbone::ObjectAction::kRemove) retiredThisPose_.push_back(d.object);
  for (const backbone::Removal& r : plan_->removals) retiredThisPose_.push_back(r.object);
  for (const backbone::ObjectDecision& d : plan_->decisions) {
    if (d.action != backbone::ObjectAction::kSend || d.option < 0) continue;
    const backbone::RepresentationCopy& copy = scene_.options[d.option].atBackbone;
    if (copy.present) promised_[copy.id] = now;
  }
  const std::vector<backbone::RepresentationRequest> requests = plan_->requests;
  for (const backbone::RepresentationRequest& r : requests) {
    promised_[r.requestId] = now;
    THINLOD_RETURN_IF_ERROR(issueRequest(r));
  }
  return Status();
}

Status BackboneCore::beginPose(const protocol::ViewerPose& pose) {
  inPose_ = true;
  pose_ = pose;
  ++poseCounter_;
  plan_.reset();
  plansThisPose_ = 0;
  requestsThisPose_ = 0;
  schedulingMicrosecondsThisPose_ = 0.0;
  retiredThisPose_.clear();

  // A pose moves the backbone's clock forward by at most kMaxPoseTimeStepNs:
  // one bogus far-future stamp would otherwise hold prediction and the link
  // shaper there. Backwards stamps keep the clock where it is.
  // Several poses in a row that far ahead are a real jump (a long pause, a
  // bogus very early first stamp) and are taken as they are.
  std::int64_t poseNs = pose.timestampNs;
  if (lastPoseNs_) {
    const std::int64_t limit =
        *lastPoseNs_ > std::numeric_limits<std::int64_t>::max() - kMaxPoseTimeStepNs
            ? std::numeric_limits<std::int64_t>::max()
            : *lastPoseNs_ + kMaxPoseTimeStepNs;
    if (poseNs <= limit) {
      posesBeyondStep_ = 0;
    } else if (++posesBeyondStep_ <= kPosesBeforeJump) {
      poseNs = limit;
    } else {
      posesBeyondStep_ = 0;  // the jump is taken; the next one is judged afresh
    }
    poseNs = std::max(poseNs, *lastPoseNs_);
    // The pose rate, for the poses' share of the link (poseLinkReserve):
    // spacing smoothed over about five poses; equal stamps say nothing.
    if (poseNs > *lastPoseNs_) {
      const double interval = double(poseNs - *lastPoseNs_) * 1e-9;
      poseIntervalSeconds_ =
          poseIntervalSeconds_ > 0.0 ? 0.8 * poseIntervalSeconds_ + 0.2 * interval : interval;
    }
  }
  lastPoseNs_ = poseNs;
  poseTimeNs_ = poseNs;
  const double time = std::max(lastTime_, double(poseNs) * 1e-9);
  lastTime_ = time;
  viewer_ = backbone::ViewerState();
  viewer_.frame = pose.sequence;
  viewer_.timeSeconds = time;
  viewer_.position = glm::dvec3(pose.position);
  viewer_.viewDirection = glm::dvec3(pose.orientation * glm::vec3(0.0f, 0.0f, -1.0f));
  viewer_.verticalFov = pose.fovY;
  const double aspect = (pose.viewportWidth > 0 && pose.viewportHeight > 0)
                            ? double(pose.viewportWidth) / double(pose.viewportHeight)
                            : options_.defaultAspect;
  viewer_.horizontalFov =
      std::min(kPi - 1e-6, 2.0 * std::atan(std::tan(0.5 * double(pose.fovY)) * aspect));

  // Promises older than any in-flight request the scheduler still awaits.
  for (auto it = promised_.begin(); it != promised_.end();) {
    it = (time - it->second > 2.0 * timeoutSeconds()) ? promised_.erase(it) : std::next(it);
  }
  planStatus_ = runPlan();
  return planStatus_;
}

Status BackboneCore::replan() {
  if (!inPose_) return Status(ErrorCode::kInternal, "replan() outside a pose");
  planStatus_ = runPlan();
  return planStatus_;
}

protocol::SceneUpdate BackboneCore::emptyUpdate(const protocol::ViewerPose& pose) {
  protocol::SceneUpdate update;
  // Plan 0: no plan. Repeating the last plan's number would let this empty
  // answer stand in for that plan's update when the update itself was lost,
  // and the frontend could not tell the loss (it reports jumps in the plan
  // numbers as refused plans: docs/frontend.md, "Updates").
  update.plan = 0;
  update.frame = pose.sequence;
  update.targetAccuracy = 0.0;
  update.unitsKappa = options_.hybridKappa;
  update.bonePoses = bonePosesAt(pose.timestampNs);
  return update;
}

PoseOutcome BackboneCore::finishPose() {
  PoseOutcome out;
  out.update.plan = poseCounter_;
  out.update.frame = pose_.sequence;
  // The frontend counts what it draws in the budget's units with it (frames.csv units).
  out.update.unitsKappa = options_.hybridKappa;
  out.plans = plansThisPose_;
  out.frontendTriangles = mirror_.triangles();
  inPose_ = false;
  if (!planStatus_.ok() || !plan_) {
    out.planError = planStatus_.ok() ? Status(ErrorCode::kInternal, "no plan") : planStatus_;
    out.row.frame = pose_.sequence;
    out.row.timeSeconds = viewer_.timeSeconds;
    out.row.scheduler = scheduler_->name();
    out.row.mode = "error";
    return out;
  }
  const backbone::Plan& plan = *plan_;
  out.planned = true;
  out.row = plan.row;
  out.expiredCopiesKept = plan.stats.expiredCopiesKept;
  out.row.requests = requestsThisPose_;
  out.row.schedulingMicroseconds = schedulingMicrosecondsThisPose_;
  out.update.targetAccuracy =
      std::isfinite(plan.targetAccuracy) && plan.targetAccuracy > 0.0 ? plan.targetAccuracy : 0.0;

  struct Add {
    std::uint32_t object = 0;
    std::uint32_t option = 0;
    double delta = 0.0;  // triangles at the frontend after minus before
    bool missing = false;
  };
  std::vector<Add> adds;
  std::vector<std::uint32_t> removes;
  std::vector<std::uint8_t> rendered(scene_.objects.size(), 0);
  for (const backbone::ObjectDecision& d : plan.decisions) {
    if (d.object >= scene_.objects.size()) continue;
    switch (d.action) {
      case backbone::ObjectAction::kSend:
      case backbone::ObjectAction::kAwait: {
        rendered[d.object] = 1;
        if (d.option < 0 || static_cast<std::size_t>(d.option) >= scene_.options.size()) break;
        const auto index = static_cast<std::uint32_t>(d.option);
        const backbone::RepresentationCopy& back = scene_.options[index].atBackbone;
        if (!back.present || !mirror_.generatedPayload(index)) break;
        // Await: deliver the copy the scheduler is waiting for once it is here.
        if (d.action == backbone::ObjectAction::kAwait && promised_.count(back.id) == 0) break;
        const double before = mirror_.trianglesOf(d.object);
        adds.push_back({d.object, index, back.triangles - before, before == 0.0});
        break;
      }
      case backbone::ObjectAction::kKeep:
      case backbone::ObjectAction::kRequest:
        rendered[d.object] = 1;
        break;
      case backbone::ObjectAction::kRemove:
        break;
    }
  }
  // Removals of every plan of this pose (the scheduler retires an object
  // once; a re-plan does not list it again) unless the final plan renders it.
  for (std::uint32_t object : retiredThisPose_) {
    if (object < scene_.objects.size() && !rendered[object] && mirror_.trianglesOf(object) > 0.0) {
      rendered[object] = 2;
      removes.push_back(object);
    }
  }

  for (std::uint32_t object : removes) {
    mirror_.remove(object, out.update.plan);
    protocol::SceneOperation op;
    op.type = protocol::SceneOperation::Type::kRemove;
    op.objectId = converted_.records[object].id;
    out.update.operations.push_back(std::move(op));
    ++out.removes;
  }

  // Downgrades first (they free polygons), then objects showing nothing,
  // then the smallest upgrades.
  std::stable_sort(adds.begin(), adds.end(), [](const Add& a, const Add& b) {
    const bool downA = a.delta <= 0.0;
    const bool downB = b.delta <= 0.0;
    if (downA != downB) return downA;
    if (a.missing != b.missing) return a.missing;
    return a.delta < b.delta;
  });

  // The link shaper runs on pose time.
  const std::int64_t nowNs = std::max(lastShaperNs_, poseTimeNs_);
  lastShaperNs_ = nowNs;
  const protocol::LinkShaper::Clock::time_point now{std::chrono::nanoseconds(nowNs)};
  const std::optional<double> linkRate = budgetAtPose().maxLinkBytesPerSecond;
  if (linkRate) {
    const double rate = std::min(std::max(1.0, std::round(*linkRate)), 1e11);
    const double burst = options_.linkBurstBytes > 0.0
                             ? options_.linkBurstBytes
                             : std::max(rate * options_.config.plannedLifetime, 65536.0);
    const auto rateBytes = static_cast<std::uint64_t>(rate);
    const auto burstBytes = static_cast<std::uint64_t>(std::clamp(std::round(burst), 1.0, 4294967296.0));
    if (!shaper_) {
      Result<protocol::TokenBucket> bucket = protocol::TokenBucket::create(rateBytes, burstBytes, now);
      if (bucket.ok()) shaper_.emplace(std::move(bucket).value());
    } else if (shaper_->bucket().rateBytesPerSecond() != rateBytes) {
      // The link schedule changed the rate: a new bucket at the new rate that
      // keeps no more tokens than the old one had (nor than its own burst),
      // so a cut holds from this planning step on.
      const std::uint64_t available = shaper_->bucket().availableBytes(now);
      Result<protocol::TokenBucket> changed =
          protocol::TokenBucket::create(rateBytes, burstBytes, now);
      if (changed.ok()) {
        protocol::TokenBucket bucket = std::move(changed).value();
        if (burstBytes > available) (void)bucket.trySend(burstBytes - available, now);
        shaper_.emplace(std::move(bucket));
      }
    }
  }
  if (shaper_) {
    shaper_->beginFrame(pose_.sequence);
    out.linkRate = shaper_->bucket().rateBytesPerSecond();
  }

  const double cap = (options_.hardPolygonCap && options_.budget.maxTriangles)
                         ? *options_.budget.maxTriangles
                         : kInf;
  const std::vector<std::uint32_t> resync = mirror_.takeResyncRemovals();
  std::vector<std::uint32_t> sentNow;
  for (const Add& add : adds) {
    const backbone::RepresentationCopy& back = scene_.options[add.option].atBackbone;
    const double delta = back.triangles - mirror_.trianglesOf(add.object);
    if (delta > 0.0 && mirror_.triangles() + delta > cap) {
      ++out.deferredByPolygonCap;
      continue;
    }
    // A shared texture the frontend does not hold yet travels with this copy.
    const protocol::Representation& payload = *mirror_.generatedPayload(add.option);
    const protocol::SharedTexture* newTexture = nullptr;
    if (payload.textureId != 0 && payload.textureId <= sharedTextures_.size() &&
        texturesAtFrontend_.count(payload.textureId) == 0)
      newTexture = &sharedTextures_[payload.textureId - 1];
    const auto bytes = static_cast<std::uint64_t>(std::llround(back.encodedBytes)) +
                       (newTexture ? newTexture->texture.data.size() : 0);
    if (shaper_) {
      if (bytes > shaper_->bucket().burstBytes()) {
        // Grow the bucket to hold this message, keeping the tokens it had.
        const std::uint64_t available = shaper_->bucket().availableBytes(now);
        Result<protocol::TokenBucket> grown =
            protocol::TokenBucket::create(shaper_->bucket().rateBytesPerSecond(), bytes, now);
        if (grown.ok()) {
          protocol::TokenBucket bucket = std::move(grown).value();
          if (bytes > available) (void)bucket.trySend(bytes - available, now);
          shaper_.emplace(std::move(bucket));
          shaper_->beginFrame(pose_.sequence);
          ++out.tooLargeForLink;
        }
      }
      if (!shaper_->trySend(bytes, now)) {
        ++out.deferredByLink;
        continue;
      }
      shapedBytes_ += bytes;
    }
    out.linkBytes += bytes;
    // What the shaper let through is what the scheduler's log holds.
    planner_.settleLinkSend(back.id, viewer_.timeSeconds, double(bytes));
    protocol::SceneOperation op;
    op.type = protocol::SceneOperation::Type::kAddOrReplace;
    op.objectId = converted_.records[add.object].id;
    op.representation = payload;
    out.update.operations.push_back(std::move(op));
    if (newTexture) {
      out.update.textures.push_back(*newTexture);
      texturesAtFrontend_[newTexture->textureId] = out.update.plan;
    }
    mirror_.send(add.object, add.option, out.update.plan);
    promised_.erase(scene_.options[add.option].atFrontend.id);  // delivered: await anew
    sentNow.push_back(add.object);
    ++out.adds;
  }
  // Objects whose frontend copy is unknown after a refused update: remove
  // what the frontend may still show, unless this update replaced it.
  for (std::uint32_t object : resync) {
    if (std::find(sentNow.begin(), sentNow.end(), object) != sentNow.end()) continue;
    if (std::find(removes.begin(), removes.end(), object) != removes.end()) continue;
    protocol::SceneOperation op;
    op.type = protocol::SceneOperation::Type::kRemove;
    op.objectId = converted_.records[object].id;
    out.update.operations.push_back(std::move(op));
    mirror_.remove(object, out.update.plan);
    ++out.resyncRemoves;
  }
  out.frontendTriangles = mirror_.triangles();
  // Each object's pose on its own: the ones the shaper has tokens for go.
  for (protocol::BonePose& pose : bonePosesAt(poseTimeNs_)) {
    const auto bytes = static_cast<std::uint64_t>(bonePoseBytes(pose.matrices.size()));
    if (shaper_ && !shaper_->trySend(bytes, now)) {
      ++out.posesDeferredByLink;
      continue;
    }
    if (shaper_) shapedBytes_ += bytes;
    out.linkBytes += bytes;
    out.bonePoseBytes += bytes;
    out.update.bonePoses.push_back(std::move(pose));
  }
  return out;
}

std::vector<protocol::BonePose> BackboneCore::bonePosesAt(std::int64_t poseNs) const {
  std::vector<protocol::BonePose> poses;
  const double seconds = double(poseNs) * 1e-9;
  for (std::uint32_t k = 0; k < animationOf_.size(); ++k) {
    const scene::SkinnedAnimation* animation = animationOf_[k];
    if (animation == nullptr || !(mirror_.trianglesOf(k) > 0.0)) continue;
    protocol::BonePose pose;
    pose.objectId = converted_.records[k].id;
    pose.matrices =
        anim::paletteMatricesAt(animation->skeleton, animation->clip, animation->palette,
                                seconds + double(animationOffsetOf_[k]), anim::ClipWrap::kLoop);
    // deform() drops w, so the bottom row plays no part: the wire's affine
    // form is exact. Finite bones of a file can still overflow float in their
    // product: such a pose is not sent (the frontend keeps its last one).
    bool finite = true;
    for (glm::mat4& m : pose.matrices) {
      m[0][3] = m[1][3] = m[2][3] = 0.0f;
      m[3][3] = 1.0f;
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 3; ++r) finite = finite && std::isfinite(m[c][r]);
      }
    }
    if (finite) poses.push_back(std::move(pose));
  }
  std::sort(poses.begin(), poses.end(),
            [](const auto& a, const auto& b) { return a.objectId < b.objectId; });
  return poses;
}

std::size_t BackboneCore::animatedObjects() const {
  return static_cast<std::size_t>(std::count_if(animationOf_.begin(), animationOf_.end(),
                                                [](const auto* a) { return a != nullptr; }));
}

Status BackboneCore::setSharedTextures(SceneTextures textures) {
  if (textures.objectTexture.size() != sceneObjects_.size())
    return invalid("shared textures: " + std::to_string(textures.objectTexture.size()) +
                   " object entries for " + std::to_string(sceneObjects_.size()) + " objects");
  for (std::size_t i = 0; i < textures.textures.size(); ++i) {
    if (textures.textures[i].textureId != i + 1)
      return invalid("shared texture " + std::to_string(i) + " has id " +
                     std::to_string(textures.textures[i].textureId) + ", expected " +
                     std::to_string(i + 1));
  }
  for (std::uint64_t id : textures.objectTexture) {
    if (id > textures.textures.size())
      return invalid("shared textures: an object names texture " + std::to_string(id) + " of " +
                     std::to_string(textures.textures.size()));
  }
  sharedTextures_ = std::move(textures.textures);
  // Per scheduled record (requests name records, not scene objects: an
  // imposter node or a collapsed LOD makes one record of several objects).
  // A record stands for its scene object (id = 1 + index); a cluster's
  // impostor is captured textured by the simplifier, its copies name none.
  objectTexture_.assign(converted_.records.size(), 0);
  for (std::size_t k = 0; k < converted_.records.size(); ++k) {
    const ObjectRecord& record = converted_.records[k];
    if (!record.cluster && record.id >= 1 && record.id <= textures.objectTexture.size())
      objectTexture_[k] = textures.objectTexture[record.id - 1];
  }
  texturesAtFrontend_.clear();
  return Status();
}

std::size_t BackboneCore::onFrameStats(const protocol::FrameStats& stats) {
  const std::vector<std::uint32_t> corrected = mirror_.acknowledge(stats.plan, stats.rejectedPlans);
  // A refused update's shared textures may not be held: send them again.
  for (auto it = texturesAtFrontend_.begin(); it != texturesAtFrontend_.end();) {
    if (std::find(stats.rejectedPlans.begin(), stats.rejectedPlans.end(), it->second) !=
        stats.rejectedPlans.end()) {
      it = texturesAtFrontend_.erase(it);
    } else {
      ++it;
    }
  }
  // The scheduler still awaits the refused copies (they were on their way to
  // the frontend): promise them again so the next update delivers them.
  for (std::uint32_t object : corrected) {
    const backbone::SceneObject& o = scene_.objects[object];
    for (std::uint32_t k = o.firstOption; k < o.firstOption + o.optionCount; ++k)
      if (scene_.options[k].atBackbone.present)
        promised_[scene_.options[k].atBackbone.id] = viewer_.timeSeconds;
  }
  return corrected.size();
}

void BackboneCore::resetFrontend() {
  mirror_.reset();
  texturesAtFrontend_.clear();
  planner_.reset();
  promised_.clear();
  shaper_.reset();
  shapedBytes_ = 0;
  lastTime_ = -1e300;
  lastPoseNs_.reset();
  poseIntervalSeconds_ = 0.0;
  posesBeyondStep_ = 0;
  lastShaperNs_ = std::numeric_limits<std::int64_t>::min();
  inPose_ = false;
  plan_.reset();
}

}  // namespace thinlod::backbone_daemon
