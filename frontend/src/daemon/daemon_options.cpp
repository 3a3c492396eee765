#include "daemon_options.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "thinlod/protocol/messages.h"

namespace thinlod::frontend::daemon {
namespace {

Status invalid(const std::string& option, const std::string& problem) {
  return Status(ErrorCode::kInvalidArgument, "--" + option + ": " + problem);
}

}  // namespace

void registerOptions(protocol::DaemonRuntime& runtime, DaemonOptions* o) {
  runtime.addOption("backbone.address", &o->backboneAddress, "backbone address to connect to");
  runtime.addOption("scene", &o->scenePath,
                    "scene file (object ids, reference frames, lights, mesh colours); required "
                    "unless --no-reference");
  runtime.addOption("models-dir", &o->modelsDir, "directory searched for the scene's mesh files");
  runtime.addOption("trace", &o->tracePath, "flight path to replay (docs/trace-format.md)");
  runtime.addOption("pose-stream", &o->poseStreamPath,
                    "live poses instead of --trace: trace lines read as they arrive from this "
                    "file or FIFO ('-' = stdin); each frame takes the newest pose");
  runtime.addOption("width", &o->gl.width, "frame width, pixels");
  runtime.addOption("height", &o->gl.height, "frame height, pixels");
  runtime.addOption("backend", &o->backend, "offscreen GL: auto|egl|osmesa");
  runtime.addOption("rate", &o->replay.rate,
                    "replay speed, frames per second; 0 = the trace's own timing (a pose stream: "
                    "a frame per arriving pose); negative = unpaced (each frame as soon as the "
                    "previous one is done)");
  runtime.addOption("lockstep", &o->replay.lockstep,
                    "wait for the backbone's SceneUpdate of each frame before rendering it");
  runtime.addOption("lockstep-timeout-ms", &o->lockstepTimeoutMs,
                    "longest lockstep wait per frame, ms");
  runtime.addOption("answer-wait-ms", &o->answerWaitMs,
                    "live (not lockstep): after sending a pose, wait up to this long for the "
                    "backbone's answer to it before drawing, so a frame can show the plan for "
                    "its own pose; 0 = draw at once (an answer not there yet shows a frame later)");
  runtime.addOption("max-upload-bytes-per-frame", &o->maxUploadBytesPerFrame,
                    "representation bytes uploaded to the GPU per frame; 0 = unbounded");
  runtime.addOption("csv", &o->csvPath, "per-frame CSV output (empty: none)");
  runtime.addOption("summary-json", &o->summaryJsonPath, "run summary JSON output (empty: none)");
  runtime.addOption("objects-csv", &o->objectsCsvPath,
                    "per-object CSV output: a row per held object per frame (kind, triangles, "
                    "vertices, skinned, posed, position; empty: none)");
  runtime.addOption("frames-dir", &o->framesDir,
                    "directory for frame_NNNN.png / reference_NNNN.png dumps (empty: none)");
  runtime.addOption("dump-every", &o->dumpEvery, "dump every Nth frame (with --frames-dir)");
  runtime.addOption("no-reference", &o->noReference,
                    "skip the full-quality reference and SNR (pure latency runs)");
  runtime.addOption("deferred-reference", &o->replay.deferMeasure,
                    "live scoring: keep every shown frame with the pose it was drawn for and "
                    "render the references and SNR after the replay, so the reference never "
                    "delays the client (frames.csv and the PNG dumps are written then)");
  runtime.addOption("deferred-reference-max-mb", &o->deferredReferenceMaxMb,
                    "memory for the kept frames, MiB (frames beyond it are not scored and are "
                    "counted as frames_not_kept)");
  runtime.addOption("completeness", &o->completeness,
                    "also render the reference in flat per-object colours to count the objects "
                    "it shows and those the frontend holds nothing of (visible_objects, "
                    "missing_objects); costs a second reference pass per measured frame");
  runtime.addOption("visible-min-pixels", &o->visibleMinPixels,
                    "completeness: an object group counts as visible when it covers at least this "
                    "many pixels of the reference (occlusion included)");
  runtime.addOption("frames", &o->frames,
                    "stop after N frames; 0 = the whole trace (or until the pose stream ends)");
  runtime.addOption("label", &o->label, "run name written into the summary");
  runtime.addOption("connect-timeout-ms", &o->connectTimeoutMs,
                    "how long to wait for the backbone handshake before replaying anyway, ms");
  runtime.addOption("frame-cost", &o->frameCostPath,
                    "this machine's frame-cost constants (TOML written by bench_calibrate), sent "
                    "to the backbone at hello for its frame-time budget (empty: none)");
  runtime.addTransportOptions(&o->transport);
}

Result<render::Backend> parseBackend(const std::string& name) {
  if (name == "auto") return render::Backend::kAuto;
  if (name == "egl") return render::Backend::kEgl;
  if (name == "osmesa") return render::Backend::kOsMesa;
  return invalid("backend", "'" + name + "' is not one of auto, egl, osmesa");
}

Status validateOptions(const DaemonOptions& o) {
  if (o.tracePath.empty() == o.poseStreamPath.empty()) {
    return invalid("trace", "give exactly one of --trace (a flight path) and --pose-stream");
  }
  if (o.scenePath.empty() && !o.noReference) {
    return invalid("scene",
                   "a scene file is required for the reference frames (or --no-reference)");
  }
  if (o.backboneAddress.empty()) return invalid("backbone.address", "empty");
  if (o.gl.width < 1 || o.gl.width > 16384) return invalid("width", "outside 1..16384");
  if (o.gl.height < 1 || o.gl.height > 16384) return invalid("height", "outside 1..16384");
  if (!parseBackend(o.backend).ok()) return parseBackend(o.backend).status();
  if (!std::isfinite(o.replay.rate)) return invalid("rate", "not finite");
  if (!o.poseStreamPath.empty() && o.replay.rate < 0.0) {
    return invalid("rate",
                   "unpaced (negative) with --pose-stream would redraw the last pose "
                   "back to back; use 0 (a frame per pose) or a positive rate");
  }
  if (o.lockstepTimeoutMs < 1) return invalid("lockstep-timeout-ms", "must be at least 1");
  if (o.answerWaitMs < 0 || o.answerWaitMs > 1000) return invalid("answer-wait-ms", "outside 0..1000");
  if (o.answerWaitMs > 0 && o.replay.lockstep) {
    return invalid("answer-wait-ms", "is for live replay; --lockstep waits per --lockstep-timeout-ms");
  }
  if (o.maxUploadBytesPerFrame < 0) return invalid("max-upload-bytes-per-frame", "negative");
  if (o.replay.deferMeasure && o.noReference) {
    return invalid("deferred-reference", "needs the reference (drop --no-reference)");
  }
  if (o.deferredReferenceMaxMb < 1 || o.deferredReferenceMaxMb > (std::int64_t{1} << 30)) {
    return invalid("deferred-reference-max-mb", "outside 1..2^30");
  }
  if (o.completeness && o.noReference) {
    return invalid("completeness", "needs the reference (drop --no-reference)");
  }
  if (o.visibleMinPixels < 1) return invalid("visible-min-pixels", "must be at least 1");
  if (o.dumpEvery < 1) return invalid("dump-every", "must be at least 1");
  if (o.frames < 0) return invalid("frames", "negative");
  if (o.connectTimeoutMs < 0) return invalid("connect-timeout-ms", "negative");
  return Status();
}

void finishOptions(DaemonOptions& o) {
  o.gl.backend = parseBackend(o.backend).value();
  o.gl.uploadBytesPerFrame = o.maxUploadBytesPerFrame == 0
                                 ? std::numeric_limits<std::size_t>::max()
                                 : static_cast<std::size_t>(o.maxUploadBytesPerFrame);
  o.gl.maxKeptBytes = static_cast<std::size_t>(o.deferredReferenceMaxMb) << 20;
  o.gl.visibleMinPixels = static_cast<std::uint32_t>(o.visibleMinPixels);
  o.replay.lockstepTimeout = std::chrono::milliseconds(o.lockstepTimeoutMs);
  o.replay.answerWait = std::chrono::milliseconds(o.answerWaitMs);
  o.replay.maxFrames = static_cast<std::size_t>(o.frames);
  o.replay.measure = !o.noReference;
  o.replay.viewportWidth = static_cast<std::uint32_t>(o.gl.width);
  o.replay.viewportHeight = static_cast<std::uint32_t>(o.gl.height);
}

}  // namespace thinlod::frontend::daemon
