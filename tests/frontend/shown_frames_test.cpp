// Live scoring (shown_frames.h): a shown frame is scored against the
// reference of the pose it was drawn for, whatever it shows and whenever it
// was shown; memory bound, coverage, completeness, blank frames.
#include "thinlod/frontend/shown_frames.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
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
  Result<double> render(const Pose& pose, RgbaImage& out,
                        std::vector<std::uint32_t>& covered) override {
    if (failAtTime && pose.time == *failAtTime) return Status(ErrorCode::kInternal, "GL lost");
    asked.push_back(pose.time);
    out = uniform ? RgbaImage(kW, kH) : pictureOf(pose);
    covered = coverage;
    return 7.5;
  }
  std::vector<double> asked;
  std::optional<double> failAtTime;
  bool uniform = false;
  std::vector<std::uint32_t> coverage;  // empty: not measured
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
  Result<std::vector<FrameScore>> scores = scoreShownFrames(log.frames(), references, {}, 16);
  ASSERT_TRUE(scores.ok()) << scores.status().toString();
  ASSERT_EQ(scores->size(), 3u);
  EXPECT_EQ(references.asked, (std::vector<double>{0.0, 0.1, 0.2}));
  EXPECT_EQ((*scores)[1].frame, 1u);
  EXPECT_TRUE(std::isinf((*scores)[1].quality.snrDb) && (*scores)[1].quality.snrDb > 0)
      << (*scores)[1].quality.snrDb;
  const double staleVsOwnPose = compareFrames(pictureOf(p1), pictureOf(p2))->snrDb;
  EXPECT_TRUE(std::isfinite(staleVsOwnPose));
  EXPECT_DOUBLE_EQ((*scores)[2].quality.snrDb, staleVsOwnPose);
  EXPECT_DOUBLE_EQ((*scores)[2].quality.psnrDb,
                   compareFrames(pictureOf(p1), pictureOf(p2))->psnrDb);
  EXPECT_DOUBLE_EQ((*scores)[2].quality.referenceMs, 7.5);
  EXPECT_EQ((*scores)[2].quality.blank, 0);
  EXPECT_EQ((*scores)[2].quality.visibleObjects, -1);  // no coverage: not measured
  EXPECT_EQ((*scores)[2].quality.missingObjects, -1);
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
                        const FrameScore& score) {
    frames.push_back(shown.frame);
    EXPECT_EQ(score.frame, shown.frame);
    referenceIsOwnPose.push_back(reference.pixels == pictureOf(shown.pose).pixels);
  };
  ASSERT_TRUE(scoreShownFrames(log.frames(), references, {}, 16, sink).ok());
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
  Result<std::vector<FrameScore>> scores = scoreShownFrames(log.frames(), references, {}, 16);
  ASSERT_FALSE(scores.ok());
  EXPECT_EQ(scores.status().code(), ErrorCode::kInternal);
  EXPECT_NE(scores.status().message().find("shown frame 5"), std::string::npos)
      << scores.status().message();
}

