#include "outputs.h"

#include <OpenImageIO/imageio.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <utility>

namespace thinlod::frontend::daemon {
namespace {

std::string number(double value, const char* format) {
  if (std::isnan(value)) return "";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

nlohmann::json jsonNumber(double value) {
  if (std::isnan(value)) return nullptr;
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return value;
}

nlohmann::json jsonPercentiles(std::vector<double> values) {
  const Percentiles p = percentiles(std::move(values));
  return nlohmann::json{{"count", p.count},
                        {"median", jsonNumber(p.median)},
                        {"p99", jsonNumber(p.p99)},
                        {"max", jsonNumber(p.max)}};
}

Status ioError(const std::string& path, const std::string& what) {
  return Status(ErrorCode::kIoError, path + ": " + what);
}

std::string withoutNewline(std::string line) {
  if (!line.empty() && line.back() == '\n') line.pop_back();
  return line;
}

}  // namespace

std::string daemonCsvHeader() {
  return withoutNewline(frameCsvHeader()) +
         ",reference_ms,wait_ms,updates_received,updates_rejected,lockstep_timeout,shown_at_ms,"
         "visible_objects,missing_objects,blank\n";
}

std::string daemonCsvRow(const FrameRecord& record, const FrameExtras& extras) {
  std::string row = withoutNewline(formatFrameCsvRow(record));
  row += ',' + number(extras.referenceMs, "%.4f");
  row += ',' + number(extras.waitMs, "%.4f");
  row += ',' + std::to_string(extras.updatesReceived);
  row += ',' + std::to_string(extras.updatesRejected);
  row += extras.lockstepTimedOut ? ",1" : ",0";
  row += ',' + number(extras.shownAtMs, "%.4f");
  const auto count = [](long value) { return value < 0 ? std::string() : std::to_string(value); };
  row += ',' + count(extras.visibleObjects);
  row += ',' + count(extras.missingObjects);
  row += ',' + count(extras.blank);
  row += '\n';
  return row;
}

Result<std::unique_ptr<CsvOutput>> CsvOutput::open(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) return ioError(path, std::strerror(errno));
  std::unique_ptr<CsvOutput> output(new CsvOutput(path, file));
  const std::string header = daemonCsvHeader();
  if (std::fwrite(header.data(), 1, header.size(), file) != header.size() ||
      std::fflush(file) != 0) {
    return ioError(path, "cannot write the header");
  }
  return output;
}

CsvOutput::~CsvOutput() { (void)close(); }

Status CsvOutput::append(const FrameRecord& record, const FrameExtras& extras) {
  if (file_ == nullptr) return ioError(path_, "already closed");
  const std::string row = daemonCsvRow(record, extras);
  if (std::fwrite(row.data(), 1, row.size(), file_) != row.size() || std::fflush(file_) != 0) {
    return ioError(path_, "cannot write frame " + std::to_string(record.frame));
  }
  return Status();
}

Status CsvOutput::close() {
  if (file_ == nullptr) return Status();
  const int closed = std::fclose(file_);
  file_ = nullptr;
  return closed == 0 ? Status() : ioError(path_, "close failed");
}

std::string runSummaryJson(const ReplayResult& result, const RunInfo& info) {
  nlohmann::json json = nlohmann::json::parse(summaryJson(summarizeFrames(result.records)));
  std::vector<double> referenceMs, waitMs;
  for (const FrameExtras& extras : result.extras) {
    referenceMs.push_back(extras.referenceMs);
    waitMs.push_back(extras.waitMs);
  }
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
  json["reference_ms"] = jsonPercentiles(referenceMs);
  json["wait_ms"] = jsonPercentiles(waitMs);
  json["updates"] = nlohmann::json{{"received", result.updatesReceived},
                                   {"applied", result.updatesApplied},
                                   {"rejected", result.updatesRejected}};
  json["lockstep_timeouts"] = result.lockstepTimeouts;
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
