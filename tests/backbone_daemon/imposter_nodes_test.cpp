// The paper's imposter nodes (Pasman & Jansen 2002, section 3.6, Figures 9
// and 10) in the backbone: SimpleImposter, MeshedImposter and
// SimplifiedPolygon are one representation of their whole subtree
// (scene_conversion.h, docs/backbone.md "Imposter nodes").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <random>
#include <limits>
#include <set>

#include "backbone_core.h"
#include "fake_simplifier.h"
#include "scene_conversion.h"
#include "thinlod/backbone/scheduler.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/protocol/codec.h"

namespace thinlod::backbone_daemon {
namespace {

using namespace testing;
using backbone::OptionKind;
using backbone::SceneNodeKind;

std::string figure10Path() {
  return std::string(THINLOD_SOURCE_DIR) + "/tests/data/scene/figure10.wrl";
}

Result<std::unique_ptr<BackboneCore>> coreFromText(const std::string& text, const std::string& name,
                                                   const CoreOptions& options) {
  Result<scene::Scene> parsed = scene::parseScene(text, name);
  if (!parsed.ok()) return parsed.status();
  return BackboneCore::create(std::move(parsed).value(), "/scenes/" + name, options);
}

Result<std::unique_ptr<BackboneCore>> figure10Core(const CoreOptions& options) {
  scene::SceneLoadOptions load;
  Result<scene::Scene> loaded = scene::loadSceneFile(figure10Path(), load);
  if (!loaded.ok()) return loaded.status();
  return BackboneCore::create(std::move(loaded).value(), figure10Path(), options);
}

// Five 0.2 m boxes on a shelf, 12 triangles each, replaced by one impostor.
const char* kShelf = R"(#VRML V2.0 utf8
SimpleImposter {
  children [
    Transform { translation 0.0 1 0 children Shape { geometry Box { size 0.2 0.2 0.2 } } }
    Transform { translation 0.25 1 0 children Shape { geometry Box { size 0.2 0.2 0.2 } } }
    Transform { translation 0.5 1 0 children Shape { geometry Box { size 0.2 0.2 0.2 } } }
    Transform { translation 0.75 1 0 children Shape { geometry Box { size 0.2 0.2 0.2 } } }
    Transform { translation 1.0 1 0 children Shape { geometry Box { size 0.2 0.2 0.2 } } }
  ]
}
)";

std::vector<OptionKind> optionKinds(const backbone::SchedulingScene& s, std::uint32_t object) {
  std::vector<OptionKind> kinds;
  const backbone::SceneObject& o = s.objects[object];
  for (std::uint32_t i = 0; i < o.optionCount; ++i) kinds.push_back(s.options[o.firstOption + i].kind);
  return kinds;
}

// ------------------------------------------------------------- Figure 10

TEST(ImposterNodes, Figure10LoadsAsOneObjectWithTheCylinderAndItsTwoImpostors) {
  auto core = figure10Core(polygonBudget(100));
  ASSERT_TRUE(core.ok()) << core.status().toString();
  // The scene numbering is unchanged (three Shape instances) ...
  EXPECT_EQ((*core)->sceneObjects().size(), 3u);
  // ... but the backbone schedules one object: the LOD's first level, id 1.
  const backbone::SchedulingScene& s = (*core)->schedulingScene();
  ASSERT_EQ((*core)->objects().size(), 1u);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ((*core)->objects()[0].id, 1u);
  EXPECT_EQ((*core)->lodNodes(), 0u);
  for (const backbone::SceneNode& node : s.nodes) EXPECT_NE(node.kind, SceneNodeKind::kLod);
  EXPECT_EQ(optionKinds(s, 0), (std::vector<OptionKind>{OptionKind::kSimplifiedMesh,
                                                        OptionKind::kMeshedImpostor,
                                                        OptionKind::kSimpleImpostor}));
  // The simple impostor's level range (distance 10 1000), the meshed one's
  // level is unrestricted: the kind's default (4 radii); the mesh everywhere.
  const backbone::RepresentationOption& mesh = s.options[0];
  const backbone::RepresentationOption& meshed = s.options[1];
  const backbone::RepresentationOption& simple = s.options[2];
  EXPECT_TRUE(mesh.validity.isEverywhere());
  EXPECT_DOUBLE_EQ(simple.validity.minDistance(), 10.0);
  EXPECT_DOUBLE_EQ(simple.validity.maxDistance(), 1000.0);
  EXPECT_NEAR(meshed.validity.minDistance(), 4.0 * (*core)->objects()[0].bounds.radius, 1e-9);
  EXPECT_TRUE(backbone::validateScene(s).ok());
}

// The object's curve is the lower envelope of its options' curves, each
// taken only where its range holds the predicted region: the scheduler's
// target at a polygon budget is the envelope's best accuracy within it.
TEST(ImposterNodes, Figure10CurveIsTheLowerEnvelopeOfItsEligibleOptions) {
  CoreOptions options = polygonBudget(100);
  // A cylinder is cheap as a mesh: with the default 64-triangle estimate
  // its meshed impostor never wins, with 16 it does between 5.7 and 10 m.
  options.meshedImpostorTriangles = 16.0;
  auto core = figure10Core(options);
  ASSERT_TRUE(core.ok()) << core.status().toString();
  const backbone::SchedulingScene& s = (*core)->schedulingScene();
  backbone::SchedulerConfig config = backbone::withoutApproximations((*core)->options().config);
  config.maxSpeed = 0.0;
  config.maxViewDistance = std::numeric_limits<double>::infinity();
  auto scheduler = backbone::makeAccuracyCurveScheduler(config);
  ASSERT_TRUE(scheduler.ok());
  const backbone::Sphere bounds = (*core)->objects()[0].bounds;
  std::set<OptionKind> chosenKinds;
  for (double distance : {3.0, 8.0, 20.0, 300.0, 1200.0}) {
    for (double budget : {2.0, 10.0, 20.0, 40.0, 64.0, 100.0, 400.0}) {
      backbone::ViewerState viewer;
      viewer.position = bounds.center + glm::dvec3(0.0, 0.0, distance);
      viewer.viewDirection = {0.0, 0.0, -1.0};
      backbone::Budget b;
      b.maxTriangles = budget;
      backbone::PlannerState state;
      Result<backbone::Plan> plan = (*scheduler)->plan(s, viewer, b, state);
      ASSERT_TRUE(plan.ok()) << plan.status().toString();
      const backbone::PredictedRegion region = plan->region;
      const double d = backbone::conversionDistance(region.center, region.reachRadius, bounds,
                                                    config.minimalDistance);
      // The envelope, built here from the options alone.
      std::vector<AccuracyCurve> absolute;
      std::vector<OptionKind> kinds;
      for (std::uint32_t i = 0; i < s.objects[0].optionCount; ++i) {
        const backbone::RepresentationOption& option = s.options[s.objects[0].firstOption + i];
        if (!backbone::containsBall(option.validity, region.reachBall())) continue;
        absolute.push_back(option.relativeTriangles.scaledAccuracy(d / (2.0 * bounds.radius)));
        kinds.push_back(option.kind);
      }
      ASSERT_FALSE(absolute.empty());
      std::vector<const AccuracyCurve*> pointers;
      for (const AccuracyCurve& c : absolute) pointers.push_back(&c);
      const AccuracyCurve envelope = AccuracyCurve::lowerEnvelope(pointers);
      const std::optional<double> best = envelope.maxAccuracyWithin(budget);
      const std::string where =
          "distance " + std::to_string(distance) + " budget " + std::to_string(budget);
      // The simple impostor only between 10 and 1000 m (Figure 10).
      const bool simpleEligible =
          std::find(kinds.begin(), kinds.end(), OptionKind::kSimpleImpostor) != kinds.end();
      EXPECT_EQ(simpleEligible, distance > 10.5 && distance < 999.0) << where;
      if (!best) {
        EXPECT_FALSE(plan->dropped.empty()) << where;
        continue;
      }
      EXPECT_NEAR(plan->targetAccuracy, *best, 1e-9 * *best) << where;
      ASSERT_EQ(plan->decisions.size(), 1u) << where;
      const backbone::ObjectDecision& decision = plan->decisions[0];
      EXPECT_LE(decision.triangles, budget) << where;
      // The decision's triangles are the envelope's at the target.
      EXPECT_NEAR(decision.triangles, envelope.resourcesFor(plan->targetAccuracy),
                  1e-9 * (1.0 + decision.triangles))
          << where;
      chosenKinds.insert(decision.kind);
    }
  }
  // The sweep really switches between the three representations.
  EXPECT_EQ(chosenKinds.size(), 3u);
}

TEST(ImposterNodes, Figure10BudgetHoldsAtTheFrontendOverARandomFlight) {
  // Too few triangles for a good cylinder: far away its impostors win.
  const double budget = 12.0;
  CoreOptions options = polygonBudget(budget);
  options.config.maxSpeed = 1.0;
  auto created = figure10Core(options);
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
  FrontendModel frontend;
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  InFlightRequests inFlight;
  std::set<protocol::RepresentationKind> shownKinds;
  double distance = 2.5;
  for (int step = 0; step < 200; ++step) {
    // In and out along a slanted line: 2.5 m to 60 m and back.
    distance = 2.5 + 57.5 * 0.5 * (1.0 - std::cos(step * 0.06));
    const glm::vec3 eye(0.3f * float(distance), 0.5f, float(distance));
    ASSERT_TRUE(core.beginPose(poseAt(step, step * 0.25, eye, glm::vec3(0.0f))).ok());
    for (OutgoingRequest& r : submitAll(core))
      inFlight.emplace_back(step + static_cast<int>(unit(random) * 3.0), std::move(r));
    answerDue(core, fake, inFlight, step);
    PoseOutcome outcome = core.finishPose();
    ASSERT_TRUE(outcome.planned) << outcome.planError.toString();
    for (const protocol::SceneOperation& op : outcome.update.operations) {
      // Only the one object is ever shown.
      EXPECT_EQ(op.objectId, 1u) << "step " << step;
      if (op.type != protocol::SceneOperation::Type::kRemove)
        shownKinds.insert(op.representation.kind);

    }
    frontend.apply(outcome.update);
    ASSERT_LE(frontend.total(), budget) << "step " << step;
  }
  // The flight shows the cylinder as a mesh and as an impostor.
  EXPECT_TRUE(shownKinds.count(protocol::RepresentationKind::kMesh)) << shownKinds.size();
  EXPECT_GE(shownKinds.size(), 2u);
}

// The workbench gallery's bunny and horse are Figure 10 LODs whose imposter
// levels USE the placed model: each is one object with three kinds.
TEST(ImposterNodes, TheGalleryStatuesAreOneObjectEach) {
  const std::string path = std::string(THINLOD_SOURCE_DIR) + "/deploy/data/gallery.wrl";
  scene::SceneLoadOptions load;
  load.meshSearchPaths = {modelsDir()};
  Result<scene::Scene> loaded = scene::loadSceneFile(path, load);
  ASSERT_TRUE(loaded.ok()) << loaded.status().toString();
  auto objects = scene::collectSceneObjects(*loaded);
  ASSERT_TRUE(objects.ok()) << objects.status().toString();
  ASSERT_EQ(objects->size(), 31u);
  Result<ConvertedScene> converted = convertScene(*loaded, *objects);
  ASSERT_TRUE(converted.ok()) << converted.status().toString();
  EXPECT_EQ(converted->collapsedLods, 2u);
  EXPECT_EQ(converted->lodNodes, 0u);
  // 31 Shape instances, two LODs of three levels each: 27 scheduled objects.
  ASSERT_EQ(converted->records.size(), 27u);
  std::size_t statues = 0;
  for (const ObjectRecord& record : converted->records) {
    if (record.object->shape->defName != "Bunny" && record.object->shape->defName != "Horse")
      continue;
    ++statues;
    EXPECT_TRUE(record.mesh.offered);
    EXPECT_TRUE(record.meshedImpostor.offered);
    ASSERT_TRUE(record.simpleImpostor.offered);
    ASSERT_TRUE(record.simpleImpostor.range.has_value());
    EXPECT_NEAR(record.simpleImpostor.range->minDistance(), 6.0, 1e-6);  // float transforms
  }
  EXPECT_EQ(statues, 2u);
}

// ------------------------------------------------ single-object imposter nodes

TEST(ImposterNodes, AnImposterNodeOverOneObjectOffersItsMeshAndItsKindOnly) {
  const std::string text = R"(#VRML V2.0 utf8
SimpleImposter { children [ Shape { geometry Sphere { radius 1 } } ] }
MeshedImposter { children [ Transform { translation 5 0 0 children Shape { geometry Box {} } } ] }
SimplifiedPolygon { children [ Transform { translation -5 0 0 children Shape { geometry Cone {} } } ] }
Shape { geometry Cylinder {} }
)";
  auto core = coreFromText(text, "single.wrl", polygonBudget(100));
  ASSERT_TRUE(core.ok()) << core.status().toString();
  const backbone::SchedulingScene& s = (*core)->schedulingScene();
  ASSERT_EQ(s.objects.size(), 4u);
  for (std::uint32_t k = 0; k < 4; ++k) EXPECT_EQ((*core)->objects()[k].id, k + 1);
  EXPECT_EQ(optionKinds(s, 0),
            (std::vector<OptionKind>{OptionKind::kSimplifiedMesh, OptionKind::kSimpleImpostor}));
  EXPECT_EQ(optionKinds(s, 1),
            (std::vector<OptionKind>{OptionKind::kSimplifiedMesh, OptionKind::kMeshedImpostor}));
  EXPECT_EQ(optionKinds(s, 2), (std::vector<OptionKind>{OptionKind::kSimplifiedMesh}));
  // A plain Shape is offered every kind, as before.
  EXPECT_EQ(optionKinds(s, 3), (std::vector<OptionKind>{OptionKind::kSimplifiedMesh,
                                                        OptionKind::kMeshedImpostor,
                                                        OptionKind::kSimpleImpostor}));
}

