// Hand-checked cases for every AccuracyCurve operation, including the
// situations of Pasman & Jansen 2002, Figures 5-7.
#include "thinlod/common/core/accuracy_curve.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "curve_test_util.h"

namespace thinlod {
namespace {

using testing::kInf;
using testing::nextDown;
using testing::nextUp;
using testing::satisfiesInvariants;

AccuracyCurve make(const std::vector<CurveTriple>& triples, double maxAccuracy) {
  auto curve = AccuracyCurve::fromTriples(triples, maxAccuracy);
  EXPECT_TRUE(curve.ok()) << curve.status().toString();
  return curve.ok() ? curve.value() : AccuracyCurve();
}

// r = 10 + 2a on [0, 5), jump to 30 at 5, then r = 25 + a up to 10.
AccuracyCurve twoPartCurve() { return make({{0, 10, 2}, {5, 25, 1}}, 10); }

void expectSegment(const CurveSegment& s, double start, double value, double slope) {
  EXPECT_DOUBLE_EQ(s.start, start);
  EXPECT_DOUBLE_EQ(s.value, value);
  EXPECT_DOUBLE_EQ(s.slope, slope);
}

::testing::AssertionResult failsWith(const Result<AccuracyCurve>& result, const char* needle) {
  if (result.ok()) return ::testing::AssertionFailure() << "unexpectedly OK";
  if (result.status().code() != ErrorCode::kInvalidArgument) {
    return ::testing::AssertionFailure() << "wrong code: " << result.status().toString();
  }
  if (result.status().message().find(needle) == std::string::npos) {
    return ::testing::AssertionFailure()
           << "message lacks '" << needle << "': " << result.status().message();
  }
  return ::testing::AssertionSuccess();
}

// --- Construction ------------------------------------------------------------

TEST(AccuracyCurve, FromTriplesStoresValueAtSegmentStart) {
  const AccuracyCurve c = twoPartCurve();
  ASSERT_EQ(c.segments().size(), 2u);
  expectSegment(c.segments()[0], 0, 10, 2);
  expectSegment(c.segments()[1], 5, 30, 1);
  EXPECT_EQ(c.minAccuracy(), 0.0);
  EXPECT_EQ(c.maxAccuracy(), 10.0);
}

// Resources mapped affinely (triangles -> link bytes): every value and slope
// mapped, the domain unchanged, monotone; scale 0 gives a constant curve.
TEST(AccuracyCurve, AffineResourcesMapsValuesAndSlopesOnTheSameDomain) {
  const AccuracyCurve c = twoPartCurve();
  const AccuracyCurve bytes = c.affineResources(100.0, 3.0);
  ASSERT_EQ(bytes.segments().size(), 2u);
  expectSegment(bytes.segments()[0], 0, 130, 6);
  expectSegment(bytes.segments()[1], 5, 190, 3);
  EXPECT_EQ(bytes.maxAccuracy(), c.maxAccuracy());
  for (const double a : {0.0, 2.5, 5.0, 7.5, 10.0}) {
    EXPECT_DOUBLE_EQ(bytes.resourcesFor(a), 100.0 + 3.0 * c.resourcesFor(a)) << a;
  }
  const AccuracyCurve flat = c.affineResources(7.0, 0.0);
  EXPECT_DOUBLE_EQ(flat.resourcesFor(0.0), 7.0);
  EXPECT_DOUBLE_EQ(flat.resourcesFor(10.0), 7.0);
  EXPECT_TRUE(AccuracyCurve().affineResources(1.0, 2.0).empty());
}

TEST(AccuracyCurve, TriplesRoundTrip) {
  const std::vector<CurveTriple> t = twoPartCurve().triples();
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t[1].A, 5);
  EXPECT_DOUBLE_EQ(t[1].R, 25);
  EXPECT_DOUBLE_EQ(t[1].K, 1);
}

TEST(AccuracyCurve, EmptyTriplesGiveEmptyCurve) { EXPECT_TRUE(make({}, 0).empty()); }

TEST(AccuracyCurve, RejectsUnsortedTriples) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{5, 0, 1}, {1, 10, 1}}, 10), "triple 1"));
}

