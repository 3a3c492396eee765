// thinlod-frontend: replays a flight path (or follows a live pose stream)
// against the backbone, renders what it holds every frame, measures each
// frame against the full-quality reference and writes the per-frame CSV and a
// run summary (docs/frontend.md, "Daemon"). Exits 0 at the end of the trace or
// stream or on SIGINT/SIGTERM (outputs written either way), 1 on a setup or
// rendering failure, 2 on bad options.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "channel_link.h"
#include "daemon_options.h"
#include "gl_frame_producer.h"
#include "outputs.h"
#include "pose_source.h"
#include "replay_loop.h"
#include "scene_setup.h"
#include "thinlod/common/core/trace.h"
#include "thinlod/protocol/daemon_runtime.h"

namespace thinlod::frontend::daemon {
namespace {

constexpr std::uint64_t kProgressEveryFrames = 10;

// A live pose stream may reject every line it sends: log the first few
// rejections in full, then at most one count per second, so an untrusted
// stream cannot flood the log from the render loop.
class RejectionLog {
 public:
  void add(const Status& error) {
    if (error.code() == ErrorCode::kIoError) {  // the stream itself failed: always say so
      spdlog::error("event=pose_stream_failed error=\"{}\" rejected_lines={}", error.toString(),
                    total_);
      return;
    }
    ++total_;
    if (total_ <= kLoggedInFull) {
      spdlog::warn("event=pose_rejected action=skipped error=\"{}\"", error.toString());
      return;
    }
    ++unlogged_;
    const auto now = std::chrono::steady_clock::now();
    if (now - lastSummary_ < std::chrono::seconds(1)) return;
    spdlog::warn("event=pose_rejected action=skipped count={} total={} last_error=\"{}\"",
                 unlogged_, total_, error.toString());
    unlogged_ = 0;
    lastSummary_ = now;
  }

 private:
  static constexpr std::size_t kLoggedInFull = 10;
  std::size_t total_ = 0;
  std::size_t unlogged_ = 0;
  std::chrono::steady_clock::time_point lastSummary_{};
};

// A live stream's pose may move its time at most this far ahead at once;
// after this many poses in a row rejected for their time the stream starts a
// new time base (TraceStreamParser::Options).
constexpr double kMaxPoseStreamJumpSeconds = 60.0;
constexpr int kPoseStreamRestartAfter = 10;

// Logs, frames.csv with the summary (FrameLog) and the PNG dumps, frame by frame.
class DaemonObserver final : public ReplayObserver {
 public:
  DaemonObserver(FrameLog& log, const GlFrameProducer& producer, const DaemonOptions& options,
                 std::FILE* objectsCsv)
      : log_(log), producer_(producer), options_(options), objectsCsv_(objectsCsv) {}

  void onFrame(const FrameRecord& record, bool scorePending) override {
    writeObjectRows(record);
    spdlog::debug(
        "event=frame frame={} polygons={} link_bytes={} snr_db={:.2f} render_ms={:.2f} "
        "reference_ms={:.2f} pose_to_frame_ms={:.2f} update_latency_ms={:.2f} plan={}",
        record.frame, record.polygons, record.linkBytes, record.quality.snrDb, record.renderMs,
        record.quality.referenceMs, record.poseToFrameMs, record.updateLatencyMs, record.plan);
    if (record.frame % kProgressEveryFrames == 0) {
      spdlog::info("event=progress frame={} polygons={} snr_db={:.2f} render_ms={:.2f} plan={}",
                   record.frame, record.polygons, record.quality.snrDb, record.renderMs,
                   record.plan);
    }
    // Deferred scoring: the row comes with the score (onFramesScored), the
    // dumps while scoring (onKeptFrameScored).
    if (scorePending) {
      report(log_.addPending(record));
      return;
    }
    report(log_.add(record));
    if (!options_.framesDir.empty() && record.frame % options_.dumpEvery == 0) dump(record.frame);
  }

  bool objectsFailed() const { return objectsFailed_; }

  void onFramesScored(const std::vector<FrameScore>& scores) override {
    report(log_.applyScores(scores));
  }

  // Deferred scoring: called while the kept frame and its reference are in the producer.
  void onKeptFrameScored(std::uint64_t frame) {
    if (!options_.framesDir.empty() && frame % options_.dumpEvery == 0) dump(frame);
  }

