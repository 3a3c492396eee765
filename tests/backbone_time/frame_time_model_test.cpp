// The frame-time cost model (per-object time, fill-bound floor, projected
// pixels, Reddy acuity) and the cost-constant fit and file format.
#include "frame_time_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <random>

#include "thinlod/common/core/frame_cost.h"

namespace thinlod::backbone {
namespace {

constexpr double kPi = 3.14159265358979323846;

FrameCostConstants someConstants() {
  FrameCostConstants c;
  c.initSeconds = 4e-4;
  c.finalSeconds = 6e-4;
  c.setupSeconds = 3e-5;
  c.triangleSeconds = 2e-8;
  c.pixelSeconds = 5e-9;
  return c;
}

TEST(FrameTimeModel, ObjectTimeIsSetupPlusTheBottleneck) {
  const FrameCostConstants c = someConstants();
  const ObjectFrameLoad load{10000.0, 20000.0};  // 2e-4 s of triangles at r = 1, 1e-4 s of fill
  EXPECT_DOUBLE_EQ(objectRenderSeconds(c, load, 1.0), 3e-5 + 2e-4);
  EXPECT_DOUBLE_EQ(objectRenderSeconds(c, load, 0.25), 3e-5 + 1e-4);  // fill-bound
  EXPECT_DOUBLE_EQ(fillBoundResolution(c, load), 0.5);
  // Below r_fill fewer triangles save nothing; above it the time is linear.
  EXPECT_DOUBLE_EQ(objectRenderSeconds(c, load, 0.3), objectRenderSeconds(c, load, 0.5));
  EXPECT_NEAR(objectRenderSeconds(c, load, 0.75) - objectRenderSeconds(c, load, 0.5),
              0.25 * 10000.0 * 2e-8, 1e-18);
  EXPECT_DOUBLE_EQ(fillBoundResolution(c, {10000.0, 1e9}), 1.0);  // always fill-bound
  EXPECT_DOUBLE_EQ(fillBoundResolution(c, {10000.0, 0.0}), 0.0);
  FrameCostConstants polygons;  // polygon budget: t_tri = 1, all else 0
  polygons.triangleSeconds = 1.0;
  EXPECT_DOUBLE_EQ(fillBoundResolution(polygons, {500.0, 1e6}), 0.0);
  EXPECT_DOUBLE_EQ(objectRenderSeconds(polygons, {500.0, 1e6}, 0.5), 250.0);
  EXPECT_DOUBLE_EQ(fillBoundResolution(c, {0.0, 10.0}), 1.0);  // nothing to reduce
  EXPECT_DOUBLE_EQ(fixedFrameSeconds(c, 10, 1e-3), 4e-4 + 6e-4 + 1e-3 + 10 * 3e-5);
}

TEST(FrameTimeModel, ProjectedSpherePixels) {
  ScreenProjection screen{640.0, 480.0, kPi / 2.0};  // focal length 240 px
  // R / d = 0.6: tan(asin(0.6)) = 0.75 -> disc radius 180 px.
  EXPECT_NEAR(projectedSpherePixels(10.0, 6.0, screen), kPi * 180.0 * 180.0, 1e-6);
  // Far away: the small-angle limit pi (f R / d)^2.
  EXPECT_NEAR(projectedSpherePixels(1e4, 1.0, screen), kPi * 0.024 * 0.024, 1e-7 * 0.0018);
  // Inside the sphere or filling the screen: the whole viewport.
  EXPECT_DOUBLE_EQ(projectedSpherePixels(0.5, 1.0, screen), 640.0 * 480.0);
  EXPECT_DOUBLE_EQ(projectedSpherePixels(1.0, 1.0, screen), 640.0 * 480.0);
  EXPECT_DOUBLE_EQ(projectedSpherePixels(1.01, 1.0, screen), 640.0 * 480.0);
  double previous = std::numeric_limits<double>::infinity();
  for (double d = 1.5; d < 1000.0; d *= 1.3) {
    const double p = projectedSpherePixels(d, 1.0, screen);
    EXPECT_LE(p, previous);
    previous = p;
  }
}

TEST(FrameTimeModel, PixelsPerDegree) {
  // 1920 x 1080 on 0.5 x 0.28125 m seen from 0.6 m: 3840 px/m.
  EXPECT_NEAR(pixelsPerDegree(1920, 1080, 0.5, 0.28125, 0.6), 0.6 * std::tan(kPi / 180.0) * 3840.0,
              1e-9);
  // The coarser axis decides.
  EXPECT_NEAR(pixelsPerDegree(1920, 540, 0.5, 0.28125, 0.6), 0.6 * std::tan(kPi / 180.0) * 1920.0,
              1e-9);
}

TEST(FrameTimeModel, ReddyAcuityIsContinuousMonotoneAndBounded) {
  EXPECT_DOUBLE_EQ(reddyVelocityFactor(0.0), 1.0);
  EXPECT_DOUBLE_EQ(reddyEccentricityFactor(0.0), 1.0);
  EXPECT_NEAR(reddyVelocityFactor(0.825), reddyVelocityFactor(0.8250001), 1e-3);
  EXPECT_NEAR(reddyVelocityFactor(118.3), reddyVelocityFactor(118.30001), 1e-3);
  EXPECT_NEAR(reddyEccentricityFactor(5.79), reddyEccentricityFactor(5.7900001), 1e-3);
  EXPECT_NEAR(reddyVelocityFactor(10.0), (57.69 - 27.78) / 60.0, 1e-12);
  EXPECT_NEAR(reddyEccentricityFactor(20.0), 7.49 / 49.0, 1e-12);
  double pv = 2.0;
  double pe = 2.0;
  for (double x = 0.0; x < 300.0; x += 0.37) {
    const double v = reddyVelocityFactor(x);
    const double e = reddyEccentricityFactor(x);
    EXPECT_LE(v, pv);
    EXPECT_LE(e, pe);
    EXPECT_GT(v, 0.0);
    EXPECT_GT(e, 0.0);
    pv = v;
    pe = e;
  }
  EXPECT_DOUBLE_EQ(reddyAcuity(10.0, 20.0),
                   reddyVelocityFactor(10.0) * reddyEccentricityFactor(20.0));
}

TEST(FrameTimeModel, EccentricityAndApparentSpeed) {
  const glm::dvec3 eye(0.0);
  const glm::dvec3 forward(0.0, 0.0, -1.0);
  EXPECT_DOUBLE_EQ(eccentricityDegrees(eye, forward, {0.0, 0.0, -5.0}, 1.0), 0.0);
  // 90 degrees off axis at distance 2, radius 1: 90 - 30 degrees.
  EXPECT_NEAR(eccentricityDegrees(eye, forward, {2.0, 0.0, 0.0}, 1.0), 60.0, 1e-9);
  EXPECT_DOUBLE_EQ(eccentricityDegrees(eye, forward, {0.5, 0.0, 0.0}, 1.0), 0.0);  // inside
  const glm::dvec3 point(0.0, 0.0, -10.0);
  EXPECT_DOUBLE_EQ(apparentSpeedDegreesPerSecond(eye, forward, eye, forward, point, 0.1), 0.0);
  // Turning the view 90 degrees in one second sweeps a fixed point by 90 deg/s.
  EXPECT_NEAR(apparentSpeedDegreesPerSecond(eye, forward, eye, {-1.0, 0.0, 0.0}, point, 1.0), 90.0,
              1e-9);
  // Tracking the point while moving: no apparent motion.
  const glm::dvec3 moved(10.0, 0.0, 0.0);
  EXPECT_NEAR(
      apparentSpeedDegreesPerSecond(eye, forward, moved, glm::normalize(point - moved), point, 1.0),
      0.0, 1e-9);
  // Sideways translation at 1 m/s past a point 10 m ahead: about 1/10 rad/s.
  EXPECT_NEAR(apparentSpeedDegreesPerSecond(eye, forward, {0.01, 0.0, 0.0}, forward, point, 0.01),
              0.1 * 180.0 / kPi, 1e-3);
  // Half turn of the view: whatever the axis chosen for it, a fixed point
  // that was straight ahead is now straight behind: 180 deg in one second.
  EXPECT_NEAR(apparentSpeedDegreesPerSecond(eye, forward, eye, -forward, point, 1.0), 180.0, 1e-9);
  EXPECT_DOUBLE_EQ(apparentSpeedDegreesPerSecond(eye, forward, eye, forward, point, 0.0), 0.0);
}

// ---------------------------------------------------------------- the fit

std::vector<FrameTimeSample> syntheticSamples(const FrameCostConstants& truth, std::uint64_t seed,
                                              double noiseShare) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> count(1, 60);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<FrameTimeSample> samples;
  for (int s = 0; s < 120; ++s) {
    FrameTimeSample sample;
    const int n = count(rng);
    const bool fillHeavy = s % 3 == 0;
    for (int j = 0; j < n; ++j) {
      DrawnObjectLoad o;
      o.triangles = std::floor(std::exp(std::log(50.0) + unit(rng) * std::log(2000.0)));
      o.coveredPixels = fillHeavy ? 1e3 + unit(rng) * 3e5 : unit(rng) * 2e3;
      sample.objects.push_back(o);
    }
    const double t = predictFrameSeconds(truth, sample.objects);
    sample.seconds = t * (1.0 + noiseShare * noise(rng));
    samples.push_back(sample);
  }
  return samples;
}

TEST(FrameCostFit, RecoversKnownConstantsFromExactData) {
  const FrameCostConstants truth = someConstants();
  const auto fit = fitFrameCostConstants(syntheticSamples(truth, 1, 0.0), 0.4);
  ASSERT_TRUE(fit.ok()) << fit.status().toString();
  const FrameCostConstants& c = fit->constants;
  EXPECT_NEAR(c.initSeconds + c.finalSeconds, 1e-3, 1e-12);
  EXPECT_NEAR(c.initSeconds, 0.4e-3, 1e-12);
  EXPECT_NEAR(c.setupSeconds, truth.setupSeconds, 1e-9 * truth.setupSeconds);
  EXPECT_NEAR(c.triangleSeconds, truth.triangleSeconds, 1e-9 * truth.triangleSeconds);
  EXPECT_NEAR(c.pixelSeconds, truth.pixelSeconds, 1e-9 * truth.pixelSeconds);
  EXPECT_NEAR(fit->rSquared, 1.0, 1e-12);
  EXPECT_GT(fit->fillBoundShare, 0.05);
  EXPECT_LT(fit->fillBoundShare, 0.95);
}

TEST(FrameCostFit, AdditiveModelRecoversItsConstants) {
  FrameCostConstants truth = someConstants();
  truth.additive = true;
  const auto samples = syntheticSamples(truth, 4, 0.0);
  const auto fit = fitFrameCostConstants(samples, 0.5, true);
  ASSERT_TRUE(fit.ok());
  EXPECT_TRUE(fit->constants.additive);
  EXPECT_NEAR(fit->constants.triangleSeconds, truth.triangleSeconds, 1e-9 * truth.triangleSeconds);
  EXPECT_NEAR(fit->constants.pixelSeconds, truth.pixelSeconds, 1e-9 * truth.pixelSeconds);
  EXPECT_NEAR(fit->constants.setupSeconds, truth.setupSeconds, 1e-9 * truth.setupSeconds);
  EXPECT_NEAR(fit->rSquared, 1.0, 1e-12);
  // The max model cannot explain additive data exactly.
  const auto wrong = fitFrameCostConstants(samples, 0.5, false);
  ASSERT_TRUE(wrong.ok());
  EXPECT_LT(wrong->rSquared, fit->rSquared);
  // Additive objects have no fill-bound floor and pay fill on top.
  const ObjectFrameLoad load{10000.0, 20000.0};
  EXPECT_DOUBLE_EQ(fillBoundResolution(truth, load), 0.0);
  EXPECT_DOUBLE_EQ(objectRenderSeconds(truth, load, 0.5), 3e-5 + 1e-4 + 1e-4);
}

TEST(FrameCostFit, NoisyDataGivesCloseConstantsAndHighRSquared) {
  const FrameCostConstants truth = someConstants();
  for (std::uint64_t seed = 2; seed < 12; ++seed) {
    const auto fit = fitFrameCostConstants(syntheticSamples(truth, seed, 0.01));
    ASSERT_TRUE(fit.ok());
    const FrameCostConstants& c = fit->constants;
    // 1 % noise on ~3 ms frames is ~30 us, about one object's setup: the
    // setup is the least determined constant.
    EXPECT_NEAR(c.setupSeconds, truth.setupSeconds, 0.25 * truth.setupSeconds);
    EXPECT_NEAR(c.triangleSeconds, truth.triangleSeconds, 0.05 * truth.triangleSeconds);
    EXPECT_NEAR(c.pixelSeconds, truth.pixelSeconds, 0.05 * truth.pixelSeconds);
    EXPECT_GT(fit->rSquared, 0.99);
    EXPECT_LT(fit->rSquared, 1.0);
  }
}

TEST(FrameCostFit, RejectsPoorDesignsAndBadValues) {
  const FrameCostConstants truth = someConstants();
  std::vector<FrameTimeSample> samples = syntheticSamples(truth, 3, 0.0);
  EXPECT_FALSE(fitFrameCostConstants({samples.begin(), samples.begin() + 5}).ok());
  EXPECT_FALSE(fitFrameCostConstants(samples, 1.5).ok());
  // Every frame with the same object count and loads in a fixed ratio: the
  // setup and the intercept cannot be told apart.
  std::vector<FrameTimeSample> same;
  for (int s = 0; s < 20; ++s) {
    FrameTimeSample f;
    for (int j = 0; j < 10; ++j) f.objects.push_back({100.0 * (s + 1), 10.0 * (s + 1)});
    f.seconds = predictFrameSeconds(truth, f.objects);
    same.push_back(f);
  }
  const auto poor = fitFrameCostConstants(same);
  ASSERT_FALSE(poor.ok());
  EXPECT_EQ(poor.status().code(), ErrorCode::kInvalidArgument);
  auto bad = samples;
  bad[4].seconds = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(fitFrameCostConstants(bad).ok());
  bad = samples;
  bad[4].objects[0].coveredPixels = -1.0;
  EXPECT_FALSE(fitFrameCostConstants(bad).ok());
  bad = samples;
  bad[7].objects[0].triangles = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(fitFrameCostConstants(bad).ok());
}

TEST(FrameCostFile, RoundTripsExactly) {
  FrameCostConstants c = someConstants();
  c.additive = true;
  const std::string text = formatFrameCostToml(c, "renderer: test\nR^2 = 0.99");
  EXPECT_NE(text.find("# renderer: test\n# R^2 = 0.99\n"), std::string::npos) << text;
  const auto parsed = parseFrameCostToml(text);
  ASSERT_TRUE(parsed.ok()) << parsed.status().toString();
  EXPECT_EQ(parsed->initSeconds, c.initSeconds);
  EXPECT_EQ(parsed->finalSeconds, c.finalSeconds);
  EXPECT_EQ(parsed->setupSeconds, c.setupSeconds);
  EXPECT_EQ(parsed->triangleSeconds, c.triangleSeconds);
  EXPECT_EQ(parsed->pixelSeconds, c.pixelSeconds);
  EXPECT_TRUE(parsed->additive);
  EXPECT_TRUE(validateFrameCostConstants(*parsed).ok());
}

TEST(FrameCostFile, RejectsMalformedFiles) {
  const std::string good = formatFrameCostToml(someConstants(), "");
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  struct Case {
    std::string text;
    ErrorCode code;
  };
  const Case cases[] = {
      {replaced("version = 1", "version = 2"), ErrorCode::kVersionMismatch},
      {replaced("pixel_seconds", "pixel_secs"), ErrorCode::kParseError},
      {replaced("setup_seconds = ", "setup_seconds "), ErrorCode::kParseError},
      {replaced("init_seconds = 0.00040000000000000002", "init_seconds = nan"),
       ErrorCode::kInvalidArgument},
      {replaced("init_seconds = 0.00040000000000000002", "init_seconds = -1"),
       ErrorCode::kInvalidArgument},
      {replaced("init_seconds = 0.00040000000000000002", "init_seconds = 1x"),
       ErrorCode::kParseError},
      {replaced("init_seconds = 0.00040000000000000002", "init_seconds ="), ErrorCode::kParseError},
      {good + "init_seconds = 1\n", ErrorCode::kParseError},
      {replaced("additive = 0", "additive = 2"), ErrorCode::kInvalidArgument},
      {std::string(70000, '#'), ErrorCode::kInvalidArgument},
  };
  for (const Case& c : cases) {
    const auto parsed = parseFrameCostToml(c.text);
    ASSERT_FALSE(parsed.ok()) << c.text;
    EXPECT_EQ(parsed.status().code(), c.code) << parsed.status().toString();
  }
  // Every truncated prefix fails cleanly until the last key has a value
  // (then a cut-off number may still parse, or not: "5e" does not).
  const std::size_t lastValue = good.find("additive = ") + 11;
  for (std::size_t n = 0; n <= good.size(); ++n) {
    const auto parsed = parseFrameCostToml(good.substr(0, n));
    if (n <= lastValue) {
      EXPECT_FALSE(parsed.ok()) << n;
    }
    if (n == good.size()) {
      EXPECT_TRUE(parsed.ok());
    }
  }
  const auto missing = parseFrameCostToml("version = 1\n");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("missing key"), std::string::npos);
}

}  // namespace
}  // namespace thinlod::backbone
