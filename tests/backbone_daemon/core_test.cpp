// BackboneCore (backbone/src/daemon/backbone_core.h) without sockets: scene
// conversion, requests and sends, the frontend polygon cap, the link shaper,
// request convergence for a standing viewer, and rejection of bad results.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <map>
#include <random>
#include <set>

#include "backbone_core.h"
#include "fake_simplifier.h"
#include "scene_conversion.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/protocol/codec.h"

namespace thinlod::backbone_daemon {
namespace {

using namespace testing;
using backbone::ObjectAction;
using backbone::OptionKind;
using backbone::SceneNodeKind;

const glm::vec3 kEntrance(2.0f, 1.1f, 3.5f);
const glm::vec3 kCow(2.0f, 0.3f, 0.55f);

std::unique_ptr<BackboneCore> makeCore(const CoreOptions& options) {
  auto core = paperRoomCore(options);
  EXPECT_TRUE(core.ok()) << core.status().toString();
  return core.ok() ? std::move(core).value() : nullptr;
}

// Answers the startup curve request(s).
void deliverCurves(BackboneCore& core) {
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
}

std::size_t countOps(const protocol::SceneUpdate& update, protocol::SceneOperation::Type type) {
  std::size_t n = 0;
  for (const auto& op : update.operations) n += op.type == type ? 1 : 0;
  return n;
}

// ---------------------------------------------------------- scene conversion

TEST(BackboneCoreScene, PaperRoomHasFourObjectsUnderTheRootGroup) {
  auto core = makeCore(polygonBudget(200));
  ASSERT_NE(core, nullptr);
  const backbone::SchedulingScene& scene = core->schedulingScene();
  ASSERT_EQ(core->objects().size(), 4u);
  ASSERT_EQ(scene.objects.size(), 4u);
  EXPECT_EQ(scene.nodes[0].kind, SceneNodeKind::kGroup);
  EXPECT_EQ(scene.nodes[0].childCount, 4u);
  EXPECT_EQ(core->lodNodes(), 0u);
  for (std::size_t k = 0; k < 4; ++k) {
    const ObjectRecord& record = core->objects()[k];
    EXPECT_EQ(record.id, k + 1);
    EXPECT_EQ(scene.objects[k].externalId, k + 1);
    EXPECT_EQ(scene.nodes[record.leafNode].kind, SceneNodeKind::kLeaf);
    EXPECT_EQ(scene.nodes[record.leafNode].object, k);
    EXPECT_GT(record.bounds.radius, 0.0);
    // simplified mesh + meshed impostor + simple impostor
    ASSERT_EQ(scene.objects[k].optionCount, 3u);
    const auto& first = scene.options[scene.objects[k].firstOption];
    EXPECT_EQ(first.kind, OptionKind::kSimplifiedMesh);
  }
  EXPECT_TRUE(backbone::validateScene(scene).ok());
  // Ids 1-3 are the primitives (spheres, cylinder), 4 the cow.
  EXPECT_TRUE(core->objects()[0].primitive);
  EXPECT_FALSE(core->objects()[3].primitive);
  // The spheres' leaf spheres are tight: radius 0.3 m.
  EXPECT_NEAR(core->objects()[0].bounds.radius, 0.3, 0.01);
}

TEST(BackboneCoreScene, PrimitivesHaveAnalyticCurvesAndTheCowWaitsForItsCurve) {
  auto core = makeCore(polygonBudget(200));
  ASSERT_NE(core, nullptr);
  const backbone::SchedulingScene& scene = core->schedulingScene();
  for (std::size_t k = 0; k < 3; ++k) {
    const auto& mesh = scene.options[scene.objects[k].firstOption];
    EXPECT_GT(mesh.relativeTriangles.segments().size(), 4u) << "object " << k + 1;
    EXPECT_LT(mesh.relativeTriangles.minAccuracy(), mesh.relativeTriangles.maxAccuracy());
  }
  EXPECT_EQ(core->curvesPending(), 1u);
  EXPECT_EQ(core->objectsWithoutMeasuredCurve(), std::vector<std::uint64_t>{4});
  EXPECT_EQ(core->objectsWithEstimatedCurve(), std::vector<std::uint64_t>{4});
  const auto& cow = scene.options[scene.objects[3].firstOption];
  // Until the curve arrives: the pessimistic estimate (curve_estimate.h).
  EXPECT_EQ(cow.relativeTriangles.resourcesFor(1.0), 40.0);
  EXPECT_EQ(cow.relativeTriangles.resourcesFor(10.0), 400.0);
  EXPECT_EQ(cow.relativeTriangles.resourcesFor(60.0), 5804.0);

  std::vector<OutgoingRequest> requests = submitAll(*core);
  ASSERT_EQ(requests.size(), 1u);
  const auto& curveRequest = std::get<protocol::SimplifyRequest>(requests[0].message);
  EXPECT_EQ(curveRequest.objectId, 4u);
  EXPECT_GT(curveRequest.curvePoints, 0u);
  EXPECT_EQ(curveRequest.sourcePath, paperRoomPath());
  FakeSimplifier fake(*core);
  answer(*core, fake, requests);

  EXPECT_EQ(core->curvesPending(), 0u);
  EXPECT_TRUE(core->objectsWithoutMeasuredCurve().empty());
  EXPECT_TRUE(core->objectsWithEstimatedCurve().empty());
  const auto& measured = core->schedulingScene().options[scene.objects[3].firstOption];
  EXPECT_GT(measured.relativeTriangles.segments().size(), 2u);
  EXPECT_LT(measured.relativeTriangles.minAccuracy(), measured.relativeTriangles.maxAccuracy());
  // The link curve covers the same accuracies and grows with the triangles.
  EXPECT_EQ(measured.relativeLinkBytes.minAccuracy(), measured.relativeTriangles.minAccuracy());
  EXPECT_GT(measured.relativeLinkBytes.resourcesFor(measured.relativeLinkBytes.maxAccuracy()),
            measured.relativeLinkBytes.resourcesFor(measured.relativeLinkBytes.minAccuracy()));
  EXPECT_TRUE(backbone::validateScene(core->schedulingScene()).ok());
}

TEST(BackboneCoreScene, LodLevelsBecomeLodNodesWithWorldRanges) {
  const std::string text = R"(#VRML V2.0 utf8
Transform {
  translation 10 0 0
  children LOD {
    center 0 0 0
    range [ 5 ]
    level [
      Shape { geometry Sphere { radius 1 } }
      Shape { geometry Box { size 1 1 1 } }
    ]
  }
}
Shape { geometry Sphere { radius 0.5 } }
)";
  Result<scene::Scene> parsed = scene::parseScene(text, "lod.wrl");
  ASSERT_TRUE(parsed.ok()) << parsed.status().toString();
  auto objects = scene::collectSceneObjects(*parsed);
  ASSERT_TRUE(objects.ok());
  Result<ConvertedScene> converted = convertScene(*parsed, *objects);
  ASSERT_TRUE(converted.ok()) << converted.status().toString();
  const backbone::SchedulingScene& s = converted->scheduling;
  EXPECT_EQ(converted->lodNodes, 1u);
  ASSERT_EQ(s.nodes[0].childCount, 2u);
  const std::uint32_t lod = s.children[s.nodes[0].firstChild];
  ASSERT_EQ(s.nodes[lod].kind, SceneNodeKind::kLod);
  ASSERT_EQ(s.nodes[lod].childCount, 2u);
  const ConicRange& near = s.childRanges[s.nodes[lod].firstChild];
  const ConicRange& far = s.childRanges[s.nodes[lod].firstChild + 1];
  // Level ranges follow the LOD's transform: centred at x = 10.
  EXPECT_NEAR(near.center().x, 10.0, 1e-6);
  EXPECT_NEAR(near.maxDistance(), 5.0, 1e-6);
  EXPECT_NEAR(far.minDistance(), 5.0, 1e-6);
  EXPECT_TRUE(near.containsPoint({12.0, 0.0, 0.0}));
  EXPECT_FALSE(near.containsPoint({16.0, 0.0, 0.0}));
  // Each level is a group holding one leaf.
  const std::uint32_t level0 = s.children[s.nodes[lod].firstChild];
  EXPECT_EQ(s.nodes[level0].kind, SceneNodeKind::kGroup);
  ASSERT_EQ(s.nodes[level0].childCount, 1u);
  EXPECT_EQ(s.nodes[s.children[s.nodes[level0].firstChild]].kind, SceneNodeKind::kLeaf);
  // Tree checks pass once options exist (the core adds them).
  backbone::SchedulingScene withOptions = s;
  for (auto& object : withOptions.objects) {
    object.firstOption = static_cast<std::uint32_t>(withOptions.options.size());
    object.optionCount = 1;
    backbone::RepresentationOption option;
    option.relativeTriangles = AccuracyCurve::point(10.0, 100.0);
    option.relativeLinkBytes = AccuracyCurve::point(10.0, 1000.0);
    withOptions.options.push_back(option);
  }
  EXPECT_TRUE(backbone::validateScene(withOptions).ok());
}

TEST(BackboneCoreScene, LodLevelIsChosenByTheViewerDistance) {
  const std::string text = R"(#VRML V2.0 utf8
Transform {
  translation 10 0 0
  children LOD {
    range [ 8 ]
    level [
      Shape { geometry Sphere { radius 1 } }
      Shape { geometry Box { size 1 1 1 } }
    ]
  }
}
)";
  Result<scene::Scene> parsed = scene::parseScene(text, "lod.wrl");
  ASSERT_TRUE(parsed.ok());
  CoreOptions options = polygonBudget(2000);
  options.simpleImpostorRadii = 0.0;
  options.meshedImpostorRadii = 0.0;
  auto created = BackboneCore::create(std::move(parsed).value(), "/scenes/lod.wrl", options);
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  auto requestedObjects = [&](glm::vec3 eye, double seconds) {
    std::set<std::uint64_t> ids;
    EXPECT_TRUE(core.beginPose(poseAt(0, seconds, eye, {10.0f, 0.0f, 0.0f})).ok());
    for (const OutgoingRequest& r : submitAll(core))
      ids.insert(std::get<protocol::SimplifyRequest>(r.message).objectId);
    (void)core.finishPose();
    return ids;
  };
  // Near: the sphere (object 1); far: the box (object 2).
  EXPECT_EQ(requestedObjects({10.0f, 0.0f, 4.0f}, 0.0), std::set<std::uint64_t>{1});
  core.resetFrontend();
  EXPECT_EQ(requestedObjects({10.0f, 0.0f, 20.0f}, 0.0), std::set<std::uint64_t>{2});
}

