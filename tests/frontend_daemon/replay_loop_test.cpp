// The replay loop with a fake clock, a scripted backbone link and a producer
// around a real FrontendScene: pacing, lockstep, latency, rejects, stop.
#include "replay_loop.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <utility>

#include "daemon_test_util.h"

namespace thinlod::frontend::daemon {
namespace {

using testing::addOp;
using testing::meshRepresentation;
using testing::sphereMesh;

constexpr std::int64_t kMs = 1'000'000;

class FakeClock final : public Clock {
 public:
  std::int64_t nowNs() override { return now; }
  std::int64_t now = 1000 * kMs;
};

// A backbone that answers poses as `responder` says, after a delay.
class FakeLink final : public BackboneLink {
 public:
  using Responder = std::function<std::optional<std::pair<std::int64_t, protocol::SceneUpdate>>(
      const protocol::ViewerPose&)>;
  explicit FakeLink(FakeClock& clock) : clock_(clock) {}

  bool connected() const override { return up && clock_.now < dropAtNs; }
  Status send(const protocol::Message& message) override {
    if (!connected()) return Status(ErrorCode::kUnavailable, "down");
    if (const auto* pose = std::get_if<protocol::ViewerPose>(&message)) {
      poses.push_back(*pose);
      poseSentNs.push_back(clock_.now);
      if (responder) {
        if (auto reply = responder(*pose)) {
          inFlight.emplace_back(clock_.now + reply->first, std::move(reply->second));
        }
      }
    } else if (const auto* stats = std::get_if<protocol::FrameStats>(&message)) {
      frameStats.push_back(*stats);
    }
    return Status();
  }
  std::vector<protocol::SceneUpdate> poll(std::chrono::milliseconds timeout, int wakeFd) override {
    wakeFds.insert(wakeFd);
    const std::int64_t deadline = clock_.now + timeout.count() * kMs;
    std::int64_t wake = deadline;
    for (const auto& [at, update] : inFlight) wake = std::min(wake, std::max(at, clock_.now));
    if (dropAtNs > clock_.now) wake = std::min(wake, dropAtNs);
    clock_.now = wake;
    std::vector<protocol::SceneUpdate> arrived;
    for (auto it = inFlight.begin(); it != inFlight.end();) {
      if (it->first <= clock_.now) {
        bytes += 1000 + payloadBytes(it->second);
        arrived.push_back(std::move(it->second));
        it = inFlight.erase(it);
      } else {
        ++it;
      }
    }
    return arrived;
  }
  std::uint64_t bytesReceived() const override { return bytes; }
  Status setHeld(std::vector<protocol::HeldRepresentation> h) override {
    held.push_back(std::move(h));
    return Status();
  }

  bool up = true;
  std::vector<std::vector<protocol::HeldRepresentation>> held;  // every setHeld, in order
  std::int64_t dropAtNs = std::numeric_limits<std::int64_t>::max();
  Responder responder;
  std::vector<protocol::ViewerPose> poses;
  std::vector<std::int64_t> poseSentNs;
  std::vector<protocol::FrameStats> frameStats;
  std::vector<std::pair<std::int64_t, protocol::SceneUpdate>> inFlight;
  std::uint64_t bytes = 0;
  std::set<int> wakeFds;  // every wakeFd poll() was given

 private:
  FakeClock& clock_;
};

// Uploads everything at once; render and measure take fixed clock time.
class SceneProducer final : public FrameProducer {
 public:
  explicit SceneProducer(FakeClock& clock) : clock_(clock) {}
  Status submit(SceneBatch batch) override {
    submittedPoseTimes.push_back(batch.poseTimeS);
    return scene.enqueue(std::move(batch));
  }
  Result<ProducedFrame> renderFrame(std::uint64_t frame, const Pose&) override {
    if (failAtFrame && *failAtFrame == frame) return Status(ErrorCode::kInternal, "GL lost");
    renderStartNs.push_back(clock_.now);
    for (const PendingUpload& upload : scene.planUploads(~std::size_t{0})) {
      EXPECT_TRUE(scene.markUploaded(upload.key).ok());
    }
    const CommitResult committed = scene.commitReady();
    clock_.now += renderNs;
    ProducedFrame produced;
    produced.triangles = scene.polygons();
    produced.points = points;
    produced.appliedPlan = scene.lastAppliedPlan();
    produced.committedBatches = committed.plans.size();
    produced.renderMs = static_cast<double>(renderNs) / kMs;
    if (committed.changed()) produced.held = heldRepresentations(scene);
    return produced;
  }
  Result<FrameQuality> measure(std::uint64_t, const Pose&) override {
    clock_.now += measureNs;
    FrameQuality quality;
    quality.snrDb = snrDb;
    quality.psnrDb = 30.0;
    quality.referenceMs = static_cast<double>(measureNs) / kMs;
    return quality;
  }

  FrontendScene scene;
  std::int64_t renderNs = 5 * kMs;
  std::int64_t measureNs = 20 * kMs;
  double snrDb = 12.0;
  std::size_t points = 0;  // discs "drawn" every frame
  std::optional<std::uint64_t> failAtFrame;
  std::vector<double> submittedPoseTimes;  // SceneBatch::poseTimeS of each submit
  std::vector<std::int64_t> renderStartNs;

