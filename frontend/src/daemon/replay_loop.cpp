#include "replay_loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <utility>

namespace thinlod::frontend::daemon {
namespace {

constexpr double kNsPerMs = 1e6;
constexpr double kNsPerS = 1e9;
// A bone matrix on the wire: three rows of four floats (payloadBytes counts the same).
constexpr std::uint64_t kWireBytesPerBoneMatrix = 48;

// An update handed to the renderer, not yet visible.
struct SubmittedUpdate {
  std::uint64_t plan = 0;
  std::uint64_t frame = 0;  // the pose it answered
  double targetAccuracy = 0.0;
};

protocol::ViewerPose wirePose(const Pose& pose, std::uint64_t sequence,
                              const ReplayOptions& options) {
  protocol::ViewerPose wire;
  wire.sequence = sequence;
  wire.timestampNs = secondsToNanoseconds(pose.time);
  wire.position = pose.position;
  wire.orientation = glm::normalize(pose.orientation);
  wire.fovY = pose.fovYRadians();
  wire.viewportWidth = options.viewportWidth;
  wire.viewportHeight = options.viewportHeight;
  return wire;
}

class Replay {
 public:
  Replay(PoseSource& source, const ReplayOptions& options, Clock& clock, BackboneLink& link,
         FrameProducer& producer, ReplayObserver& observer,
         const std::function<bool()>& stopRequested)
      : source_(source),
        options_(options),
        clock_(clock),
        link_(link),
        producer_(producer),
        observer_(observer),
        stop_(stopRequested) {}

  ReplayResult run() {
    const std::int64_t startNs = clock_.nowNs();
    std::uint64_t bytesBefore = link_.bytesReceived();
    std::optional<Pose> last;
    for (std::size_t i = 0; options_.maxFrames == 0 || i < options_.maxFrames; ++i) {
      if (stop_()) {
        result_.interrupted = true;
        break;
      }
      record_ = FrameRecord{};
      poseSent_ = false;
      source_.refresh();
      if (source_.ended()) break;  // every pose drawn: no slot to wait for
      // The frame's slot: a fixed rate, or the source's own timing at rate 0.
      if (options_.rate > 0.0) {
        waitUntil(startNs + std::llround(static_cast<double>(i) * kNsPerS / options_.rate),
                  [] { return false; });
      } else if (options_.rate == 0.0) {
        if (const auto due = source_.dueOffsetNs()) waitUntil(startNs + *due, [] { return false; });
      }
      // Its pose: a new one if the source has it (waiting for the first one,
      // and for every one at rate 0); at a rate, the last one drawn again.
      source_.refresh();
      if ((!last || options_.rate == 0.0) && !source_.ready() && !source_.ended()) {
        waitUntil(std::numeric_limits<std::int64_t>::max(), [&] {
          source_.refresh();
          return source_.ready() || source_.ended();
        });
      }
      if (stop_()) {
        result_.interrupted = true;
        break;
      }
      const bool fresh = source_.ready();
      if (!fresh && (source_.ended() || !last || options_.rate == 0.0)) break;
      const Pose pose = fresh ? source_.take() : *last;
      last = pose;
      if (!fresh) ++result_.framesRedrawingAPose;
      poseSentNs_.push_back(-1);
      poseTimeS_.push_back(pose.time);
      answered_.push_back(false);
      const std::int64_t sampledNs =
          fresh ? source_.lastArrivalNs().value_or(clock_.nowNs()) : clock_.nowNs();
      const std::int64_t sentNs = fresh ? sendPose(pose, i) : clock_.nowNs();
      absorb(link_.poll(std::chrono::milliseconds(0)));
      // One wait for this pose's answer: lockstep's (a miss is reported) or
      // the live answer wait's (a miss is only counted).
      const std::chrono::milliseconds answerWait =
          options_.lockstep ? options_.lockstepTimeout : options_.answerWait;
      if (poseSent_ && (options_.lockstep || answerWait.count() > 0)) {
        waitUntil(sentNs + answerWait.count() * 1'000'000LL,
                  [&] { return answered_[i] || !link_.connected(); });
        if (!answered_[i] && link_.connected() && !stop_()) {
          if (options_.lockstep) {
            record_.lockstepTimedOut = true;
            ++result_.lockstepTimeouts;
            observer_.onLockstepTimeout(i, (clock_.nowNs() - sentNs) / kNsPerMs);
          } else {
            ++result_.answerWaitsExpired;
          }
        }
      }
      record_.ownAnswer = poseSent_ && answered_[i];
      record_.waitMs = (clock_.nowNs() - sentNs) / kNsPerMs;

      Result<ProducedFrame> produced = producer_.renderFrame(i, pose);
      if (!produced.ok()) {
        result_.status = produced.status();
        break;
      }
      const std::int64_t frameDoneNs = clock_.nowNs();
      if (produced->held) {
        const Status held = link_.setHeld(std::move(*produced->held));
        if (!held.ok()) observer_.onSendFailed("Hello.held", i, held);
      }
      recordDrawn(i, pose, *produced, frameDoneNs);
      if (fresh) record_.poseToFrameMs = (frameDoneNs - sampledNs) / kNsPerMs;

      if (!firstSampledNs_) firstSampledNs_ = sampledNs;
      record_.shownAtMs = (frameDoneNs - *firstSampledNs_) / kNsPerMs;
      const bool deferred = options_.measure && options_.deferMeasure;
      if (deferred) {
        // The image and the pose it was drawn for; scored after the replay.
        if (!producer_.keepShown(i, pose, frameDoneNs)) ++result_.framesNotKept;
      } else if (options_.measure) {
        Result<FrameQuality> quality = producer_.measure(i, pose);
        if (!quality.ok()) {
          result_.status = quality.status();
          break;
        }
        record_.quality = *quality;
      }
      const std::uint64_t bytesNow = link_.bytesReceived();
      record_.linkBytes = bytesNow - bytesBefore;
      bytesBefore = bytesNow;
      sendStats(pose);
      ++result_.frames;
      observer_.onFrame(record_, deferred);
    }
    result_.posesSkipped = source_.skipped();
    if (options_.measure && options_.deferMeasure) scoreDeferred();
    return std::move(result_);
  }

