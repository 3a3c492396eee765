// BackboneCore: everything the backbone daemon decides, without sockets,
// files or logging (main.cpp is the thin shell around it).
//
// Contract:
// - create() converts the scene (scene_conversion.h) and gives every object
//   its representation options: a simplified mesh (relative triangle curve:
//   primitives analytic, meshes measured by the simplifier, a pessimistic
//   estimate until then: curve_estimate.h) and, when enabled, meshed and
//   simple impostors (point curves from the texture size, learned from
//   results). Link bytes are estimated from the results' encoded sizes
//   (docs/backbone.md, "Link estimates").
// - Requests: one id end to end (request_ledger.h). The scheduler's request
//   id is the wire requestId, the reply's and the copy's; startup requests
//   draw from the same counter (ids start at CoreOptions::firstRequestId).
//   The core queues the requests; the shell submits them under that id and
//   reports requestSubmitted(id) / requestNotSubmitted(id). Replies are
//   matched by id in the RequestLedger: unknown ids, duplicate and late
//   replies, mismatched objects/kinds and malformed payloads are rejected
//   with a Status. One plan request per option is open at a time: a newer
//   one (the scheduler asking again) replaces it, and the older id appears
//   in takeCancellations().
// - Startup curve requests (one per mesh object) are queued at create().
//   With deferCurveRequests they are held back and released one at a time,
//   smallest mesh first, after a pose has been planned, when no plan
//   request is open (takeRequests) or when the shell calls
//   releaseHeldCurve() (its duty-cycle rule, main.cpp): a first measurement
//   of a large mesh occupies a simplifier for seconds, and the
//   representations the viewer waits for go first. A measured curve replaces the estimate in the
//   scheduling scene (the leaf's content version is bumped; no restart).
// - Link: the LinkShaper is the one model of the link. Every byte it lets
//   through is settled in the scheduler's link log under the copy's id
//   (PlannerState::settleLinkSend), and a request that will never be shipped
//   releases its reservation, so the budget the scheduler plans against is
//   what the shaper sent (docs/backbone.md, "Link").
// - Poses: beginPose() plans (queues requests); replan() plans the same pose
//   again (after results arrived); finishPose() builds the pose's one
//   SceneUpdate (frame = pose sequence). Removals first, then downgrades,
//   then upgrades; an AddOrReplace that would leave the frontend above the
//   polygon budget, or that the link shaper (pose timestamps as its clock)
//   has no tokens for, waits for a later pose. The core's model of the
//   frontend is what it sent: one displayed copy per object.
// - Time is the pose timestamp (clamped to never run backwards).
// - Not thread-safe; one frontend session at a time (resetFrontend() when it
//   changes). The daemon serves several frontends with one core each; the
//   cores share measured curves and copies through adoptMeasuredCurves /
//   adoptGeneratedCopies.
// - Frame cost (Budget::maxFrameSeconds): a frontend session's frame-time
//   model uses the constants the frontend's Hello carries (its own renderer,
//   calibrated by bench_calibrate), else CoreOptions::defaultFrameCost (the
//   daemon's --frame-cost); with neither, admitFrontend refuses the
//   frontend. Without a frame-time budget the constants are not used.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "curve_estimate.h"
#include "frontend_mirror.h"
#include "link_schedule.h"
#include "request_ledger.h"
#include "scene_conversion.h"
#include "scene_textures.h"
#include "thinlod/backbone/scheduler.h"
#include "thinlod/protocol/link_shaper.h"
#include "thinlod/protocol/messages.h"