 private:
  FakeClock& clock_;
};

// Collects the records the loop hands on; deferred scores are merged by a
// real FrameLog (no CSV), as the daemon does.
class RecordingObserver final : public ReplayObserver {
 public:
  void onUpdateRejected(const protocol::SceneUpdate& update, const Status& why) override {
    rejectedPlans.push_back(update.plan);
    reasons.push_back(why.message());
  }
  void onLockstepTimeout(std::uint64_t frame, double) override { timeouts.push_back(frame); }
  void onFrame(const FrameRecord& record, bool scorePending) override {
    frames.push_back(record.frame);
    pendingDuringReplay.push_back(scorePending);
    snrDuringReplay.push_back(record.quality.snrDb);
    if (scorePending) {
      EXPECT_TRUE(log->addPending(record).ok());
    } else {
      records.push_back(record);
    }
  }
  void onFramesScored(const std::vector<FrameScore>& scores) override {
    ++scoredCalls;
    EXPECT_TRUE(log->applyScores(scores,
                                 [this](const FrameRecord& record) {
                                   records.push_back(record);
                                   scoredFrames.push_back(record.frame);
                                   scoredSnr.push_back(record.quality.snrDb);
                                   missing.push_back(record.quality.missingObjects);
                                 })
                    .ok());
  }
  std::vector<std::uint64_t> rejectedPlans;
  std::vector<std::string> reasons;
  std::vector<std::uint64_t> timeouts;
  std::vector<std::uint64_t> frames;
  std::vector<FrameRecord> records;  // finished: scored or never pending
  std::vector<bool> pendingDuringReplay;
  std::vector<double> snrDuringReplay;
  int scoredCalls = 0;
  std::vector<std::uint64_t> scoredFrames;
  std::vector<double> scoredSnr;
  std::vector<long> missing;
  std::unique_ptr<FrameLog> log = std::move(FrameLog::open("")).value();
};
using ScoreObserver = RecordingObserver;

// The loop's result with the records its observer collected.
struct Replayed : ReplayResult {
  std::vector<FrameRecord> records;
};

Replayed collect(ReplayResult result, const RecordingObserver& observer) {
  Replayed replayed;
  static_cast<ReplayResult&>(replayed) = std::move(result);
  replayed.records = observer.records;
  EXPECT_EQ(replayed.frames, replayed.records.size());
  return replayed;
}

Trace traceAt(const std::vector<double>& times) {
  Trace trace;
  for (std::size_t i = 0; i < times.size(); ++i) {
    Pose pose;
    pose.time = times[i];
    pose.position = glm::vec3(static_cast<float>(i), 1.0f, 5.0f);
    pose.fovYDegrees = 45.0f;
    trace.poses.push_back(pose);
  }
  return trace;
}

// A live stream on the fake clock: pose k becomes readable at arrivalsMs[k]
// and, like a real stream, is stamped when refresh() reads it.
class ScriptedStream final : public PoseSource {
 public:
  ScriptedStream(FakeClock& clock, std::vector<std::int64_t> arrivalsMs)
      : clock_(clock), start_(clock.now), arrivalsMs_(std::move(arrivalsMs)) {}
  void refresh() override {
    while (delivered_ < arrivalsMs_.size() &&
           clock_.now - start_ >= arrivalsMs_[delivered_] * kMs) {
      if (newest_) ++skipped_;
      Pose pose;
      pose.time = static_cast<double>(arrivalsMs_[delivered_]) / 1000.0;
      pose.position = glm::vec3(static_cast<float>(delivered_), 1.0f, 5.0f);
      newest_ = pose;
      newestArrivalNs_ = clock_.now;
      ++delivered_;
    }
  }
  bool ready() const override { return newest_.has_value(); }
  Pose take() override {
    Pose pose = *newest_;
    newest_.reset();
    lastArrivalNs_ = newestArrivalNs_;
    return pose;
  }
  bool ended() const override { return !newest_ && delivered_ == arrivalsMs_.size(); }
  std::optional<std::int64_t> lastArrivalNs() const override { return lastArrivalNs_; }
  int wakeFd() const override { return ended() ? -1 : kStreamFd; }
  static constexpr int kStreamFd = 42;
  std::optional<std::int64_t> dueOffsetNs() const override { return std::nullopt; }
  std::size_t skipped() const override { return skipped_; }