 private:
  // Deferred measurement: the kept frames' scores, for the observer to merge
  // into the records it holds (by frame number).
  void scoreDeferred() {
    Result<std::vector<FrameScore>> scores = producer_.scoreKept();
    if (!scores.ok()) {
      if (result_.status.ok()) result_.status = scores.status();
      observer_.onFramesScored({});
      return;
    }
    observer_.onFramesScored(*scores);
  }

  // Polls the link in slices until `done()`, the deadline, or a stop request.
  template <typename Done>
  void waitUntil(std::int64_t deadlineNs, Done done) {
    while (!stop_() && !done()) {
      const std::int64_t now = clock_.nowNs();
      if (now >= deadlineNs) return;
      const std::int64_t remainingMs = (deadlineNs - now + 999'999) / 1'000'000;
      absorb(link_.poll(std::chrono::milliseconds(
                            std::min<std::int64_t>(remainingMs, options_.pollSlice.count())),
                        source_.wakeFd()));
      source_.refresh();  // also clears the descriptor's readability, or waits would spin
    }
  }

  // Returns the clock time of the send (also when it failed).
  std::int64_t sendPose(const Pose& pose, std::size_t frame) {
    const std::int64_t now = clock_.nowNs();
    if (!link_.connected()) {
      ++result_.posesNotSent;
      return now;
    }
    const Status sent = link_.send(wirePose(pose, frame, options_));
    if (!sent.ok()) {
      ++result_.posesNotSent;
      observer_.onSendFailed("ViewerPose", frame, sent);
      return now;
    }
    poseSentNs_[frame] = now;
    poseSent_ = true;
    return now;
  }

  void absorb(std::vector<protocol::SceneUpdate> updates) {
    for (protocol::SceneUpdate& update : updates) {
      ++result_.updatesReceived;
      ++record_.updatesReceived;
      for (const protocol::BonePose& pose : update.bonePoses)
        record_.poseBytes += kWireBytesPerBoneMatrix * pose.matrices.size();
      notePlanGap(update.plan);
      if (update.unitsKappa > 0.0) unitsKappa_ = update.unitsKappa;
      if (update.frame < answered_.size()) answered_[update.frame] = true;
      Result<SceneBatch> batch = convertUpdate(update, options_.conversion);
      // The pose time its bone poses were computed for: the timestamp of the
      // pose it answered (unknown for a frame this replay did not send).
      if (batch.ok() && update.frame < poseTimeS_.size())
        batch->poseTimeS = poseTimeS_[update.frame];
      const Status submitted =
          batch.ok() ? producer_.submit(std::move(batch).value()) : batch.status();
      if (!submitted.ok()) {
        ++result_.updatesRejected;
        ++record_.updatesRejected;
        observer_.onUpdateRejected(update, submitted);
        refusedPlans_.push_back(update.plan);  // the backbone corrects its mirror
        continue;
      }
      submitted_.push_back({update.plan, update.frame, update.targetAccuracy});
    }
  }

  // The backbone numbers the updates of its process 1, 2, ... (one per pose
  // it plans; the empty answer to a superseded pose has plan 0, no plan, and
  // is no evidence either way). A jump means updates lost on the way (or
  // never sent): they are reported as refused, so the backbone's mirror
  // takes back what they carried. Reporting a plan that carried nothing, or
  // one of an earlier session (whose mirror was reset), changes nothing
  // there, so the count starts at 0: the first update seen by a new
  // frontend reports every plan before it (at most kMaxRejectedPlans), and
  // a lost first update of a session is caught like any other. A smaller
  // number is a new backbone process counting from 1 again: the old
  // process's refusals mean nothing to it.
  void notePlanGap(std::uint64_t plan) {
    if (plan == 0) return;
    if (plan < lastPlanSeen_) {
      refusalsToRepeat_.clear();
      refusedPlans_.clear();  // all of the old process (this update is not absorbed yet)
      lastPlanSeen_ = 0;
    }
    if (plan > lastPlanSeen_ + 1) {
      const std::uint64_t first = std::max<std::uint64_t>(
          lastPlanSeen_ + 1,
          plan > protocol::kMaxRejectedPlans ? plan - protocol::kMaxRejectedPlans : 0);
      for (std::uint64_t missing = first; missing < plan; ++missing) {
        refusedPlans_.push_back(missing);
        ++result_.updatesMissed;
      }
    }
    lastPlanSeen_ = std::max(lastPlanSeen_, plan);
  }

  // The frame's identity and what was drawn, into record_.
  void recordDrawn(std::size_t frame, const Pose& pose, const ProducedFrame& produced,
                   std::int64_t frameDoneNs) {
    FrameRecord& record = record_;
    record.frame = frame;
    record.timeS = pose.time;
    record.polygons = produced.triangles;
    record.points = produced.points;
    record.units = primitiveUnits(produced.triangles, produced.points, unitsKappa_);
    record.plan = produced.appliedPlan;
    record.earlyPolygons = std::min(produced.earlyPolygons, produced.triangles);
    record.renderMs = produced.renderMs;
    record.drawCalls = produced.drawCalls;
    record.uploadedBytes = produced.uploadedBytes;
    record.skinnedObjects = produced.skinnedObjects;
    record.deformedVertices = produced.deformedVertices;
    if (produced.droppedBatches > 0) observer_.onUploadDropped(frame, produced.lastUploadError);
    refusedPlans_.insert(refusedPlans_.end(), produced.droppedPlans.begin(),
                         produced.droppedPlans.end());
    if (produced.committedBatches > 0) {
      result_.updatesApplied += produced.committedBatches;
      // Batches become visible in arrival order; the newest visible one is
      // the first queued with the applied plan.
      auto newest = std::find_if(submitted_.begin(), submitted_.end(),
                                 [&](const auto& u) { return u.plan == produced.appliedPlan; });
      if (newest != submitted_.end()) {
        targetAccuracy_ = newest->targetAccuracy;
        if (newest->frame < poseSentNs_.size() && poseSentNs_[newest->frame] >= 0) {
          record.updateLatencyMs = (frameDoneNs - poseSentNs_[newest->frame]) / kNsPerMs;
        }
        submitted_.erase(submitted_.begin(), newest + 1);
      }
    }
    record.targetAccuracy = targetAccuracy_;
  }

  void sendStats(const Pose& pose) {
    if (!link_.connected()) return;
    // A FrameStats can be lost like any message, so each refusal is reported
    // in kRefusalReports FrameStats in a row (a repeat is a no-op at the
    // backbone). Oldest first; a flood beyond the message's limit keeps the
    // newest.
    std::vector<std::uint64_t> report;
    for (const auto& [plan, left] : refusalsToRepeat_) report.push_back(plan);
    report.insert(report.end(), refusedPlans_.begin(), refusedPlans_.end());
    const std::size_t skip = report.size() > protocol::kMaxRejectedPlans
                                 ? report.size() - protocol::kMaxRejectedPlans
                                 : 0;
    report.erase(report.begin(), report.begin() + static_cast<std::ptrdiff_t>(skip));
    const Status sent =
        link_.send(toFrameStats(record_, secondsToNanoseconds(pose.time), std::move(report)));
    if (!sent.ok()) {
      observer_.onSendFailed("FrameStats", record_.frame, sent);
      return;
    }
    for (auto it = refusalsToRepeat_.begin(); it != refusalsToRepeat_.end();)
      it = --it->second == 0 ? refusalsToRepeat_.erase(it) : std::next(it);
    if (kRefusalReports > 1)
      for (std::uint64_t plan : refusedPlans_)
        refusalsToRepeat_.push_back({plan, kRefusalReports - 1});
    while (refusalsToRepeat_.size() > protocol::kMaxRejectedPlans) refusalsToRepeat_.pop_front();
    refusedPlans_.clear();
  }

  PoseSource& source_;
  const ReplayOptions& options_;
  Clock& clock_;
  BackboneLink& link_;
  FrameProducer& producer_;
  ReplayObserver& observer_;
  const std::function<bool()>& stop_;
  std::vector<std::int64_t> poseSentNs_;  // -1: not sent
  std::vector<double> poseTimeS_;         // each frame's pose time (SceneBatch::poseTimeS)
  std::vector<bool> answered_;            // an update for this pose arrived
  std::deque<SubmittedUpdate> submitted_;
  // Plans of updates refused, dropped or missed since the last FrameStats.
  std::vector<std::uint64_t> refusedPlans_;
  // Refusals already reported, with the reports still to repeat them.
  static constexpr int kRefusalReports = 3;
  std::deque<std::pair<std::uint64_t, int>> refusalsToRepeat_;
  std::uint64_t lastPlanSeen_ = 0;  // the highest plan number of this backbone process
  double targetAccuracy_ = kMissingValue;
  double unitsKappa_ = 0.0;  // the newest SceneUpdate.unitsKappa > 0 (0: none yet)
  std::optional<std::int64_t> firstSampledNs_;  // frame 0's pose
  FrameRecord record_;                          // the frame being made
  bool poseSent_ = false;                       // this frame's pose went out
  ReplayResult result_;
};

}  // namespace

std::int64_t SteadyClock::nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

ReplayResult runReplay(PoseSource& source, const ReplayOptions& options, Clock& clock,
                       BackboneLink& link, FrameProducer& producer, ReplayObserver& observer,
                       const std::function<bool()>& stopRequested) {
  return Replay(source, options, clock, link, producer, observer, stopRequested).run();
}

ReplayResult runReplay(const Trace& trace, const ReplayOptions& options, Clock& clock,
                       BackboneLink& link, FrameProducer& producer, ReplayObserver& observer,
                       const std::function<bool()>& stopRequested) {
  if (trace.poses.empty()) {
    ReplayResult result;
    result.status = Status(ErrorCode::kInvalidArgument, "trace has no poses");
    return result;
  }
  TracePoseSource source(trace);
  return runReplay(source, options, clock, link, producer, observer, stopRequested);
}

}  // namespace thinlod::frontend::daemon