TEST(AccuracyCurve, RejectsDuplicateA) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{1, 0, 1}, {1, 10, 1}}, 10), "duplicate"));
}

TEST(AccuracyCurve, RejectsNaN) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{0, 0, 1}, {nan, 10, 1}}, 10), "triple 1"));
}

TEST(AccuracyCurve, RejectsInfinity) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{0, kInf, 1}}, 10), "triple 0"));
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{0, 1, 1}}, kInf), "maxAccuracy"));
}

TEST(AccuracyCurve, RejectsNegativeSlope) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{0, 10, -1}}, 10), "negative slope"));
}

TEST(AccuracyCurve, RejectsDecreaseAcrossKnot) {
  // Part 0 reaches 20 at a = 5, part 1 starts at 5.
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{0, 10, 2}, {5, 5, 0}}, 10), "decreases"));
}

TEST(AccuracyCurve, RejectsNegativeResources) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{0, -1, 0}}, 10), "negative resources"));
}

TEST(AccuracyCurve, RejectsMaxAccuracyBelowLastKnot) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fromTriples({{0, 1, 0}, {4, 1, 0}}, 3), "maxAccuracy"));
}

TEST(AccuracyCurve, FromSegmentsRepairsOneUlpDecrease) {
  auto c = AccuracyCurve::fromSegments({{0, 1, 1}, {1, nextDown(2.0), 0}}, 2);
  ASSERT_TRUE(c.ok()) << c.status().toString();
  EXPECT_EQ(c->segments()[1].value, 2.0);
}

TEST(AccuracyCurve, FromSegmentsRejectsRealDecrease) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fromSegments({{0, 1, 1}, {1, 1.5, 0}}, 2), "segment 1"));
}

TEST(AccuracyCurve, PointCurveHasZeroWidthDomain) {
  const AccuracyCurve p = AccuracyCurve::point(4, 100);
  EXPECT_EQ(p.minAccuracy(), 4);
  EXPECT_EQ(p.maxAccuracy(), 4);
  EXPECT_EQ(p.resourcesFor(1), 100);
  EXPECT_EQ(p.resourcesFor(4), 100);
  EXPECT_EQ(p.resourcesFor(nextUp(4)), kInf);
}

// --- Evaluation ----------------------------------------------------------------

TEST(AccuracyCurve, ResourcesForInsideDomain) {
  const AccuracyCurve c = twoPartCurve();
  EXPECT_DOUBLE_EQ(c.resourcesFor(2.5), 15);
  EXPECT_DOUBLE_EQ(c.resourcesFor(nextDown(5)), 20);
  EXPECT_DOUBLE_EQ(c.resourcesFor(5), 30);  // segments are [A_i, A_i+1)
  EXPECT_DOUBLE_EQ(c.resourcesFor(10), 35);
}

TEST(AccuracyCurve, ResourcesForExtendsLeftOnly) {
  const AccuracyCurve c = twoPartCurve();
  EXPECT_EQ(c.resourcesFor(-100), 10);
  EXPECT_EQ(c.resourcesFor(nextUp(10)), kInf);
  EXPECT_EQ(c.resourcesFor(std::numeric_limits<double>::quiet_NaN()), kInf);
}

TEST(AccuracyCurve, ResourcesForClampedExtendsBothSides) {
  const AccuracyCurve c = twoPartCurve();
  EXPECT_EQ(c.resourcesForClamped(-100), 10);
  EXPECT_DOUBLE_EQ(c.resourcesForClamped(1e9), 35);
}