namespace thinlod::backbone_daemon {

// Encoded bytes a SceneUpdate operation adds besides its mesh and texture
// (ids, transform, validity, FlatBuffers tables).
inline constexpr double kOperationOverheadBytes = 256.0;
// Mesh bytes = frame overhead + bytes per triangle * triangles (defaults
// until the first result of the object has been measured).
inline constexpr double kMeshFrameOverheadBytes = 300.0;
inline constexpr double kDefaultMeshBytesPerTriangle = 2.0;
// Impostor texture bytes per texel before the first result (PNG of a
// partly covered RGBA image; docs/backbone.md).
inline constexpr double kDefaultTextureBytesPerTexel = 0.35;
// Share of the error budget Draco quantization may add (the simplifier's
// kQuantizationBudget): analytic primitive curves are credited 1/(1+this).
inline constexpr double kQuantizationShare = 0.1;

struct CoreOptions {
  std::string scheduler = "accuracy-curve";  // a name of backbone::schedulerCatalogue()
  backbone::SchedulerConfig config;
  backbone::Budget budget;
  // active-set options; its `costs` are replaced by each frontend session's
  // frame-cost constants (startFrontendSession).
  backbone::TimeCriticalConfig timeCritical;
  // The frame-cost constants of a session whose frontend sent none (the
  // daemon's --frame-cost); unset: such a frontend is refused when the
  // budget has a frame time.
  std::optional<FrameCostConstants> defaultFrameCost;
  std::uint32_t textureSize = 256;
  protocol::TextureCodec textureCodec = protocol::TextureCodec::kPng;
  double simpleImpostorRadii = 10.0;      // usable from this many bounding radii; 0: disabled
  double meshedImpostorRadii = 4.0;       // 0: disabled
  double meshedImpostorTriangles = 64.0;  // estimate until the first result
  std::uint16_t curvePoints = 32;         // samples asked for per mesh curve
  std::uint32_t curveRequestTriangles = 2000;
  MeshCurveEstimate curveEstimate;  // meshes until their measured curve arrives
  // Hold startup curve requests back while plan requests are open (live
  // serving); false: queue them all at create() (lockstep: the shell waits
  // for them before the first plan, as the paper experiment always did).
  bool deferCurveRequests = false;
  bool hardPolygonCap = true;         // never let the frontend hold more than budget.maxTriangles
  double linkBurstBytes = 0.0;        // 0: max(budget-link * plannedLifetime, 64 KiB)
  // Steps of the link's capacity over trace time (link_schedule.h); before
  // the first one budget.maxLinkBytesPerSecond holds. Empty: that budget
  // throughout. The automatic burst follows each step's rate.
  std::vector<LinkStep> linkSchedule;
  double defaultAspect = 16.0 / 9.0;  // width/height when the pose has no viewport
  // The first request id (> 0, < 2^62). The shell draws a random one per
  // process, so a reply computed for an earlier backbone never matches.
  std::uint64_t firstRequestId = 1;
  // Queue the startup requests (curve measurements, the warm-up) at
  // create(). false: a further session's core, which takes the curves the
  // daemon's first core measures (adoptMeasuredCurves) instead of asking
  // again, so one measurement of each runs at a time.
  bool startupRequests = true;
  // > 1: every mesh object gets one more option, a Hybrid (triangles + disc
  // points, docs/hybrid.md) whose graph the simplifier builds with this
  // kappa, the frontend renderer's measured point rate / triangle rate; its
  // primitive units count against the polygon budget. 0: off (the default).
  double hybridKappa = 0.0;
};
Status validateCoreOptions(const CoreOptions& options);

// Where a session's frame-cost constants came from.
enum class FrameCostSource : std::uint8_t {
  kUnused = 0,          // no frame-time budget: the constants play no part
  kFrontend = 1,        // the frontend's Hello
  kBackboneDefault = 2  // CoreOptions::defaultFrameCost
};
const char* frameCostSourceName(FrameCostSource source);

struct SessionFrameCost {
  FrameCostSource source = FrameCostSource::kUnused;
  FrameCostConstants constants;  // meaningful unless kUnused
};

// Encoded bytes of one object's bone pose in a SceneUpdate: 48 per matrix
// (three rows of four floats) plus its table (measured: at most 64,
// tests/protocol/bone_pose_fields_test.cpp).
inline constexpr double kBonePoseOverheadBytes = 64.0;
inline constexpr double kBytesPerBoneMatrix = 48.0;
// The link bytes of one object's pose of `bones` matrices: what the shaper
// charges (finishPose) and what planning reserves (poseLinkReserve).
inline constexpr double bonePoseBytes(std::size_t bones) {
  return kBonePoseOverheadBytes + kBytesPerBoneMatrix * double(bones);
}

struct OutgoingRequest {
  std::uint64_t requestId = 0;  // == the message's requestId
  std::variant<protocol::SimplifyRequest, protocol::ImpostorRequest> message;
};

struct PoseOutcome {
  protocol::SceneUpdate update;
  backbone::DecisionRow row;  // the final plan's row; requests and time summed over the pose
  bool planned = false;       // false: planning failed (planError), the update is empty
  Status planError;
  int plans = 0;
  std::uint32_t adds = 0;
  std::uint32_t removes = 0;
  std::uint32_t deferredByPolygonCap = 0;
  std::uint32_t deferredByLink = 0;
  std::uint32_t tooLargeForLink = 0;  // larger than the shaper's burst: dropped
  std::uint32_t resyncRemoves = 0;    // removals of objects a refused update left unknown
  std::uint64_t linkBytes = 0;        // shaped bytes of this update
  std::uint64_t linkRate = 0;         // the shaper's rate at this pose (bytes/s; 0: no link budget)
  double frontendTriangles = 0.0;     // after the update is applied
  std::uint32_t expiredCopiesKept = 0;  // PlanStats::expiredCopiesKept of the final plan
  // Bytes of update.bonePoses (the held animated objects' poses at the
  // pose's time, bonePosesAt), counted in linkBytes; with a link budget each
  // object's pose passes the shaper after the operations, and one that finds
  // no tokens is left out of this frame (posesDeferredByLink counts them: the
  // frontend keeps the last pose it has).
  std::uint64_t bonePoseBytes = 0;
  std::uint32_t posesDeferredByLink = 0;
};

class BackboneCore {
 public:
  // `scenePath` is sent in SimplifyRequests (absolute). The scene is kept.
  static Result<std::unique_ptr<BackboneCore>> create(scene::Scene scene, std::string scenePath,
                                                      CoreOptions options);
  ~BackboneCore();
  BackboneCore(const BackboneCore&) = delete;
  BackboneCore& operator=(const BackboneCore&) = delete;

