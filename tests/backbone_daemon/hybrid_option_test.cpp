// BackboneCore's Hybrid option (CoreOptions::hybridKappa, docs/hybrid.md):
// off by default; when on, one more option per mesh object whose curve and
// representations come from Hybrid SimplifyRequests, units against the
// polygon budget.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "backbone_core.h"
#include "fake_simplifier.h"
#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::backbone_daemon {
namespace {

using namespace testing;
using backbone::OptionKind;

const glm::vec3 kEntrance(2.0f, 1.1f, 3.5f);
const glm::vec3 kCow(2.0f, 0.3f, 0.55f);
constexpr double kKappa = 1.5;

// The fake simplifier's mesh answer, as a hybrid: a third of the units as
// points (pointCount = units / 3 * kappa), the same accuracy per unit; with
// `cheaper` the curve needs 0.6x the units for the same accuracy.
protocol::SimplifyResult hybridAnswer(const FakeSimplifier& fake,
                                      const protocol::SimplifyRequest& request, bool cheaper) {
  protocol::SimplifyResult result = fake.simplify(request);
  result.kind = protocol::RepresentationKind::kHybrid;
  result.kappa = request.kappa;
  const double units = result.triangleCount;
  result.triangleCount = static_cast<std::uint32_t>(std::ceil(units * 2.0 / 3.0));
  result.pointCount = static_cast<std::uint32_t>(std::floor(units / 3.0 * request.kappa));
  const double factor = cheaper ? 0.6 : 1.0;
  for (AccuracySample& s : result.curve) s.resources *= factor;
  // Delivers what its curve promises for these units.
  result.accuracy = FakeSimplifier::meshAccuracy(units / factor);
  return result;
}

void answerAll(BackboneCore& core, const FakeSimplifier& fake,
               const std::vector<OutgoingRequest>& requests, bool cheaper) {
  for (const OutgoingRequest& r : requests) {
    if (const auto* s = std::get_if<protocol::SimplifyRequest>(&r.message)) {
      protocol::SimplifyRequest wire = *s;
      wire.requestId = r.requestId;
      const protocol::SimplifyResult result =
          wire.representation == protocol::RepresentationKind::kHybrid
              ? hybridAnswer(fake, wire, cheaper)
              : fake.simplify(wire);
      EXPECT_TRUE(core.onSimplifyResult(result).ok());
    } else {
      protocol::ImpostorRequest wire = std::get<protocol::ImpostorRequest>(r.message);
      wire.requestId = r.requestId;
      EXPECT_TRUE(core.onImpostorResult(fake.impostor(wire)).ok());
    }
  }
}

std::size_t hybridOptions(const BackboneCore& core) {
  std::size_t n = 0;
  for (const auto& option : core.schedulingScene().options) n += option.kind == OptionKind::kHybrid;
  return n;
}

TEST(BackboneCoreHybrid, OffByDefault) {
  auto core = paperRoomCore(polygonBudget(300));
  ASSERT_TRUE(core.ok());
  EXPECT_EQ(hybridOptions(**core), 0u);
  for (const OutgoingRequest& r : submitAll(**core)) {
    const auto& s = std::get<protocol::SimplifyRequest>(r.message);
    EXPECT_EQ(s.representation, protocol::RepresentationKind::kMesh);
    EXPECT_EQ(s.kappa, 0.0);
  }
  ASSERT_TRUE((*core)->beginPose(poseAt(0, 0.0, kEntrance, kCow)).ok());
  EXPECT_EQ((*core)->finishPose().update.unitsKappa, 0.0) << "no hybrids: no kappa";
}

TEST(BackboneCoreHybrid, KappaOutsideItsRangeIsRefused) {
  for (double kappa : {0.5, 1.0, -2.0, 100.0}) {
    CoreOptions options = polygonBudget(300);
    options.hybridKappa = kappa;
    EXPECT_FALSE(validateCoreOptions(options).ok()) << kappa;
  }
}

TEST(BackboneCoreHybrid, MeshObjectsGetAHybridOptionWithItsOwnCurve) {
  CoreOptions options = polygonBudget(300);
  options.hybridKappa = kKappa;
  auto created = paperRoomCore(options);
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  EXPECT_EQ(hybridOptions(core), 1u) << "the cow only: primitives have no hybrid";
  const std::vector<OutgoingRequest> startup = submitAll(core);
  std::size_t hybridRequests = 0;
  for (const OutgoingRequest& r : startup) {
    const auto& s = std::get<protocol::SimplifyRequest>(r.message);
    if (s.representation != protocol::RepresentationKind::kHybrid) continue;
    ++hybridRequests;
    EXPECT_EQ(s.kappa, kKappa);
    EXPECT_GT(s.curvePoints, 0u);
  }
  EXPECT_EQ(hybridRequests, 1u);
  FakeSimplifier fake(core);
  answerAll(core, fake, startup, true);
  EXPECT_EQ(core.curvesPending(), 0u);
  for (const auto& option : core.schedulingScene().options) {
    if (option.kind != OptionKind::kHybrid) continue;
    EXPECT_LT(option.relativeTriangles.minAccuracy(), option.relativeTriangles.maxAccuracy());
  }
}

// Hybrids carry no uvs: a textured mesh object is offered none (its hybrid
// would drop the texture while credited like a textured copy).
TEST(BackboneCoreHybrid, TexturedMeshObjectsGetNoHybrid) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) /
                                    ("hybrid-textured-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::filesystem::copy_file("/usr/share/assimp/models/glTF2/BoxTextured-glTF/CesiumLogoFlat.png",
                             dir / "logo.png");
  const std::string tetrahedron =
      "geometry IndexedFaceSet { coord Coordinate { point [ 0 0 0, 1 0 0, 0 1 0, 0 0 1 ] } "
      "coordIndex [ 0 2 1 -1 0 1 3 -1 0 3 2 -1 1 2 3 -1 ] "
      "texCoord TextureCoordinate { point [ 0 0, 1 0, 0 1, 1 1 ] } }";
  std::ofstream(dir / "scene.wrl")
      << "#VRML V2.0 utf8\n"
      << "Shape { appearance Appearance { texture ImageTexture { url \"logo.png\" } } "
      << tetrahedron << " }\n"
      << "Transform { translation 3 0 0 children Shape { " << tetrahedron << " } }\n";
  const std::string path = (dir / "scene.wrl").string();
  Result<scene::Scene> loaded = scene::loadSceneFile(path);
  ASSERT_TRUE(loaded.ok()) << loaded.status().toString();
  CoreOptions options = polygonBudget(300);
  options.hybridKappa = kKappa;
  auto created = BackboneCore::create(std::move(loaded).value(), path, options);
  ASSERT_TRUE(created.ok()) << created.status().toString();
  const BackboneCore& core = **created;
  ASSERT_EQ(core.sceneObjects().size(), 2u);
  ASSERT_FALSE(core.sceneObjects()[0].shape->appearance.texturePath.empty());
  ASSERT_FALSE(core.sceneObjects()[0].fullMesh->uvs.empty());
  const backbone::SchedulingScene& scene = core.schedulingScene();
  std::vector<std::size_t> hybridsPerObject(scene.objects.size(), 0);
  for (std::size_t k = 0; k < scene.objects.size(); ++k) {
    for (std::uint32_t o = 0; o < scene.objects[k].optionCount; ++o) {
      hybridsPerObject[k] += scene.options[scene.objects[k].firstOption + o].kind == OptionKind::kHybrid;
    }
  }
  EXPECT_EQ(hybridsPerObject, (std::vector<std::size_t>{0, 1}))
      << "the textured tetrahedron none, the plain one its hybrid";
  std::filesystem::remove_all(dir);
}

