// The on-disk cache of a skinned ladder's bounds under a clip
// (animated_bound_cache.h): the key changes with everything the bounds
// depend on, stored bounds read back exactly, and damaged, stale or forged
// files are refused and measured again.
#include "thinlod/simplifier/animated_bound_cache.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <set>

#include "articulated_figure.h"

namespace thinlod::simplifier {
namespace {

using anim::testing::ArticulatedFigure;
using anim::testing::makeArticulatedFigure;

AnimatedLadderInputs inputsOf(const ArticulatedFigure& f) {
  return AnimatedLadderInputs{f.mesh, f.skin, f.skeleton, f.clip, "producer", {10, 100, 1000}, {}};
}

std::filesystem::path freshDirectory(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("thinlod-animated-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir;
}

TEST(AnimatedBoundCache, KeyChangesWithEveryInput) {
  const ArticulatedFigure f = makeArticulatedFigure({6, 8});
  std::set<std::string> keys;
  keys.insert(animatedBoundCacheKey(inputsOf(f)));
  EXPECT_EQ(animatedBoundCacheKey(inputsOf(f)), *keys.begin());  // deterministic

  auto changed = [&](auto edit) {
    ArticulatedFigure g = f;
    AnimatedLadderInputs in = inputsOf(g);
    edit(g, in);
    return keys.insert(animatedBoundCacheKey(in)).second;
  };
  EXPECT_TRUE(
      changed([](ArticulatedFigure& g, AnimatedLadderInputs&) { g.mesh.positions[0].x += 1e-3f; }));
  EXPECT_TRUE(changed([](ArticulatedFigure& g, AnimatedLadderInputs&) {
    for (anim::VertexSkin& s : g.skin) {
      if (!s.rigid()) {
        s.weightB *= 0.5f;
        break;
      }
    }
  }));
  EXPECT_TRUE(changed([](ArticulatedFigure& g, AnimatedLadderInputs&) {
    g.skeleton.bones[1].restLocal[3][0] += 0.1f;
  }));
  EXPECT_TRUE(changed([](ArticulatedFigure& g, AnimatedLadderInputs&) {
    g.skeleton.bones[1].inverseBind[3][1] += 0.1f;
  }));
  EXPECT_TRUE(changed([](ArticulatedFigure& g, AnimatedLadderInputs&) { g.clip.duration *= 2.0; }));
  EXPECT_TRUE(changed([](ArticulatedFigure& g, AnimatedLadderInputs&) {
    ASSERT_FALSE(g.clip.channels.empty());
    ASSERT_FALSE(g.clip.channels[0].rotations.empty());
    g.clip.channels[0].rotations.back().value.x += 0.01f;
  }));
  EXPECT_TRUE(changed([](ArticulatedFigure&, AnimatedLadderInputs& in) { in.producer += "x"; }));
  EXPECT_TRUE(
      changed([](ArticulatedFigure&, AnimatedLadderInputs& in) { in.rungTriangles[1] = 101; }));
  EXPECT_TRUE(
      changed([](ArticulatedFigure&, AnimatedLadderInputs& in) { in.options.maxPoses = 17; }));
  EXPECT_TRUE(changed(
      [](ArticulatedFigure&, AnimatedLadderInputs& in) { in.options.surface.samplesPerMesh = 7; }));
  EXPECT_TRUE(changed([](ArticulatedFigure&, AnimatedLadderInputs& in) {
    in.options.wrap = anim::ClipWrap::kClamp;
  }));
}

TEST(AnimatedBoundCache, StoredBoundsReadBackAndBadFilesAreMeasuredAgain) {
  const ArticulatedFigure f = makeArticulatedFigure({6, 8});
  const AnimatedLadderInputs in = inputsOf(f);
  const std::filesystem::path dir = freshDirectory("roundtrip");
  int measurements = 0;
  const std::vector<double> bounds = {0.5, 0.125, 1.0 / 3.0};
  auto measure = [&]() -> Result<std::vector<double>> {
    ++measurements;
    return bounds;
  };
  AnimatedBoundCache cache(dir);
  Result<std::vector<double>> first = cache.getOrMeasure(in, measure);
  ASSERT_TRUE(first.ok());
  EXPECT_EQ(measurements, 1);
  Result<std::vector<double>> second = cache.getOrMeasure(in, measure);
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(measurements, 1);
  EXPECT_EQ(*second, bounds);  // bit for bit (JSON round-trips doubles)
  EXPECT_EQ(cache.stats().hits, 1);

  const std::string key = animatedBoundCacheKey(in);
  const std::string header =
      R"({"format": "thinlod-animated-bounds", "version": 1, "key": ")" + key + "\", ";
  const std::vector<std::string> bad = {
      "",
      "[1, 2]",
      header + R"("bounds": [0.5, 0.1]})",            // one rung short
      header + R"("bounds": [0.5, 0.1, 0.2, 0.3]})",  // one too many
      header + R"("bounds": [0.5, -0.1, 0.2]})",      // negative
      header + R"("bounds": [0.5, null, 0.2]})",      // not a number
      header + R"("bounds": [0.5, "0.1", 0.2]})",
      header + R"("bounds": [0.5, 1e400, 0.2]})",  // infinite
      header + R"("bounds": {"a": 1}})",
      header + "}",
      R"({"format": "thinlod-animated-bounds", "version": 2, "key": ")" + key +
          R"(", "bounds": [1, 2, 3]})",
      R"({"format": "thinlod-animated-bounds", "version": 1, "key": "0", "bounds": [1, 2, 3]})",
      R"({"format": "thinlod-hybrid-curves", "version": 1, "key": ")" + key +
          R"(", "bounds": [1, 2, 3]})",
  };
  for (const std::string& text : bad) {
    EXPECT_FALSE(parseAnimatedBounds(text, key, 3).ok()) << text;
    std::ofstream(cache.fileFor(key), std::ios::trunc) << text;
    const int before = measurements;
    Result<std::vector<double>> again = cache.getOrMeasure(in, measure);
    ASSERT_TRUE(again.ok()) << text;
    EXPECT_EQ(measurements, before + 1) << text;
    EXPECT_EQ(*again, bounds);
  }
  // The last measurement rewrote a good file.
  EXPECT_TRUE(cache.getOrMeasure(in, measure).ok());
  EXPECT_EQ(measurements, 1 + static_cast<int>(bad.size()));

  // A measurement error is returned and nothing is stored.
  AnimatedLadderInputs other = in;
  other.producer = "other";
  Result<std::vector<double>> failed = cache.getOrMeasure(
      other,
      []() -> Result<std::vector<double>> { return Status(ErrorCode::kInvalidArgument, "x"); });
  EXPECT_FALSE(failed.ok());
  EXPECT_FALSE(std::filesystem::exists(cache.fileFor(animatedBoundCacheKey(other))));
  // A measurement a reader would refuse is returned but never stored.
  Result<std::vector<double>> nan = cache.getOrMeasure(other, []() -> Result<std::vector<double>> {
    return std::vector<double>{1.0, std::numeric_limits<double>::quiet_NaN(), 2.0};
  });
  EXPECT_TRUE(nan.ok());
  EXPECT_EQ(cache.stats().writeFailures, 1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace thinlod::simplifier