 private:
  FakeClock& clock_;
  std::int64_t start_;
  std::vector<std::int64_t> arrivalsMs_;
  std::size_t delivered_ = 0;
  std::optional<Pose> newest_;
  std::int64_t newestArrivalNs_ = 0;
  std::optional<std::int64_t> lastArrivalNs_;
  std::size_t skipped_ = 0;
};

// Update answering pose `frame`: object `id` becomes a sphere with 8*4-ish triangles.
protocol::SceneUpdate sphereUpdate(std::uint64_t plan, std::uint64_t frame, std::uint64_t id,
                                   double target) {
  protocol::SceneUpdate update;
  update.plan = plan;
  update.frame = frame;
  update.targetAccuracy = target;
  update.operations.push_back(addOp(id, meshRepresentation(sphereMesh(1.0f, 8, 4))));
  return update;
}

const std::size_t kSphereTriangles = sphereMesh(1.0f, 8, 4).triangleCount();

class ReplayLoopTest : public ::testing::Test {
 protected:
  Replayed run(const Trace& trace) {
    return collect(
        runReplay(trace, options, clock, link, producer, observer, [this] { return stop(); }),
        observer);
  }
  Replayed run(PoseSource& stream) {
    return collect(
        runReplay(stream, options, clock, link, producer, observer, [] { return false; }),
        observer);
  }
  FakeClock clock;
  FakeLink link{clock};
  SceneProducer producer{clock};
  RecordingObserver observer;
  ReplayOptions options;
  std::function<bool()> stop = [] { return false; };
};

TEST_F(ReplayLoopTest, LockstepAppliesEachAnswerInTheFrameOfItsPose) {
  options.lockstep = true;
  options.rate = -1.0;
  options.viewportWidth = 640;
  options.viewportHeight = 480;
  link.responder = [](const protocol::ViewerPose& pose) {
    return std::make_optional(
        std::make_pair(3 * kMs, sphereUpdate(pose.sequence + 1, pose.sequence,
                                             pose.sequence % 2 + 1, 10.0 * (pose.sequence + 1))));
  };
  const Trace trace = traceAt({0.0, 0.1, 0.2, 0.35});
  Replayed result = run(trace);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  ASSERT_EQ(result.records.size(), 4u);
  EXPECT_EQ(result.updatesReceived, 4u);
  EXPECT_EQ(result.updatesApplied, 4u);
  EXPECT_EQ(result.lockstepTimeouts, 0u);
  for (std::size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    const FrameRecord& r = result.records[i];
    EXPECT_EQ(r.frame, i);
    EXPECT_DOUBLE_EQ(r.timeS, trace.poses[i].time);
    EXPECT_EQ(r.plan, i + 1);
    EXPECT_DOUBLE_EQ(r.targetAccuracy, 10.0 * (i + 1));
    EXPECT_EQ(r.polygons, (i == 0 ? 1 : 2) * kSphereTriangles);
    // Answer after 3 ms, then 5 ms of rendering: in lockstep the frame's own
    // latency includes the wait, and the update shown is this pose's answer.
    EXPECT_DOUBLE_EQ(r.poseToFrameMs, 8.0);
    EXPECT_DOUBLE_EQ(r.updateLatencyMs, 8.0);
    EXPECT_DOUBLE_EQ(result.records[i].waitMs, 3.0);
    EXPECT_DOUBLE_EQ(r.renderMs, 5.0);
    EXPECT_DOUBLE_EQ(r.quality.snrDb, 12.0);
    EXPECT_DOUBLE_EQ(result.records[i].quality.referenceMs, 20.0);
    EXPECT_GT(r.linkBytes, 1000u);
    // The pose on the wire.
    const protocol::ViewerPose& pose = link.poses[i];
    EXPECT_EQ(pose.sequence, i);
    EXPECT_EQ(pose.timestampNs, std::llround(trace.poses[i].time * 1e9));
    EXPECT_EQ(pose.position, trace.poses[i].position);
    EXPECT_FLOAT_EQ(pose.fovY, glm::radians(45.0f));
    EXPECT_EQ(pose.viewportWidth, 640u);
    EXPECT_EQ(pose.viewportHeight, 480u);
    // FrameStats back.
    const protocol::FrameStats& stats = link.frameStats[i];
    EXPECT_EQ(stats.frame, i);
    EXPECT_EQ(stats.plan, i + 1);
    EXPECT_EQ(stats.polygons, r.polygons);
    EXPECT_EQ(stats.linkBytes, r.linkBytes);
    EXPECT_TRUE(stats.hasSnr);
    EXPECT_DOUBLE_EQ(stats.snrDb, 12.0);
  }
}

// Live with an answer wait: a frame whose answer comes within the wait shows
// it (ownAnswer), one whose answer is later draws what it holds after the
// wait, without a lockstep timeout or a warning; without the wait the same
// answers show a frame late.
TEST_F(ReplayLoopTest, AnswerWaitShowsAnAnswerThatComesWithinIt) {
  options.rate = 0.0;  // the trace's own timing: 100 ms per frame
  link.responder = [](const protocol::ViewerPose& pose) {
    // Frame 1's answer takes 30 ms, the others 1 ms.
    const std::int64_t delay = pose.sequence == 1 ? 30 * kMs : 1 * kMs;
    return std::make_optional(std::make_pair(
        delay, sphereUpdate(pose.sequence + 1, pose.sequence, 1, 10.0 * (pose.sequence + 1))));
  };
  const Trace trace = traceAt({0.0, 0.1, 0.2});

  options.answerWait = std::chrono::milliseconds(2);
  Replayed waited = run(trace);
  ASSERT_TRUE(waited.status.ok()) << waited.status.toString();
  ASSERT_EQ(waited.records.size(), 3u);
  EXPECT_EQ(waited.answerWaitsExpired, 1u);
  EXPECT_EQ(waited.lockstepTimeouts, 0u);
  EXPECT_TRUE(observer.timeouts.empty()) << "an expired answer wait is not a lockstep timeout";
  EXPECT_TRUE(waited.records[0].ownAnswer);
  EXPECT_DOUBLE_EQ(waited.records[0].waitMs, 1.0);
  EXPECT_EQ(waited.records[0].plan, 1u);
  EXPECT_FALSE(waited.records[1].ownAnswer);
  EXPECT_DOUBLE_EQ(waited.records[1].waitMs, 2.0);  // the whole wait, then what it holds
  EXPECT_EQ(waited.records[1].plan, 1u);
  EXPECT_TRUE(waited.records[2].ownAnswer);
  EXPECT_EQ(waited.records[2].plan, 3u);
}

TEST_F(ReplayLoopTest, WithoutAnAnswerWaitTheAnswerShowsAFrameLate) {
  options.rate = 0.0;
  link.responder = [](const protocol::ViewerPose& pose) {
    return std::make_optional(std::make_pair(
        1 * kMs, sphereUpdate(pose.sequence + 1, pose.sequence, 1, 10.0 * (pose.sequence + 1))));
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2}));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  ASSERT_EQ(result.records.size(), 3u);
  EXPECT_EQ(result.answerWaitsExpired, 0u);
  for (std::size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE(i);
    EXPECT_FALSE(result.records[i].ownAnswer);
    EXPECT_DOUBLE_EQ(result.records[i].waitMs, 0.0);
    EXPECT_EQ(result.records[i].plan, i);  // the previous pose's answer (none for frame 0)
  }
}

TEST_F(ReplayLoopTest, LockstepTimeoutRendersWhatItHolds) {
  options.lockstep = true;
  options.lockstepTimeout = std::chrono::milliseconds(40);
  options.rate = -1.0;
  link.responder = [](const protocol::ViewerPose& pose) {
    std::optional<std::pair<std::int64_t, protocol::SceneUpdate>> reply;
    if (pose.sequence == 0) reply = std::make_pair(2 * kMs, sphereUpdate(1, 0, 1, 5.0));
    return reply;
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2}));
  ASSERT_EQ(result.records.size(), 3u);
  EXPECT_EQ(result.lockstepTimeouts, 2u);
  EXPECT_EQ(observer.timeouts, (std::vector<std::uint64_t>{1, 2}));
  for (std::size_t i = 1; i < 3; ++i) {
    EXPECT_TRUE(result.records[i].lockstepTimedOut);
    EXPECT_DOUBLE_EQ(result.records[i].waitMs, 40.0);
    EXPECT_EQ(result.records[i].polygons, kSphereTriangles);
    EXPECT_EQ(result.records[i].plan, 1u);
    EXPECT_DOUBLE_EQ(result.records[i].targetAccuracy, 5.0);
    EXPECT_TRUE(std::isnan(result.records[i].updateLatencyMs));  // nothing new shown
    EXPECT_DOUBLE_EQ(result.records[i].poseToFrameMs, 45.0);     // the whole wait + render
  }
}

TEST_F(ReplayLoopTest, LiveModeAppliesALateAnswerWhenItArrivesWithItsTrueLatency) {
  options.rate = 10.0;  // one frame every 100 ms
  link.responder = [](const protocol::ViewerPose& pose) {
    std::optional<std::pair<std::int64_t, protocol::SceneUpdate>> reply;
    if (pose.sequence == 0) reply = std::make_pair(130 * kMs, sphereUpdate(1, 0, 1, 5.0));
    return reply;
  };
  const std::int64_t start = clock.now;
  Replayed result = run(traceAt({0.0, 0.1, 0.2, 0.3}));
  ASSERT_EQ(result.records.size(), 4u);
  ASSERT_EQ(producer.renderStartNs.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(producer.renderStartNs[i] - start, static_cast<std::int64_t>(i) * 100 * kMs);
  }
  // Arrived at 130 ms, during the wait for frame 2's slot: drawn in frame 2.
  EXPECT_EQ(result.records[1].polygons, 0u);
  EXPECT_EQ(result.records[2].polygons, kSphereTriangles);
  EXPECT_EQ(result.records[2].plan, 1u);
  EXPECT_DOUBLE_EQ(result.records[2].updateLatencyMs, 205.0);  // slot 200 + 5 ms render
  EXPECT_TRUE(std::isnan(result.records[3].updateLatencyMs));  // nothing new in frame 3
  // Live frames do not wait: each pose is drawn 5 ms (the render) after it was sampled.
  for (const FrameRecord& record : result.records) EXPECT_DOUBLE_EQ(record.poseToFrameMs, 5.0);
  EXPECT_EQ(result.records[2].linkBytes, link.bytes);
  EXPECT_EQ(result.records[3].linkBytes, 0u);
}