TEST(AccuracyCurve, EmptyCurveCostsNothing) {
  const AccuracyCurve empty;
  EXPECT_EQ(empty.resourcesFor(5), 0);
  EXPECT_EQ(empty.resourcesForClamped(5), 0);
  EXPECT_EQ(empty.maxAccuracyWithin(0), kInf);
  EXPECT_FALSE(empty.maxAccuracyWithin(-1).has_value());
}

// --- Inversion -----------------------------------------------------------------

TEST(AccuracyCurve, MaxAccuracyWithinInsideSegment) {
  // r(2.5) = 15 exactly; r(nextUp(2.5)) also rounds to 15 (a tie to even),
  // so the answer is the double after 2.5.
  const AccuracyCurve c = twoPartCurve();
  const double a = *c.maxAccuracyWithin(15);
  EXPECT_EQ(a, nextUp(2.5));
  EXPECT_LE(c.resourcesFor(a), 15);
  EXPECT_GT(c.resourcesFor(nextUp(a)), 15);
}

TEST(AccuracyCurve, MaxAccuracyWithinExactlyRepresentable) {
  const AccuracyCurve c = make({{0, 0, 4}}, 10);  // r = 4a, no rounding
  EXPECT_EQ(c.maxAccuracyWithin(10), 2.5);
}

TEST(AccuracyCurve, MaxAccuracyWithinBelowMinimumIsNullopt) {
  EXPECT_FALSE(twoPartCurve().maxAccuracyWithin(9.999).has_value());
  EXPECT_FALSE(twoPartCurve().maxAccuracyWithin(std::nan("")).has_value());
}

TEST(AccuracyCurve, MaxAccuracyWithinInJumpIsJustBelowJump) {
  EXPECT_EQ(twoPartCurve().maxAccuracyWithin(25), nextDown(5));
}

TEST(AccuracyCurve, MaxAccuracyWithinAtJumpTop) {
  // The part after the jump starts at exactly the budget; the answer is on
  // it (a few ulps past 5, where 30 + (a - 5) still rounds to 30).
  const AccuracyCurve c = twoPartCurve();
  const double a = *c.maxAccuracyWithin(30);
  EXPECT_GE(a, 5);
  EXPECT_LT(a, 5 + 1e-14);
  EXPECT_LE(c.resourcesFor(a), 30);
  EXPECT_GT(c.resourcesFor(nextUp(a)), 30);
}

TEST(AccuracyCurve, MaxAccuracyWithinLargeBudgetIsMaxAccuracy) {
  EXPECT_EQ(twoPartCurve().maxAccuracyWithin(1000), 10);
  EXPECT_EQ(twoPartCurve().maxAccuracyWithin(kInf), 10);
}

TEST(AccuracyCurve, MaxAccuracyWithinFlatSegmentTakesItsEnd) {
  const AccuracyCurve c = make({{1, 7, 0}, {3, 9, 0}}, 6);
  EXPECT_EQ(c.maxAccuracyWithin(8), nextDown(3));
  EXPECT_EQ(c.maxAccuracyWithin(9), 6);
}

TEST(AccuracyCurve, MaxAccuracyWithinExtremeSlope) {
  // r climbs by 1e300 per unit: the answer sits a few ulps above the start.
  auto c = AccuracyCurve::fromSegments({{1, 0, 1e300}}, 2).value();
  const double a = *c.maxAccuracyWithin(1.0);
  EXPECT_LE(c.resourcesFor(a), 1.0);
  EXPECT_GT(c.resourcesFor(nextUp(a)), 1.0);
}

// --- Scaling -------------------------------------------------------------------

TEST(AccuracyCurve, ScaledAccuracyStretchesTheAxis) {
  const AccuracyCurve s = twoPartCurve().scaledAccuracy(2);
  EXPECT_EQ(s.minAccuracy(), 0);
  EXPECT_EQ(s.maxAccuracy(), 20);
  EXPECT_DOUBLE_EQ(s.resourcesFor(5), 15);
  EXPECT_DOUBLE_EQ(s.resourcesFor(10), 30);
  EXPECT_DOUBLE_EQ(s.resourcesFor(20), 35);
}

