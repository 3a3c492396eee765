#include "outputs.h"

#include <OpenImageIO/imageio.h>

#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>
#include <utility>

namespace thinlod::frontend::daemon {
namespace {

Status ioError(const std::string& path, const std::string& what) {
  return Status(ErrorCode::kIoError, path + ": " + what);
}

}  // namespace

std::string runSummaryJson(const ReplaySummary& frames, const ReplayResult& result,
                           const RunInfo& info) {
  nlohmann::json json = nlohmann::json::parse(summaryJson(frames));
  json["label"] = info.label;
  json["trace"] = info.tracePath;
  json["pose_stream"] = info.poseStreamPath;
  json["pose_stream_received"] = info.streamPosesReceived;
  json["pose_stream_lines_rejected"] = info.streamLinesRejected;
  json["poses_skipped"] = result.posesSkipped;
  json["frames_redrawing_a_pose"] = result.framesRedrawingAPose;
  json["scene"] = info.scenePath;
  json["backend"] = info.backend;
  json["width"] = info.width;
  json["height"] = info.height;
  json["lockstep"] = info.lockstep;
  json["answer_wait_ms"] = info.answerWaitMs;
  json["rate"] = info.rate;
  json["reference"] = info.reference;
  // inline: each frame measured as it is drawn; deferred: shown frames kept and
  // scored after the replay (live runs); none: no SNR.
  json["reference_mode"] = !info.reference          ? "none"
                           : info.deferredReference ? "deferred"
                                                    : "inline";
  json["frames_not_kept"] = result.framesNotKept;
  json["kept_bytes"] = info.keptBytes;
  json["reference_triangles"] = info.referenceTriangles;
  json["connected_at_start"] = info.connectedAtStart;
  json["interrupted"] = result.interrupted;
  json["error"] = info.error.empty() ? nlohmann::json(nullptr) : nlohmann::json(info.error);
  json["updates"] = nlohmann::json{{"received", result.updatesReceived},
                                   {"applied", result.updatesApplied},
                                   {"rejected", result.updatesRejected}};
  json["lockstep_timeouts"] = result.lockstepTimeouts;
  json["answer_waits_expired"] = result.answerWaitsExpired;
  json["poses_not_sent"] = result.posesNotSent;
  return json.dump(2) + "\n";
}

Status writeTextFile(const std::string& path, const std::string& text) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) return ioError(path, std::strerror(errno));
  const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
  const bool closed = std::fclose(file) == 0;
  return written && closed ? Status() : ioError(path, "write failed");
}

Status writePng(const std::string& path, const RgbaImage& image) {
  if (image.empty() || !image.consistent()) return ioError(path, "empty or inconsistent image");
  std::unique_ptr<OIIO::ImageOutput> output = OIIO::ImageOutput::create(path);
  if (output == nullptr) return ioError(path, "no PNG writer: " + OIIO::geterror());
  const OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::UINT8);
  // RgbaImage rows are top-down, as OIIO scanlines are.
  if (!output->open(path, spec) ||
      !output->write_image(OIIO::TypeDesc::UINT8, image.pixels.data()) || !output->close()) {
    return ioError(path, output->geterror());
  }
  return Status();
}

std::string dumpPath(const std::string& dir, const std::string& prefix, std::uint64_t frame) {
  char name[64];
  std::snprintf(name, sizeof(name), "%s_%04llu.png", prefix.c_str(),
                static_cast<unsigned long long>(frame));
  return dir + "/" + name;
}

}  // namespace thinlod::frontend::daemon