TEST(BackboneCoreHybrid, AMeshAnswerToAHybridRequestIsRefused) {
  CoreOptions options = polygonBudget(300);
  options.hybridKappa = kKappa;
  auto created = paperRoomCore(options);
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  for (const OutgoingRequest& r : submitAll(core)) {
    protocol::SimplifyRequest wire = std::get<protocol::SimplifyRequest>(r.message);
    wire.requestId = r.requestId;
    if (wire.representation != protocol::RepresentationKind::kHybrid) continue;
    EXPECT_EQ(core.onSimplifyResult(fake.simplify(wire)).code(), ErrorCode::kInvalidArgument);
  }
}

// With a cheaper hybrid curve (and no impostors to compete) the cow is sent
// as a Hybrid, its units (triangles + points / kappa) within the polygon budget.
TEST(BackboneCoreHybrid, ACheaperHybridIsSentWithinThePolygonBudget) {
  CoreOptions options = polygonBudget(300);
  options.hybridKappa = kKappa;
  options.simpleImpostorRadii = 0.0;
  options.meshedImpostorRadii = 0.0;
  auto created = paperRoomCore(options);
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answerAll(core, fake, submitAll(core), true);
  double units = 0.0;
  bool sawHybrid = false;
  for (std::uint64_t step = 0; step < 4; ++step) {
    ASSERT_TRUE(core.beginPose(poseAt(step, 0.5 * step, kEntrance, kCow)).ok());
    const std::vector<OutgoingRequest> requests = submitAll(core);
    const PoseOutcome outcome = core.finishPose();
    ASSERT_TRUE(outcome.planned) << outcome.planError.toString();
    // The update names the kappa its units count points with (the frontend's units).
    EXPECT_EQ(outcome.update.unitsKappa, kKappa);
    for (const auto& op : outcome.update.operations) {
      if (op.type != protocol::SceneOperation::Type::kAddOrReplace) continue;
      if (op.representation.kind == protocol::RepresentationKind::kHybrid) {
        sawHybrid = true;
        EXPECT_EQ(op.objectId, 4u);
        EXPECT_GT(op.representation.pointCount, 0u);
      }
    }
    EXPECT_LE(outcome.frontendTriangles, 300.0 + 1e-6);
    units = outcome.frontendTriangles;
    answerAll(core, fake, requests, true);
  }
  EXPECT_TRUE(sawHybrid);
  EXPECT_GT(units, 0.0);
}

}  // namespace
}  // namespace thinlod::backbone_daemon