TEST(AccuracyCurve, ScaledAccuracyOfEmptyIsEmpty) {
  EXPECT_TRUE(AccuracyCurve().scaledAccuracy(3).empty());
}

// --- Group sum (Figure 5) ------------------------------------------------------

TEST(AccuracyCurve, SumWithDifferentStartAndEndExtendsHorizontally) {
  const AccuracyCurve child1 = make({{1, 0, 1}}, 4);  // r = a on [1, 4]
  const AccuracyCurve child2 = make({{2, 6, 2}}, 6);  // r = 10 + 2 (a - 2) on [2, 6]
  const AccuracyCurve sum = AccuracyCurve::sum({&child1, &child2});
  ASSERT_TRUE(satisfiesInvariants(sum));
  EXPECT_EQ(sum.minAccuracy(), 1);
  EXPECT_EQ(sum.maxAccuracy(), 6);
  ASSERT_EQ(sum.segments().size(), 3u);
  expectSegment(sum.segments()[0], 1, 11, 1);  // child2 held at its start, 10
  expectSegment(sum.segments()[1], 2, 12, 3);
  expectSegment(sum.segments()[2], 4, 18, 2);  // child1 held at its best, 4
  EXPECT_DOUBLE_EQ(sum.resourcesFor(6), 22);
}

TEST(AccuracyCurve, SumAddsJumps) {
  const AccuracyCurve a = twoPartCurve();
  const AccuracyCurve b = make({{0, 1, 0}}, 10);
  const AccuracyCurve sum = AccuracyCurve::sum({&a, &b});
  ASSERT_EQ(sum.segments().size(), 2u);
  expectSegment(sum.segments()[0], 0, 11, 2);
  expectSegment(sum.segments()[1], 5, 31, 1);
}

TEST(AccuracyCurve, SumMergesCollinearKnots) {
  const AccuracyCurve a = make({{0, 0, 1}, {2, 0, 1}}, 4);  // one line in two parts
  const AccuracyCurve b = make({{0, 5, 0}}, 4);
  const AccuracyCurve sum = AccuracyCurve::sum({&a, &b});
  ASSERT_EQ(sum.segments().size(), 1u);
  expectSegment(sum.segments()[0], 0, 5, 1);
}

TEST(AccuracyCurve, SumOfPointCurves) {
  const AccuracyCurve p = AccuracyCurve::point(1, 10);
  const AccuracyCurve q = AccuracyCurve::point(2, 5);
  const AccuracyCurve sum = AccuracyCurve::sum({&p, &q});
  EXPECT_EQ(sum.minAccuracy(), 1);
  EXPECT_EQ(sum.maxAccuracy(), 2);
  EXPECT_EQ(sum.resourcesFor(1.5), 15);
  EXPECT_EQ(sum.resourcesFor(2), 15);
}

TEST(AccuracyCurve, SumIgnoresEmptyChildren) {
  const AccuracyCurve a = twoPartCurve();
  const AccuracyCurve empty;
  const AccuracyCurve sum = AccuracyCurve::sum({&empty, &a, &empty});
  ASSERT_EQ(sum.segments().size(), 2u);
  expectSegment(sum.segments()[1], 5, 30, 1);
  EXPECT_TRUE(AccuracyCurve::sum({}).empty());
  EXPECT_TRUE(AccuracyCurve::sum({&empty}).empty());
}

// --- LOD lower envelope (Figures 6 and 7) ---------------------------------------