  void onUpdateRejected(const protocol::SceneUpdate& update, const Status& why) override {
    spdlog::warn(
        "event=update_rejected plan={} frame={} operations={} action=dropped_whole "
        "error=\"{}\"",
        update.plan, update.frame, update.operations.size(), why.toString());
  }
  void onLockstepTimeout(std::uint64_t frame, double waitedMs) override {
    spdlog::warn("event=lockstep_timeout frame={} waited_ms={:.1f} action=render_held_state", frame,
                 waitedMs);
  }
  void onUploadDropped(std::uint64_t frame, const std::string& error) override {
    spdlog::warn("event=upload_failed frame={} action=batch_dropped error=\"{}\"", frame, error);
  }
  void onSendFailed(const char* what, std::uint64_t frame, const Status& why) override {
    spdlog::debug("event=send_failed message={} frame={} error=\"{}\"", what, frame,
                  why.toString());
  }

 private:
  // The first output error is logged; FrameLog keeps it for the exit code.
  void report(const Status& status) {
    if (status.ok() || reported_) return;
    reported_ = true;
    spdlog::error("event=csv_failed error=\"{}\"", status.toString());
  }

  // objects.csv: what the scene holds right after the frame drawn (the next
  // batches commit in the next renderFrame). Needs no score, so also in
  // deferred mode the rows go out now.
  void writeObjectRows(const FrameRecord& record) {
    if (objectsCsv_ == nullptr || objectsFailed_) return;
    const std::string rows = formatObjectCsvRows(record.frame, record.timeS, producer_.scene());
    if (std::fwrite(rows.data(), 1, rows.size(), objectsCsv_) != rows.size() ||
        std::fflush(objectsCsv_) != 0) {
      objectsFailed_ = true;
      spdlog::error("event=objects_csv_failed path={} frame={}", options_.objectsCsvPath,
                    record.frame);
    }
  }

  void dump(std::uint64_t frame) {
    Status written = writePng(dumpPath(options_.framesDir, "frame", frame), producer_.frame());
    if (written.ok() && !options_.noReference) {
      written =
          writePng(dumpPath(options_.framesDir, "reference", frame), producer_.referenceFrame());
      Result<RgbaImage> difference = differenceImage(producer_.frame(), producer_.referenceFrame());
      if (written.ok() && difference.ok()) {
        written = writePng(dumpPath(options_.framesDir, "difference", frame), *difference);
      }
    }
    if (!written.ok()) spdlog::warn("event=dump_failed error=\"{}\"", written.toString());
  }