TEST(BackboneCoreScene, SceneWithoutObjectsAnswersEmptyUpdates) {
  Result<scene::Scene> parsed = scene::parseScene(
      "#VRML V2.0 utf8\nViewpoint { position 0 1 5 }\nGroup { children [ ] }\n", "empty.wrl");
  ASSERT_TRUE(parsed.ok()) << parsed.status().toString();
  auto created =
      BackboneCore::create(std::move(parsed).value(), "/scenes/empty.wrl", polygonBudget(100));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  EXPECT_TRUE(core.objects().empty());
  EXPECT_EQ(core.curvesPending(), 0u);
  EXPECT_TRUE(core.beginPose(poseAt(9, 0.0, {0.0f, 1.0f, 5.0f}, {0.0f, 0.0f, 0.0f})).ok());
  EXPECT_TRUE(submitAll(core).empty());
  PoseOutcome outcome = core.finishPose();
  EXPECT_TRUE(outcome.planned) << outcome.planError.toString();
  EXPECT_EQ(outcome.update.frame, 9u);
  EXPECT_TRUE(outcome.update.operations.empty());
}

TEST(BackboneCoreScene, PrimitiveOnlySceneMakesTheSimplifierLoadIt) {
  Result<scene::Scene> parsed =
      scene::parseScene("#VRML V2.0 utf8\nShape { geometry Sphere { radius 1 } }\n", "ball.wrl");
  ASSERT_TRUE(parsed.ok());
  auto created =
      BackboneCore::create(std::move(parsed).value(), "/scenes/ball.wrl", polygonBudget(100));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  EXPECT_TRUE(core.objectsWithoutMeasuredCurve().empty());  // analytic
  EXPECT_EQ(core.curvesPending(), 1u);
  const std::vector<OutgoingRequest> requests = submitAll(core);
  ASSERT_EQ(requests.size(), 1u);
  const auto& warmup = std::get<protocol::SimplifyRequest>(requests[0].message);
  EXPECT_EQ(warmup.sourcePath, "/scenes/ball.wrl");
  EXPECT_EQ(warmup.curvePoints, 0u);
  const AccuracyCurve before = core.schedulingScene().options[0].relativeTriangles;
  answer(core, FakeSimplifier(core), requests);
  EXPECT_EQ(core.curvesPending(), 0u);
  // The answer only loaded the scene: the analytic curve stays, no copy kept.
  EXPECT_EQ(core.schedulingScene().options[0].relativeTriangles.segments().size(),
            before.segments().size());
  EXPECT_FALSE(core.schedulingScene().options[0].atBackbone.present);
}

// ------------------------------------------------------------ pose -> update

TEST(BackboneCorePose, RequestsFirstThenSendsOnceResultsArrive) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);

  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  std::vector<OutgoingRequest> requests = submitAll(*core);
  EXPECT_FALSE(requests.empty());
  EXPECT_EQ(core->awaitedResults(), requests.size());
  PoseOutcome first = core->finishPose();
  ASSERT_TRUE(first.planned) << first.planError.toString();
  EXPECT_EQ(first.update.frame, 0u);
  EXPECT_TRUE(first.update.operations.empty());  // nothing generated yet
  EXPECT_GT(first.row.requests, 0u);
  EXPECT_GT(first.update.targetAccuracy, 0.0);

  answer(*core, fake, requests);
  ASSERT_TRUE(core->beginPose(poseAt(1, 0.5, kEntrance, kCow)).ok());
  submitAll(*core);
  PoseOutcome second = core->finishPose();
  EXPECT_EQ(second.update.frame, 1u);
  const std::size_t adds = countOps(second.update, protocol::SceneOperation::Type::kAddOrReplace);
  EXPECT_EQ(adds, requests.size());
  std::set<std::uint64_t> ids;
  for (const auto& op : second.update.operations) {
    ids.insert(op.objectId);
    EXPECT_GE(op.objectId, 1u);
    EXPECT_LE(op.objectId, 4u);
    EXPECT_GT(op.representation.triangleCount, 0u);
    EXPECT_FALSE(op.representation.mesh.empty());
  }
  // Encodable: the frontend's decoder would accept it.
  EXPECT_TRUE(protocol::validate(protocol::Message(second.update)).ok());
  EXPECT_EQ(ids.size(), adds);  // object ids unique within the batch
  EXPECT_LE(second.frontendTriangles, 400.0);
  EXPECT_EQ(core->frontendTriangles(), second.frontendTriangles);
}

// Two sessions' cores of one scene (the daemon's several frontends): the
// second takes the first one's measured curve (its own startup request is
// withdrawn, nothing to ask) and the meshes the first one made, which it
// then sends to its frontend under the same ids without a request of its
// own; a core of another scene is refused.
TEST(BackboneCoreSessions, ASecondCoreTakesTheCurvesAndMeshesTheFirstOneMade) {
  // Meshes only: impostors are shared too, but one not on display must fit
  // the reach ball grown by rangeHysteresis (the kind's Schmitt trigger), so
  // at the first core's own pose its impostors do not serve the second.
  CoreOptions options = polygonBudget(400);
  options.simpleImpostorRadii = 0.0;
  options.meshedImpostorRadii = 0.0;
  auto first = makeCore(options);
  auto second = makeCore(options);
  ASSERT_NE(first, nullptr);
  ASSERT_NE(second, nullptr);
  deliverCurves(*first);
  ASSERT_EQ(second->curvesPending(), 1u);
  Result<std::size_t> curves = second->adoptMeasuredCurves(*first);
  ASSERT_TRUE(curves.ok()) << curves.status().toString();
  EXPECT_EQ(*curves, 1u);
  EXPECT_EQ(second->curvesPending(), 0u);
  EXPECT_TRUE(second->objectsWithoutMeasuredCurve().empty());
  EXPECT_TRUE(second->takeRequests().empty());  // the startup request was withdrawn

  // The first session's frontend is served: requests, results, sends.
  FakeSimplifier fake(*first);
  ASSERT_TRUE(first->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  answer(*first, fake, submitAll(*first));
  ASSERT_TRUE(first->replan().ok());
  const PoseOutcome served = first->finishPose();
  const std::size_t sentFirst =
      countOps(served.update, protocol::SceneOperation::Type::kAddOrReplace);
  ASSERT_GT(sentFirst, 0u);
  std::map<std::uint64_t, std::uint64_t> madeForFirst;  // object -> representation id
  for (const auto& op : served.update.operations)
    madeForFirst[op.objectId] = op.representation.representationId;

  Result<std::size_t> copies = second->adoptGeneratedCopies(*first);
  ASSERT_TRUE(copies.ok()) << copies.status().toString();
  EXPECT_EQ(*copies, sentFirst);  // what the first frontend holds
  ASSERT_TRUE(second->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  EXPECT_TRUE(submitAll(*second).empty());  // nothing to ask: the meshes are there
  const PoseOutcome reused = second->finishPose();
  ASSERT_TRUE(reused.planned) << reused.planError.toString();
  std::size_t sameIds = 0;
  for (const auto& op : reused.update.operations) {
    if (op.type != protocol::SceneOperation::Type::kAddOrReplace) continue;
    sameIds += madeForFirst.count(op.objectId) &&
               madeForFirst.at(op.objectId) == op.representation.representationId;
  }
  EXPECT_EQ(sameIds, sentFirst);
  EXPECT_LE(reused.frontendTriangles, 400.0);
  // The first core's own frontend model is untouched.
  EXPECT_EQ(first->frontendTriangles(), served.frontendTriangles);

  // Another scene (a primitive-only room): refused, nothing taken.
  Result<scene::Scene> other = scene::parseScene(
      "#VRML V2.0 utf8\nShape { geometry Sphere { radius 1 } }\n", "other.wrl");
  ASSERT_TRUE(other.ok()) << other.status().toString();
  auto foreign = BackboneCore::create(std::move(other).value(), "/tmp/other.wrl", options);
  ASSERT_TRUE(foreign.ok()) << foreign.status().toString();
  EXPECT_EQ(second->adoptMeasuredCurves(**foreign).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(second->adoptGeneratedCopies(**foreign).status().code(), ErrorCode::kInvalidArgument);
}

// --measured-generation-delay sets the horizon through setGenerationDelay:
// a longer delay is a larger region to serve, so at the same budget and pose
// the guaranteed target is lower; a bad value is refused and changes nothing.
TEST(BackboneCorePose, ALongerGenerationDelayLowersTheGuaranteedTarget) {
  double target[2] = {0.0, 0.0};
  for (int k = 0; k < 2; ++k) {
    auto core = makeCore(polygonBudget(400));
    ASSERT_NE(core, nullptr);
    deliverCurves(*core);
    if (k == 1) {
      EXPECT_FALSE(core->setGenerationDelay(-1.0).ok());
      EXPECT_FALSE(core->setGenerationDelay(std::nan("")).ok());
      EXPECT_EQ(core->generationDelay(), CoreOptions{}.config.generationDelay);
      ASSERT_TRUE(core->setGenerationDelay(20.0).ok());
      EXPECT_EQ(core->generationDelay(), 20.0);
    }
    ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
    submitAll(*core);
    const PoseOutcome outcome = core->finishPose();
    ASSERT_TRUE(outcome.planned) << outcome.planError.toString();
    target[k] = outcome.update.targetAccuracy;
  }
  EXPECT_GT(target[0], 0.0);
  EXPECT_LT(target[1], target[0]);
}

TEST(BackboneCorePose, SyncWaitReplanSendsInTheSameUpdate) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  ASSERT_TRUE(core->beginPose(poseAt(7, 0.0, kEntrance, kCow)).ok());
  std::vector<OutgoingRequest> requests = submitAll(*core);
  ASSERT_FALSE(requests.empty());
  answer(*core, fake, requests);
  EXPECT_EQ(core->awaitedResults(), 0u);
  ASSERT_TRUE(core->replan().ok());
  submitAll(*core);
  PoseOutcome outcome = core->finishPose();
  EXPECT_EQ(outcome.plans, 2);
  EXPECT_EQ(outcome.update.frame, 7u);
  EXPECT_EQ(countOps(outcome.update, protocol::SceneOperation::Type::kAddOrReplace),
            requests.size());
  // Mesh representations carry the object's transform (content frame geometry).
  for (const auto& op : outcome.update.operations) {
    if (op.representation.kind != protocol::RepresentationKind::kMesh) continue;
    const auto& object = core->sceneObjects()[op.objectId - 1];
    EXPECT_EQ(op.representation.transform, object.objectToWorld);
    EXPECT_TRUE(std::isinf(op.representation.validity.distanceMax));
  }
}

TEST(BackboneCorePose, RemovalsOfTheFirstPlanSurviveTheReplan) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  FrontendModel frontend;
  for (int step = 0; step < 3; ++step) {
    ASSERT_TRUE(core->beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok());
    answer(*core, fake, submitAll(*core));
    frontend.apply(core->finishPose().update);
  }
  const std::size_t shown = frontend.triangles.size();
  ASSERT_GT(shown, 0u);
  // Turn around: every object is behind the viewer. The first plan retires
  // them; the re-plan (as after a sync wait) has nothing more to say.
  const glm::vec3 behind = kEntrance + glm::vec3(0.0f, 0.0f, 5.0f);
  ASSERT_TRUE(core->beginPose(poseAt(3, 1.5, kEntrance, behind)).ok());
  answer(*core, fake, submitAll(*core));
  ASSERT_TRUE(core->replan().ok());
  PoseOutcome outcome = core->finishPose();
  EXPECT_EQ(outcome.plans, 2);
  EXPECT_EQ(outcome.removes, shown);
  frontend.apply(outcome.update);
  EXPECT_TRUE(frontend.triangles.empty());
  EXPECT_EQ(core->frontendTriangles(), 0.0);
}

// One far-future stamp must not hold the backbone's clock (prediction, link
// shaper) there: a pose moves it forward by at most 60 s; backwards stamps keep it.
TEST(BackboneCorePose, APoseMovesTheClockForwardByAtMostAMinuteUnlessTheJumpPersists) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  // 0; a bogus 1e6 (clamped to +60 s); 2 and 50 (backwards: held); 130
  // (+10 s); then eleven poses 1e4 s on: ten clamped steps, the eleventh a
  // real jump taken as it is.
  std::vector<double> stamps = {0.0, 1e6, 2.0, 130.0, 50.0};
  std::vector<double> expected = {0.0, 60.0, 60.0, 120.0, 120.0};
  for (int k = 0; k < 11; ++k) {
    stamps.push_back(1e4 + k);
    expected.push_back(k < 10 ? 120.0 + 60.0 * (k + 1) : 1e4 + k);
  }
  for (std::size_t i = 0; i < stamps.size(); ++i) {
    ASSERT_TRUE(core->beginPose(poseAt(i, stamps[i], kEntrance, kCow)).ok());
    submitAll(*core);
    const PoseOutcome outcome = core->finishPose();
    EXPECT_DOUBLE_EQ(outcome.row.timeSeconds, expected[i]) << "pose " << i;
  }
}