TEST(AccuracyCurve, EnvelopeSplitsAtCrossing) {
  const AccuracyCurve steep = make({{0, 0, 2}}, 10);    // r = 2a
  const AccuracyCurve shallow = make({{0, 5, 1}}, 10);  // r = 5 + a, cheaper from a = 5
  std::vector<int> owner;
  const AccuracyCurve env = AccuracyCurve::lowerEnvelope({&steep, &shallow}, &owner);
  ASSERT_TRUE(satisfiesInvariants(env));
  ASSERT_EQ(env.segments().size(), 2u);
  expectSegment(env.segments()[0], 0, 0, 2);
  expectSegment(env.segments()[1], 5, 10, 1);
  EXPECT_EQ(owner, (std::vector<int>{0, 1}));
}

TEST(AccuracyCurve, EnvelopeDoesNotExtendRight) {
  // Figure 7: a cheap child valid up to 4 must not be chosen above 4.
  const AccuracyCurve cheap = make({{0, 1, 0}}, 4);
  const AccuracyCurve fine = make({{0, 10, 1}}, 10);
  std::vector<int> owner;
  const AccuracyCurve env = AccuracyCurve::lowerEnvelope({&cheap, &fine}, &owner);
  ASSERT_TRUE(satisfiesInvariants(env));
  EXPECT_EQ(env.maxAccuracy(), 10);
  EXPECT_EQ(env.resourcesFor(4), 1);
  EXPECT_DOUBLE_EQ(env.resourcesFor(4.5), 14.5);
  EXPECT_DOUBLE_EQ(env.resourcesFor(nextUp(4)), 14);
  EXPECT_EQ(env.maxAccuracyWithin(5), 4);
  ASSERT_EQ(env.segments().size(), 2u);
  EXPECT_EQ(env.segments()[1].start, nextUp(4));
  EXPECT_EQ(owner, (std::vector<int>{0, 1}));
}

TEST(AccuracyCurve, EnvelopeExtendsLeft) {
  // A child that starts at 5 but is cheap may be rendered for lower requests.
  const AccuracyCurve coarseStart = make({{5, 3, 0}}, 10);
  const AccuracyCurve linear = make({{0, 0, 1}}, 10);
  std::vector<int> owner;
  const AccuracyCurve env = AccuracyCurve::lowerEnvelope({&coarseStart, &linear}, &owner);
  ASSERT_EQ(env.segments().size(), 2u);
  expectSegment(env.segments()[0], 0, 0, 1);
  expectSegment(env.segments()[1], 3, 3, 0);
  EXPECT_EQ(owner, (std::vector<int>{1, 0}));
}

TEST(AccuracyCurve, EnvelopeOfPointCurves) {
  const AccuracyCurve coarse = AccuracyCurve::point(1, 10);
  const AccuracyCurve fine = AccuracyCurve::point(2, 20);
  std::vector<int> owner;
  const AccuracyCurve env = AccuracyCurve::lowerEnvelope({&coarse, &fine}, &owner);
  EXPECT_EQ(env.resourcesFor(1), 10);
  EXPECT_EQ(env.resourcesFor(1.5), 20);
  EXPECT_EQ(env.resourcesFor(2), 20);
  EXPECT_EQ(env.resourcesFor(3), kInf);
  EXPECT_EQ(owner, (std::vector<int>{0, 1}));
}

TEST(AccuracyCurve, EnvelopeOwnersIndexTheInputIncludingEmpties) {
  const AccuracyCurve empty;
  const AccuracyCurve steep = make({{0, 0, 2}}, 10);
  const AccuracyCurve shallow = make({{0, 5, 1}}, 10);
  std::vector<int> owner;
  AccuracyCurve::lowerEnvelope({&empty, &steep, &shallow}, &owner);
  EXPECT_EQ(owner, (std::vector<int>{1, 2}));
}

TEST(AccuracyCurve, EnvelopeOfIdenticalChildrenKeepsOneOwner) {
  const AccuracyCurve a = twoPartCurve();
  const AccuracyCurve b = twoPartCurve();
  std::vector<int> owner;
  const AccuracyCurve env = AccuracyCurve::lowerEnvelope({&a, &b}, &owner);
  EXPECT_EQ(env.segments().size(), 2u);
  EXPECT_EQ(owner, (std::vector<int>{0, 0}));
}

