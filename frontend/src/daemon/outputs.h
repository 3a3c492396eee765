// The daemon's files: the per-frame CSV (the library's columns plus the
// daemon's extra columns at the end), the run summary JSON (the library's
// summary plus the run's settings and counters), PNG frame dumps (OIIO).
// File errors are kIoError naming the path. Not thread-safe.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "replay_loop.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"
#include "thinlod/frontend/frame_record.h"

namespace thinlod::frontend::daemon {

// Extra columns after the library's: reference_ms, wait_ms, updates_received,
// updates_rejected, lockstep_timeout (0/1), shown_at_ms, visible_objects,
// missing_objects, blank (0/1; the last three empty when not measured).
std::string daemonCsvHeader();
std::string daemonCsvRow(const FrameRecord& record, const FrameExtras& extras);

class CsvOutput {
 public:
  static Result<std::unique_ptr<CsvOutput>> open(const std::string& path);
  ~CsvOutput();
  Status append(const FrameRecord& record, const FrameExtras& extras);  // flushed per row
  Status close();

 private:
  CsvOutput(std::string path, std::FILE* file) : path_(std::move(path)), file_(file) {}
  std::string path_;
  std::FILE* file_;
};

// What the summary adds to the library's ReplaySummary.
struct RunInfo {
  std::string label;
  std::string tracePath;       // empty with a pose stream
  std::string poseStreamPath;  // empty with a trace
  std::size_t streamPosesReceived = 0;
  std::size_t streamLinesRejected = 0;
  std::string scenePath;
  std::string backend;  // as created, e.g. "egl, llvmpipe (...)"
  int width = 0;
  int height = 0;
  bool lockstep = false;
  double rate = 0.0;
  bool reference = true;
  bool deferredReference = false;
  std::size_t keptBytes = 0;  // deferred: pixels held for scoring at the end
  bool connectedAtStart = false;
  std::size_t referenceTriangles = 0;
  std::string error;  // empty when the replay ended normally
};

std::string runSummaryJson(const ReplayResult& result, const RunInfo& info);
Status writeTextFile(const std::string& path, const std::string& text);
Status writePng(const std::string& path, const RgbaImage& image);
// "<dir>/<prefix>_0042.png"
std::string dumpPath(const std::string& dir, const std::string& prefix, std::uint64_t frame);

}  // namespace thinlod::frontend::daemon