TEST(BackboneCorePose, PlanningFailureStillAnswersWithAnEmptyUpdate) {
  auto core = makeCore(polygonBudget(200));
  ASSERT_NE(core, nullptr);
  protocol::ViewerPose pose = poseAt(3, 0.0, kEntrance, kCow);
  pose.position = glm::vec3(std::nanf(""), 0.0f, 0.0f);  // the codec would reject it; the core too
  EXPECT_FALSE(core->beginPose(pose).ok());
  PoseOutcome outcome = core->finishPose();
  EXPECT_FALSE(outcome.planned);
  EXPECT_EQ(outcome.update.frame, 3u);
  EXPECT_TRUE(outcome.update.operations.empty());
  // The next valid pose is served normally.
  EXPECT_TRUE(core->beginPose(poseAt(4, 0.1, kEntrance, kCow)).ok());
  EXPECT_TRUE(core->finishPose().planned);
}

// --------------------------------------------------------------- polygon cap

// A random flight through the room; results arrive 0..3 poses late; the
// simplifier delivers `inflation` x the triangles asked for.
void flyAndCheckCap(double inflation, std::uint64_t seed) {
  const double budget = 200.0;
  auto core = makeCore(polygonBudget(budget));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  fake.inflation = inflation;
  FrontendModel frontend;
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  InFlightRequests inFlight;
  glm::dvec3 position(2.0, 1.1, 3.4);
  glm::dvec3 velocity(0.0);
  const double dt = 0.25;
  std::size_t adds = 0;
  std::size_t deferred = 0;
  for (int step = 0; step < 240; ++step) {
    // Bounded random walk: |v| <= 0.09 m/s, inside the room.
    velocity += glm::dvec3(unit(random) - 0.5, 0.0, unit(random) - 0.5) * 0.03;
    if (glm::length(velocity) > 0.09) velocity *= 0.09 / glm::length(velocity);
    position += velocity * dt;
    position = glm::clamp(position, glm::dvec3(0.3, 1.1, 0.3), glm::dvec3(3.7, 1.1, 3.4));
    const glm::vec3 target(kCow.x + 1.5f * std::sin(step * 0.05f), 0.4f, kCow.z + 1.0f);
    ASSERT_TRUE(core->beginPose(poseAt(step, step * dt, glm::vec3(position), target)).ok());
    for (OutgoingRequest& r : submitAll(*core))
      inFlight.emplace_back(step + static_cast<int>(unit(random) * 4.0), std::move(r));
    answerDue(*core, fake, inFlight, step);
    PoseOutcome outcome = core->finishPose();
    ASSERT_TRUE(outcome.planned) << outcome.planError.toString();
    frontend.apply(outcome.update);
    adds += outcome.adds;
    deferred += outcome.deferredByPolygonCap;
    ASSERT_LE(frontend.total(), budget) << "step " << step;
    ASSERT_EQ(frontend.total(), core->frontendTriangles()) << "step " << step;
  }
  EXPECT_GT(adds, 4u);  // the flight did get representations
  if (inflation > 1.0) {
    EXPECT_GT(deferred, 0u);  // the cap had work to do
  }
}

TEST(BackboneCoreCap, PolygonBudgetHoldsAtTheFrontendOverARandomFlight) { flyAndCheckCap(1.0, 11); }

TEST(BackboneCoreCap, PolygonBudgetHoldsWhenTheSimplifierDeliversTooMuch) {
  flyAndCheckCap(1.6, 12);
}

// ----------------------------------------------------------------- link shaper

// Flies towards the cow; returns (time, shaped bytes) per pose and the
// number of deferred operations.
struct LinkRun {
  std::vector<std::pair<double, double>> sent;
  std::vector<PoseOutcome> outcomes;
  std::size_t deferred = 0;
  std::size_t adds = 0;
};

LinkRun flyWithLinkBudget(double rate, double burst, double meshBytesPerTriangle,
                          std::vector<LinkStep> schedule = {}) {
  LinkRun run;
  CoreOptions options;
  options.config.maxSpeed = 0.1;
  options.budget.maxLinkBytesPerSecond = rate;
  options.linkBurstBytes = burst;
  options.linkSchedule = std::move(schedule);
  auto core = makeCore(options);
  EXPECT_NE(core, nullptr);
  if (!core) return run;
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  // From now on meshes are larger than the curve result taught the core.
  fake.meshBytesPerTriangle = meshBytesPerTriangle;
  fake.texturebytes = 9000;
  for (int step = 0; step < 80; ++step) {
    const double t = step * 0.2;
    const glm::vec3 position(2.0f, 1.1f, 3.4f - 0.018f * step);
    EXPECT_TRUE(core->beginPose(poseAt(step, t, position, kCow)).ok());
    answer(*core, fake, submitAll(*core));  // immediate results
    PoseOutcome outcome = core->finishPose();
    run.sent.emplace_back(t, double(outcome.linkBytes));
    run.deferred += outcome.deferredByLink;
    run.adds += outcome.adds;
    run.outcomes.push_back(std::move(outcome));
  }
  return run;
}

void expectWithinBucket(const LinkRun& run, double rate, double burst) {
  double total = 0.0;
  for (std::size_t i = 0; i < run.sent.size(); ++i) {
    double window = 0.0;
    for (std::size_t j = i; j < run.sent.size(); ++j) {
      window += run.sent[j].second;
      const double span = run.sent[j].first - run.sent[i].first;
      ASSERT_LE(window, rate * span + burst + 1e-6) << "window " << i << ".." << j;
    }
    total += run.sent[i].second;
  }
  EXPECT_GT(total, 0.0);
}

TEST(BackboneCoreLink, ShapedBytesStayWithinRateTimesWindowPlusBurst) {
  const LinkRun run = flyWithLinkBudget(12000.0, 16000.0, 1.5);
  expectWithinBucket(run, 12000.0, 16000.0);
}

TEST(BackboneCoreLink, ShaperDefersWhatTheEstimatesMissedAndSendsItLater) {
  // 40 B/triangle where the core learned 1.5: sends overrun the scheduler's
  // link plan and the shaper holds them back.
  const LinkRun run = flyWithLinkBudget(6000.0, 12000.0, 40.0);
  expectWithinBucket(run, 6000.0, 12000.0);
  EXPECT_GT(run.deferred, 0u);
  EXPECT_GT(run.adds, 3u);
}

