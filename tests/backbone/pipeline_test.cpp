// Prediction, culling, conversion, candidates and scene validation.
#include <gtest/gtest.h>

#include "scheduler_test_util.h"

namespace thinlod::backbone {
namespace {
using namespace testing;

TEST(Prediction, ReachRadiusIsSpeedTimesLifetimePlusDelays) {
  SchedulerConfig c;
  c.maxSpeed = 0.1;
  c.plannedLifetime = 1.0;
  c.linkDelay = 0.05;
  c.generationDelay = 0.2;
  c.keepSlack = 0.05;
  const PredictedRegion r = predictRegion(viewerAt({1, 2, 3}, {0, 0, -2}), c);
  EXPECT_DOUBLE_EQ(r.reachRadius, 0.1 * 1.25);
  EXPECT_DOUBLE_EQ(r.keepRadius, 0.1 * 0.3);
  EXPECT_EQ(r.center, glm::dvec3(1, 2, 3));
  EXPECT_NEAR(glm::length(r.viewDirection), 1.0, 1e-15);
}

TEST(Prediction, ViewConeIsFrustumCornerPlusRotation) {
  SchedulerConfig c;
  c.maxAngularSpeed = 0.2;
  c.plannedLifetime = 1.0;
  c.linkDelay = 0.0;
  c.generationDelay = 0.0;
  ViewerState v = viewerAt({0, 0, 0}, {0, 0, -1});
  v.horizontalFov = kPi / 2;  // tan = 1 each way
  v.verticalFov = kPi / 2;
  const PredictedRegion r = predictRegion(v, c);
  EXPECT_NEAR(r.viewHalfAngle, std::atan(std::sqrt(2.0)) + 0.2, 1e-12);
  c.maxAngularSpeed = 100.0;
  EXPECT_DOUBLE_EQ(predictRegion(v, c).viewHalfAngle, kPi);
}

TEST(Culling, BehindTheViewerIsCulledInFrontIsInside) {
  SchedulerConfig c = exactConfig();
  const PredictedRegion r = predictRegion(viewerAt({0, 0, 0}, {0, 0, -1}), c);
  EXPECT_EQ(classifySphere(r, {{0, 0, 50}, 1.0}), Visibility::kCulled);
  EXPECT_EQ(classifySphere(r, {{0, 0, -50}, 1.0}), Visibility::kInside);
  EXPECT_EQ(classifySphere(r, {{0, 0, 0.05}, 0.5}), Visibility::kPartial);  // around the viewer
}

TEST(Culling, RotationWidensTheCone) {
  SchedulerConfig c = exactConfig();
  c.maxAngularSpeed = 0.0;
  const Sphere side{{50, 0, -10}, 1.0};  // ~79 degrees off axis
  EXPECT_EQ(classifySphere(predictRegion(viewerAt({0, 0, 0}, {0, 0, -1}), c), side),
            Visibility::kCulled);
  c.maxAngularSpeed = 1.0;  // 1.15 rad more
  EXPECT_NE(classifySphere(predictRegion(viewerAt({0, 0, 0}, {0, 0, -1}), c), side),
            Visibility::kCulled);
}

// Deferred visibility: a view-cone horizon shorter than the reach horizon
// narrows the cone only (the balls keep their radii); a longer one changes
// nothing. An object the viewer could turn to within the lifetime but not
// within the shorter time is culled.
TEST(Culling, AShorterViewConeHorizonNarrowsOnlyTheCone) {
  SchedulerConfig c = exactConfig();
  c.maxAngularSpeed = 1.0;
  c.plannedLifetime = 1.0;
  c.linkDelay = 0.05;
  c.generationDelay = 0.1;
  const ViewerState v = viewerAt({0, 0, 0}, {0, 0, -1});
  const PredictedRegion paper = predictRegion(v, c);
  c.viewConeHorizon = 0.3;
  const PredictedRegion deferred = predictRegion(v, c);
  EXPECT_NEAR(paper.viewHalfAngle - deferred.viewHalfAngle, 1.15 - 0.3, 1e-12);
  EXPECT_EQ(deferred.reachRadius, paper.reachRadius);
  EXPECT_EQ(deferred.keepRadius, paper.keepRadius);
  const Sphere side{{50, 0, -10}, 1.0};  // ~79 degrees off axis
  EXPECT_NE(classifySphere(paper, side), Visibility::kCulled);
  EXPECT_EQ(classifySphere(deferred, side), Visibility::kCulled);
  c.viewConeHorizon = 5.0;  // longer than the reach horizon: the paper's cone
  EXPECT_EQ(predictRegion(v, c).viewHalfAngle, paper.viewHalfAngle);
}

TEST(Culling, FarPlaneCulls) {
  SchedulerConfig c = exactConfig();
  c.maxViewDistance = 100.0;
  const PredictedRegion r = predictRegion(viewerAt({0, 0, 0}, {0, 0, -1}), c);
  EXPECT_EQ(classifySphere(r, {{0, 0, -200}, 1.0}), Visibility::kCulled);
  EXPECT_EQ(classifySphere(r, {{0, 0, -100.5}, 1.0}), Visibility::kPartial);
}

TEST(Conversion, DistanceFromRegionToSphereClampedBelow) {
  EXPECT_DOUBLE_EQ(conversionDistance({0, 0, 0}, 1.0, {{10, 0, 0}, 2.0}, 0.1), 7.0);
  EXPECT_DOUBLE_EQ(conversionDistance({0, 0, 0}, 1.0, {{1, 0, 0}, 2.0}, 0.1), 0.1);
}

TEST(Regions, GrownRegionContainsOriginalAndNearbyOnes) {
  SchedulerConfig c = exactConfig();
  const PredictedRegion r = predictRegion(viewerAt({0, 0, 0}, {0, 0, -1}), c);
  const PredictedRegion grown = growRegion(r, 0.5, 0.1);
  EXPECT_TRUE(regionContains(grown, r));
  EXPECT_FALSE(regionContains(r, grown));
  const PredictedRegion moved = predictRegion(viewerAt({0.4, 0, 0}, {0, 0, -1}), c);
  EXPECT_TRUE(regionContains(grown, moved));
  const PredictedRegion far = predictRegion(viewerAt({0.6, 0, 0}, {0, 0, -1}), c);
  EXPECT_FALSE(regionContains(grown, far));
  const PredictedRegion turned = predictRegion(viewerAt({0, 0, 0}, {0.2, 0, -1}), c);
  EXPECT_FALSE(regionContains(grown, turned));  // atan(0.2) = 0.197 > 0.1
}

TEST(Candidates, ImpostorOnlyWhenItsRangeHoldsTheWholeRegion) {
  SceneBuilder b;
  const int root = b.group(-1);
  auto imp = pointOption(OptionKind::kSimpleImpostor, 30, 2, 6000);
  imp.validity = fromDistance({0, 0, -10}, 5.0);
  b.leaf(root, {{0, 0, -10}, 0.5}, {meshOption(5, 10, 100, 1000), imp});
  const SchedulingScene scene = b.build();
  ASSERT_TRUE(validateScene(scene).ok());
  SchedulerConfig c = exactConfig();
  std::vector<LeafCandidate> out;
  const Sphere bounds = scene.nodes[1].bounds;
  collectLeafCandidates(scene, 0, predictRegion(viewerAt({0, 0, -4.95}, {0, 0, -1}), c), c,
                        CandidateContext::kExact, nullptr, bounds, out);
  ASSERT_EQ(out.size(), 1u);  // 5.05 m away, reach radius 0.115: the ball crosses 5 m
  collectLeafCandidates(scene, 0, predictRegion(viewerAt({0, 0, -4.8}, {0, 0, -1}), c), c,
                        CandidateContext::kExact, nullptr, bounds, out);
  EXPECT_EQ(out.size(), 2u);
  c.rangeHysteresis = 0.2;  // not on display: must fit the region grown by 0.2 m
  collectLeafCandidates(scene, 0, predictRegion(viewerAt({0, 0, -4.8}, {0, 0, -1}), c), c,
                        CandidateContext::kExact, nullptr, bounds, out);
  EXPECT_EQ(out.size(), 1u);
}

TEST(Candidates, FrontendCopyIsCreditedOverTheKeepBall) {
  SceneBuilder b;
  const int root = b.group(-1);
  auto mesh = meshOption(5, 10, 100, 1000);
  mesh.atFrontend.present = true;
  mesh.atFrontend.relativeAccuracy = 50.0;
  mesh.atFrontend.triangles = 500.0;
  b.leaf(root, {{0, 0, -10}, 0.5}, {mesh});
  const SchedulingScene scene = b.build();
  const SchedulerConfig c = exactConfig();
  const PredictedRegion region = predictRegion(viewerAt({0, 0, 0}, {0, 0, -1}), c);
  std::vector<LeafCandidate> out;
  collectLeafCandidates(scene, 0, region, c, CandidateContext::kExact, nullptr,
                        scene.nodes[1].bounds, out);
  ASSERT_EQ(out.size(), 2u);
  const LeafCandidate& copy = out[1];
  EXPECT_EQ(copy.source, CandidateSource::kFrontendCopy);
  const double dReach = 9.5 - region.reachRadius;
  const double dKeep = 9.5 - region.keepRadius;
  EXPECT_NEAR(copy.maxRelativeAccuracy, 50.0 * dKeep / dReach, 1e-12);
  EXPECT_EQ(copy.fixedLinkBytes, 0.0);
  collectLeafCandidates(scene, 0, region, c, CandidateContext::kConservative, nullptr,
                        scene.nodes[1].bounds, out);
  EXPECT_DOUBLE_EQ(out[1].maxRelativeAccuracy, 50.0);
}

SchedulingScene twoLeafScene() {
  SceneBuilder b;
  const int root = b.group(-1);
  b.leaf(root, {{0, 0, -10}, 0.5}, {meshOption(5, 10, 100, 1000)});
  b.leaf(root, {{2, 0, -10}, 0.5}, {meshOption(5, 10, 100, 1000)});
  return b.build();
}

TEST(SceneValidation, AcceptsAWellFormedScene) { EXPECT_TRUE(validateScene(twoLeafScene()).ok()); }

TEST(SceneValidation, RejectsChildIndexOutOfRange) {
  SchedulingScene s = twoLeafScene();
  s.children[1] = 99;
  const Status st = validateScene(s);
  EXPECT_EQ(st.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(st.message().find("child 99"), std::string::npos) << st.message();
}

TEST(SceneValidation, RejectsChildBeforeParentAndSharedChild) {
  SchedulingScene s = twoLeafScene();
  s.children[1] = s.children[0];
  EXPECT_FALSE(validateScene(s).ok());
  s = twoLeafScene();
  s.children[0] = 0;
  EXPECT_FALSE(validateScene(s).ok());
}

TEST(SceneValidation, RejectsNonFiniteBoundsAndZeroRadius) {
  SchedulingScene s = twoLeafScene();
  s.nodes[1].bounds.center.x = std::nan("");
  EXPECT_NE(validateScene(s).message().find("node 1"), std::string::npos);
  s = twoLeafScene();
  s.nodes[2].bounds.radius = 0.0;
  EXPECT_FALSE(validateScene(s).ok());
}

TEST(SceneValidation, RejectsChildOutsideParentBounds) {
  SchedulingScene s = twoLeafScene();
  s.nodes[1].bounds.center.z = -100.0;
  EXPECT_NE(validateScene(s).message().find("not inside"), std::string::npos);
}

TEST(SceneValidation, RejectsEmptyOrMismatchedCurves) {
  SchedulingScene s = twoLeafScene();
  s.options[0].relativeLinkBytes = AccuracyCurve();
  EXPECT_NE(validateScene(s).message().find("relativeLinkBytes is empty"), std::string::npos);
  s = twoLeafScene();
  s.options[1].relativeLinkBytes = curveThrough({5, 50}, {10, 20});
  EXPECT_NE(validateScene(s).message().find("same accuracies"), std::string::npos);
}

TEST(SceneValidation, RejectsBadCopiesAndObjectsWithoutOptions) {
  SchedulingScene s = twoLeafScene();
  s.options[0].atFrontend.present = true;
  s.options[0].atFrontend.relativeAccuracy = -1.0;
  EXPECT_FALSE(validateScene(s).ok());
  s = twoLeafScene();
  s.objects[1].optionCount = 0;
  EXPECT_FALSE(validateScene(s).ok());
  s = twoLeafScene();
  s.objects[1].firstOption = 0;  // shares option 0 with object 0
  EXPECT_NE(validateScene(s).message().find("shared"), std::string::npos);
}

TEST(SceneValidation, RejectsMismatchedRangeArrayAndEmptyScene) {
  SchedulingScene s = twoLeafScene();
  s.childRanges.pop_back();
  EXPECT_FALSE(validateScene(s).ok());
  EXPECT_FALSE(validateScene(SchedulingScene{}).ok());
}

TEST(SceneValidation, SyntheticScenesValidate) {
  SyntheticSceneOptions o;
  o.objects = 500;
  o.lodShare = 0.3;
  auto scene = makeSyntheticScene(o);
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  EXPECT_TRUE(validateScene(*scene).ok()) << validateScene(*scene).toString();
  EXPECT_GT(scene->nodes.size(), 500u);
}

TEST(SceneValidation, SubtreeVersionsChangeWithAnyDescendant) {
  SchedulingScene s = twoLeafScene();
  const std::uint64_t root = s.nodes[0].subtreeVersion;
  const std::uint64_t sibling = s.nodes[1].subtreeVersion;
  ++s.nodes[2].contentVersion;
  updateSubtreeVersions(s);
  EXPECT_NE(s.nodes[0].subtreeVersion, root);
  EXPECT_EQ(s.nodes[1].subtreeVersion, sibling);
}

TEST(Config, RejectsInvalidValues) {
  SchedulerConfig c;
  c.plannedLifetime = 0.0;
  EXPECT_NE(validateConfig(c).message().find("plannedLifetime"), std::string::npos);
  c = SchedulerConfig{};
  c.budgetReserveShare = 1.0;
  EXPECT_FALSE(makeAccuracyCurveScheduler(c).ok());
  c = SchedulerConfig{};
  c.maxSpeed = std::nan("");
  EXPECT_FALSE(validateConfig(c).ok());
  for (double weight : {-0.5, std::nan(""), std::numeric_limits<double>::infinity()}) {
    c = SchedulerConfig{};
    c.fillShadingWeight = weight;
    EXPECT_NE(validateConfig(c).message().find("fillShadingWeight"), std::string::npos) << weight;
  }
  c = SchedulerConfig{};
  c.fillShadingWeight = 2.0;
  EXPECT_TRUE(validateConfig(c).ok());
  for (double horizon : {0.0, -1.0, std::nan("")}) {
    c = SchedulerConfig{};
    c.viewConeHorizon = horizon;
    EXPECT_NE(validateConfig(c).message().find("viewConeHorizon"), std::string::npos) << horizon;
  }
  c.viewConeHorizon = 0.25;
  EXPECT_TRUE(validateConfig(c).ok());
}

TEST(ObjectDecisionCsv, HeaderAndRowsHaveTheSameColumns) {
  const std::string header = objectDecisionCsvHeader();
  ObjectDecision keep;
  keep.object = 7;
  keep.action = ObjectAction::kKeep;
  keep.option = 2;
  keep.kind = OptionKind::kMeshedImpostor;
  keep.source = CandidateSource::kFrontendCopy;
  keep.relativeAccuracy = 57.5;
  keep.absoluteAccuracy = std::numeric_limits<double>::infinity();
  keep.triangles = 64.0;
  keep.belowTarget = true;
  ObjectDecision removal;  // no option: kind and source left empty
  removal.object = 3;
  for (const ObjectDecision& d : {keep, removal}) {
    const std::string row = objectDecisionCsv(41, 4.1, d);
    EXPECT_EQ(std::count(header.begin(), header.end(), ','),
              std::count(row.begin(), row.end(), ','))
        << row;
    EXPECT_EQ(row.find('\n'), std::string::npos);
  }
  EXPECT_EQ(objectDecisionCsv(41, 4.1, keep),
            "41,4.1,7,keep,2,meshed-impostor,frontend,57.5,inf,64,0,1");
  EXPECT_EQ(objectDecisionCsv(41, 4.1, removal), "41,4.1,3,remove,-1,,,0,0,0,0,0");
}

TEST(DecisionRowCsv, HeaderAndRowHaveTheSameColumns) {
  DecisionRow r;
  r.frame = 12;
  r.scheduler = "accuracy-curve";
  r.mode = "polygon";
  r.targetAccuracy = std::numeric_limits<double>::infinity();
  r.predictedTriangles = 199.5;
  const std::string header = decisionRowCsvHeader();
  const std::string row = decisionRowCsv(r);
  EXPECT_EQ(std::count(header.begin(), header.end(), ','), std::count(row.begin(), row.end(), ','));
  EXPECT_EQ(row.rfind("12,0,accuracy-curve,polygon,inf,", 0), 0u) << row;
  EXPECT_NE(row.find(",199.5,"), std::string::npos);
  EXPECT_EQ(row.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace thinlod::backbone