  // The scene's shared textures (scene_textures.h, loaded by the daemon):
  // a mesh copy of a textured object names its texture id, and the first
  // update of a frontend session that sends such a copy carries the texture
  // (SceneUpdate::textures), its bytes counted on the link like the mesh's.
  // A texture whose update the frontend refused is sent again. kInvalidArgument
  // when `textures` does not fit the scene (objectTexture size, ids).
  Status setSharedTextures(SceneTextures textures);
  std::size_t sharedTextureCount() const { return sharedTextures_.size(); }
  std::size_t texturesAtFrontend() const { return texturesAtFrontend_.size(); }

  // ---- the prediction horizon ----
  // The generation delay the scheduler plans with from the next pose on (the
  // daemon's measured one, delay_estimate.h, under --measured-generation-delay);
  // also the requests' expected-by time. kInvalidArgument (unchanged) when it
  // is not finite or < 0.
  Status setGenerationDelay(double seconds);
  double generationDelay() const { return options_.config.generationDelay; }

  // ---- requests to the simplifier ----
  std::vector<OutgoingRequest> takeRequests();
  std::vector<std::uint64_t> takeCancellations();  // request ids
  void requestSubmitted(std::uint64_t requestId);
  void requestNotSubmitted(std::uint64_t requestId);
  Status onSimplifyResult(const protocol::SimplifyResult& result);
  Status onImpostorResult(const protocol::ImpostorResult& result);

  // ---- startup curves ----
  std::size_t curvesPending() const;
  std::size_t curvesWanted() const { return curvesWanted_; }
  std::size_t curvesHeld() const { return heldCurves_.size(); }  // not released yet
  // A released curve request without its answer yet.
  bool curveRequestOpen() const;
  // Releases the smallest held curve request now (queued for takeRequests)
  // unless none is held, no pose was planned yet or one is open; true when
  // one was released.
  bool releaseHeldCurve();
  std::vector<std::uint64_t> objectsWithoutMeasuredCurve() const;  // mesh objects
  // Mesh objects planning from the estimate (curve_estimate.h) right now.
  std::vector<std::uint64_t> objectsWithEstimatedCurve() const;

