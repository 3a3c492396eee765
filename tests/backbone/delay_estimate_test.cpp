// DelayEstimate (the measured generation delay) and Scheduler::setConfig.
#include "thinlod/backbone/delay_estimate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "thinlod/backbone/scheduler.h"

namespace thinlod::backbone {
namespace {

DelayEstimate::Options windowed(std::size_t window, std::size_t minSamples) {
  DelayEstimate::Options o;
  o.window = window;
  o.minSamples = minSamples;
  return o;
}

TEST(DelayEstimate, IsTheFloorUntilEnoughSamples) {
  DelayEstimate e;  // minSamples 4
  EXPECT_EQ(e.estimate(0.1), 0.1);
  for (int i = 0; i < 3; ++i) e.observe(5.0);
  EXPECT_EQ(e.estimate(0.1), 0.1);
  e.observe(5.0);
  EXPECT_GE(e.estimate(0.1), 5.0);
}

TEST(DelayEstimate, NearestRankQuantileRoundedUpOntoTheFloorsGrid) {
  const DelayEstimate::Options o = windowed(10, 1);
  DelayEstimate e(o);
  for (int i = 1; i <= 10; ++i) e.observe(0.1 * i);  // 0.1 .. 1.0
  EXPECT_DOUBLE_EQ(e.rawQuantile(), 0.9);            // ceil(0.9 * 10) = 9th smallest
  const double v = e.estimate(0.1);
  // The first 0.1 x 1.25^k at or above 0.9: 0.1 x 1.25^10 = 0.931.
  EXPECT_NEAR(v, 0.1 * std::pow(1.25, 10), 1e-12);
  // Below the floor: the floor.
  DelayEstimate fast(o);
  fast.observe(0.01);
  EXPECT_EQ(fast.estimate(0.2), 0.2);
}

TEST(DelayEstimate, KeepsOnlyTheWindowAndIgnoresBadValues) {
  DelayEstimate e(windowed(4, 4));
  for (int i = 0; i < 4; ++i) e.observe(9.0);
  for (int i = 0; i < 4; ++i) e.observe(0.05);
  EXPECT_EQ(e.samples(), 4u);
  EXPECT_EQ(e.rawQuantile(), 0.05);
  for (const double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()})
    EXPECT_FALSE(e.observe(bad));
  EXPECT_EQ(e.samples(), 4u);
}

TEST(DelayEstimate, IsMonotoneInTheSamplesAndBounded) {
  // Property: raising any kept observation never lowers the estimate; the
  // estimate lies in [floor, maxSeconds] and, once enough samples are kept,
  // is at least the raw quantile (capped); across magnitudes 1e-9..1e9 s.
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> exponent(-9.0, 9.0);
  for (int trial = 0; trial < 500; ++trial) {
    DelayEstimate::Options o;
    o.window = 1 + rng() % 40;
    o.minSamples = 1 + rng() % o.window;
    o.quantile = std::uniform_real_distribution<double>(0.05, 1.0)(rng);
    ASSERT_TRUE(DelayEstimate::validate(o).ok());
    std::vector<double> values(1 + rng() % 60);
    for (double& v : values) v = std::pow(10.0, exponent(rng));
    const double floor = trial % 3 == 0 ? 0.0 : std::pow(10.0, exponent(rng) / 3);
    DelayEstimate a(o), b(o);
    for (std::size_t i = 0; i < values.size(); ++i) {
      a.observe(values[i]);
      b.observe(i % 2 == 0 ? values[i] * 3.0 : values[i]);
    }
    const double ea = a.estimate(floor), eb = b.estimate(floor);
    EXPECT_LE(ea, eb) << "trial " << trial;
    EXPECT_GE(ea, std::min(floor, o.maxSeconds));
    EXPECT_LE(ea, std::max(floor, o.maxSeconds));
    if (a.samples() >= o.minSamples) {
      EXPECT_GE(ea, std::min(a.rawQuantile(), o.maxSeconds)) << "trial " << trial;
    }
  }
}

TEST(DelayEstimate, OptionsAreValidated) {
  DelayEstimate::Options o;
  EXPECT_TRUE(DelayEstimate::validate(o).ok());
  auto refused = [](DelayEstimate::Options bad) { return !DelayEstimate::validate(bad).ok(); };
  DelayEstimate::Options x = o;
  x.window = 0;
  EXPECT_TRUE(refused(x));
  x = o;
  x.minSamples = o.window + 1;
  EXPECT_TRUE(refused(x));
  x = o;
  x.quantile = 0.0;
  EXPECT_TRUE(refused(x));
  x = o;
  x.ratio = 1.0;
  EXPECT_TRUE(refused(x));
  x = o;
  x.maxSeconds = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(refused(x));
}

TEST(SchedulerConfig, SetConfigChangesTheHorizonAndRefusesBadValues) {
  Result<std::unique_ptr<Scheduler>> s = makeAccuracyCurveScheduler(SchedulerConfig{});
  ASSERT_TRUE(s.ok()) << s.status().toString();
  SchedulerConfig c = (*s)->config();
  c.generationDelay = 2.5;
  ASSERT_TRUE((*s)->setConfig(c).ok());
  EXPECT_EQ((*s)->config().generationDelay, 2.5);
  ViewerState v;
  const PredictedRegion r = predictRegion(v, (*s)->config());
  EXPECT_DOUBLE_EQ(r.reachRadius, c.maxSpeed * (c.plannedLifetime + c.linkDelay + 2.5));
  c.generationDelay = -1.0;
  EXPECT_FALSE((*s)->setConfig(c).ok());
  EXPECT_EQ((*s)->config().generationDelay, 2.5);
}

}  // namespace
}  // namespace thinlod::backbone
