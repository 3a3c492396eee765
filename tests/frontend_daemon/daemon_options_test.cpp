// Option validation of thinlod-frontend: each bad value is named.
#include "daemon_options.h"

#include <gtest/gtest.h>

namespace thinlod::frontend::daemon {
namespace {

DaemonOptions validOptions() {
  DaemonOptions options;
  options.tracePath = "flight.trace";
  options.scenePath = "room.wrl";
  return options;
}

void expectRejected(const DaemonOptions& options, const std::string& option) {
  const Status status = validateOptions(options);
  EXPECT_EQ(status.code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(status.message().rfind("--" + option + ":", 0), 0u) << status.message();
}

TEST(DaemonOptions, DefaultsWithTraceAndSceneAreValid) {
  EXPECT_TRUE(validateOptions(validOptions()).ok());
}

TEST(DaemonOptions, TraceIsRequired) {
  DaemonOptions options = validOptions();
  options.tracePath.clear();
  expectRejected(options, "trace");
}

TEST(DaemonOptions, ExactlyOneOfTraceAndPoseStream) {
  DaemonOptions options = validOptions();
  options.poseStreamPath = "-";
  expectRejected(options, "trace");  // both
  options.tracePath.clear();
  EXPECT_TRUE(validateOptions(options).ok());
}

TEST(DaemonOptions, APoseStreamCannotBeUnpaced) {
  DaemonOptions options = validOptions();
  options.tracePath.clear();
  options.poseStreamPath = "poses.fifo";
  options.rate = -1.0;
  expectRejected(options, "rate");
  options.rate = 30.0;
  EXPECT_TRUE(validateOptions(options).ok());
}

TEST(DaemonOptions, SceneIsRequiredOnlyForTheReference) {
  DaemonOptions options = validOptions();
  options.scenePath.clear();
  expectRejected(options, "scene");
  options.noReference = true;
  EXPECT_TRUE(validateOptions(options).ok());
}

TEST(DaemonOptions, OutOfRangeValuesAreNamed) {
  DaemonOptions options = validOptions();
  options.width = 0;
  expectRejected(options, "width");
  options = validOptions();
  options.height = 20000;
  expectRejected(options, "height");
  options = validOptions();
  options.backend = "vulkan";
  expectRejected(options, "backend");
  options = validOptions();
  options.rate = std::nan("");
  expectRejected(options, "rate");
  options = validOptions();
  options.lockstepTimeoutMs = 0;
  expectRejected(options, "lockstep-timeout-ms");
  options = validOptions();
  options.maxUploadBytesPerFrame = -1;
  expectRejected(options, "max-upload-bytes-per-frame");
  options = validOptions();
  options.dumpEvery = 0;
  expectRejected(options, "dump-every");
  options = validOptions();
  options.frames = -3;
  expectRejected(options, "frames");
}

TEST(DaemonOptions, BackendNames) {
  EXPECT_EQ(parseBackend("auto").value(), render::Backend::kAuto);
  EXPECT_EQ(parseBackend("egl").value(), render::Backend::kEgl);
  EXPECT_EQ(parseBackend("osmesa").value(), render::Backend::kOsMesa);
  EXPECT_FALSE(parseBackend("EGL").ok());
}

}  // namespace
}  // namespace thinlod::frontend::daemon