TEST_F(ReplayLoopTest, PoseBytesCountTheBonePosesOfTheUpdatesReceivedInTheFrame) {
  options.rate = 10.0;  // one frame every 100 ms
  // Pose 0's answer brings a sphere and no pose; poses 1 and 2 are answered
  // with two objects' poses (3 and 5 matrices), pose 2's 30 ms late (while
  // frame 3 waits for its slot), so frame 2 receives nothing and frame 3 it.
  link.responder = [](const protocol::ViewerPose& pose) {
    std::optional<std::pair<std::int64_t, protocol::SceneUpdate>> reply;
    protocol::SceneUpdate update = sphereUpdate(pose.sequence + 1, pose.sequence, 1, 5.0);
    if (pose.sequence > 0) {
      update.operations.clear();
      update.bonePoses = {{1, std::vector<glm::mat4>(3, glm::mat4(1.0f))},
                          {2, std::vector<glm::mat4>(5, glm::mat4(1.0f))}};
    }
    if (pose.sequence < 3) reply = std::make_pair(pose.sequence == 2 ? 30 * kMs : 0, update);
    return reply;
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2, 0.3}));
  ASSERT_EQ(result.records.size(), 4u);
  EXPECT_EQ(result.records[0].poseBytes, 0u);
  EXPECT_EQ(result.records[1].poseBytes, 8u * 48u);
  EXPECT_EQ(result.records[2].poseBytes, 0u);
  EXPECT_EQ(result.records[3].poseBytes, 8u * 48u);
  // They are part of link_bytes (the fake link counts 1000 bytes of framing an update).
  EXPECT_EQ(result.records[1].linkBytes, 1000u + 8u * 48u);
}

TEST_F(ReplayLoopTest, EachBatchCarriesThePoseTimeOfThePoseItsUpdateAnswered) {
  options.rate = 10.0;
  // Pose 1's answer claims a frame this replay never sent: its time is unknown.
  link.responder = [](const protocol::ViewerPose& pose) {
    const std::uint64_t frame = pose.sequence == 1 ? 99 : pose.sequence;
    return std::make_optional(
        std::make_pair(std::int64_t{0}, sphereUpdate(pose.sequence + 1, frame, 1, 5.0)));
  };
  Replayed result = run(traceAt({0.0, 0.25, 0.5}));
  ASSERT_EQ(result.records.size(), 3u);
  ASSERT_EQ(producer.submittedPoseTimes.size(), 3u);
  EXPECT_DOUBLE_EQ(producer.submittedPoseTimes[0], 0.0);
  EXPECT_TRUE(std::isnan(producer.submittedPoseTimes[1]));
  EXPECT_DOUBLE_EQ(producer.submittedPoseTimes[2], 0.5);
}

// The units are counted with the kappa the backbone's budget counts points
// with (SceneUpdate.unitsKappa), kept after the update that brought it.
TEST_F(ReplayLoopTest, PointsAndUnitsOfEachFrameAtTheBackbonesKappa) {
  options.rate = 10.0;
  link.responder = [](const protocol::ViewerPose& pose) {
    std::optional<std::pair<std::int64_t, protocol::SceneUpdate>> reply;
    if (pose.sequence == 0) {
      protocol::SceneUpdate update = sphereUpdate(1, 0, 1, 5.0);
      update.unitsKappa = 1.5;
      reply = std::make_pair(0, std::move(update));
    }
    return reply;
  };
  producer.points = 30;
  Replayed result = run(traceAt({0.0, 0.1}));
  ASSERT_EQ(result.records.size(), 2u);
  for (const FrameRecord& record : result.records) {
    EXPECT_EQ(record.points, 30u);
    EXPECT_DOUBLE_EQ(record.units, double(record.polygons) + 20.0) << record.frame;
  }
  EXPECT_GT(result.records[1].polygons, 0u);
}

TEST_F(ReplayLoopTest, UnitsAreMissingWhenPointsWereDrawnAtAnUnknownKappa) {
  options.rate = 10.0;
  producer.points = 30;
  Replayed result = run(traceAt({0.0, 0.1}));
  ASSERT_EQ(result.records.size(), 2u);
  for (const FrameRecord& record : result.records) {
    EXPECT_EQ(record.points, 30u);
    EXPECT_TRUE(std::isnan(record.units)) << record.frame;
  }
}

TEST_F(ReplayLoopTest, UnitsAreTheTrianglesWhenNoPointsWereDrawn) {
  options.rate = 10.0;
  link.responder = [](const protocol::ViewerPose& pose) {
    std::optional<std::pair<std::int64_t, protocol::SceneUpdate>> reply;
    if (pose.sequence == 0) reply = std::make_pair(0, sphereUpdate(1, 0, 1, 5.0));
    return reply;
  };
  Replayed result = run(traceAt({0.0, 0.1}));
  ASSERT_EQ(result.records.size(), 2u);
  EXPECT_GT(result.records[1].polygons, 0u);
  for (const FrameRecord& record : result.records) {
    EXPECT_EQ(record.points, 0u);
    EXPECT_EQ(record.units, double(record.polygons)) << record.frame;
  }
}

TEST_F(ReplayLoopTest, ATraceGivesWaitsNoDescriptorToWakeOn) {
  options.rate = 10.0;
  run(traceAt({0.0, 0.1, 0.2}));
  EXPECT_EQ(link.wakeFds, (std::set<int>{-1}));
}

TEST_F(ReplayLoopTest, DefaultPacingFollowsTheTraceTimes) {
  const std::int64_t start = clock.now;
  Replayed result = run(traceAt({2.0, 2.25, 2.3, 3.0}));
  ASSERT_EQ(producer.renderStartNs.size(), 4u);
  // Each frame takes 25 ms (render + reference), less than every gap.
  const std::vector<std::int64_t> expected = {0, 250, 300, 1000};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(producer.renderStartNs[i] - start, expected[i] * kMs) << i;
  }
  EXPECT_EQ(result.records.size(), 4u);
}