// The link cut to 10 % at trace time 6 s (issue 21's fault): from the first
// pose at or after the cut the plan's link window and the shaper's rate are the
// new one, and the bytes shaped from then on stay within new rate x window +
// burst (the new bucket keeps no more tokens than the old one had), while the
// same flight uncut sends more in that time.
TEST(BackboneCoreLink, ALinkCutToTenPercentHoldsFromTheFirstPlanningStepAfterIt) {
  constexpr double kRate = 12000.0, kBurst = 16000.0, kCutAt = 6.0;
  const LinkRun uncut = flyWithLinkBudget(kRate, kBurst, 1.5);
  const LinkRun cut = flyWithLinkBudget(kRate, kBurst, 1.5, {{kCutAt, 0.1 * kRate}});
  ASSERT_EQ(cut.sent.size(), uncut.sent.size());
  LinkRun after;
  double uncutAfter = 0.0;
  for (std::size_t i = 0; i < cut.sent.size(); ++i) {
    const double t = cut.sent[i].first;
    const PoseOutcome& outcome = cut.outcomes[i];
    ASSERT_TRUE(outcome.planned) << outcome.planError.toString();
    const double rateNow = t >= kCutAt ? 0.1 * kRate : kRate;
    EXPECT_EQ(outcome.linkRate, static_cast<std::uint64_t>(rateNow)) << "t " << t;
    // One step sends at most the link window's allowance, rate x W with W =
    // max(lifetime, burst / rate): the explicit burst is the scheduler's too
    // (Budget::linkBurstBytes); the bucket checks below bound every span.
    const double lifetime = CoreOptions{}.config.plannedLifetime;
    const double window = std::max(lifetime, kBurst / rateNow);
    EXPECT_LE(outcome.row.linkBytesPerSecond * lifetime, rateNow * window * (1.0 + 1e-9))
        << "t " << t;
    if (t < kCutAt) continue;
    after.sent.push_back(cut.sent[i]);
    uncutAfter += uncut.sent[i].second;
  }
  ASSERT_GT(after.sent.size(), 20u);
  double cutAfter = 0.0;
  for (const auto& [t, bytes] : after.sent) cutAfter += bytes;
  EXPECT_LT(cutAfter, uncutAfter);
  // Every window that starts at or after the cut.
  for (std::size_t i = 0; i < after.sent.size(); ++i) {
    double window = 0.0;
    for (std::size_t j = i; j < after.sent.size(); ++j) {
      window += after.sent[j].second;
      const double span = after.sent[j].first - after.sent[i].first;
      ASSERT_LE(window, 0.1 * kRate * span + kBurst + 1e-6) << "window " << i << ".." << j;
    }
  }
  // And before the cut the run is the uncut one.
  for (std::size_t i = 0; i < cut.sent.size() && cut.sent[i].first < kCutAt; ++i)
    EXPECT_EQ(cut.sent[i].second, uncut.sent[i].second) << i;
}

TEST(BackboneCoreLink, ALinkScheduleNeedsALinkBudgetAndOrderedSteps) {
  CoreOptions options;
  options.budget.maxTriangles = 200.0;
  options.linkSchedule = {{1.0, 1000.0}};
  EXPECT_EQ(validateCoreOptions(options).code(), ErrorCode::kInvalidArgument);
  options.budget.maxLinkBytesPerSecond = 5000.0;
  EXPECT_TRUE(validateCoreOptions(options).ok());
  options.linkSchedule = {{2.0, 1000.0}, {1.0, 800.0}};
  EXPECT_EQ(validateCoreOptions(options).code(), ErrorCode::kInvalidArgument);
  options.linkSchedule = {{1.0, std::numeric_limits<double>::quiet_NaN()}};
  EXPECT_EQ(validateCoreOptions(options).code(), ErrorCode::kInvalidArgument);
  options.linkSchedule = {{1.0, 0.5}};
  EXPECT_EQ(validateCoreOptions(options).code(), ErrorCode::kInvalidArgument);
}

TEST(LinkSchedule, ParsesStepsCommentsAndBlankLines) {
  Result<std::vector<LinkStep>> steps =
      parseLinkSchedule("# the link drops to 10 %\n0 125000\n\n  6.5   12500 # cut\n1e1 1.25e5\n",
                        "cut.link");
  ASSERT_TRUE(steps.ok()) << steps.status().toString();
  ASSERT_EQ(steps->size(), 3u);
  EXPECT_EQ((*steps)[1].timeSeconds, 6.5);
  EXPECT_EQ((*steps)[1].bytesPerSecond, 12500.0);
  EXPECT_EQ((*steps)[2].timeSeconds, 10.0);
  EXPECT_EQ(linkRateAt(*steps, 6.4999, 1.0), std::optional<double>(125000.0));
  EXPECT_EQ(linkRateAt(*steps, 6.5, 1.0), std::optional<double>(12500.0));
  EXPECT_EQ(linkRateAt(*steps, 1e9, 1.0), std::optional<double>(125000.0));
  const std::vector<LinkStep> late = {{3.0, 900.0}};
  EXPECT_EQ(linkRateAt(late, 2.0, 5000.0), std::optional<double>(5000.0));
  EXPECT_EQ(linkRateAt(late, 2.0, std::nullopt), std::nullopt);
}

TEST(LinkSchedule, RejectsBadLinesNamingTheLine) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"", "no steps"},
      {"# only a comment\n", "no steps"},
      {"1\n", "cut.link:1: expected"},
      {"1 2 3\n", "cut.link:1: unexpected"},
      {"0 100\nnan 100\n", "cut.link:2: time"},
      {"-1 100\n", "cut.link:1: time"},
      {"0 inf\n", "cut.link:1: rate"},
      {"0 0.5\n", "cut.link:1: rate"},
      {"0 2e11\n", "cut.link:1: rate"},
      {"0 +100\n", "cut.link:1: rate"},
      {"0 100x\n", "cut.link:1: rate"},
      {"0 100\n3 100\n3 50\n", "cut.link:3: times must increase"},
      {std::string(1u << 20, '#') + "\n", "larger than"},
  };
  for (const auto& [text, expected] : bad) {
    Result<std::vector<LinkStep>> steps = parseLinkSchedule(text, "cut.link");
    ASSERT_FALSE(steps.ok()) << text.substr(0, 40);
    EXPECT_EQ(steps.status().code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(steps.status().message().find(expected), std::string::npos)
        << steps.status().message();
  }
}

// The scheduler's link log holds what the shaper let through: after every
// pose the bytes it logged as sent within its window equal the shaped bytes
// of the poses in that window, and over the whole flight the shaper's total
// equals the bytes of the updates.
TEST(BackboneCoreLink, SchedulerLogAndShaperAgreeOnTheBytesSent) {
  for (const double meshBytesPerTriangle : {1.5, 40.0}) {  // estimates right, estimates short
    CoreOptions options;
    options.config.maxSpeed = 0.1;
    options.budget.maxLinkBytesPerSecond = 8000.0;
    options.linkBurstBytes = 12000.0;
    auto core = makeCore(options);
    ASSERT_NE(core, nullptr);
    deliverCurves(*core);
    FakeSimplifier fake(*core);
    fake.meshBytesPerTriangle = meshBytesPerTriangle;
    fake.texturebytes = 9000;
    const double window = core->options().config.plannedLifetime;
    std::vector<std::pair<double, double>> sent;  // (pose time, shaped bytes)
    double total = 0.0;
    std::size_t deferred = 0;
    std::mt19937_64 random(21);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    double t = 0.0;
    for (int step = 0; step < 90; ++step) {
      t += 0.05 + 0.3 * unit(random);  // irregular pose spacing
      const glm::vec3 position(2.0f, 1.1f, 3.4f - 0.02f * step);
      ASSERT_TRUE(core->beginPose(poseAt(step, t, position, kCow)).ok());
      std::vector<OutgoingRequest> requests = submitAll(*core);
      if (step % 3 != 2) answer(*core, fake, requests);  // some replies never come
      PoseOutcome outcome = core->finishPose();
      ASSERT_TRUE(outcome.planned) << outcome.planError.toString();
      sent.emplace_back(t, double(outcome.linkBytes));
      total += double(outcome.linkBytes);
      deferred += outcome.deferredByLink;
      double inWindow = 0.0;
      for (const auto& [time, bytes] : sent)
        if (time > t - window) inWindow += bytes;
      const backbone::PlannerState::LinkLogTotals logged = core->linkLogAfter(t - window);
      ASSERT_DOUBLE_EQ(logged.settledBytes, inWindow) << "step " << step;
      ASSERT_GE(logged.reservedBytes, 0.0);
      ASSERT_EQ(double(core->shapedLinkBytes()), total) << "step " << step;
    }
    EXPECT_GT(total, 0.0);
    if (meshBytesPerTriangle > 10.0) {
      EXPECT_GT(deferred, 0u);  // the shaper had work to do
    }
  }
}

// ------------------------------------------------------------ convergence

void standStill(const CoreOptions& options) {
  auto core = makeCore(options);
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  const glm::vec3 position(2.0f, 1.1f, 2.6f);
  std::vector<std::uint32_t> requests;
  for (int step = 0; step < 16; ++step) {
    ASSERT_TRUE(core->beginPose(poseAt(step, step * 0.5, position, kCow)).ok());
    answer(*core, fake, submitAll(*core));
    PoseOutcome outcome = core->finishPose();
    ASSERT_TRUE(outcome.planned);
    requests.push_back(outcome.row.requests);
  }
  std::uint32_t early = 0;
  for (int step = 0; step < 4; ++step) early += requests[step];
  EXPECT_GT(early, 0u);
  for (int step = 8; step < 16; ++step) EXPECT_EQ(requests[step], 0u) << "step " << step;
  EXPECT_GT(core->frontendTriangles(), 0.0);
}

TEST(BackboneCoreConvergence, StandingViewerStopsRequestingUnderAPolygonBudget) {
  standStill(polygonBudget(300));
}

TEST(BackboneCoreConvergence, StandingViewerStopsRequestingAtAFixedAccuracy) {
  CoreOptions options;
  options.config.maxSpeed = 0.1;
  options.budget.fixedAccuracy = 150.0;
  standStill(options);
}

