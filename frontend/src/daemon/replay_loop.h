// The trace replay of thinlod-frontend, independent of sockets, GL and the
// wall clock so it can be tested with fakes (docs/frontend.md, "Daemon").
//
// Contract:
// - runReplay() drives frames i = 0, 1, ... (up to maxFrames) from a
//   PoseSource (pose_source.h; a Trace is wrapped in a TracePoseSource): wait
//   for the frame's slot (pacing), take the frame's pose, send
//   ViewerPose{sequence = i, timestampNs = pose time in ns}, take what the
//   link has (0 ms) or, in lockstep, wait up
//   to lockstepTimeout for the SceneUpdate with frame == i (live with
//   answerWait > 0: up to answerWait, silently); convert and submit
//   every update in arrival order (a bad update is rejected whole); render
//   the frame; then measure it against the reference (FrameProducer::measure
//   fills FrameRecord::quality), hand the frame's FrameRecord to
//   ReplayObserver::onFrame and send FrameStats (toFrameStats, wire_conversion.h).
// - Refusals: FrameStats.rejectedPlans lists the plans of updates refused
//   (bad update, upload dropped) and of updates missed (a jump in the plan
//   numbers of one backbone process: lost on the way); each is repeated in 3
//   FrameStats in a row, since a FrameStats can be lost too.
// - Resynchronisation: whenever a frame's holdings changed
//   (ProducedFrame::held), they go to BackboneLink::setHeld, so the Hello a
//   reconnect says (a restarted or timed-out backbone) tells the new session
//   what is held; the frontend keeps drawing it meanwhile.
// - Memory: the loop keeps no records (the observer streams them, e.g. into a
//   FrameLog); per frame it keeps 16 bytes (when the pose was sent, for
//   update_latency_ms of a later answer, and the pose's time, which the
//   answer's bone poses were computed for: SceneBatch::poseTimeS) and 1 bit
//   (answered), whatever the run length.
// - Deferred measurement (measure && deferMeasure, the live workbench mode):
//   instead of rendering the reference inline, the frame just shown is kept
//   with the pose it was drawn for (FrameProducer::keepShown) and nothing
//   else delays the client. After the last frame (also after a stop),
//   FrameProducer::scoreKept scores every kept frame against the reference of
//   its own pose and ReplayObserver::onFramesScored gets the scores once
//   (ascending by frame; empty when scoring failed) to merge into the records
//   it was given with scorePending = true (FrameLog::applyScores).
// - Waiting is always link.poll(timeout, source.wakeFd()) in slices of at
//   most pollSlice, then source.refresh(), so updates and poses keep flowing
//   (a pose is stamped when it is read) and a stop request ends the wait
//   within one slice.
//   Nothing blocks on the network except the bounded lockstep wait, which
//   ends early when the link is not connected.
// - Pacing: rate > 0: frame i starts at start + i / rate; rate == 0: at start
//   + (t_i - t_0) of a trace, or when the next pose of a stream arrives;
//   rate < 0: unpaced (frames back to back). Late frames start at once (the
//   schedule is not re-anchored).
// - Poses: each frame takes a new pose when the source has one; before the
//   first pose, and at rate 0 before every one, the loop waits for it (input
//   keeps flowing). At a rate (or unpaced) with nothing new from a stream,
//   the frame draws the last pose again: no pose is sent, no lockstep wait,
//   pose_to_frame_ms is NaN, and framesRedrawingAPose counts it. The replay
//   ends when the source has ended and its last pose was drawn.
// - Answer wait (live, answerWait > 0, ignored in lockstep): after sending a
//   fresh pose the loop waits up to answerWait for the update answering it,
//   so a frame can show the plan for its own pose rather than the previous
//   one; an answer still missing then is counted (answerWaitsExpired), not
//   logged, and the frame draws what it holds. FrameRecord::ownAnswer says
//   whether the frame's own answer had arrived, in every mode.
// - pose_to_frame_ms: every frame with a new pose: clock time when the frame
//   was read back minus clock time when its pose was sampled: a trace pose
//   when the frame takes it at its slot, a stream pose when it was read
//   (PoseSource::lastArrivalNs). In lockstep it includes the wait.
// - update_latency_ms: on a frame where at least one update became visible,
//   clock time when the frame was read back minus clock time when the pose
//   that the newest visible update answered (SceneUpdate.frame) was sent;
//   NaN on other frames or when that pose was not sent by this process.
// - link_bytes: link.bytesReceived() since the previous frame; pose_bytes: the
//   bone poses of the updates received since then, 48 bytes a matrix (also
//   those of updates then rejected: they crossed the link).
// - points: hybrid discs drawn; units: primitiveUnits(triangles, points,
//   kappa) (frame_record.h), kappa the SceneUpdate.unitsKappa of the newest
//   update received with one (> 0): what the backbone's budget counts.
// - Errors: a failed render or measurement ends the replay; the frames so
//   far have been handed on and the Status is in ReplayResult::status.
// - Single-threaded; the interfaces are called from the caller's thread.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pose_source.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/core/trace.h"
#include "thinlod/frontend/frame_record.h"
#include "thinlod/frontend/frontend_scene.h"
#include "thinlod/protocol/messages.h"
#include "wire_conversion.h"

namespace thinlod::frontend::daemon {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t nowNs() = 0;  // monotonic
};

class SteadyClock final : public Clock {
 public:
  std::int64_t nowNs() override;
};