TEST(ImposterNodes, AnExplicitImposterNodeIsOfferedEvenWhenItsKindIsOffByDefault) {
  CoreOptions options = polygonBudget(100);
  options.simpleImpostorRadii = 0.0;
  options.meshedImpostorRadii = 0.0;
  auto core = coreFromText(
      "#VRML V2.0 utf8\nSimpleImposter { children [ Shape { geometry Sphere {} } ] }\n"
      "Shape { geometry Box {} }\n",
      "off.wrl", options);
  ASSERT_TRUE(core.ok()) << core.status().toString();
  const backbone::SchedulingScene& s = (*core)->schedulingScene();
  EXPECT_EQ(optionKinds(s, 0),
            (std::vector<OptionKind>{OptionKind::kSimplifiedMesh, OptionKind::kSimpleImpostor}));
  EXPECT_EQ(optionKinds(s, 1), (std::vector<OptionKind>{OptionKind::kSimplifiedMesh}));
}

TEST(ImposterNodes, AnLodOfDifferentShapesStaysAnLod) {
  const std::string text = R"(#VRML V2.0 utf8
LOD { range [ 20 ] level [
  Shape { geometry Sphere {} }
  SimpleImposter { children [ Shape { geometry Box {} } ] }
] }
)";
  auto core = coreFromText(text, "lod.wrl", polygonBudget(100));
  ASSERT_TRUE(core.ok()) << core.status().toString();
  const backbone::SchedulingScene& s = (*core)->schedulingScene();
  EXPECT_EQ((*core)->lodNodes(), 1u);
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(optionKinds(s, 1),
            (std::vector<OptionKind>{OptionKind::kSimplifiedMesh, OptionKind::kSimpleImpostor}));
}