// ------------------------------------------------------------- rejections

class BackboneCoreResults : public ::testing::Test {
 protected:
  void SetUp() override {
    core_ = makeCore(polygonBudget(400));
    ASSERT_NE(core_, nullptr);
    deliverCurves(*core_);
    ASSERT_TRUE(core_->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
    requests_ = submitAll(*core_);
    (void)core_->finishPose();
    for (const OutgoingRequest& r : requests_) {
      if (std::holds_alternative<protocol::SimplifyRequest>(r.message) && !mesh_) mesh_ = &r;
    }
    ASSERT_NE(mesh_, nullptr);
  }
  protocol::SimplifyResult goodMeshResult() const {
    protocol::SimplifyRequest wire = std::get<protocol::SimplifyRequest>(mesh_->message);
    wire.requestId = wireIdOf(*mesh_);
    return FakeSimplifier(*core_).simplify(wire);
  }
  void expectRejected(const protocol::SimplifyResult& result, ErrorCode code) {
    const Status status = core_->onSimplifyResult(result);
    EXPECT_EQ(status.code(), code) << status.toString();
    // The request is closed as failed: the good answer now is a late reply.
    const std::uint64_t id = goodMeshResult().requestId;
    EXPECT_EQ(core_->requestLedger().state(id), RequestState::kFailed);
    const Status late = core_->onSimplifyResult(goodMeshResult());
    EXPECT_EQ(late.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(late.message().find("late reply"), std::string::npos) << late.toString();
    // And the core keeps planning.
    EXPECT_TRUE(core_->beginPose(poseAt(1, 0.5, kEntrance, kCow)).ok());
    EXPECT_TRUE(core_->finishPose().planned);
  }

  std::unique_ptr<BackboneCore> core_;
  std::vector<OutgoingRequest> requests_;
  const OutgoingRequest* mesh_ = nullptr;
};

TEST_F(BackboneCoreResults, UnknownRequestIdIsNotFound) {
  protocol::SimplifyResult result = goodMeshResult();
  result.requestId = 987654321;
  EXPECT_EQ(core_->onSimplifyResult(result).code(), ErrorCode::kNotFound);
  protocol::ImpostorResult impostor;
  impostor.requestId = 987654322;
  impostor.objectIds = {1};
  EXPECT_EQ(core_->onImpostorResult(impostor).code(), ErrorCode::kNotFound);
  EXPECT_TRUE(core_->onSimplifyResult(goodMeshResult()).ok());  // the real one still counts
}

TEST_F(BackboneCoreResults, WrongObjectIdIsRejected) {
  protocol::SimplifyResult result = goodMeshResult();
  result.objectId = result.objectId % 4 + 1;
  expectRejected(result, ErrorCode::kInvalidArgument);
}

TEST_F(BackboneCoreResults, EmptyMeshIsRejected) {
  protocol::SimplifyResult result = goodMeshResult();
  result.mesh.clear();
  expectRejected(result, ErrorCode::kInvalidArgument);
}

TEST_F(BackboneCoreResults, ZeroTrianglesAreRejected) {
  protocol::SimplifyResult result = goodMeshResult();
  result.triangleCount = 0;
  expectRejected(result, ErrorCode::kInvalidArgument);
}

TEST_F(BackboneCoreResults, NonFiniteAccuracyIsRejected) {
  protocol::SimplifyResult result = goodMeshResult();
  result.accuracy = std::numeric_limits<double>::quiet_NaN();
  expectRejected(result, ErrorCode::kInvalidArgument);
}

TEST_F(BackboneCoreResults, SimplifierErrorIsPassedOnAndForgotten) {
  protocol::SimplifyResult result;
  result.requestId = goodMeshResult().requestId;
  result.objectId = goodMeshResult().objectId;
  result.status = Status(ErrorCode::kNotFound, "no such object");
  expectRejected(result, ErrorCode::kNotFound);
}

TEST_F(BackboneCoreResults, ImpostorResultForAMeshRequestIsRejected) {
  protocol::ImpostorResult result;
  result.requestId = goodMeshResult().requestId;
  result.objectIds = {goodMeshResult().objectId};
  EXPECT_EQ(core_->onImpostorResult(result).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(core_->onSimplifyResult(goodMeshResult()).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(core_->requestLedger().state(result.requestId), RequestState::kFailed);
}

TEST(BackboneCoreCurve, MalformedCurveSamplesKeepTheFallbackCurve) {
  auto core = makeCore(polygonBudget(200));
  ASSERT_NE(core, nullptr);
  std::vector<OutgoingRequest> requests = submitAll(*core);
  ASSERT_EQ(requests.size(), 1u);
  protocol::SimplifyRequest wire = std::get<protocol::SimplifyRequest>(requests[0].message);
  wire.requestId = wireIdOf(requests[0]);
  protocol::SimplifyResult result = FakeSimplifier(*core).simplify(wire);
  result.curve[1].accuracy = std::numeric_limits<double>::infinity();
  EXPECT_EQ(core->onSimplifyResult(result).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(core->curvesPending(), 0u);
  EXPECT_EQ(core->objectsWithoutMeasuredCurve(), std::vector<std::uint64_t>{4});
  EXPECT_TRUE(backbone::validateScene(core->schedulingScene()).ok());
}

// A standing viewer far enough from a sphere for impostors: impostor
// results with a bad kind or a malformed validity range are rejected.
class BackboneCoreImpostors : public ::testing::Test {
 protected:
  void SetUp() override {
    CoreOptions options;
    options.config.maxSpeed = 0.1;
    options.budget.maxTriangles = 20.0;  // too few for meshes: impostors win
    options.simpleImpostorRadii = 3.0;
    options.meshedImpostorRadii = 0.0;
    core_ = makeCore(options);
    ASSERT_NE(core_, nullptr);
    deliverCurves(*core_);
    ASSERT_TRUE(core_->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
    for (OutgoingRequest& r : submitAll(*core_)) {
      if (std::holds_alternative<protocol::ImpostorRequest>(r.message)) impostors_.push_back(r);
    }
    (void)core_->finishPose();
    ASSERT_FALSE(impostors_.empty());
  }
  protocol::ImpostorResult good() const {
    protocol::ImpostorRequest wire = std::get<protocol::ImpostorRequest>(impostors_[0].message);
    wire.requestId = wireIdOf(impostors_[0]);
    return FakeSimplifier(*core_).impostor(wire);
  }
  std::unique_ptr<BackboneCore> core_;
  std::vector<OutgoingRequest> impostors_;
};

TEST_F(BackboneCoreImpostors, RequestCarriesRegionCentreBoundAndTextureSize) {
  const auto& request = std::get<protocol::ImpostorRequest>(impostors_[0].message);
  EXPECT_EQ(request.objectIds.size(), 1u);
  EXPECT_EQ(request.kind, protocol::RepresentationKind::kSimpleImpostor);
  EXPECT_EQ(request.textureWidth, 256u);
  EXPECT_GT(request.accuracyBound, 0.0);
  EXPECT_LT(request.accuracyBound, 0.5);
  EXPECT_LT(glm::length(request.eye - kEntrance), 1e-3f);
  EXPECT_TRUE(core_->onImpostorResult(good()).ok());
}

// Under a budget the bound is what the planned relative accuracy allows at
// the region's distance, and a copy is credited exactly that.
TEST_F(BackboneCoreImpostors, BoundFollowsThePlannedAccuracyAndTheCopyKeepsIt) {
  const backbone::Plan* plan = core_->latestPlan();
  ASSERT_NE(plan, nullptr);
  const auto& request = std::get<protocol::ImpostorRequest>(impostors_[0].message);
  const backbone::RepresentationRequest* planned = nullptr;
  for (const auto& r : plan->requests)
    if (core_->objects()[r.object].id == request.objectIds[0]) planned = &r;
  ASSERT_NE(planned, nullptr);
  const ObjectRecord& record = core_->objects()[planned->object];
  const double distance =
      backbone::conversionDistance(planned->viewRegion.center, planned->viewRegion.radius,
                                   record.bounds, core_->options().config.minimalDistance);
  const double absolute = planned->relativeAccuracy * distance / record.diameter;
  EXPECT_NEAR(request.accuracyBound, 1.0 / absolute, 1e-9 / absolute);
  ASSERT_TRUE(core_->onImpostorResult(good()).ok());
  const auto& option = core_->schedulingScene().options[planned->option];
  ASSERT_TRUE(option.atBackbone.present);
  EXPECT_NEAR(option.atBackbone.relativeAccuracy, planned->relativeAccuracy,
              1e-9 * planned->relativeAccuracy);
}

TEST(BackboneCoreImpostorBound, FixedAccuracyLoosensTheBoundToWhatItNeeds) {
  CoreOptions options;
  options.config.maxSpeed = 0.1;
  options.budget.fixedAccuracy = 20.0;  // far below what an impostor can reach
  options.simpleImpostorRadii = 3.0;
  options.meshedImpostorRadii = 0.0;
  auto core = makeCore(options);
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  int impostors = 0;
  for (const OutgoingRequest& r : submitAll(*core)) {
    if (const auto* i = std::get_if<protocol::ImpostorRequest>(&r.message)) {
      ++impostors;
      EXPECT_NEAR(i->accuracyBound, 1.0 / 20.0, 1e-12);
    }
  }
  EXPECT_GT(impostors, 0);
  (void)core->finishPose();
}

TEST_F(BackboneCoreImpostors, WrongKindIsRejected) {
  protocol::ImpostorResult result = good();
  result.representation.kind = protocol::RepresentationKind::kMeshedImpostor;
  EXPECT_EQ(core_->onImpostorResult(result).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(core_->onImpostorResult(good()).code(), ErrorCode::kInvalidArgument);  // late
  EXPECT_EQ(core_->requestLedger().state(result.requestId), RequestState::kFailed);
}

TEST_F(BackboneCoreImpostors, InvertedValidityIsRejected) {
  protocol::ImpostorResult result = good();
  result.representation.validity.distanceMin = 5.0f;
  result.representation.validity.distanceMax = 1.0f;
  EXPECT_EQ(core_->onImpostorResult(result).code(), ErrorCode::kInvalidArgument);
}

TEST_F(BackboneCoreImpostors, MissingTextureIsRejected) {
  protocol::ImpostorResult result = good();
  result.representation.texture = protocol::Texture();
  EXPECT_EQ(core_->onImpostorResult(result).code(), ErrorCode::kInvalidArgument);
}

TEST_F(BackboneCoreImpostors, ForeignObjectIdsAreRejected) {
  protocol::ImpostorResult result = good();
  result.objectIds = {1, 2};
  EXPECT_EQ(core_->onImpostorResult(result).code(), ErrorCode::kInvalidArgument);
}

// ------------------------------------------------------- one request id

// The id the plan gives a missing representation is the id on the wire,
// the reply's, the backbone copy's and the one the frontend receives.
TEST(BackboneCoreRequestIds, OneIdFromThePlanToTheFrontend) {
  CoreOptions options = polygonBudget(400);
  options.firstRequestId = 5000;
  auto core = makeCore(options);
  ASSERT_NE(core, nullptr);
  std::vector<OutgoingRequest> startup = submitAll(*core);
  ASSERT_EQ(startup.size(), 1u);           // the cow's curve
  EXPECT_EQ(startup[0].requestId, 5000u);  // startup requests draw from the same counter
  answer(*core, FakeSimplifier(*core), startup);
  FakeSimplifier fake(*core);

  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  const backbone::Plan* plan = core->latestPlan();
  ASSERT_NE(plan, nullptr);
  ASSERT_FALSE(plan->requests.empty());
  std::vector<OutgoingRequest> requests = submitAll(*core);
  ASSERT_EQ(requests.size(), plan->requests.size());
  std::map<std::uint64_t, std::uint32_t> optionOfId;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const std::uint64_t planned = plan->requests[i].requestId;
    EXPECT_GT(planned, 5000u);
    EXPECT_EQ(requests[i].requestId, planned);
    const std::uint64_t onWire =
        std::visit([](const auto& m) { return m.requestId; }, requests[i].message);
    EXPECT_EQ(onWire, planned);
    EXPECT_EQ(core->requestLedger().state(planned), RequestState::kInFlight);
    optionOfId[planned] = plan->requests[i].option;
  }
  answer(*core, fake, requests);  // replies carry the same ids
  for (const auto& [id, option] : optionOfId) {
    EXPECT_EQ(core->requestLedger().state(id), RequestState::kAnswered);
    EXPECT_EQ(core->schedulingScene().options[option].atBackbone.id, id);
  }
  ASSERT_TRUE(core->replan().ok());  // as the daemon's sync wait does
  PoseOutcome outcome = core->finishPose();
  std::size_t delivered = 0;
  for (const auto& op : outcome.update.operations) {
    if (op.type != protocol::SceneOperation::Type::kAddOrReplace) continue;
    EXPECT_EQ(optionOfId.count(op.representation.representationId), 1u)
        << "representation id " << op.representation.representationId;
    ++delivered;
  }
  EXPECT_EQ(delivered, requests.size());
}

// The pool gives up on a request (its kTimeout reply after the last
// attempt); the worker's real reply comes later and is dropped cleanly.
TEST(BackboneCoreRequestIds, LateReplyAfterTimeoutIsRefusedAndNothingIsStored) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  std::vector<OutgoingRequest> requests = submitAll(*core);
  (void)core->finishPose();
  const OutgoingRequest* mesh = nullptr;
  for (const OutgoingRequest& r : requests)
    if (std::holds_alternative<protocol::SimplifyRequest>(r.message)) mesh = &r;
  ASSERT_NE(mesh, nullptr);
  const auto& request = std::get<protocol::SimplifyRequest>(mesh->message);
  const std::size_t openBefore = core->outstandingRequests();

  protocol::SimplifyResult timedOut;
  timedOut.requestId = mesh->requestId;
  timedOut.objectId = request.objectId;
  timedOut.status = Status(ErrorCode::kTimeout, "no worker answered in 3 attempts");
  EXPECT_EQ(core->onSimplifyResult(timedOut).code(), ErrorCode::kTimeout);
  EXPECT_EQ(core->requestLedger().state(mesh->requestId), RequestState::kTimedOut);
  EXPECT_EQ(core->outstandingRequests(), openBefore - 1);

  const Status late = core->onSimplifyResult(fake.simplify(request));
  EXPECT_EQ(late.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(late.message().find("late reply"), std::string::npos) << late.toString();
  EXPECT_EQ(core->requestLedger().state(mesh->requestId), RequestState::kTimedOut);
  for (const backbone::RepresentationOption& option : core->schedulingScene().options)
    EXPECT_FALSE(option.atBackbone.present && option.atBackbone.id == mesh->requestId);
  ASSERT_TRUE(core->beginPose(poseAt(1, 0.5, kEntrance, kCow)).ok());
  EXPECT_TRUE(core->finishPose().planned);
}

TEST(BackboneCoreRequestIds, DuplicateReplyIsRefusedAndChangesNothing) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  std::vector<OutgoingRequest> requests = submitAll(*core);
  answer(*core, fake, requests);
  ASSERT_TRUE(core->replan().ok());
  ASSERT_TRUE(submitAll(*core).empty());
  PoseOutcome first = core->finishPose();
  ASSERT_GT(first.adds, 0u);
  const double triangles = core->frontendTriangles();
  for (const OutgoingRequest& r : requests) {
    Status again;
    if (const auto* s = std::get_if<protocol::SimplifyRequest>(&r.message)) {
      protocol::SimplifyResult result = fake.simplify(*s);
      result.triangleCount += 1;  // a different payload must not replace the stored one
      again = core->onSimplifyResult(result);
    } else {
      again = core->onImpostorResult(fake.impostor(std::get<protocol::ImpostorRequest>(r.message)));
    }
    EXPECT_EQ(again.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(again.message().find("duplicate reply"), std::string::npos) << again.toString();
    EXPECT_EQ(core->requestLedger().state(r.requestId), RequestState::kAnswered);
  }
  EXPECT_EQ(core->requestLedger().closedCount(RequestState::kAnswered),
            requests.size() + 1);  // + the curve
  ASSERT_TRUE(core->beginPose(poseAt(1, 0.5, kEntrance, kCow)).ok());
  PoseOutcome second = core->finishPose();
  EXPECT_EQ(second.adds, 0u);  // nothing new arrived
  EXPECT_EQ(core->frontendTriangles(), triangles);
}

// A request the scheduler stops waiting for and asks again: the new id
// replaces the old, which is cancelled on the wire; the old reply is late.
TEST(BackboneCoreRequestIds, AskingAgainRetriesUnderTheNewIdAndCancelsTheOld) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  std::vector<OutgoingRequest> first = submitAll(*core);
  (void)core->finishPose();
  ASSERT_FALSE(first.empty());
  // Unanswered past the scheduler's in-flight timeout (lifetime + delays).
  ASSERT_TRUE(core->beginPose(poseAt(1, 5.0, kEntrance, kCow)).ok());
  std::vector<OutgoingRequest> second = submitAll(*core);
  (void)core->finishPose();
  ASSERT_FALSE(second.empty());
  const std::vector<std::uint64_t> cancelled = core->takeCancellations();
  const std::set<std::uint64_t> cancelledSet(cancelled.begin(), cancelled.end());
  std::size_t retried = 0;
  for (const OutgoingRequest& r : second) {
    const LedgerRequest* open = core->requestLedger().open(r.requestId);
    ASSERT_NE(open, nullptr);
    if (open->retryOf == 0) continue;
    ++retried;
    EXPECT_EQ(open->attempt, 2);
    EXPECT_EQ(core->requestLedger().state(open->retryOf), RequestState::kRetried);
    EXPECT_EQ(cancelledSet.count(open->retryOf), 1u);
  }
  EXPECT_GT(retried, 0u);
  for (const OutgoingRequest& r : first) {
    if (core->requestLedger().state(r.requestId) != RequestState::kRetried) continue;
    Status late;
    if (const auto* s = std::get_if<protocol::SimplifyRequest>(&r.message)) {
      late = core->onSimplifyResult(fake.simplify(*s));
    } else {
      late = core->onImpostorResult(fake.impostor(std::get<protocol::ImpostorRequest>(r.message)));
    }
    EXPECT_NE(late.message().find("late reply"), std::string::npos) << late.toString();
  }
}

// ------------------------------------------------------------ sessions

TEST(BackboneCoreSession, NewFrontendSessionIsServedFromStoredCopies) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  for (int step = 0; step < 3; ++step) {
    ASSERT_TRUE(core->beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok());
    answer(*core, fake, submitAll(*core));
    (void)core->finishPose();
  }
  ASSERT_GT(core->frontendTriangles(), 0.0);
  core->resetFrontend();
  EXPECT_EQ(core->frontendTriangles(), 0.0);
  // The new session starts its clock at 0 again; before any new result
  // arrives it gets the representations generated for the old one.
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  submitAll(*core);  // not answered
  PoseOutcome outcome = core->finishPose();
  EXPECT_GT(outcome.adds, 0u);
  EXPECT_EQ(outcome.removes, 0u);  // the new frontend holds nothing to remove
  EXPECT_GT(outcome.frontendTriangles, 0.0);
  EXPECT_LE(outcome.frontendTriangles, 400.0);
}

// ------------------------------------------------------ resynchronisation

// A frontend served by one backbone process for a few poses.
FrontendModel servedByAFirstBackbone(double budget) {
  FrontendModel holdings;
  auto core = makeCore(polygonBudget(budget));
  EXPECT_NE(core, nullptr);
  if (!core) return holdings;
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  for (int step = 0; step < 4; ++step) {
    EXPECT_TRUE(core->beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok());
    answer(*core, fake, submitAll(*core));
    holdings.apply(core->finishPose().update);
  }
  return holdings;
}

std::unique_ptr<BackboneCore> restartedCore(double budget) {
  CoreOptions options = polygonBudget(budget);
  options.firstRequestId = std::uint64_t{7} << 40;  // another process's ids
  auto core = makeCore(options);
  if (core) deliverCurves(*core);
  return core;
}

// A restarted backbone (new process: empty stock, its own ids) learns from
// the Hello what the frontend kept drawing: its mirror equals the frontend
// from the first pose on, never over the polygon budget, and whatever the
// old process sent is replaced by this one's copies or removed.
TEST(BackboneCoreResync, RestartedBackboneStartsFromWhatTheFrontendHolds) {
  FrontendModel holdings = servedByAFirstBackbone(400);
  ASSERT_GT(holdings.total(), 0.0);
  ASSERT_LE(holdings.total(), 400.0);
  std::set<std::uint64_t> oldIds;
  for (const auto& [id, h] : holdings.held) oldIds.insert(h.representationId);

  auto core = restartedCore(400);
  ASSERT_NE(core, nullptr);
  const protocol::Hello hello = holdings.hello();
  ASSERT_TRUE(protocol::validate(protocol::Message(hello)).ok());
  ASSERT_TRUE(core->admitFrontend(hello).ok());
  ASSERT_TRUE(core->startFrontendSession(hello).ok());
  EXPECT_EQ(core->heldForeign(), holdings.held.size());
  EXPECT_EQ(core->heldTakenBack(), 0u);
  EXPECT_EQ(core->frontendTriangles(), holdings.total());

  FakeSimplifier fake(*core);
  std::vector<OutgoingRequest> late;  // answered one pose later
  for (int step = 0; step < 12; ++step) {
    const glm::vec3 eye = kEntrance + glm::vec3(0.05f * step, 0.0f, -0.05f * step);
    ASSERT_TRUE(core->beginPose(poseAt(step, step * 0.5, eye, kCow)).ok());
    std::vector<OutgoingRequest> now = submitAll(*core);
    for (std::uint64_t cancelled : core->takeCancellations()) {
      late.erase(std::remove_if(late.begin(), late.end(),
                                [&](const OutgoingRequest& r) { return wireIdOf(r) == cancelled; }),
                 late.end());
    }
    answer(*core, fake, late);
    late = std::move(now);
    const PoseOutcome outcome = core->finishPose();
    ASSERT_TRUE(outcome.planned) << outcome.planError.toString();
    holdings.apply(outcome.update);
    ASSERT_EQ(holdings.total(), core->frontendTriangles()) << "step " << step;
    ASSERT_LE(holdings.total(), 400.0) << "step " << step;
  }
  ASSERT_FALSE(holdings.held.empty());
  for (const auto& [id, h] : holdings.held)
    EXPECT_EQ(oldIds.count(h.representationId), 0u) << "object " << id << " still shows the "
                                                    << "old process's copy";
}

// Held copies of objects the new session does not show are removed with its
// first update (they would otherwise stay at the frontend, unmirrored).
TEST(BackboneCoreResync, HeldObjectsTheNewSessionDoesNotShowAreRemoved) {
  FrontendModel holdings = servedByAFirstBackbone(400);
  ASSERT_FALSE(holdings.held.empty());
  auto core = restartedCore(400);
  ASSERT_NE(core, nullptr);
  ASSERT_TRUE(core->startFrontendSession(holdings.hello()).ok());
  const glm::vec3 away = kEntrance + glm::vec3(0.0f, 0.0f, 10.0f);
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, away)).ok());
  submitAll(*core);
  const PoseOutcome outcome = core->finishPose();
  EXPECT_EQ(countOps(outcome.update, protocol::SceneOperation::Type::kRemove),
            holdings.held.size());
  holdings.apply(outcome.update);
  EXPECT_TRUE(holdings.held.empty());
  EXPECT_EQ(core->frontendTriangles(), 0.0);
  EXPECT_TRUE(protocol::validate(protocol::Message(outcome.update)).ok());
}

// A restarted backbone with a smaller budget than what the frontend holds:
// it never adds to the excess, and brings the frontend within its budget.
TEST(BackboneCoreResync, HoldingsOverTheNewBudgetOnlyShrink) {
  FrontendModel holdings = servedByAFirstBackbone(400);
  const double start = holdings.total();
  ASSERT_GT(start, 150.0);
  auto core = restartedCore(100);
  ASSERT_NE(core, nullptr);
  ASSERT_TRUE(core->startFrontendSession(holdings.hello()).ok());
  FakeSimplifier fake(*core);
  double previous = start;
  for (int step = 0; step < 12; ++step) {
    ASSERT_TRUE(core->beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok());
    answer(*core, fake, submitAll(*core));
    const PoseOutcome outcome = core->finishPose();
    holdings.apply(outcome.update);
    ASSERT_EQ(holdings.total(), core->frontendTriangles()) << "step " << step;
    if (previous > 100.0) {
      ASSERT_LE(holdings.total(), previous) << "step " << step;
    } else {
      ASSERT_LE(holdings.total(), 100.0) << "step " << step;
    }
    previous = holdings.total();
  }
  EXPECT_LE(holdings.total(), 100.0);
}

// The same backbone process (a session that timed out during a stall): the
// held copies it still has in its stock are taken back whole (a copy whose
// stock place a newer result took is foreign, as in another process), and
// none of them is shipped again.
TEST(BackboneCoreResync, ANewSessionOfTheSameProcessTakesItsOwnCopiesBack) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  FrontendModel holdings;
  for (int step = 0; step < 3; ++step) {
    ASSERT_TRUE(core->beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok());
    answer(*core, fake, submitAll(*core));
    holdings.apply(core->finishPose().update);
  }
  ASSERT_FALSE(holdings.held.empty());
  ASSERT_TRUE(core->startFrontendSession(holdings.hello()).ok());
  EXPECT_EQ(core->heldTakenBack() + core->heldForeign(), holdings.held.size());
  EXPECT_GT(core->heldTakenBack(), 0u);
  EXPECT_EQ(core->frontendTriangles(), holdings.total());
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  submitAll(*core);
  const PoseOutcome outcome = core->finishPose();
  holdings.apply(outcome.update);
  EXPECT_EQ(holdings.total(), core->frontendTriangles());
  // What was taken back is not shipped again.
  EXPECT_LE(outcome.adds, core->heldForeign());
  for (const auto& op : outcome.update.operations)
    EXPECT_EQ(op.type, protocol::SceneOperation::Type::kAddOrReplace);
}