TEST_F(ReplayLoopTest, LateFramesStartAtOnceWithoutSkippingPoses) {
  options.rate = 100.0;  // 10 ms slots, but a frame takes 25 ms
  const std::int64_t start = clock.now;
  Replayed result = run(traceAt({0.0, 1.0, 2.0}));
  ASSERT_EQ(result.records.size(), 3u);
  EXPECT_EQ(producer.renderStartNs[1] - start, 25 * kMs);
  EXPECT_EQ(producer.renderStartNs[2] - start, 50 * kMs);
}

TEST_F(ReplayLoopTest, BackboneDownKeepsRenderingWithoutWaiting) {
  link.up = false;
  options.lockstep = true;
  options.rate = -1.0;
  const std::int64_t start = clock.now;
  Replayed result = run(traceAt({0.0, 0.1, 0.2}));
  ASSERT_TRUE(result.status.ok());
  EXPECT_EQ(result.records.size(), 3u);
  EXPECT_EQ(result.posesNotSent, 3u);
  EXPECT_EQ(result.lockstepTimeouts, 0u);
  EXPECT_TRUE(link.frameStats.empty());
  EXPECT_EQ(clock.now - start, 3 * 25 * kMs);  // render + measure only
}

TEST_F(ReplayLoopTest, LockstepWaitEndsWhenTheLinkDrops) {
  options.lockstep = true;
  options.lockstepTimeout = std::chrono::milliseconds(5000);
  options.rate = -1.0;
  link.dropAtNs = clock.now + 10 * kMs;
  Replayed result = run(traceAt({0.0, 0.1}));
  ASSERT_EQ(result.records.size(), 2u);
  EXPECT_DOUBLE_EQ(result.records[0].waitMs, 10.0);
  EXPECT_EQ(result.lockstepTimeouts, 0u);
  EXPECT_EQ(link.poses.size(), 1u);  // frame 1's pose was not sent (link down)
}

TEST_F(ReplayLoopTest, MalformedUpdateIsDroppedWholeAndLaterOnesStillApply) {
  options.lockstep = true;
  options.rate = -1.0;
  link.responder = [](const protocol::ViewerPose& pose) {
    protocol::SceneUpdate update = sphereUpdate(pose.sequence + 1, pose.sequence, 1, 1.0);
    if (pose.sequence == 1) {
      // A valid replacement of 1 and a second object with broken Draco bytes.
      protocol::SceneOperation broken = addOp(2, meshRepresentation(sphereMesh(1.0f, 6, 3)));
      broken.representation.mesh.resize(broken.representation.mesh.size() / 2);
      update.operations[0] = addOp(1, meshRepresentation(sphereMesh(1.0f, 16, 8)));
      update.operations.push_back(broken);
    }
    return std::make_optional(std::make_pair(kMs, update));
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2}));
  ASSERT_EQ(result.records.size(), 3u);
  EXPECT_EQ(result.updatesReceived, 3u);
  EXPECT_EQ(result.updatesRejected, 1u);
  EXPECT_EQ(observer.rejectedPlans, (std::vector<std::uint64_t>{2}));
  EXPECT_NE(observer.reasons[0].find("operation 1 (object 2): mesh:"), std::string::npos)
      << observer.reasons[0];
  EXPECT_EQ(result.records[1].updatesRejected, 1u);
  // Frame 1 still shows frame 0's state; no half-applied replacement of object 1.
  EXPECT_EQ(result.records[1].polygons, kSphereTriangles);
  EXPECT_EQ(result.records[1].plan, 1u);
  EXPECT_FALSE(result.records[1].lockstepTimedOut);  // the answer came, it was just bad
  EXPECT_EQ(result.records[2].plan, 3u);
  EXPECT_EQ(producer.scene.objects().size(), 1u);
  // The backbone hears of the refusal from the FrameStats of that frame on,
  // repeated in the next ones (a FrameStats can be lost).
  ASSERT_EQ(link.frameStats.size(), 3u);
  EXPECT_TRUE(link.frameStats[0].rejectedPlans.empty());
  EXPECT_EQ(link.frameStats[1].rejectedPlans, (std::vector<std::uint64_t>{2}));
  EXPECT_EQ(link.frameStats[2].rejectedPlans, (std::vector<std::uint64_t>{2}));
}

TEST_F(ReplayLoopTest, RefusalsAreRepeatedInThreeFrameStatsThenDropped) {
  options.lockstep = true;
  options.rate = -1.0;
  link.responder = [](const protocol::ViewerPose& pose) {
    protocol::SceneUpdate update = sphereUpdate(pose.sequence + 1, pose.sequence, 1, 1.0);
    if (pose.sequence == 1) update.operations[0].representation.mesh.resize(3);  // refused
    return std::make_optional(std::make_pair(kMs, update));
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2, 0.3, 0.4, 0.5}));
  ASSERT_EQ(link.frameStats.size(), 6u);
  const std::vector<std::uint64_t> none;
  const std::vector<std::uint64_t> two = {2};
  EXPECT_EQ(link.frameStats[0].rejectedPlans, none);
  EXPECT_EQ(link.frameStats[1].rejectedPlans, two);
  EXPECT_EQ(link.frameStats[2].rejectedPlans, two);
  EXPECT_EQ(link.frameStats[3].rejectedPlans, two);
  EXPECT_EQ(link.frameStats[4].rejectedPlans, none);
  EXPECT_EQ(link.frameStats[5].rejectedPlans, none);
  EXPECT_EQ(result.updatesMissed, 0u);
}

// A SceneUpdate lost on the way (the fault campaign's --drop): the next
// update's plan number jumps, and the frontend reports the missing plan as
// refused so the backbone's mirror takes back what it carried.
TEST_F(ReplayLoopTest, LostUpdateIsReportedAsRefusedWhenTheNextOneArrives) {
  options.lockstep = true;
  options.lockstepTimeout = std::chrono::milliseconds(50);
  options.rate = -1.0;
  link.responder = [](const protocol::ViewerPose& pose)
      -> std::optional<std::pair<std::int64_t, protocol::SceneUpdate>> {
    if (pose.sequence == 1) return std::nullopt;  // plan 2 lost
    return std::make_pair(kMs, sphereUpdate(pose.sequence + 1, pose.sequence, 1, 1.0));
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2, 0.3, 0.4, 0.5}));
  ASSERT_EQ(result.records.size(), 6u);
  EXPECT_EQ(result.lockstepTimeouts, 1u);  // frame 1's answer never came
  EXPECT_EQ(result.updatesMissed, 1u);
  ASSERT_EQ(link.frameStats.size(), 6u);
  const std::vector<std::uint64_t> none;
  const std::vector<std::uint64_t> two = {2};
  EXPECT_EQ(link.frameStats[0].rejectedPlans, none);
  EXPECT_EQ(link.frameStats[1].rejectedPlans, none);  // nothing known yet
  EXPECT_EQ(link.frameStats[2].rejectedPlans, two);
  EXPECT_EQ(link.frameStats[3].rejectedPlans, two);
  EXPECT_EQ(link.frameStats[4].rejectedPlans, two);
  EXPECT_EQ(link.frameStats[5].rejectedPlans, none);
}