// Figure 9's size / center with autosize / autocenter FALSE reach the
// simplifier as the request's fixed frame (world: the node's frame mapped).
TEST(ImposterNodes, FixedSizeAndCentreOfTheNodeAreTheRequestsFrame) {
  const std::string text = R"(#VRML V2.0 utf8
Transform { translation 10 0 0 scale 2 2 2 children [
  SimpleImposter { size 3 4 autosize FALSE center 0.5 1 0 autocenter FALSE
    children [ Shape { geometry Sphere {} } Transform { translation 1 0 0 children Shape { geometry Box {} } } ] }
  SimpleImposter { children [ Transform { translation 0 5 0 children Shape { geometry Sphere {} } } ] }
] }
)";
  auto created = coreFromText(text, "frame.wrl", polygonBudget(10));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  ASSERT_EQ(core.objects().size(), 4u);  // two objects + their cluster, one alone
  const ObjectRecord& cluster = core.objects()[2];
  ASSERT_TRUE(cluster.cluster);
  ASSERT_TRUE(cluster.simpleImpostor.frameCenter.has_value());
  EXPECT_NEAR(glm::length(*cluster.simpleImpostor.frameCenter - glm::vec3(11.0f, 2.0f, 0.0f)), 0.0f,
              1e-5f);
  EXPECT_NEAR(cluster.simpleImpostor.frameSize.x, 6.0f, 1e-5f);
  EXPECT_NEAR(cluster.simpleImpostor.frameSize.y, 8.0f, 1e-5f);
  // The defaults (autosize / autocenter TRUE) leave the framing to the simplifier.
  EXPECT_FALSE(core.objects()[3].simpleImpostor.frameCenter.has_value());
  EXPECT_EQ(core.objects()[3].simpleImpostor.frameSize, glm::vec2(0.0f));

  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
  const glm::vec3 target(11.0f, 2.0f, 0.0f);
  ASSERT_TRUE(core.beginPose(poseAt(0, 0.0, target + glm::vec3(0, 0, 60), target)).ok());
  bool sawFramed = false;
  for (const OutgoingRequest& r : submitAll(core)) {
    const auto* impostor = std::get_if<protocol::ImpostorRequest>(&r.message);
    if (impostor == nullptr || impostor->objectIds.size() != 2) continue;
    sawFramed = true;
    ASSERT_TRUE(impostor->frameCenter.has_value());
    EXPECT_NEAR(glm::length(*impostor->frameCenter - glm::vec3(11.0f, 2.0f, 0.0f)), 0.0f, 1e-5f);
    EXPECT_NEAR(impostor->frameWidth, 6.0f, 1e-5f);
    EXPECT_NEAR(impostor->frameHeight, 8.0f, 1e-5f);
    EXPECT_TRUE(protocol::validate(protocol::Message(*impostor)).ok());
  }
  EXPECT_TRUE(sawFramed);
}