TEST(BackboneCoreResync, AHelloHoldingAnObjectTheSceneLacksIsRefused) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  protocol::Hello hello;
  hello.role = protocol::Role::kFrontend;
  hello.name = "frontend@test";
  protocol::HeldRepresentation h;
  h.objectId = 99;
  h.triangleCount = 10;
  hello.held.push_back(h);
  const Status admitted = core->admitFrontend(hello);
  ASSERT_FALSE(admitted.ok());
  EXPECT_EQ(admitted.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(admitted.message().find("object 99"), std::string::npos) << admitted.toString();
  EXPECT_FALSE(core->startFrontendSession(hello).ok());
  EXPECT_EQ(core->frontendTriangles(), 0.0);
}

// The loop is closed: a SceneUpdate the frontend refused (FrameStats
// rejected_plans) is corrected in the backbone's mirror and its objects are
// sent again; an applied one is simply forgotten.
TEST(BackboneCoreAcknowledgement, RefusedUpdateIsCorrectedAndItsObjectsAreSentAgain) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  answer(*core, fake, submitAll(*core));
  const PoseOutcome first = core->finishPose();
  ASSERT_TRUE(core->beginPose(poseAt(1, 0.5, kEntrance, kCow)).ok());
  const std::vector<OutgoingRequest> later = submitAll(*core);
  const PoseOutcome sent = core->finishPose();
  answer(*core, fake, later);  // nothing is in flight when the refusal comes
  ASSERT_GT(sent.adds, 0u);
  ASSERT_GT(core->frontendTriangles(), 0.0);
  EXPECT_GT(core->frontendMirror().unacknowledged(), 0u);
  std::set<std::uint64_t> refusedIds;
  for (const auto& op : sent.update.operations) refusedIds.insert(op.objectId);

  protocol::FrameStats stats;
  stats.frame = 1;
  stats.plan = first.update.plan;  // the empty first update was applied
  stats.rejectedPlans = {sent.update.plan};
  EXPECT_EQ(core->onFrameStats(stats), refusedIds.size());
  EXPECT_EQ(core->frontendTriangles(), 0.0);  // the frontend kept nothing of it
  EXPECT_EQ(core->frontendMirror().unacknowledged(), 0u);

  ASSERT_TRUE(core->beginPose(poseAt(2, 1.0, kEntrance, kCow)).ok());
  submitAll(*core);
  const PoseOutcome again = core->finishPose();
  std::set<std::uint64_t> resent;
  for (const auto& op : again.update.operations) {
    EXPECT_EQ(op.type, protocol::SceneOperation::Type::kAddOrReplace);  // sent, not removed
    resent.insert(op.objectId);
  }
  EXPECT_EQ(resent, refusedIds);
  EXPECT_EQ(again.resyncRemoves, 0u);
  EXPECT_EQ(again.frontendTriangles, sent.frontendTriangles);
  EXPECT_TRUE(protocol::validate(protocol::Message(again.update)).ok());

  // Applied: the mirror keeps its picture and forgets the change.
  stats.plan = again.update.plan;
  stats.rejectedPlans.clear();
  EXPECT_EQ(core->onFrameStats(stats), 0u);
  EXPECT_EQ(core->frontendTriangles(), again.frontendTriangles);
  EXPECT_EQ(core->frontendMirror().unacknowledged(), 0u);
}

