// Options of thinlod-frontend (TOML keys = flags, see DaemonRuntime) and
// their validation. Each option is registered once, on the field it
// configures: straight on ReplayOptions / GlProducerOptions where the type
// fits (their defaults are the only ones), else on a shell field below whose
// default is taken from those structs and which finishOptions() converts.
// Pure apart from registering with the runtime.
#pragma once

#include <cstdint>
#include <string>

#include "gl_frame_producer.h"
#include "replay_loop.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/protocol/daemon_runtime.h"
#include "thinlod/protocol/transport.h"

namespace thinlod::frontend::daemon {

struct DaemonOptions {
  // Bound directly: replay.lockstep, replay.rate, replay.deferMeasure,
  // gl.width, gl.height.
  ReplayOptions replay;
  GlProducerOptions gl;

  // Converted into `replay` / `gl` by finishOptions(); defaults from them.
  std::string backend = render::backendName(GlProducerOptions{}.backend);
  int lockstepTimeoutMs = static_cast<int>(ReplayOptions{}.lockstepTimeout.count());
  int answerWaitMs = static_cast<int>(ReplayOptions{}.answerWait.count());
  std::int64_t maxUploadBytesPerFrame =  // 0 = unbounded
      static_cast<std::int64_t>(GlProducerOptions{}.uploadBytesPerFrame);
  std::int64_t deferredReferenceMaxMb =
      static_cast<std::int64_t>(GlProducerOptions{}.maxKeptBytes >> 20);
  int visibleMinPixels = static_cast<int>(GlProducerOptions{}.visibleMinPixels);
  std::int64_t frames = static_cast<std::int64_t>(ReplayOptions{}.maxFrames);  // 0 = all
  bool noReference = !ReplayOptions{}.measure;

  // The daemon's own.
  std::string backboneAddress = protocol::kDefaultFrontendAddress;
  std::string scenePath;
  std::string modelsDir;
  std::string tracePath;
  std::string poseStreamPath;  // "-" = stdin
  std::string csvPath;
  std::string objectsCsvPath;
  std::string summaryJsonPath;
  std::string framesDir;
  int dumpEvery = 10;
  bool completeness = false;  // coverage pass: visible / missing objects per frame
  std::string label;
  int connectTimeoutMs = 10000;
  // This machine's frame-cost constants (TOML of bench_calibrate), sent in
  // the Hello for the backbone's frame-time budget (empty: none sent).
  std::string frameCostPath;
  protocol::TransportOptions transport;
};

void registerOptions(protocol::DaemonRuntime& runtime, DaemonOptions* options);
Result<render::Backend> parseBackend(const std::string& name);
// kInvalidArgument naming the option.
Status validateOptions(const DaemonOptions& options);
// After validateOptions: the shell fields into `replay` and `gl` (and the
// viewport from the frame size).
void finishOptions(DaemonOptions& options);

}  // namespace thinlod::frontend::daemon