// ------------------------------------------------------------ clusters

TEST(ImposterNodes, AShelfUnderASimpleImposterIsAnLodOfItsObjectsAndOneClusterImpostor) {
  auto core = coreFromText(kShelf, "shelf.wrl", polygonBudget(100));
  ASSERT_TRUE(core.ok()) << core.status().toString();
  const backbone::SchedulingScene& s = (*core)->schedulingScene();
  const std::vector<ObjectRecord>& records = (*core)->objects();
  ASSERT_EQ((*core)->sceneObjects().size(), 5u);
  ASSERT_EQ(records.size(), 6u);
  for (std::uint32_t k = 0; k < 5; ++k) {
    EXPECT_EQ(records[k].id, k + 1);
    EXPECT_FALSE(records[k].cluster);
    EXPECT_EQ(optionKinds(s, k), (std::vector<OptionKind>{OptionKind::kSimplifiedMesh}));
  }
  const ObjectRecord& cluster = records[5];
  EXPECT_TRUE(cluster.cluster);
  EXPECT_EQ(cluster.id, 6u);  // above every object id
  EXPECT_EQ(cluster.members, (std::vector<std::uint64_t>{1, 2, 3, 4, 5}));
  EXPECT_EQ(optionKinds(s, 5), (std::vector<OptionKind>{OptionKind::kSimpleImpostor}));
  // Its sphere is the group's reference sphere (relative_accuracy.h).
  std::vector<BoundingSphere> spheres;
  for (const scene::SceneObject& o : (*core)->sceneObjects()) spheres.push_back(o.worldSphere);
  const BoundingSphere group = enclosingSphere(spheres);
  EXPECT_NEAR(cluster.bounds.radius, group.radius, 1e-6);
  // Tree: root -> LOD -> { Group of the five, the cluster leaf }.
  const backbone::SceneNode& lod = s.nodes[s.children[s.nodes[0].firstChild]];
  ASSERT_EQ(lod.kind, SceneNodeKind::kLod);
  ASSERT_EQ(lod.childCount, 2u);
  EXPECT_EQ(s.nodes[s.children[lod.firstChild]].childCount, 5u);
  EXPECT_EQ(s.nodes[s.children[lod.firstChild + 1]].kind, SceneNodeKind::kLeaf);
  EXPECT_TRUE(backbone::validateScene(s).ok());
}

