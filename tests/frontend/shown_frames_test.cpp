// Live scoring (shown_frames.h): a shown frame is scored against the
// reference of the pose it was drawn for, whatever it shows and whenever it
// was shown; memory bound, visibility, completeness, blank frames.
#include "thinlod/frontend/shown_frames.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <vector>

#include "thinlod/frontend/frame_metrics.h"

namespace thinlod::frontend {
namespace {

constexpr int kW = 32;
constexpr int kH = 24;
constexpr std::int64_t kMs = 1'000'000;

Pose poseAt(double time, float x) {
  Pose pose;
  pose.time = time;
  pose.position = glm::vec3(x, 1.0f, 5.0f);
  pose.fovYDegrees = 45.0f;
  return pose;
}

// What a perfect reference of `pose` looks like here: a gradient with a
// bright column whose place depends on the pose (so two poses differ).
RgbaImage pictureOf(const Pose& pose) {
  RgbaImage image(kW, kH);
  const int column = static_cast<int>(std::lround(pose.position.x * 4.0f)) % kW;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      std::uint8_t* p = image.at(x, y);
      p[0] = static_cast<std::uint8_t>(x == column ? 250 : 4 * x);
      p[1] = static_cast<std::uint8_t>(5 * y);
      p[2] = 60;
      p[3] = 255;
    }
  }
  return image;
}

class FakeReferences final : public ReferenceSource {
 public:
  Result<double> render(const Pose& pose, RgbaImage& out, glm::mat4& viewProjection) override {
    if (failAtTime && pose.time == *failAtTime) return Status(ErrorCode::kInternal, "GL lost");
    asked.push_back(pose.time);
    out = uniform ? RgbaImage(kW, kH) : pictureOf(pose);
    viewProjection = camera;
    return 7.5;
  }
  std::vector<double> asked;
  std::optional<double> failAtTime;
  bool uniform = false;
  glm::mat4 camera{1.0f};
};

HeldObjects held(std::vector<std::uint64_t> ids) {
  return std::make_shared<const std::vector<std::uint64_t>>(std::move(ids));
}

TEST(ShownFrames, AFrameShownLateIsScoredAgainstThePoseItWasDrawnFor) {
  const Pose p0 = poseAt(0.0, 1.0f), p1 = poseAt(0.1, 2.0f), p2 = poseAt(0.2, 3.0f);
  ShownFrameLog log(std::size_t{1} << 20);
  ASSERT_TRUE(log.record(0, p0, 0 * kMs, pictureOf(p0), nullptr));
  // Frame 1 was drawn for p1 but only shown at 250 ms, after p2 was due
  // (200 ms): it is p1's picture, so against p1's reference it is perfect.
  ASSERT_TRUE(log.record(1, p1, 250 * kMs, pictureOf(p1), nullptr));
  // Frame 2 is drawn for p2 but still shows what was planned for p1 (stale
  // representations): scored against p2, it is not perfect.
  ASSERT_TRUE(log.record(2, p2, 260 * kMs, pictureOf(p1), nullptr));
  FakeReferences references;
  Result<std::vector<ShownFrameScore>> scores = scoreShownFrames(log.frames(), references, {});
  ASSERT_TRUE(scores.ok()) << scores.status().toString();
  ASSERT_EQ(scores->size(), 3u);
  EXPECT_EQ(references.asked, (std::vector<double>{0.0, 0.1, 0.2}));
  EXPECT_EQ((*scores)[1].frame, 1u);
  EXPECT_TRUE(std::isinf((*scores)[1].snrDb) && (*scores)[1].snrDb > 0) << (*scores)[1].snrDb;
  const double staleVsOwnPose = compareFrames(pictureOf(p1), pictureOf(p2))->snrDb;
  EXPECT_TRUE(std::isfinite(staleVsOwnPose));
  EXPECT_DOUBLE_EQ((*scores)[2].snrDb, staleVsOwnPose);
  EXPECT_DOUBLE_EQ((*scores)[2].psnrDb, compareFrames(pictureOf(p1), pictureOf(p2))->psnrDb);
  EXPECT_DOUBLE_EQ((*scores)[2].referenceMs, 7.5);
  EXPECT_FALSE((*scores)[2].blank);
}

