// Replay bookkeeping: one record per rendered frame, a CSV row formatter with
// a thin file wrapper, and a run summary as a struct and JSON text.
//
// Contract:
// - Units: time_s = trace time of the frame's pose (seconds); *_ms =
//   milliseconds of wall-clock time; link_bytes = bytes received from the
//   backbone since the previous frame; target_accuracy = the plan's target
//   (1/rad, as the backbone defines it); snr_db/psnr_db as frame_metrics.h.
// - pose_to_frame_ms: the pose was sampled -> the frame drawn for it, with the
//   newest state held then, was read back (the thin client's own latency, the
//   paper's 8 ms). update_latency_ms: the pose was sent -> the backbone's
//   update answering it became visible (the round trip through the backbone,
//   and the simplifier when it waited for one); only on frames that show one.
// - Missing values are NaN: written as an empty CSV field and JSON null.
//   Infinite SNR/PSNR (identical frames) is written "inf" / "-inf" in both.
// - Percentiles are nearest-rank over the finite values: the p-th of n
//   sorted values is element ceil(p/100 * n) - 1; the median is p = 50 (the
//   lower middle for even n). min/median of SNR include infinities.
// - formatFrameCsvRow / frameCsvHeader / summarizeFrames / summaryJson are
//   pure and thread-safe. FrameCsvWriter owns one file (not thread-safe);
//   I/O failures are kIoError naming the path.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod::frontend {

struct FrameRecord {
  static constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();
  std::uint64_t frame = 0;
  double timeS = 0.0;
  std::size_t polygons = 0;
  std::uint64_t linkBytes = 0;
  double targetAccuracy = kMissing;
  double snrDb = kMissing;
  double psnrDb = kMissing;
  double renderMs = kMissing;
  double poseToFrameMs = kMissing;
  double updateLatencyMs = kMissing;
  std::uint64_t plan = 0;  // last applied SceneUpdate plan
  std::size_t drawCalls = 0;
  std::size_t uploadedBytes = 0;  // representation bytes uploaded to the GPU this frame
};

// "frame,time_s,polygons,link_bytes,target_accuracy,snr_db,psnr_db,render_ms,
//  pose_to_frame_ms,update_latency_ms,plan,draw_calls,uploaded_bytes\n"
std::string frameCsvHeader();
// One line, '\n'-terminated, columns as in the header.
std::string formatFrameCsvRow(const FrameRecord& record);

struct Percentiles {
  std::size_t count = 0;  // finite values used
  double median = FrameRecord::kMissing;
  double p99 = FrameRecord::kMissing;
  double max = FrameRecord::kMissing;
};

struct ReplaySummary {
  std::size_t frames = 0;
  Percentiles renderMs;
  Percentiles poseToFrameMs;
  Percentiles updateLatencyMs;
  std::size_t snrFrames = 0;  // frames with a measured SNR (infinite included)
  double snrMedianDb = FrameRecord::kMissing;
  double snrMinDb = FrameRecord::kMissing;
  double psnrMedianDb = FrameRecord::kMissing;
  double polygonsMean = FrameRecord::kMissing;
  std::size_t polygonsMax = 0;
  std::uint64_t linkBytesTotal = 0;
};

Percentiles percentiles(std::vector<double> values);  // drops non-finite values
ReplaySummary summarizeFrames(const std::vector<FrameRecord>& records);
// A JSON object (nlohmann_json), indented by 2.
std::string summaryJson(const ReplaySummary& summary);

class FrameCsvWriter {
 public:
  // Creates/truncates `path` and writes the header.
  static Result<std::unique_ptr<FrameCsvWriter>> open(const std::string& path);
  ~FrameCsvWriter();
  Status append(const FrameRecord& record);  // flushed per row so a crash loses little
  Status close();

 private:
  FrameCsvWriter(std::string path, std::FILE* file) : path_(std::move(path)), file_(file) {}
  std::string path_;
  std::FILE* file_;
};

// Writes summaryJson(summary) to `path` (kIoError on failure).
Status writeSummaryJson(const std::string& path, const ReplaySummary& summary);

}  // namespace thinlod::frontend