// From afar the five boxes (60 triangles) do not fit 30 triangles, their one
// impostor does: the request names all five, the frontend gets id 6. Near
// (inside the impostor's 10 radii) the boxes come back.
TEST(ImposterNodes, TheShelfSeenFromAfarIsOneImpostorOfAllItsObjects) {
  const double budget = 30.0;
  auto created = coreFromText(kShelf, "shelf.wrl", polygonBudget(budget));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
  FrontendModel frontend;
  const glm::vec3 shelf(0.5f, 1.0f, 0.0f);
  bool sawClusterRequest = false;
  for (int step = 0; step < 6; ++step) {
    ASSERT_TRUE(core.beginPose(poseAt(step, step * 0.5, shelf + glm::vec3(0, 0, 30), shelf)).ok());
    std::vector<OutgoingRequest> requests = submitAll(core);
    for (const OutgoingRequest& r : requests) {
      if (const auto* impostor = std::get_if<protocol::ImpostorRequest>(&r.message)) {
        EXPECT_EQ(impostor->objectIds, (std::vector<std::uint64_t>{1, 2, 3, 4, 5}));
        sawClusterRequest = true;
      }
    }
    answer(core, fake, requests);
    PoseOutcome outcome = core.finishPose();
    ASSERT_TRUE(outcome.planned) << outcome.planError.toString();
    frontend.apply(outcome.update);
    ASSERT_LE(frontend.total(), budget);
  }
  EXPECT_TRUE(sawClusterRequest);
  EXPECT_EQ(frontend.triangles.size(), 1u);
  EXPECT_EQ(frontend.triangles.count(6), 1u);

  // The budget holds the five boxes near by; the impostor is not valid there.
  auto nearCore = coreFromText(kShelf, "shelf.wrl", polygonBudget(100));
  ASSERT_TRUE(nearCore.ok());
  FakeSimplifier nearFake(**nearCore);
  answer(**nearCore, nearFake, submitAll(**nearCore));
  FrontendModel nearFrontend;
  for (int step = 0; step < 6; ++step) {
    ASSERT_TRUE(
        (*nearCore)->beginPose(poseAt(step, step * 0.5, shelf + glm::vec3(0, 0, 1.5f), shelf)).ok());
    answer(**nearCore, nearFake, submitAll(**nearCore));
    PoseOutcome outcome = (*nearCore)->finishPose();
    ASSERT_TRUE(outcome.planned);
    nearFrontend.apply(outcome.update);
    ASSERT_LE(nearFrontend.total(), 100.0);
  }
  EXPECT_EQ(nearFrontend.triangles.size(), 5u);
  EXPECT_EQ(nearFrontend.triangles.count(6), 0u);
}