TEST(ShownFrames, AShownFrameOfADifferentSizeIsAnError) {
  ShownFrameLog log(std::size_t{1} << 20);
  log.record(3, poseAt(0.0, 1.0f), 0, RgbaImage(kW + 1, kH), nullptr);
  FakeReferences references;
  Result<std::vector<FrameScore>> scores = scoreShownFrames(log.frames(), references, {}, 16);
  ASSERT_FALSE(scores.ok());
  EXPECT_EQ(scores.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(scores.status().message().find("frame 3"), std::string::npos);
}

TEST(ShownFrames, AUniformFrameIsBlankOnlyWhenTheReferenceIsNot) {
  ShownFrameLog log(std::size_t{1} << 20);
  log.record(0, poseAt(0.0, 1.0f), 0, RgbaImage(kW, kH), nullptr);  // all black
  FakeReferences references;
  Result<std::vector<FrameScore>> scores = scoreShownFrames(log.frames(), references, {}, 16);
  ASSERT_TRUE(scores.ok());
  EXPECT_EQ((*scores)[0].quality.blank, 1);
  EXPECT_TRUE(std::isinf((*scores)[0].quality.snrDb) && (*scores)[0].quality.snrDb < 0);
  references.uniform = true;  // nothing in view: a black frame is right
  scores = scoreShownFrames(log.frames(), references, {}, 16);
  ASSERT_TRUE(scores.ok());
  EXPECT_EQ((*scores)[0].quality.blank, 0);
  EXPECT_EQ((*scores)[0].quality.snrDb, 0.0);
}

TEST(ShownFrames, CoverageColoursRoundTripThroughAnRgba8Image) {
  const std::vector<std::size_t> indices = {0, 1, 254, 255, 256, 70000};
  RgbaImage ids(8, 1);  // pixel 7 stays background
  for (std::size_t k = 0; k < indices.size(); ++k) {
    const glm::vec4 c = coverageColor(indices[k]);
    for (int channel = 0; channel < 4; ++channel) {
      // What an RGBA8 target stores for a float colour.
      ids.at(static_cast<int>(k), 0)[channel] =
          static_cast<std::uint8_t>(std::lround(c[channel] * 255.0f));
    }
  }
  ids.at(6, 0)[0] = 2;  // a second pixel of index 1
  Result<std::vector<std::uint32_t>> covered = coverageFromIdImage(ids, 70001);
  ASSERT_TRUE(covered.ok()) << covered.status().toString();
  EXPECT_EQ((*covered)[0], 1u);
  EXPECT_EQ((*covered)[1], 2u);
  EXPECT_EQ((*covered)[254], 1u);
  EXPECT_EQ((*covered)[255], 1u);
  EXPECT_EQ((*covered)[256], 1u);
  EXPECT_EQ((*covered)[70000], 1u);
  EXPECT_EQ((*covered)[2], 0u);
  // A colour naming no object is an error, not a silent miscount.
  EXPECT_EQ(coverageFromIdImage(ids, 300).status().code(), ErrorCode::kInvalidArgument);
}

TEST(ShownFrames, CompletenessCountsCoveredGroupsWithNothingHeld) {
  const std::vector<ObjectExtent> objects = {
      {1, 1},    // 500 pixels, held
      {2, 2},    // 40 pixels, not held
      {3, 100},  // LOD group 100, level 0: 30 pixels, not held
      {4, 100},  // LOD group 100, level 1: not drawn in the reference, held
      {5, 5},    // hidden (0 pixels), not held
      {6, 6},    // 10 pixels: below the threshold of 16
  };
  const std::vector<std::uint32_t> covered = {500, 40, 30, 0, 0, 10};
  Result<Completeness> c = frameCompleteness(objects, covered, {1, 4}, 16);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->visibleGroups, 3u);  // 1, 2, 100
  EXPECT_EQ(c->missingGroups, 1u);  // 2
  Result<Completeness> none = frameCompleteness(objects, covered, {}, 16);
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->missingGroups, 3u);
  Result<Completeness> tiny = frameCompleteness(objects, covered, {}, 1);
  ASSERT_TRUE(tiny.ok());
  EXPECT_EQ(tiny->visibleGroups, 4u);  // the 10-pixel object counts too
  EXPECT_EQ(frameCompleteness(objects, {1, 2}, {}, 16).status().code(),
            ErrorCode::kInvalidArgument);

  ShownFrameLog log(std::size_t{1} << 20);
  log.record(0, poseAt(0.0, 1.0f), 0, pictureOf(poseAt(0.0, 1.0f)), held({1, 2, 4}));
  FakeReferences references;
  references.coverage = covered;
  Result<std::vector<FrameScore>> scores = scoreShownFrames(log.frames(), references, objects, 16);
  ASSERT_TRUE(scores.ok());
  EXPECT_EQ((*scores)[0].quality.visibleObjects, 3);
  EXPECT_EQ((*scores)[0].quality.missingObjects, 0);
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