TEST_F(ReplayLoopTest, PlanNumbersCountFromOneInEveryBackboneProcess) {
  options.lockstep = true;
  options.rate = -1.0;
  // Plan 5 first (refused): plans 1-4 were never seen (another session's, or
  // lost), then plan 0 (a superseded pose's empty answer: no plan, no
  // restart), then a new backbone process: 1, 2, then a jump over 3 and 4.
  const std::vector<std::uint64_t> plans = {5, 0, 1, 2, 5};
  link.responder = [&plans](const protocol::ViewerPose& pose) {
    protocol::SceneUpdate update = sphereUpdate(plans[pose.sequence], pose.sequence, 1, 1.0);
    if (pose.sequence == 0) update.operations[0].representation.mesh.resize(3);
    if (pose.sequence == 1) update.operations.clear();
    return std::make_optional(std::make_pair(kMs, update));
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2, 0.3, 0.4}));
  ASSERT_EQ(link.frameStats.size(), 5u);
  const std::vector<std::uint64_t> upToFive = {1, 2, 3, 4, 5};
  EXPECT_EQ(link.frameStats[0].rejectedPlans, upToFive);
  EXPECT_EQ(link.frameStats[1].rejectedPlans, upToFive);
  // The new process never sent the old one's plans: their repeats stop.
  EXPECT_TRUE(link.frameStats[2].rejectedPlans.empty());
  EXPECT_TRUE(link.frameStats[3].rejectedPlans.empty());
  EXPECT_EQ(link.frameStats[4].rejectedPlans, (std::vector<std::uint64_t>{3, 4}));
  EXPECT_EQ(result.updatesMissed, 6u);
}

// The first update of a session lost: the next one's number says so.
TEST_F(ReplayLoopTest, LostFirstUpdateOfASessionIsReported) {
  options.lockstep = true;
  options.lockstepTimeout = std::chrono::milliseconds(50);
  options.rate = -1.0;
  link.responder = [](const protocol::ViewerPose& pose)
      -> std::optional<std::pair<std::int64_t, protocol::SceneUpdate>> {
    if (pose.sequence == 0) return std::nullopt;  // plan 1 lost
    return std::make_pair(kMs, sphereUpdate(pose.sequence + 1, pose.sequence, 1, 1.0));
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2}));
  ASSERT_EQ(link.frameStats.size(), 3u);
  EXPECT_TRUE(link.frameStats[0].rejectedPlans.empty());
  EXPECT_EQ(link.frameStats[1].rejectedPlans, (std::vector<std::uint64_t>{1}));
  EXPECT_EQ(result.updatesMissed, 1u);
}

// Resynchronisation: what is held goes to the link (the Hello of the next
// reconnect) each time it changes, and only then.
TEST_F(ReplayLoopTest, HoldingsGoToTheLinkWheneverTheyChange) {
  options.lockstep = true;
  options.lockstepTimeout = std::chrono::milliseconds(50);
  options.rate = -1.0;
  link.responder = [](const protocol::ViewerPose& pose)
      -> std::optional<std::pair<std::int64_t, protocol::SceneUpdate>> {
    if (pose.sequence == 1) return std::nullopt;  // frame 1: nothing new
    protocol::SceneUpdate update =
        sphereUpdate(pose.sequence + 1, pose.sequence, pose.sequence == 0 ? 7 : 3, 1.0);
    update.operations[0].representation.representationId = 100 + pose.sequence;
    return std::make_pair(kMs, update);
  };
  Replayed result = run(traceAt({0.0, 0.1, 0.2}));
  ASSERT_EQ(result.records.size(), 3u);
  ASSERT_EQ(link.held.size(), 2u);  // frames 0 and 2
  ASSERT_EQ(link.held[0].size(), 1u);
  EXPECT_EQ(link.held[0][0].objectId, 7u);
  EXPECT_EQ(link.held[0][0].representationId, 100u);
  EXPECT_EQ(link.held[0][0].kind, protocol::RepresentationKind::kMesh);
  EXPECT_EQ(link.held[0][0].triangleCount, kSphereTriangles);
  ASSERT_EQ(link.held[1].size(), 2u);  // ascending ids
  EXPECT_EQ(link.held[1][0].objectId, 3u);
  EXPECT_EQ(link.held[1][0].representationId, 102u);
  EXPECT_EQ(link.held[1][1].objectId, 7u);
}

TEST_F(ReplayLoopTest, StopRequestEndsTheReplayEarly) {
  options.rate = -1.0;
  stop = [this] { return observer.frames.size() >= 2; };
  Replayed result = run(traceAt({0.0, 0.1, 0.2, 0.3, 0.4}));
  EXPECT_TRUE(result.interrupted);
  EXPECT_TRUE(result.status.ok());
  EXPECT_EQ(result.records.size(), 2u);
}

TEST_F(ReplayLoopTest, StopRequestEndsAPacingWaitWithoutRenderingTheFrame) {
  const std::int64_t start = clock.now;
  stop = [this, start] { return clock.now - start >= 500 * kMs; };
  Replayed result = run(traceAt({0.0, 10.0}));
  EXPECT_TRUE(result.interrupted);
  EXPECT_EQ(result.records.size(), 1u);
  EXPECT_LT(clock.now - start, 600 * kMs);  // within one poll slice of the request
}

TEST_F(ReplayLoopTest, MaxFramesLimitsTheReplay) {
  options.rate = -1.0;
  options.maxFrames = 2;
  Replayed result = run(traceAt({0.0, 0.1, 0.2, 0.3}));
  EXPECT_FALSE(result.interrupted);
  EXPECT_EQ(result.records.size(), 2u);
  EXPECT_EQ(link.poses.size(), 2u);
}