TEST(ImposterNodes, AClusterResultMustNameEveryObjectOfTheCluster) {
  auto created = coreFromText(kShelf, "shelf.wrl", polygonBudget(30));
  ASSERT_TRUE(created.ok());
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
  const glm::vec3 shelf(0.5f, 1.0f, 0.0f);
  ASSERT_TRUE(core.beginPose(poseAt(0, 0.0, shelf + glm::vec3(0, 0, 30), shelf)).ok());
  std::vector<OutgoingRequest> requests = submitAll(core);
  ASSERT_EQ(requests.size(), 1u);
  protocol::ImpostorRequest wire = std::get<protocol::ImpostorRequest>(requests[0].message);
  protocol::ImpostorResult result = fake.impostor(wire);
  result.objectIds = {1};
  EXPECT_FALSE(core.onImpostorResult(result).ok());
}

// Levels of an LOD are alternatives: an impostor node over an LOD (and
// something else) is no cluster; the LOD stays an LOD.
TEST(ImposterNodes, AnImposterNodeOverAnLodStaysTransparent) {
  const std::string text = R"(#VRML V2.0 utf8
SimpleImposter { children [
  LOD { range [ 5 ] level [ Shape { geometry Sphere {} } Shape { geometry Box {} } ] }
  Transform { translation 3 0 0 children Shape { geometry Cone {} } }
] }
)";
  auto core = coreFromText(text, "lodinside.wrl", polygonBudget(100));
  ASSERT_TRUE(core.ok()) << core.status().toString();
  EXPECT_EQ((*core)->lodNodes(), 1u);
  ASSERT_EQ((*core)->objects().size(), 3u);
  for (const ObjectRecord& record : (*core)->objects()) EXPECT_FALSE(record.cluster);
}

TEST(ImposterNodes, ASimplifiedPolygonOfSeveralObjectsOffersThemMeshesOnly) {
  const std::string text = R"(#VRML V2.0 utf8
SimplifiedPolygon { children [
  Shape { geometry Sphere {} }
  Transform { translation 3 0 0 children Shape { geometry Box {} } }
] }
)";
  auto core = coreFromText(text, "sp.wrl", polygonBudget(100));
  ASSERT_TRUE(core.ok()) << core.status().toString();
  const backbone::SchedulingScene& s = (*core)->schedulingScene();
  ASSERT_EQ(s.objects.size(), 2u);
  for (std::uint32_t k = 0; k < 2; ++k)
    EXPECT_EQ(optionKinds(s, k), (std::vector<OptionKind>{OptionKind::kSimplifiedMesh}));
}

}  // namespace
}  // namespace thinlod::backbone_daemon