  // ---- poses ----
  Status beginPose(const protocol::ViewerPose& pose);
  Status replan();
  // Requests of the current pose still without a result.
  std::size_t awaitedResults() const;
  PoseOutcome finishPose();
  // Answers a pose without planning (e.g. superseded by a newer one): no
  // operations, plan 0 (no plan: it never stands for a plan's update); the
  // held animated objects' bone poses at the pose's time (not shaped: a
  // superseded pose's answer is small and keeps the motion going).
  protocol::SceneUpdate emptyUpdate(const protocol::ViewerPose& pose);

  // Forgets the frontend (mirror, planner state, shaper); the frame-cost
  // constants stay those of the last session.
  void resetFrontend();
  // A new frontend session: resetFrontend(), then the scheduler's frame-cost
  // constants are the ones this frontend's Hello earns (frameCostFor). Errors
  // as frameCostFor's; the core is then reset but keeps its old constants.
  // Then the mirror starts from what the Hello says the frontend holds
  // (Hello.held, checked by checkHeld): a held copy this process still has
  // in its stock under the same id is taken back whole; any other is a
  // foreign copy credited with nothing (no accuracy, valid nowhere) whose
  // primitive units count against the polygon budget until a copy of this
  // session replaces it or the plan removes the object. A backbone that
  // restarted thus neither over-fills the frontend nor leaves what it never
  // sent there unmirrored (docs/backbone.md, "Resynchronisation").
  Status startFrontendSession(const protocol::Hello& hello);
  // Hello.held against this scene: every object id known (the decoder
  // checked count, order, kinds and sizes). kInvalidArgument naming the
  // first unknown id.
  Status checkHeld(const std::vector<protocol::HeldRepresentation>& held) const;
  // Foreign and taken-back copies of the last startFrontendSession.
  std::size_t heldForeign() const { return heldForeign_; }
  std::size_t heldTakenBack() const { return heldTakenBack_; }
  // The constants a session of this frontend would use (see the contract);
  // kInvalidArgument when the frame-time budget has none for it or the
  // Hello's are unusable (validateCalibratedFrameCost).
  Result<SessionFrameCost> frameCostFor(const protocol::Hello& hello) const;
  const SessionFrameCost& sessionFrameCost() const { return sessionFrameCost_; }
  // The frontend's acknowledgement: corrects the mirror for refused updates
  // (FrontendMirror::acknowledge); returns the objects corrected.
  std::size_t onFrameStats(const protocol::FrameStats& stats);

  // ---- several frontend sessions (the daemon runs one core per session) ----
  // Takes over the measured curves `other` (a core of the same scene and
  // options) has and this one lacks: each mesh or hybrid option's curve,
  // its calibration and the object's learned mesh bytes per triangle (and
  // a lower calibration of a curve both have: what the simplifier really
  // delivers is the same for every session); this
  // core's startup request for such a curve is withdrawn (closed as
  // kRetried: what it asked for is in; cancelled on the wire when it was
  // submitted). Returns how many curves were taken; kInvalidArgument when
  // `other` holds another scene or option layout.
  Result<std::size_t> adoptMeasuredCurves(const BackboneCore& other);
  // Fills this core's empty stock slots from `other`'s copies: its stock
  // copy, else the copy its frontend holds, of an option where this core
  // has none in stock; any kind (a mesh is valid everywhere, an impostor
  // within its validity cone, each credited the accuracy its result
  // earned; this core's scheduler checks them against its own viewer). A
  // representation made for one session is then sent to another without
  // asking a simplifier again. Returns how many copies were taken;
  // kInvalidArgument as adoptMeasuredCurves.
  Result<std::size_t> adoptGeneratedCopies(const BackboneCore& other);

  // ---- animation (docs/animation.md) ----
  // The clock: every skinned object's clip plays looped on pose time, clip
  // time = the pose's timestamp in seconds, so lockstep replays are
  // deterministic and every frontend of one trace sees the same motion.
  // Bone poses at `poseNs` of the animated objects the frontend holds a
  // representation of (the mirror after the last update), ascending ids.
  std::vector<protocol::BonePose> bonePosesAt(std::int64_t poseNs) const;
  // Scene objects with a skinned animation.
  std::size_t animatedObjects() const;
  // Validity under motion: an animated object's leaf sphere encloses it at
  // every pose of its clip (its reference sphere grown by the clip's motion
  // bound m, scene_objects.h), and every accuracy the simplifier reports for
  // it at the bind pose (the estimate, a cold-start level) is converted by
  // anim::animatedRelativeAccuracy with motionRatio = 2 m / L: what the
  // level keeps at any pose against that sphere. Results measured under the
  // clip (SimplifyResult::motionIncluded) are taken as they are. The whole
  // clip bounds every planned lifetime's window. 0 for a static object.
  double motionRatio(std::uint32_t object) const {
    return object < motionRatio_.size() ? motionRatio_[object] : 0.0;
  }