TEST(AccuracyCurve, EnvelopeOfNothingIsEmpty) {
  std::vector<int> owner{7};
  EXPECT_TRUE(AccuracyCurve::lowerEnvelope({}, &owner).empty());
  EXPECT_TRUE(owner.empty());
}

// --- Conservative fit ----------------------------------------------------------

TEST(AccuracyCurve, FitWithEnoughSegmentsIsTheStaircase) {
  // (3, 40) is dominated by (4, 30).
  auto fit = AccuracyCurve::fitConservative({{4, 30}, {1, 10}, {3, 40}, {2, 20}}, 5);
  ASSERT_TRUE(fit.ok()) << fit.status().toString();
  EXPECT_EQ(fit->minAccuracy(), 1);
  EXPECT_EQ(fit->maxAccuracy(), 4);
  ASSERT_EQ(fit->segments().size(), 3u);
  EXPECT_EQ(fit->resourcesFor(1), 10);
  EXPECT_EQ(fit->resourcesFor(nextUp(1)), 20);
  EXPECT_EQ(fit->resourcesFor(2), 20);
  EXPECT_EQ(fit->resourcesFor(2.5), 30);
  EXPECT_EQ(fit->resourcesFor(4), 30);
  EXPECT_EQ(fit->maxAccuracyWithin(20), 2);
}

TEST(AccuracyCurve, FitSingleLineHugsLinearSamples) {
  // r = 10 a measured at a = 1..100. The staircase needs 10 k just above
  // k - 1, so the tightest single line is r = 10 a + 10.
  std::vector<AccuracySample> samples;
  for (int k = 1; k <= 100; ++k) samples.push_back({double(k), 10.0 * k});
  auto fit = AccuracyCurve::fitConservative(samples, 1);
  ASSERT_TRUE(fit.ok());
  ASSERT_EQ(fit->segments().size(), 1u);
  EXPECT_NEAR(fit->resourcesFor(50), 510, 1e-6);
  EXPECT_NEAR(fit->segments()[0].slope, 10, 1e-9);
}

TEST(AccuracyCurve, FitUsesDomainOfLowestSample) {
  // The lowest-accuracy sample is dominated, but still sets the domain.
  auto fit = AccuracyCurve::fitConservative({{1, 50}, {2, 20}, {3, 30}}, 1);
  ASSERT_TRUE(fit.ok());
  EXPECT_EQ(fit->minAccuracy(), 1);
  EXPECT_GE(fit->resourcesFor(1), 20);
  EXPECT_GE(fit->resourcesFor(2.5), 30);
}

TEST(AccuracyCurve, FitOfOneSampleIsAPoint) {
  auto fit = AccuracyCurve::fitConservative({{3, 7}, {3, 9}}, 4);
  ASSERT_TRUE(fit.ok());
  EXPECT_EQ(fit->minAccuracy(), 3);
  EXPECT_EQ(fit->maxAccuracy(), 3);
  EXPECT_EQ(fit->resourcesFor(3), 7);
}

TEST(AccuracyCurve, FitRejectsNoSamples) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fitConservative({}, 3), "no samples"));
}

TEST(AccuracyCurve, FitRejectsNonFiniteSample) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fitConservative({{1, 1}, {kInf, 2}}, 3), "sample 1"));
  EXPECT_TRUE(failsWith(AccuracyCurve::fitConservative({{1, std::nan("")}}, 3), "sample 0"));
}

TEST(AccuracyCurve, FitRejectsNegativeResources) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fitConservative({{1, -1}}, 3), "negative"));
}

TEST(AccuracyCurve, FitRejectsZeroSegments) {
  EXPECT_TRUE(failsWith(AccuracyCurve::fitConservative({{1, 1}}, 0), "maxSegments"));
}

}  // namespace
}  // namespace thinlod