  FrameLog& log_;
  const GlFrameProducer& producer_;
  const DaemonOptions& options_;
  std::FILE* objectsCsv_;
  bool objectsFailed_ = false;
  bool reported_ = false;
};

int run(protocol::DaemonRuntime& runtime, DaemonOptions& options) {
  const Status valid = validateOptions(options);
  if (!valid.ok()) {
    spdlog::error("event=bad_options error=\"{}\"", valid.toString());
    return 2;
  }
  finishOptions(options);
  std::optional<FrameCostConstants> frameCost;
  if (!options.frameCostPath.empty()) {
    Result<FrameCostConstants> loaded = loadFrameCostFile(options.frameCostPath);
    if (!loaded.ok()) {
      spdlog::error("event=bad_options error=\"--frame-cost {}\"", loaded.status().toString());
      return 2;
    }
    frameCost = *loaded;
    spdlog::info("event=frame_cost path={} triangle_ns={:.4g} pixel_ns={:.4g} additive={}",
                 options.frameCostPath, frameCost->triangleSeconds * 1e9,
                 frameCost->pixelSeconds * 1e9, frameCost->additive ? 1 : 0);
  }
  // Poses: a trace loaded whole, or a live stream read as it arrives.
  SteadyClock clock;
  Trace trace;
  std::unique_ptr<PoseSource> source;
  StreamPoseSource* stream = nullptr;
  RejectionLog rejections;
  if (!options.tracePath.empty()) {
    Result<Trace> loaded = loadTraceFile(options.tracePath);
    if (!loaded.ok()) {
      spdlog::error("event=trace_failed error=\"{}\"", loaded.status().toString());
      return 1;
    }
    trace = std::move(loaded).value();
    source = std::make_unique<TracePoseSource>(trace);
  } else {
    StreamPoseSource::Options streamOptions;
    streamOptions.parser.maxTimeJumpSeconds = kMaxPoseStreamJumpSeconds;
    streamOptions.parser.timeBaseRestartAfter = kPoseStreamRestartAfter;
    streamOptions.nowNs = [&clock] { return clock.nowNs(); };
    streamOptions.onError = [&rejections](const Status& error) { rejections.add(error); };
    Result<std::unique_ptr<StreamPoseSource>> live =
        StreamPoseSource::open(options.poseStreamPath, std::move(streamOptions));
    if (!live.ok()) {
      spdlog::error("event=pose_stream_failed path={} error=\"{}\"", options.poseStreamPath,
                    live.status().toString());
      return 1;
    }
    stream = live->get();
    source = std::move(live).value();
  }

  std::optional<LoadedScene> scene;
  if (!options.scenePath.empty()) {
    Result<LoadedScene> loaded = loadFrontendScene(options.scenePath, options.modelsDir);
    if (!loaded.ok()) {
      spdlog::error("event=scene_failed error=\"{}\"", loaded.status().toString());
      return 1;
    }
    scene = std::move(loaded).value();
    spdlog::info("event=scene_loaded path={} objects={} reference_triangles={} lights={}",
                 options.scenePath, scene->objects.size(), scene->referenceTriangles,
                 scene->lighting.lights.size());
    if (scene->laterLodLevelObjects > 0) {
      spdlog::info(
          "event=reference_lod note=\"objects of later LOD levels left out of the "
          "reference\" count={}",
          scene->laterLodLevelObjects);
    }
    for (const std::string& warning : scene->warnings) {
      spdlog::warn("event=scene_warning message=\"{}\"", warning);
    }
    if (scene->droppedLights > 0) {
      spdlog::warn("event=lights_dropped count={}", scene->droppedLights);
    }
    if (scene->unlitObjects > 0) {
      spdlog::warn(
          "event=unlit_objects count={} note=\"objects without a Material are drawn "
          "lit by the frontend, unlit in the reference\"",
          scene->unlitObjects);
    }
  } else {
    spdlog::warn("event=no_scene note=\"meshes from the backbone are drawn white\"");
  }

  const render::Lighting lighting = scene ? scene->lighting : render::Lighting{};
  std::vector<ReferenceItem> reference;
  std::vector<ObjectExtent> extents;
  if (scene && !options.noReference) {
    reference = scene->reference;
    // Without extents the producer renders no coverage pass.
    if (options.completeness) extents = scene->extents;
  }
  Result<std::unique_ptr<GlFrameProducer>> producer =
      GlFrameProducer::create(options.gl, lighting, std::move(reference), std::move(extents));
  if (!producer.ok()) {
    spdlog::error("event=gl_failed error=\"{}\"", producer.status().toString());
    return 1;
  }
  spdlog::info("event=gl_ready backend=\"{}\" width={} height={}", (*producer)->describe(),
               options.gl.width, options.gl.height);

  Result<std::unique_ptr<FrameLog>> log = FrameLog::open(options.csvPath);
  if (!log.ok()) {
    spdlog::error("event=csv_failed error=\"{}\"", log.status().toString());
    return 1;
  }
  // objects.csv (--objects-csv): closed at exit by the unique_ptr.
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> objectsCsv(nullptr, &std::fclose);
  if (!options.objectsCsvPath.empty()) {
    objectsCsv.reset(std::fopen(options.objectsCsvPath.c_str(), "wb"));
    const std::string header = objectCsvHeader();
    if (!objectsCsv ||
        std::fwrite(header.data(), 1, header.size(), objectsCsv.get()) != header.size()) {
      spdlog::error("event=objects_csv_failed path={} error=\"cannot create\"",
                    options.objectsCsvPath);
      return 1;
    }
  }
  if (!options.framesDir.empty()) {
    std::error_code error;
    std::filesystem::create_directories(options.framesDir, error);
    if (error) {
      spdlog::error("event=frames_dir_failed path={} error=\"{}\"", options.framesDir,
                    error.message());
      return 1;
    }
  }

  Result<std::unique_ptr<ChannelLink>> link = ChannelLink::connect(
      options.backboneAddress, defaultPeerName(), options.transport, runtime.wakeFd(),
      scene ? scene->scene->fingerprint : 0, options.scenePath, frameCost);
  if (!link.ok()) {
    spdlog::error("event=connect_failed address={} error=\"{}\"", options.backboneAddress,
                  link.status().toString());
    return 1;
  }
  const auto stop = [&runtime] { return runtime.shutdownRequested(); };
  const bool connected = (*link)->waitConnected(std::chrono::milliseconds(options.connectTimeoutMs),
                                                std::chrono::milliseconds(1000), stop);
  if (const Status* refused = (*link)->rejection()) {
    spdlog::error("event=backbone_refused address={} error=\"{}\"", options.backboneAddress,
                  refused->toString());
    return 1;
  }
  if (!connected && !runtime.shutdownRequested()) {
    spdlog::warn("event=backbone_unavailable address={} waited_ms={} action=replay_anyway",
                 options.backboneAddress, options.connectTimeoutMs);
  }
  spdlog::info(
      "event=ready address={} connected={} trace={} poses={} pose_stream={} lockstep={} "
      "reference={} deferred_reference={}",
      options.backboneAddress, connected, options.tracePath, trace.poses.size(),
      options.poseStreamPath, options.replay.lockstep, !options.noReference,
      options.replay.deferMeasure);

  ReplayOptions replay = options.replay;
  if (scene) replay.conversion.meshColors = &scene->meshColors;
  // Shared textures the backbone sent (docs/protocol.md, "Shared textures").
  SharedTextureCache sharedTextures;
  replay.conversion.sharedTextures = &sharedTextures;

  DaemonObserver observer(**log, **producer, options, objectsCsv.get());
  (*producer)->setScoredSink(
      [&observer](std::uint64_t frame) { observer.onKeptFrameScored(frame); });
  ReplayResult result = runReplay(*source, replay, clock, **link, **producer, observer, stop);

  int exitCode = 0;
  RunInfo info;
  info.label = options.label;
  info.tracePath = options.tracePath;
  info.poseStreamPath = options.poseStreamPath;
  if (stream != nullptr) {
    info.streamPosesReceived = stream->received();
    info.streamLinesRejected = stream->rejectedLines();
  }
  info.scenePath = options.scenePath;
  info.backend = (*producer)->describe();
  info.width = options.gl.width;
  info.height = options.gl.height;
  info.lockstep = options.replay.lockstep;
  info.answerWaitMs = options.answerWaitMs;
  info.rate = options.replay.rate;
  info.reference = !options.noReference;
  info.deferredReference = options.replay.deferMeasure && !options.noReference;
  info.keptBytes = (*producer)->keptBytes();
  info.connectedAtStart = connected;
  info.referenceTriangles = scene && !options.noReference ? scene->referenceTriangles : 0;
  if (!result.status.ok()) {
    info.error = result.status.toString();
    spdlog::error("event=replay_failed frame={} error=\"{}\"", result.frames, info.error);
    exitCode = 1;
  }
  if (observer.objectsFailed() || (objectsCsv && std::fclose(objectsCsv.release()) != 0)) {
    spdlog::error("event=objects_csv_failed path={} error=\"cannot write\"",
                  options.objectsCsvPath);
    exitCode = 1;
  }
  const Status closed = (*log)->close();
  if (!closed.ok()) {
    spdlog::error("event=csv_failed error=\"{}\"", closed.toString());
    exitCode = 1;
  }
  const ReplaySummary summary = (*log)->summary().summarize();
  if (!options.summaryJsonPath.empty()) {
    const Status written =
        writeTextFile(options.summaryJsonPath, runSummaryJson(summary, result, info));
    if (!written.ok()) {
      spdlog::error("event=summary_failed error=\"{}\"", written.toString());
      exitCode = 1;
    }
  }
  spdlog::info(
      "event=finished frames={} interrupted={} updates_received={} updates_applied={} "
      "updates_rejected={} lockstep_timeouts={} answer_waits_expired={} own_answer_frames={} "
      "render_ms_median={:.2f} snr_db_median={:.2f} polygons_max={}",
      result.frames, result.interrupted, result.updatesReceived, result.updatesApplied,
      result.updatesRejected, result.lockstepTimeouts, result.answerWaitsExpired,
      summary.ownAnswerFrames, summary.renderMs.median, summary.snrMedianDb, summary.polygonsMax);
  return exitCode;
}

}  // namespace
}  // namespace thinlod::frontend::daemon

int main(int argc, char** argv) {
  using namespace thinlod;
  protocol::DaemonRuntime runtime("thinlod-frontend",
                                  "Thin client: replays a flight path against the backbone, "
                                  "renders what it holds, measures SNR per frame");
  frontend::daemon::DaemonOptions options;
  frontend::daemon::registerOptions(runtime, &options);
  if (auto exitCode = runtime.parse(argc, argv)) return *exitCode;
  // CURVE keys beyond loopback (docs/protocol.md, "Security"): fail before loading the scene.
  const Status secure = protocol::checkLinkSecurity(
      options.backboneAddress, options.transport.curve, protocol::LinkSide::kConnect);
  if (!secure.ok()) {
    spdlog::error("event=bad_options error=\"{}\"", secure.toString());
    return 2;
  }
  return frontend::daemon::run(runtime, options);
}