  // ---- introspection (tests, logs) ----
  const backbone::SchedulingScene& schedulingScene() const { return scene_; }
  const std::vector<ObjectRecord>& objects() const { return converted_.records; }
  const std::vector<scene::SceneObject>& sceneObjects() const { return sceneObjects_; }
  std::uint32_t lodNodes() const { return converted_.lodNodes; }
  double frontendTriangles() const { return mirror_.triangles(); }
  const FrontendMirror& frontendMirror() const { return mirror_; }
  // The latest plan of the current (or last) pose; null before the first.
  const backbone::Plan* latestPlan() const { return plan_ ? &*plan_ : nullptr; }
  std::size_t outstandingRequests() const { return ledger_.openCount(); }
  const RequestLedger& requestLedger() const { return ledger_; }
  // The scheduler's link log within its window (settled = shipped bytes).
  backbone::PlannerState::LinkLogTotals linkLogAfter(double afterSeconds) const {
    return planner_.linkLogAfter(afterSeconds);
  }
  // Bytes the link shaper let through since the frontend session began
  // (kept here: a grown burst replaces the shaper).
  std::uint64_t shapedLinkBytes() const { return shapedBytes_; }
  // The link rate the scheduler leaves to bone poses (it plans geometry with
  // the rest): bytes per second of the poses of the animated objects the
  // frontend holds, at the measured pose rate, capped at half the link rate
  // (the other half stays for geometry). 0 without a link budget or before
  // two poses with distinct times.
  double poseLinkReserve() const;
  // What the scheduler plans with: the pose's budget (the link schedule's
  // rate) less poseLinkReserve(), so geometry and poses together fit the
  // link; the shaper still enforces the whole rate.
  backbone::Budget schedulingBudget() const;
  const CoreOptions& options() const { return options_; }
  const char* schedulerName() const;
  std::uint64_t sceneFingerprint() const { return sceneGraph_.fingerprint; }
  // The frontend handshake: a frontend that loaded another scene is refused
  // (protocol::checkSameScene), so is one frameCostFor() refuses; other
  // roles pass.
  Status admitFrontend(const protocol::Hello& hello) const;

 private:
  struct OptionState {
    std::uint32_t object = 0;
    protocol::RepresentationKind wireKind = protocol::RepresentationKind::kMesh;
    // Mesh kinds: scheduler-relative curve before calibration, and the
    // factor that delivered accuracies taught us (<= 1).
    AccuracyCurve baseTriangles;
    double calibration = 1.0;
    bool measuredCurve = false;
    bool estimatedCurve = false;  // baseTriangles is estimatedMeshCurve (until measured)
    // Impostor kinds: point-curve estimates.
    double textureAccuracy = 0.0;  // scheduler-relative, what the texture supports
    double parallaxFactor = 1.0;   // lowered when validity cones miss the reach ball
    double estimatedTriangles = 0.0;
    double estimatedBytes = 0.0;
    bool learned = false;
  };

  BackboneCore(scene::Scene scene, std::string scenePath, CoreOptions options);
  Status initialize();
  Status checkSameLayout(const BackboneCore& other) const;
  void queueStartupRequest(std::uint32_t object, std::uint32_t option, bool warmup);
  void rebuildCurves(std::uint32_t option);
  void touchObject(std::uint32_t object);
  Status runPlan();
  Status issueRequest(const backbone::RepresentationRequest& request);
  // Drops a request's queued message (if not taken yet) and its link
  // reservation; cancels it on the wire when it was submitted.
  void withdraw(const LedgerRequest& request);
  Result<LedgerRequest> claim(std::uint64_t id, const char* what);
  // A claimed reply the core refused (or an error reply): closes it as
  // failed or timed out and releases its link reservation.
  void refuse(const LedgerRequest& request, const Status& replyStatus);
  Status useSimplifyResult(const LedgerRequest& request, const protocol::SimplifyResult& result);
  Status useImpostorResult(const LedgerRequest& request, const protocol::ImpostorResult& result);
  void learnMeshBytes(std::uint32_t object, double meshBytes, double triangles);
  void storeBackboneCopy(std::uint32_t option, backbone::RepresentationCopy copy,
                         protocol::Representation payload);
  double timeoutSeconds() const;

