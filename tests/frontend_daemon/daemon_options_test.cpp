// Option validation of thinlod-frontend: each bad value is named.
#include "daemon_options.h"

#include <gtest/gtest.h>

#include <limits>

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
  options.replay.rate = -1.0;
  expectRejected(options, "rate");
  options.replay.rate = 30.0;
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
  options.gl.width = 0;
  expectRejected(options, "width");
  options = validOptions();
  options.gl.height = 20000;
  expectRejected(options, "height");
  options = validOptions();
  options.backend = "vulkan";
  expectRejected(options, "backend");
  options = validOptions();
  options.replay.rate = std::nan("");
  expectRejected(options, "rate");
  options = validOptions();
  options.lockstepTimeoutMs = 0;
  expectRejected(options, "lockstep-timeout-ms");
  for (int wait : {-1, 1001}) {
    options = validOptions();
    options.answerWaitMs = wait;
    expectRejected(options, "answer-wait-ms");
  }
  options = validOptions();
  options.answerWaitMs = 2;
  EXPECT_TRUE(validateOptions(options).ok());
  options.replay.lockstep = true;  // lockstep has its own wait
  expectRejected(options, "answer-wait-ms");
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

TEST(DaemonOptions, FinishingConvertsEachOptionIntoTheStructItConfigures) {
  DaemonOptions options = validOptions();
  // Untouched, the converted values are the structs' own defaults.
  DaemonOptions defaults = options;
  finishOptions(defaults);
  EXPECT_EQ(defaults.gl.backend, GlProducerOptions{}.backend);
  EXPECT_EQ(defaults.gl.uploadBytesPerFrame, GlProducerOptions{}.uploadBytesPerFrame);
  EXPECT_EQ(defaults.gl.maxKeptBytes, GlProducerOptions{}.maxKeptBytes);
  EXPECT_EQ(defaults.gl.visibleMinPixels, GlProducerOptions{}.visibleMinPixels);
  EXPECT_EQ(defaults.replay.lockstepTimeout, ReplayOptions{}.lockstepTimeout);
  EXPECT_EQ(defaults.replay.maxFrames, ReplayOptions{}.maxFrames);
  EXPECT_EQ(defaults.replay.measure, ReplayOptions{}.measure);
  EXPECT_EQ(defaults.replay.viewportWidth, static_cast<std::uint32_t>(GlProducerOptions{}.width));

  options.backend = "osmesa";
  options.maxUploadBytesPerFrame = 0;  // unbounded
  options.deferredReferenceMaxMb = 3;
  options.visibleMinPixels = 40;
  options.lockstepTimeoutMs = 250;
  options.frames = 7;
  options.noReference = true;
  options.gl.width = 320;
  options.gl.height = 200;
  ASSERT_TRUE(validateOptions(options).ok());
  finishOptions(options);
  EXPECT_EQ(options.gl.backend, render::Backend::kOsMesa);
  EXPECT_EQ(options.gl.uploadBytesPerFrame, std::numeric_limits<std::size_t>::max());
  EXPECT_EQ(options.gl.maxKeptBytes, std::size_t{3} << 20);
  EXPECT_EQ(options.gl.visibleMinPixels, 40u);
  EXPECT_EQ(options.replay.lockstepTimeout, std::chrono::milliseconds(250));
  EXPECT_EQ(options.replay.maxFrames, 7u);
  EXPECT_FALSE(options.replay.measure);
  EXPECT_EQ(options.replay.viewportWidth, 320u);
  EXPECT_EQ(options.replay.viewportHeight, 200u);
}

}  // namespace
}  // namespace thinlod::frontend::daemon
