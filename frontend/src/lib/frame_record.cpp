#include "thinlod/frontend/frame_record.h"

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

namespace thinlod::frontend {
namespace {

// Empty for NaN, "inf"/"-inf" for infinities, else printf with `format`.
std::string formatNumber(double value, const char* format) {
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

nlohmann::json jsonPercentiles(const Percentiles& p) {
  return nlohmann::json{{"count", p.count},
                        {"median", jsonNumber(p.median)},
                        {"p99", jsonNumber(p.p99)},
                        {"max", jsonNumber(p.max)}};
}

// Nearest rank: element ceil(q * n) - 1 of the sorted values, q in (0, 1].
double nearestRank(const std::vector<double>& sorted, double q) {
  const auto n = static_cast<double>(sorted.size());
  const auto rank = static_cast<std::size_t>(std::ceil(q * n));
  return sorted[std::max<std::size_t>(rank, 1) - 1];
}

}  // namespace

std::string frameCsvHeader() {
  return "frame,time_s,polygons,link_bytes,target_accuracy,snr_db,psnr_db,render_ms,"
         "pose_to_frame_ms,update_latency_ms,plan,draw_calls,uploaded_bytes\n";
}

std::string formatFrameCsvRow(const FrameRecord& r) {
  std::string row;
  row.reserve(128);
  row += std::to_string(r.frame);
  row += ',' + formatNumber(r.timeS, "%.6f");
  row += ',' + std::to_string(r.polygons);
  row += ',' + std::to_string(r.linkBytes);
  row += ',' + formatNumber(r.targetAccuracy, "%.6g");
  row += ',' + formatNumber(r.snrDb, "%.4f");
  row += ',' + formatNumber(r.psnrDb, "%.4f");
  row += ',' + formatNumber(r.renderMs, "%.4f");
  row += ',' + formatNumber(r.poseToFrameMs, "%.4f");
  row += ',' + formatNumber(r.updateLatencyMs, "%.4f");
  row += ',' + std::to_string(r.plan);
  row += ',' + std::to_string(r.drawCalls);
  row += ',' + std::to_string(r.uploadedBytes);
  row += '\n';
  return row;
}

Percentiles percentiles(std::vector<double> values) {
  values.erase(
      std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
      values.end());
  Percentiles p;
  p.count = values.size();
  if (values.empty()) return p;
  std::sort(values.begin(), values.end());
  p.median = nearestRank(values, 0.5);
  p.p99 = nearestRank(values, 0.99);
  p.max = values.back();
  return p;
}

ReplaySummary summarizeFrames(const std::vector<FrameRecord>& records) {
  ReplaySummary s;
  s.frames = records.size();
  std::vector<double> render, latency, updateLatency, snr, psnr;
  double polygonSum = 0.0;
  for (const FrameRecord& r : records) {
    render.push_back(r.renderMs);
    latency.push_back(r.poseToFrameMs);
    updateLatency.push_back(r.updateLatencyMs);
    if (!std::isnan(r.snrDb)) snr.push_back(r.snrDb);
    if (!std::isnan(r.psnrDb)) psnr.push_back(r.psnrDb);
    polygonSum += static_cast<double>(r.polygons);
    s.polygonsMax = std::max(s.polygonsMax, r.polygons);
    s.linkBytesTotal += r.linkBytes;
  }
  s.renderMs = percentiles(render);
  s.poseToFrameMs = percentiles(latency);
  s.updateLatencyMs = percentiles(updateLatency);
  s.snrFrames = snr.size();
  if (!snr.empty()) {
    std::sort(snr.begin(), snr.end());
    s.snrMedianDb = nearestRank(snr, 0.5);
    s.snrMinDb = snr.front();
  }
  if (!psnr.empty()) {
    std::sort(psnr.begin(), psnr.end());
    s.psnrMedianDb = nearestRank(psnr, 0.5);
  }
  if (!records.empty()) s.polygonsMean = polygonSum / static_cast<double>(records.size());
  return s;
}

std::string summaryJson(const ReplaySummary& s) {
  const nlohmann::json json{
      {"frames", s.frames},
      {"render_ms", jsonPercentiles(s.renderMs)},
      {"pose_to_frame_ms", jsonPercentiles(s.poseToFrameMs)},
      {"update_latency_ms", jsonPercentiles(s.updateLatencyMs)},
      {"snr_db",
       {{"count", s.snrFrames},
        {"median", jsonNumber(s.snrMedianDb)},
        {"min", jsonNumber(s.snrMinDb)}}},
      {"psnr_db", {{"median", jsonNumber(s.psnrMedianDb)}}},
      {"polygons", {{"mean", jsonNumber(s.polygonsMean)}, {"max", s.polygonsMax}}},
      {"link_bytes_total", s.linkBytesTotal},
  };
  return json.dump(2);
}

Result<std::unique_ptr<FrameCsvWriter>> FrameCsvWriter::open(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) {
    return Status(ErrorCode::kIoError, path + ": cannot create (" + std::strerror(errno) + ")");
  }
  std::unique_ptr<FrameCsvWriter> writer(new FrameCsvWriter(path, file));
  const std::string header = frameCsvHeader();
  if (std::fwrite(header.data(), 1, header.size(), file) != header.size() ||
      std::fflush(file) != 0) {
    return Status(ErrorCode::kIoError, path + ": cannot write the CSV header");
  }
  return writer;
}

FrameCsvWriter::~FrameCsvWriter() {
  if (file_ != nullptr) std::fclose(file_);
}

Status FrameCsvWriter::append(const FrameRecord& record) {
  if (file_ == nullptr) return Status(ErrorCode::kIoError, path_ + ": already closed");
  const std::string row = formatFrameCsvRow(record);
  if (std::fwrite(row.data(), 1, row.size(), file_) != row.size() || std::fflush(file_) != 0) {
    return Status(ErrorCode::kIoError,
                  path_ + ": cannot write frame " + std::to_string(record.frame));
  }
  return Status();
}

Status FrameCsvWriter::close() {
  if (file_ == nullptr) return Status();
  const int result = std::fclose(file_);
  file_ = nullptr;
  if (result != 0) return Status(ErrorCode::kIoError, path_ + ": cannot close");
  return Status();
}

Status writeSummaryJson(const std::string& path, const ReplaySummary& summary) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) {
    return Status(ErrorCode::kIoError, path + ": cannot create (" + std::strerror(errno) + ")");
  }
  const std::string text = summaryJson(summary) + "\n";
  const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) return Status(ErrorCode::kIoError, path + ": cannot write the summary");
  return Status();
}

}  // namespace thinlod::frontend