TEST_F(ReplayLoopTest, InfiniteSnrIsSentAsNoSnr) {
  options.rate = -1.0;
  producer.snrDb = std::numeric_limits<double>::infinity();
  Replayed result = run(traceAt({0.0}));
  ASSERT_EQ(link.frameStats.size(), 1u);
  EXPECT_FALSE(link.frameStats[0].hasSnr);
  EXPECT_EQ(link.frameStats[0].snrDb, 0.0);
  EXPECT_TRUE(std::isinf(result.records[0].quality.snrDb));
}

TEST_F(ReplayLoopTest, WithoutMeasurementSnrIsMissing) {
  options.rate = -1.0;
  options.measure = false;
  const std::int64_t start = clock.now;
  Replayed result = run(traceAt({0.0, 0.1}));
  ASSERT_EQ(result.records.size(), 2u);
  EXPECT_TRUE(std::isnan(result.records[0].quality.snrDb));
  EXPECT_TRUE(std::isnan(result.records[0].quality.referenceMs));
  EXPECT_FALSE(link.frameStats[0].hasSnr);
  EXPECT_EQ(clock.now - start, 2 * 5 * kMs);  // no reference work
}

TEST_F(ReplayLoopTest, RenderFailureEndsTheReplayWithItsStatus) {
  options.rate = -1.0;
  producer.failAtFrame = 1;
  Replayed result = run(traceAt({0.0, 0.1, 0.2}));
  EXPECT_EQ(result.status.code(), ErrorCode::kInternal);
  EXPECT_EQ(result.records.size(), 1u);
}

TEST_F(ReplayLoopTest, LiveStreamAtRateZeroDrawsEachPoseWhenItArrives) {
  options.rate = 0.0;
  options.measure = false;
  options.pollSlice = std::chrono::milliseconds(1);
  const std::int64_t start = clock.now;
  ScriptedStream stream(clock, {30, 40, 100});
  Replayed result = run(stream);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  ASSERT_EQ(result.records.size(), 3u);
  const std::vector<std::int64_t> expectedStartMs = {30, 40, 100};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(producer.renderStartNs[i] - start, expectedStartMs[i] * kMs) << i;
    EXPECT_DOUBLE_EQ(result.records[i].poseToFrameMs, 5.0) << i;  // the render only
    EXPECT_EQ(link.poses[i].sequence, i);
    EXPECT_EQ(link.poses[i].position.x, static_cast<float>(i));
  }
  EXPECT_EQ(result.framesRedrawingAPose, 0u);
  EXPECT_EQ(result.posesSkipped, 0u);
}

TEST_F(ReplayLoopTest, LiveStreamAtARateTakesTheNewestPoseOrDrawsTheLastOneAgain) {
  options.rate = 100.0;  // a frame every 10 ms
  options.measure = false;
  options.pollSlice = std::chrono::milliseconds(1);
  const std::int64_t start = clock.now;
  // Nothing until 25 ms; then two poses within one frame; then one more at 52 ms.
  ScriptedStream stream(clock, {25, 27, 52});
  Replayed result = run(stream);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  // Frame 0 waits for the first pose and starts at 25 ms; frame 1 (slot 10 ms,
  // late) takes pose 27 at 30 ms; frames 2-5 (35, 40, 45, 50 ms) find nothing
  // new and draw pose 27 again; frame 6 (60 ms) takes pose 52; at frame 7 the
  // stream has ended.
  ASSERT_EQ(result.records.size(), 7u);
  const std::vector<std::int64_t> startMs = {25, 30, 35, 40, 45, 50, 60};
  const std::vector<double> timeS = {0.025, 0.027, 0.027, 0.027, 0.027, 0.027, 0.052};
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(producer.renderStartNs[i] - start, startMs[i] * kMs) << i;
    EXPECT_EQ(result.records[i].timeS, timeS[i]) << i;
  }
  // Latency counts from when the pose was read: 25 -> 30; pose 27 arrived
  // while frame 0 rendered and was read at 30 -> 35; pose 52 arrived while
  // frame 5 rendered (50-55) and was read at 55 by the refresh after the
  // first poll of the wait for the 60 ms slot -> 65 ms (without that refresh
  // it would be read at 60 and the frame would claim 5 ms).
  EXPECT_DOUBLE_EQ(result.records[0].poseToFrameMs, 5.0);
  EXPECT_DOUBLE_EQ(result.records[1].poseToFrameMs, 5.0);
  EXPECT_DOUBLE_EQ(result.records[6].poseToFrameMs, 10.0);
  EXPECT_TRUE(link.wakeFds.count(ScriptedStream::kStreamFd));  // waits woke on the stream
  for (std::size_t i = 2; i < 6; ++i) EXPECT_TRUE(std::isnan(result.records[i].poseToFrameMs)) << i;
  EXPECT_EQ(result.framesRedrawingAPose, 4u);
  EXPECT_EQ(link.poses.size(), 3u);  // poses are sent once, redraws send nothing
  EXPECT_EQ(result.posesSkipped, 0u);
  EXPECT_EQ(result.records.back().timeS, 0.052);
}

TEST_F(ReplayLoopTest, LiveStreamSkipsPosesOvertakenBeforeAFrameTakesThem) {
  options.rate = 20.0;  // a frame every 50 ms
  options.measure = false;
  options.pollSlice = std::chrono::milliseconds(1);
  ScriptedStream stream(clock, {0, 10, 20, 30, 60});
  Replayed result = run(stream);
  ASSERT_TRUE(result.status.ok());
  ASSERT_EQ(result.records.size(),
            3u);  // 0 ms: pose 0; 50 ms: pose 30 (10, 20 skipped); 100 ms: 60
  EXPECT_EQ(result.posesSkipped, 2u);
  EXPECT_EQ(result.records[1].timeS, 0.030);
  EXPECT_EQ(result.records[2].timeS, 0.060);
  // A pose waits for its frame's slot, and that wait is latency: pose 30 is
  // drawn by the frame at 50 ms (done at 55), pose 60 by the one at 100 ms.
  EXPECT_DOUBLE_EQ(result.records[1].poseToFrameMs, 25.0);
  EXPECT_DOUBLE_EQ(result.records[2].poseToFrameMs, 45.0);
}