  scene::Scene sceneGraph_;
  std::vector<scene::SceneObject> sceneObjects_;
  std::string scenePath_;
  CoreOptions options_;
  ConvertedScene converted_;
  backbone::SchedulingScene scene_;
  FrontendMirror mirror_{scene_, [this](std::uint32_t object) { touchObject(object); }};
  std::vector<protocol::SharedTexture> sharedTextures_;  // id i + 1 at index i
  std::vector<std::uint64_t> objectTexture_;             // per record, 0 = untextured
  std::map<std::uint64_t, std::uint64_t> texturesAtFrontend_;  // texture id -> plan that sent it
  std::vector<OptionState> optionStates_;
  std::vector<double> meshBytesPerTriangle_;  // per object
  std::vector<bool> meshBytesLearned_;
  std::unique_ptr<backbone::Scheduler> scheduler_;
  SessionFrameCost sessionFrameCost_;
  backbone::PlannerState planner_{options_.firstRequestId};
  bool dirty_ = true;

  // Requests.
  RequestLedger ledger_;
  std::vector<OutgoingRequest> queued_;
  std::vector<std::uint64_t> cancellations_;
  // Startup curve requests held back (deferCurveRequests), their mesh sizes,
  // and the one released last (its id; 0 = none).
  std::vector<std::pair<double, OutgoingRequest>> heldCurves_;
  std::uint64_t releasedCurve_ = 0;
  std::size_t curvesWanted_ = 0;
  std::map<std::uint32_t, std::uint64_t> curveRequestOfOption_;  // startup curve requests
  std::uint64_t posesPlanned_ = 0;

  // Current pose.
  bool inPose_ = false;
  protocol::ViewerPose pose_;
  backbone::ViewerState viewer_;
  std::uint64_t poseCounter_ = 0;
  std::optional<backbone::Plan> plan_;
  Status planStatus_;
  int plansThisPose_ = 0;
  std::uint32_t requestsThisPose_ = 0;
  double schedulingMicrosecondsThisPose_ = 0.0;
  // Objects a plan of this pose retired: a re-plan does not repeat them.
  std::vector<std::uint32_t> retiredThisPose_;

  // Frontend session.
  double lastTime_ = -1e300;
  std::optional<std::int64_t> lastPoseNs_;  // the clamped pose time (see beginPose)
  int posesBeyondStep_ = 0;                 // in a row, stamps beyond the step limit
  std::int64_t poseTimeNs_ = 0;
  std::int64_t lastShaperNs_ = std::numeric_limits<std::int64_t>::min();
  // The budget of this pose: options_.budget with the link schedule's rate.
  backbone::Budget budgetAtPose() const;
  // poseLinkReserve() at a given link rate (the budget's, computed once).
  double poseLinkReserve(std::optional<double> linkRate) const;
  double poseIntervalSeconds_ = 0.0;  // smoothed pose spacing (pose time); 0: unknown
  std::optional<protocol::LinkShaper> shaper_;
  std::uint64_t shapedBytes_ = 0;
  std::map<std::uint64_t, double> promised_;  // copy/request id -> time it was planned
  std::map<std::uint64_t, std::uint32_t> objectById_;  // wire object id -> object index
  // Per record: its Shape's skinned animation (null: static, a cluster).
  std::vector<const scene::SkinnedAnimation*> animationOf_;
  std::vector<float> animationOffsetOf_;  // its Inline's animationOffset (s)
  // Per record: 2 m / L, its motion bound over its bind reference length
  // (0: static); accuracies convert by anim::animatedRelativeAccuracy.
  std::vector<double> motionRatio_;
  std::size_t heldForeign_ = 0;
  std::size_t heldTakenBack_ = 0;
};

}  // namespace thinlod::backbone_daemon