// A refused update whose objects cannot be sent again at once (here the
// polygon cap is full of other objects the frontend still shows) is resolved
// by removing what the frontend may still show of them.
TEST(BackboneCoreAcknowledgement, RefusedObjectThatIsNotResentIsRemovedAtTheFrontend) {
  auto core = makeCore(polygonBudget(400));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  FakeSimplifier fake(*core);
  ASSERT_TRUE(core->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  answer(*core, fake, submitAll(*core));
  (void)core->finishPose();
  ASSERT_TRUE(core->beginPose(poseAt(1, 0.5, kEntrance, kCow)).ok());
  submitAll(*core);
  const PoseOutcome sent = core->finishPose();
  ASSERT_GT(sent.adds, 0u);
  protocol::FrameStats stats;
  stats.rejectedPlans = {sent.update.plan};
  ASSERT_GT(core->onFrameStats(stats), 0u);
  // The viewer turns away: nothing is visible, so nothing is sent again and
  // every refused object is removed at the frontend.
  const glm::vec3 away = kEntrance + glm::vec3(0.0f, 0.0f, 10.0f);
  ASSERT_TRUE(core->beginPose(poseAt(2, 1.0, kEntrance, away)).ok());
  submitAll(*core);
  const PoseOutcome resync = core->finishPose();
  EXPECT_EQ(resync.resyncRemoves, sent.adds);
  EXPECT_EQ(countOps(resync.update, protocol::SceneOperation::Type::kRemove), sent.adds);
  EXPECT_EQ(core->frontendTriangles(), 0.0);
  EXPECT_TRUE(protocol::validate(protocol::Message(resync.update)).ok());
}

TEST(BackboneCoreOptions, InvalidOptionsAreRefused) {
  CoreOptions options = polygonBudget(200);
  options.scheduler = "random";
  EXPECT_FALSE(validateCoreOptions(options).ok());
  options = polygonBudget(200);
  options.textureSize = 4;
  EXPECT_FALSE(validateCoreOptions(options).ok());
  options = CoreOptions();
  EXPECT_FALSE(validateCoreOptions(options).ok());  // no budget at all
  options.scheduler = "greedy";
  options.budget.fixedAccuracy = 100.0;
  EXPECT_FALSE(validateCoreOptions(options).ok());  // greedy needs polygons
  options.budget.maxTriangles = 100.0;
  EXPECT_TRUE(validateCoreOptions(options).ok());
}

TEST(BackboneCoreOptions, BaselineSchedulersServePoses) {
  for (const char* name : {"static", "greedy"}) {
    CoreOptions options = polygonBudget(300);
    options.scheduler = name;
    auto core = makeCore(options);
    ASSERT_NE(core, nullptr);
    deliverCurves(*core);
    FakeSimplifier fake(*core);
    FrontendModel frontend;
    for (int step = 0; step < 4; ++step) {
      ASSERT_TRUE(core->beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok()) << name;
      answer(*core, fake, submitAll(*core));
      PoseOutcome outcome = core->finishPose();
      ASSERT_TRUE(outcome.planned) << name;
      frontend.apply(outcome.update);
      EXPECT_LE(frontend.total(), 300.0) << name;
    }
    EXPECT_GT(frontend.triangles.size(), 0u) << name;
  }
}

}  // namespace
}  // namespace thinlod::backbone_daemon