// Deferred measurement: frames kept during the replay, scored after it.
class DeferringProducer final : public FrameProducer {
 public:
  explicit DeferringProducer(FakeClock& clock) : clock_(clock) {}
  Status submit(SceneBatch batch) override { return scene.enqueue(std::move(batch)); }
  Result<ProducedFrame> renderFrame(std::uint64_t, const Pose&) override {
    renderStartNs.push_back(clock_.now);
    for (const PendingUpload& upload : scene.planUploads(~std::size_t{0})) {
      EXPECT_TRUE(scene.markUploaded(upload.key).ok());
    }
    const CommitResult committed = scene.commitReady();
    clock_.now += renderNs.empty() ? 5 * kMs : renderNs[renderStartNs.size() - 1];
    ProducedFrame produced;
    produced.triangles = scene.polygons();
    produced.appliedPlan = scene.lastAppliedPlan();
    produced.committedBatches = committed.plans.size();
    return produced;
  }
  Result<FrameQuality> measure(std::uint64_t frame, const Pose&) override {
    ADD_FAILURE() << "inline measure of frame " << frame << " in deferred mode";
    return FrameQuality{};
  }
  bool keepShown(std::uint64_t frame, const Pose& pose, std::int64_t shownAtNs) override {
    kept.push_back({frame, pose.time, shownAtNs});
    return true;
  }
  Result<std::vector<FrameScore>> scoreKept() override {
    ++scoreCalls;
    scoredAtFrames = renderStartNs.size();
    // The score of a frame is a function of the pose it was kept with (what
    // the real producer does: the reference of that pose), here 100 x time.
    std::vector<FrameScore> out;
    for (const Kept& k : kept) {
      FrameScore q;
      q.frame = k.frame;
      q.quality.snrDb = 100.0 * k.poseTime;
      q.quality.psnrDb = 40.0;
      q.quality.referenceMs = 80.0;
      q.quality.visibleObjects = 2;
      q.quality.missingObjects = k.frame == 0 ? 1 : 0;
      q.quality.blank = 0;
      out.push_back(q);
    }
    return out;
  }
  struct Kept {
    std::uint64_t frame;
    double poseTime;
    std::int64_t shownAtNs;
  };
  FrontendScene scene;
  std::vector<std::int64_t> renderNs;  // per frame; default 5 ms
  std::vector<std::int64_t> renderStartNs;
  std::vector<Kept> kept;
  int scoreCalls = 0;
  std::size_t scoredAtFrames = 0;

 private:
  FakeClock& clock_;
};

TEST_F(ReplayLoopTest, DeferredScoringKeepsEachFrameWithThePoseItWasDrawnForEvenWhenLate) {
  DeferringProducer deferring(clock);
  ScoreObserver scores;
  options.deferMeasure = true;
  options.rate = 10.0;  // 100 ms slots
  // Frame 1 takes 250 ms: frame 2 starts late (at 350 ms, after its slot at
  // 200 ms and after pose 3's slot at 300 ms).
  deferring.renderNs = {5 * kMs, 250 * kMs, 5 * kMs, 5 * kMs};
  const std::int64_t start = clock.now;
  Replayed result = collect(runReplay(traceAt({0.0, 0.1, 0.2, 0.3}), options, clock, link,
                                      deferring, scores, [] { return false; }),
                            scores);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  ASSERT_EQ(result.records.size(), 4u);
  ASSERT_EQ(deferring.kept.size(), 4u);
  EXPECT_EQ(deferring.renderStartNs[2] - start, 350 * kMs);  // late: no pose skipped
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(deferring.kept[i].frame, i);
    // Kept with the pose it was drawn for, not the pose due when it was shown.
    EXPECT_DOUBLE_EQ(deferring.kept[i].poseTime, 0.1 * static_cast<double>(i));
    EXPECT_DOUBLE_EQ(result.records[i].quality.snrDb, 100.0 * 0.1 * static_cast<double>(i));
    EXPECT_EQ(result.records[i].quality.missingObjects, i == 0 ? 1 : 0);
    EXPECT_DOUBLE_EQ(result.records[i].quality.referenceMs, 80.0);
  }
  EXPECT_EQ(deferring.kept[2].shownAtNs - start, 355 * kMs);
  EXPECT_DOUBLE_EQ(result.records[2].shownAtMs, 355.0);
  // Scored once, after the last frame; nothing scored during the replay.
  EXPECT_EQ(deferring.scoreCalls, 1);
  EXPECT_EQ(deferring.scoredAtFrames, 4u);
  EXPECT_EQ(scores.pendingDuringReplay, (std::vector<bool>{true, true, true, true}));
  for (double snr : scores.snrDuringReplay) EXPECT_TRUE(std::isnan(snr));
  EXPECT_EQ(scores.scoredFrames, (std::vector<std::uint64_t>{0, 1, 2, 3}));
  EXPECT_DOUBLE_EQ(scores.scoredSnr[3], 30.0);
  // The reference never delays the client: frames 0 and 1 start on their slots.
  EXPECT_EQ(deferring.renderStartNs[0] - start, 0);
  EXPECT_EQ(deferring.renderStartNs[1] - start, 100 * kMs);
  for (const FrameRecord& record : result.records) EXPECT_LE(record.poseToFrameMs, 250.0);
}

TEST_F(ReplayLoopTest, DeferredScoringScoresTheFramesKeptBeforeAStop) {
  DeferringProducer deferring(clock);
  ScoreObserver scores;
  options.deferMeasure = true;
  options.rate = 10.0;
  Replayed result =
      collect(runReplay(traceAt({0.0, 0.1, 0.2, 0.3}), options, clock, link, deferring, scores,
                        [&] { return deferring.renderStartNs.size() >= 2; }),
              scores);
  EXPECT_TRUE(result.interrupted);
  ASSERT_EQ(result.records.size(), 2u);
  EXPECT_EQ(deferring.scoreCalls, 1);
  EXPECT_EQ(scores.scoredFrames.size(), result.records.size());
  for (std::size_t i = 0; i < result.records.size(); ++i) {
    EXPECT_DOUBLE_EQ(result.records[i].quality.snrDb, 10.0 * static_cast<double>(i));
  }
}

TEST_F(ReplayLoopTest, AFrameThatCannotBeKeptIsCountedAndStaysUnscored) {
  // SceneProducer keeps nothing (FrameProducer's default keepShown).
  options.deferMeasure = true;
  options.rate = -1.0;
  Replayed result = run(traceAt({0.0, 0.1}));
  ASSERT_EQ(result.records.size(), 2u);
  EXPECT_EQ(result.framesNotKept, 2u);
  for (const FrameRecord& record : result.records) EXPECT_TRUE(std::isnan(record.quality.snrDb));
}

TEST_F(ReplayLoopTest, EmptyTraceIsAnError) {
  Replayed result = run(Trace{});
  EXPECT_EQ(result.status.code(), ErrorCode::kInvalidArgument);
  EXPECT_TRUE(result.records.empty());
}

}  // namespace
}  // namespace thinlod::frontend::daemon