TEST(ShownFrames, TheSinkSeesEachShownFrameWithItsOwnReference) {
  const Pose p0 = poseAt(0.0, 1.0f), p1 = poseAt(0.5, 5.0f);
  ShownFrameLog log(std::size_t{1} << 20);
  log.record(7, p0, 0, pictureOf(p1), nullptr);
  log.record(8, p1, 0, pictureOf(p1), nullptr);
  FakeReferences references;
  std::vector<std::uint64_t> frames;
  std::vector<bool> referenceIsOwnPose;
  const auto sink = [&](const ShownFrame& shown, const RgbaImage& reference,
                        const ShownFrameScore& score) {
    frames.push_back(shown.frame);
    EXPECT_EQ(score.frame, shown.frame);
    referenceIsOwnPose.push_back(reference.pixels == pictureOf(shown.pose).pixels);
  };
  ASSERT_TRUE(scoreShownFrames(log.frames(), references, {}, sink).ok());
  EXPECT_EQ(frames, (std::vector<std::uint64_t>{7, 8}));
  EXPECT_EQ(referenceIsOwnPose, (std::vector<bool>{true, true}));
}

TEST(ShownFrames, TheLogKeepsCopiesWithinItsMemoryBoundAndCountsTheRest) {
  const std::size_t frameBytes = std::size_t{kW} * kH * 4;
  ShownFrameLog log(2 * frameBytes + 10);
  RgbaImage image = pictureOf(poseAt(0.0, 1.0f));
  EXPECT_TRUE(log.record(0, poseAt(0.0, 1.0f), 0, image, nullptr));
  image.pixels[0] = 1;  // the log holds a copy
  EXPECT_NE(log.frames()[0].image.pixels[0], 1);
  EXPECT_TRUE(log.record(1, poseAt(0.1, 1.0f), 0, image, nullptr));
  EXPECT_FALSE(log.record(2, poseAt(0.2, 1.0f), 0, image, nullptr));
  EXPECT_EQ(log.frames().size(), 2u);
  EXPECT_EQ(log.dropped(), 1u);
  EXPECT_EQ(log.bytes(), 2 * frameBytes);
}

TEST(ShownFrames, AReferenceFailureNamesTheFrame) {
  ShownFrameLog log(std::size_t{1} << 20);
  log.record(0, poseAt(0.0, 1.0f), 0, pictureOf(poseAt(0.0, 1.0f)), nullptr);
  log.record(5, poseAt(0.3, 1.0f), 0, pictureOf(poseAt(0.3, 1.0f)), nullptr);
  FakeReferences references;
  references.failAtTime = 0.3;
  Result<std::vector<ShownFrameScore>> scores = scoreShownFrames(log.frames(), references, {});
  ASSERT_FALSE(scores.ok());
  EXPECT_EQ(scores.status().code(), ErrorCode::kInternal);
  EXPECT_NE(scores.status().message().find("shown frame 5"), std::string::npos)
      << scores.status().message();
}

TEST(ShownFrames, AShownFrameOfADifferentSizeIsAnError) {
  ShownFrameLog log(std::size_t{1} << 20);
  log.record(3, poseAt(0.0, 1.0f), 0, RgbaImage(kW + 1, kH), nullptr);
  FakeReferences references;
  Result<std::vector<ShownFrameScore>> scores = scoreShownFrames(log.frames(), references, {});
  ASSERT_FALSE(scores.ok());
  EXPECT_EQ(scores.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(scores.status().message().find("frame 3"), std::string::npos);
}

TEST(ShownFrames, AUniformFrameIsBlankOnlyWhenTheReferenceIsNot) {
  ShownFrameLog log(std::size_t{1} << 20);
  log.record(0, poseAt(0.0, 1.0f), 0, RgbaImage(kW, kH), nullptr);  // all black
  FakeReferences references;
  Result<std::vector<ShownFrameScore>> scores = scoreShownFrames(log.frames(), references, {});
  ASSERT_TRUE(scores.ok());
  EXPECT_TRUE((*scores)[0].blank);
  EXPECT_TRUE(std::isinf((*scores)[0].snrDb) && (*scores)[0].snrDb < 0);
  references.uniform = true;  // nothing in view: a black frame is right
  scores = scoreShownFrames(log.frames(), references, {});
  ASSERT_TRUE(scores.ok());
  EXPECT_FALSE((*scores)[0].blank);
  EXPECT_EQ((*scores)[0].snrDb, 0.0);
}

glm::mat4 lookingDownMinusZ() {
  const glm::mat4 view =
      glm::lookAt(glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, -1.0f), glm::vec3(0.0f, 1.0f, 0.0f));
  return glm::perspective(glm::radians(60.0f), 4.0f / 3.0f, 0.1f, 100.0f) * view;
}

