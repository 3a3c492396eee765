// The daemon's files besides frames.csv (FrameLog, frame_record.h): the run
// summary JSON (the library's summary plus the run's settings and counters),
// PNG frame dumps (OIIO). File errors are kIoError naming the path.
#pragma once

#include <memory>
#include <string>

#include "replay_loop.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"
#include "thinlod/frontend/frame_record.h"

namespace thinlod::frontend::daemon {

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
  int answerWaitMs = 0;  // --answer-wait-ms
  double rate = 0.0;
  bool reference = true;
  bool deferredReference = false;
  std::size_t keptBytes = 0;  // deferred: pixels held for scoring at the end
  bool connectedAtStart = false;
  std::size_t referenceTriangles = 0;
  std::string error;  // empty when the replay ended normally
};

std::string runSummaryJson(const ReplaySummary& frames, const ReplayResult& result,
                           const RunInfo& info);
Status writeTextFile(const std::string& path, const std::string& text);
Status writePng(const std::string& path, const RgbaImage& image);
// "<dir>/<prefix>_0042.png"
std::string dumpPath(const std::string& dir, const std::string& prefix, std::uint64_t frame);

}  // namespace thinlod::frontend::daemon