// ------------------------------------------------ frame cost per frontend session

namespace thinlod::backbone_daemon {
namespace {

FrameCostConstants costsWithTriangleSeconds(double triangleSeconds) {
  FrameCostConstants c;
  c.initSeconds = 5e-4;
  c.finalSeconds = 5e-4;
  c.setupSeconds = 2e-5;
  c.triangleSeconds = triangleSeconds;
  c.pixelSeconds = 1e-9;
  c.additive = true;
  return c;
}

CoreOptions frameBudget(double milliseconds, std::optional<FrameCostConstants> fallback) {
  CoreOptions options;
  options.config.maxSpeed = 0.1;
  options.scheduler = "active-set";
  options.budget.maxFrameSeconds = milliseconds * 1e-3;
  options.defaultFrameCost = fallback;
  return options;
}

protocol::Hello frontendHello(std::optional<FrameCostConstants> costs) {
  protocol::Hello hello;
  hello.role = protocol::Role::kFrontend;
  hello.name = "frontend@test";
  hello.frameCost = costs;
  return hello;
}

// Plans a few poses at the entrance for one session and returns the last
// plan's triangles.
double sessionTriangles(BackboneCore& core, const protocol::Hello& hello) {
  EXPECT_TRUE(core.startFrontendSession(hello).ok());
  FakeSimplifier fake(core);
  double triangles = -1.0;
  for (int step = 0; step < 3; ++step) {
    EXPECT_TRUE(core.beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok());
    answer(core, fake, submitAll(core));
    PoseOutcome outcome = core.finishPose();
    EXPECT_TRUE(outcome.planned) << outcome.planError.toString();
    EXPECT_STREQ(outcome.row.mode, "frame-time");
    triangles = outcome.row.predictedTriangles;
  }
  return triangles;
}

// A triangle budget of the frame time the constants leave (additive model:
// every triangle costs t_tri on top of the fixed and per-object parts).
double trianglesWithin(double milliseconds, const FrameCostConstants& c) {
  return (milliseconds * 1e-3 - c.initSeconds - c.finalSeconds) / c.triangleSeconds;
}

TEST(BackboneCoreFrameCost, TheFrontendsConstantsComeFirstThenTheBackboneDefault) {
  const FrameCostConstants slow = costsWithTriangleSeconds(4e-6);  // ~2k triangles in 10 ms
  const FrameCostConstants fast = costsWithTriangleSeconds(1e-9);  // everything at full
  auto core = makeCore(frameBudget(10.0, slow));
  ASSERT_NE(core, nullptr);
  deliverCurves(*core);
  EXPECT_EQ(core->sessionFrameCost().source, FrameCostSource::kBackboneDefault);

  const double withFast = sessionTriangles(*core, frontendHello(fast));
  EXPECT_EQ(core->sessionFrameCost().source, FrameCostSource::kFrontend);
  EXPECT_EQ(core->sessionFrameCost().constants.triangleSeconds, fast.triangleSeconds);

  const double withDefault = sessionTriangles(*core, frontendHello(std::nullopt));
  EXPECT_EQ(core->sessionFrameCost().source, FrameCostSource::kBackboneDefault);
  EXPECT_EQ(core->sessionFrameCost().constants.triangleSeconds, slow.triangleSeconds);

  const double withSlow = sessionTriangles(*core, frontendHello(slow));
  EXPECT_EQ(core->sessionFrameCost().source, FrameCostSource::kFrontend);

  // The slow machine's plans fit its own model; the fast one gets far more.
  EXPECT_GT(withFast, 0.0);
  EXPECT_GT(withSlow, 0.0);
  EXPECT_LE(withSlow, trianglesWithin(10.0, slow));
  EXPECT_LE(withDefault, trianglesWithin(10.0, slow));
  EXPECT_GT(withFast, 2.0 * withSlow) << withFast << " vs " << withSlow;
  EXPECT_GT(withFast, 2.0 * withDefault) << withFast << " vs " << withDefault;
}

TEST(BackboneCoreFrameCost, WithoutADefaultAFrontendWithoutConstantsIsRefused) {
  auto core = makeCore(frameBudget(10.0, std::nullopt));
  ASSERT_NE(core, nullptr);
  const Status refused = core->admitFrontend(frontendHello(std::nullopt));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.code(), ErrorCode::kInvalidArgument);
  for (const char* part : {"--budget-frame-ms", "--frame-cost", "bench_calibrate"})
    EXPECT_NE(refused.message().find(part), std::string::npos) << refused.message();
  EXPECT_FALSE(core->startFrontendSession(frontendHello(std::nullopt)).ok());
  EXPECT_TRUE(core->admitFrontend(frontendHello(costsWithTriangleSeconds(1e-7))).ok());
  // Simplifiers and tools are not asked for frame costs.
  protocol::Hello worker = frontendHello(std::nullopt);
  worker.role = protocol::Role::kSimplifier;
  EXPECT_TRUE(core->admitFrontend(worker).ok());
}

TEST(BackboneCoreFrameCost, UnusableConstantsInAHelloAreRefusedWithTheReason) {
  auto core = makeCore(frameBudget(10.0, costsWithTriangleSeconds(1e-7)));
  ASSERT_NE(core, nullptr);
  struct Case {
    double FrameCostConstants::*field;
    double value;
    const char* expected;
  };
  const Case cases[] = {
      {&FrameCostConstants::triangleSeconds, std::numeric_limits<double>::quiet_NaN(),
       "triangleSeconds must be finite"},
      {&FrameCostConstants::pixelSeconds, -1e-9, "pixelSeconds must be finite and >= 0"},
      {&FrameCostConstants::initSeconds, std::numeric_limits<double>::infinity(), "initSeconds"},
      {&FrameCostConstants::setupSeconds, 5.0, "exceeds the limit"},
      {&FrameCostConstants::triangleSeconds, 0.0, "must be > 0"},
  };
  for (const Case& c : cases) {
    FrameCostConstants bad = costsWithTriangleSeconds(1e-7);
    bad.*c.field = c.value;
    const Status refused = core->admitFrontend(frontendHello(bad));
    ASSERT_FALSE(refused.ok()) << c.expected;
    EXPECT_NE(refused.message().find("the frontend's frame cost"), std::string::npos)
        << refused.message();
    EXPECT_NE(refused.message().find(c.expected), std::string::npos) << refused.message();
  }
  // A bad default is an option error at start-up.
  CoreOptions options = frameBudget(10.0, costsWithTriangleSeconds(-1.0));
  const Status invalidDefault = validateCoreOptions(options);
  ASSERT_FALSE(invalidDefault.ok());
  EXPECT_NE(invalidDefault.message().find("default frame cost"), std::string::npos);
}

TEST(BackboneCoreFrameCost, APolygonBudgetIgnoresTheConstants) {
  CoreOptions options = polygonBudget(300);
  options.scheduler = "active-set";
  auto core = makeCore(options);
  ASSERT_NE(core, nullptr);
  EXPECT_TRUE(core->admitFrontend(frontendHello(std::nullopt)).ok());
  ASSERT_TRUE(core->startFrontendSession(frontendHello(costsWithTriangleSeconds(1e-3))).ok());
  EXPECT_EQ(core->sessionFrameCost().source, FrameCostSource::kUnused);
}

}  // namespace
}  // namespace thinlod::backbone_daemon