TEST(ShownFrames, BoxesOutsideOneClipPlaneAreNotVisible) {
  const glm::mat4 vp = lookingDownMinusZ();
  EXPECT_TRUE(boxMayBeVisible({-1, -1, -6}, {1, 1, -4}, vp));       // ahead
  EXPECT_FALSE(boxMayBeVisible({-1, -1, 4}, {1, 1, 6}, vp));        // behind
  EXPECT_FALSE(boxMayBeVisible({50, -1, -6}, {52, 1, -4}, vp));     // far right
  EXPECT_FALSE(boxMayBeVisible({-1, -1, -300}, {1, 1, -200}, vp));  // beyond the far plane
  EXPECT_TRUE(boxMayBeVisible({-100, -1, -6}, {100, 1, -4}, vp));   // spans the view
  EXPECT_TRUE(boxMayBeVisible({-1, -1, -1}, {1, 1, 1}, vp));        // around the eye
}

TEST(ShownFrames, CompletenessCountsVisibleGroupsWithNothingHeld) {
  const glm::mat4 vp = lookingDownMinusZ();
  std::vector<ObjectExtent> objects = {
      {1, 1, {-1, -1, -6}, {1, 1, -4}},   // visible, held
      {2, 2, {2, -1, -10}, {3, 1, -9}},   // visible, not held
      {3, 100, {-1, 2, -8}, {1, 3, -7}},  // LOD group 100, level 0: visible, not held
      {4, 100, {-1, 2, -8}, {1, 3, -7}},  // LOD group 100, level 1: held
      {5, 5, {-1, -1, 4}, {1, 1, 6}},     // behind: not visible, not held
  };
  const Completeness c = frameCompleteness(objects, {1, 4}, vp);
  EXPECT_EQ(c.visibleGroups, 3u);
  EXPECT_EQ(c.missingGroups, 1u);
  const Completeness none = frameCompleteness(objects, {}, vp);
  EXPECT_EQ(none.visibleGroups, 3u);
  EXPECT_EQ(none.missingGroups, 3u);
  ShownFrameLog log(std::size_t{1} << 20);
  log.record(0, poseAt(0.0, 1.0f), 0, pictureOf(poseAt(0.0, 1.0f)), held({1, 2, 4}));
  FakeReferences references;
  references.camera = vp;
  Result<std::vector<ShownFrameScore>> scores = scoreShownFrames(log.frames(), references, objects);
  ASSERT_TRUE(scores.ok());
  EXPECT_EQ((*scores)[0].completeness.visibleGroups, 3u);
  EXPECT_EQ((*scores)[0].completeness.missingGroups, 0u);
}

TEST(ShownFrames, DifferenceImageIsTheAbsoluteDifferencePerChannel) {
  RgbaImage a(2, 1), b(2, 1);
  a.pixels = {10, 200, 0, 255, 5, 5, 5, 0};
  b.pixels = {20, 100, 0, 255, 5, 6, 4, 255};
  Result<RgbaImage> d = differenceImage(a, b);
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d->pixels, (std::vector<std::uint8_t>{10, 100, 0, 255, 0, 1, 1, 255}));
  EXPECT_EQ(differenceImage(a, RgbaImage(1, 1)).status().code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::frontend