// The backbone as the loop sees it.
class BackboneLink {
 public:
  virtual ~BackboneLink() = default;
  virtual bool connected() const = 0;
  virtual Status send(const protocol::Message& message) = 0;
  // Waits up to `timeout` for input (less when something arrives, `wakeFd`
  // (if >= 0) becomes readable, or a stop is requested) and returns the
  // SceneUpdates received, in order.
  virtual std::vector<protocol::SceneUpdate> poll(std::chrono::milliseconds timeout,
                                                  int wakeFd = -1) = 0;
  virtual std::uint64_t bytesReceived() const = 0;  // encoded bytes, all messages, ever
  // What the frontend holds now, for the Hello of every later (re)connect
  // (Hello.held): a new backbone session starts its mirror from it.
  virtual Status setHeld(std::vector<protocol::HeldRepresentation> held) = 0;
};

struct ProducedFrame {
  std::size_t triangles = 0;  // drawn
  std::size_t points = 0;     // hybrid disc points drawn (FrameReport::discs)
  std::uint64_t appliedPlan = 0;
  std::size_t earlyPolygons = 0;  // of triangles, first representations shown before their plan
  std::size_t committedBatches = 0;
  std::size_t droppedBatches = 0;
  std::vector<std::uint64_t> droppedPlans;  // plans of the dropped batches
  std::string lastUploadError;
  double renderMs = 0.0;
  std::size_t drawCalls = 0;
  std::size_t uploadedBytes = 0;
  std::size_t skinnedObjects = 0;    // FrameReport::skinnedObjects
  std::size_t deformedVertices = 0;  // FrameReport::deformedVertices
  // Set when what the frontend holds changed since the previous frame
  // (heldRepresentations of the scene drawn); the loop hands it to
  // BackboneLink::setHeld.
  std::optional<std::vector<protocol::HeldRepresentation>> held;
};

// Renders the frontend frame and its reference.
class FrameProducer {
 public:
  virtual ~FrameProducer() = default;
  virtual Status submit(SceneBatch batch) = 0;
  virtual Result<ProducedFrame> renderFrame(std::uint64_t frame, const Pose& pose) = 0;
  // Compares the frame just rendered with the full-quality frame of `pose`.
  virtual Result<FrameQuality> measure(std::uint64_t frame, const Pose& pose) = 0;
  // Deferred measurement: keeps the frame just rendered with the pose it was
  // drawn for and the clock time it was shown. false: not kept (memory bound,
  // or a producer that cannot defer).
  virtual bool keepShown(std::uint64_t /*frame*/, const Pose& /*pose*/,
                         std::int64_t /*shownAtNs*/) {
    return false;
  }
  // Scores every kept frame against the reference of its own pose.
  // Ascending by frame.
  virtual Result<std::vector<FrameScore>> scoreKept() { return std::vector<FrameScore>{}; }
};

// Hooks for logs and outputs; every method has a no-op default.
class ReplayObserver {
 public:
  virtual ~ReplayObserver() = default;
  // Every frame, in order, once drawn (and measured inline). scorePending:
  // deferred measurement, the record's quality comes with onFramesScored.
  virtual void onFrame(const FrameRecord&, bool /*scorePending*/) {}
  // Deferred measurement only, once after the replay (also after a stop or
  // an error): the kept frames' scores, ascending by frame.
  virtual void onFramesScored(const std::vector<FrameScore>&) {}
  virtual void onUpdateRejected(const protocol::SceneUpdate&, const Status&) {}
  virtual void onLockstepTimeout(std::uint64_t /*frame*/, double /*waitedMs*/) {}
  virtual void onUploadDropped(std::uint64_t /*frame*/, const std::string& /*error*/) {}
  virtual void onSendFailed(const char* /*what*/, std::uint64_t /*frame*/, const Status&) {}
};

// The defaults of the daemon's options (daemon_options.h binds them here).
struct ReplayOptions {
  bool lockstep = false;
  std::chrono::milliseconds lockstepTimeout{5000};
  std::chrono::milliseconds answerWait{0};  // live only; see "Answer wait"
  double rate = 0.0;          // see the pacing rule above
  std::size_t maxFrames = 0;  // 0: every pose of the trace
  bool measure = true;        // false: no reference, SNR/PSNR missing
  bool deferMeasure = false;  // with measure: keep shown frames, score after the replay
  std::uint32_t viewportWidth = 0;
  std::uint32_t viewportHeight = 0;
  std::chrono::milliseconds pollSlice{50};
  ConversionOptions conversion;
};

struct ReplayResult {
  std::size_t frames = 0;  // handed to ReplayObserver::onFrame
  std::size_t updatesReceived = 0;
  std::size_t updatesApplied = 0;  // became visible
  std::size_t updatesRejected = 0;
  // Plan numbers skipped by the updates that arrived (lost on the way);
  // reported as refused in FrameStats.
  std::size_t updatesMissed = 0;
  std::size_t lockstepTimeouts = 0;
  std::size_t answerWaitsExpired = 0;  // live answer waits that ended without the answer
  std::size_t posesNotSent = 0;  // link down at the time
  std::size_t posesSkipped = 0;  // a stream's poses overtaken by newer ones before a frame
  std::size_t framesRedrawingAPose = 0;
  std::size_t framesNotKept = 0;  // deferred measurement: over the memory bound, never scored
  bool interrupted = false;       // stopRequested() ended it early
  Status status;                  // why it ended early with an error
};

ReplayResult runReplay(PoseSource& source, const ReplayOptions& options, Clock& clock,
                       BackboneLink& link, FrameProducer& producer, ReplayObserver& observer,
                       const std::function<bool()>& stopRequested);
// A trace without poses is kInvalidArgument in ReplayResult::status.
ReplayResult runReplay(const Trace& trace, const ReplayOptions& options, Clock& clock,
                       BackboneLink& link, FrameProducer& producer, ReplayObserver& observer,
                       const std::function<bool()>& stopRequested);

}  // namespace thinlod::frontend::daemon
