// Options of thinlod-frontend (TOML keys = flags, see DaemonRuntime) and
// their validation. Pure apart from registering with the runtime.
#pragma once

#include <cstdint>
#include <string>

#include "thinlod/common/core/status.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/protocol/daemon_runtime.h"
#include "thinlod/protocol/transport.h"

namespace thinlod::frontend::daemon {

struct DaemonOptions {
  std::string backboneAddress = protocol::kDefaultFrontendAddress;
  std::string scenePath;
  std::string modelsDir;
  std::string tracePath;
  std::string poseStreamPath;  // "-" = stdin
  int width = 640;
  int height = 480;
  std::string backend = "auto";
  double rate = 0.0;  // frames/s; 0 = the trace's timing; < 0 = unpaced
  bool lockstep = false;
  int lockstepTimeoutMs = 5000;
  std::int64_t maxUploadBytesPerFrame = 600 * 1024;  // 0 = unbounded
  std::string csvPath;
  std::string summaryJsonPath;
  std::string framesDir;
  int dumpEvery = 10;
  bool noReference = false;
  bool deferredReference = false;  // keep shown frames, score after the replay
  std::int64_t deferredReferenceMaxMb = 4096;
  bool completeness = false;  // coverage pass: visible / missing objects per frame
  int visibleMinPixels = 16;  // completeness: pixels an object group must cover
  std::int64_t frames = 0;    // 0 = the whole trace
  std::string label;
  int connectTimeoutMs = 10000;
  protocol::TransportOptions transport;
};

void registerOptions(protocol::DaemonRuntime& runtime, DaemonOptions* options);
Result<render::Backend> parseBackend(const std::string& name);
// kInvalidArgument naming the option.
Status validateOptions(const DaemonOptions& options);

}  // namespace thinlod::frontend::daemon
