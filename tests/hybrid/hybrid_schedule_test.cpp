// The backbone's scheduler choosing hybrids on measured curves (issue 16):
// a row of instances of the generated multi-manifold model
// (generateScatteredParts), the real SimplifierService answering the real
// BackboneCore in-process (no sockets), impostors off so that each object is
// a mesh or a hybrid. At a coarse polygon budget (where the paper's
// multi-manifold models gain most: triangle collapses cannot merge separate
// parts, points can) the scheduler must pick hybrids for some objects, and
// the units it counts against the budget (triangles + points / kappa, with
// the kappa the graphs were built with) must never exceed it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <map>
#include <sstream>
#include <string>

#include "backbone_core.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/simplifier/hybrid_graph.h"
#include "thinlod/simplifier/service.h"

namespace thinlod {
namespace {

using backbone_daemon::BackboneCore;
using backbone_daemon::CoreOptions;
using backbone_daemon::OutgoingRequest;
using backbone_daemon::PoseOutcome;

// The kappa measured for point sprites on llvmpipe (docs/results/hybrid.md,
// bench_kappa: 1.4-1.9 at 3-8 pixel discs): the graphs are built with it and
// the backbone converts units with it.
constexpr double kKappa = 1.5;
constexpr int kInstances = 8;

std::string scratchDir() {
  static const std::string dir = [] {
    const std::filesystem::path path = std::filesystem::path(THINLOD_BINARY_DIR) / "test-tmp" /
                                       ("hybrid-schedule-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    return path.string();
  }();
  return dir;
}

// kInstances copies of one 60-part model (19,200 triangles) in a row along
// -z, 1.5 to 12 model sizes from the eye at the origin; one mesh file, one
// DEF'd Shape USEd by the others (one model for the service).
std::string writeScene() {
  const std::string dir = scratchDir();
  const IndexedMesh parts = simplifier::generateScatteredParts(60, 2, 7);
  EXPECT_TRUE(saveMeshFile(parts, dir + "/parts.ply", true).ok());
  std::ostringstream wrl;
  wrl << "#VRML V2.0 utf8\n"
      << "DirectionalLight { direction 0.3 -1 -0.5 }\n";
  for (int i = 0; i < kInstances; ++i) {
    const double z = -(1.5 + 1.5 * i);
    const double x = (i % 2 == 0 ? -0.6 : 0.6) - 0.5;
    wrl << "Transform { translation " << x << " -0.5 " << z << " children ";
    if (i == 0) {
      wrl << "DEF Parts Shape { appearance Appearance { material Material { diffuseColor 0.8 0.6 "
             "0.4 } } geometry Inline { url \"parts.ply\" } }";
    } else {
      wrl << "USE Parts";
    }
    wrl << " }\n";
  }
  const std::string path = dir + "/parts-row.wrl";
  std::ofstream(path) << wrl.str();
  return path;
}

protocol::ViewerPose poseLookingDownZ(std::uint64_t sequence) {
  protocol::ViewerPose pose;
  pose.sequence = sequence;
  pose.timestampNs = static_cast<std::int64_t>(sequence) * 100'000'000;
  pose.position = glm::vec3(0.0f, 0.0f, 0.0f);
  pose.orientation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);  // looks down -z, +y up
  pose.fovY = 0.9f;
  return pose;
}

struct Served {
  std::size_t hybridResults = 0;
  std::size_t meshResults = 0;
};

// Every request of the core answered by the service (in order).
Status serve(BackboneCore& core, simplifier::SimplifierService& service, double kappa,
             Served& served) {
  for (const OutgoingRequest& r : core.takeRequests()) {
    core.requestSubmitted(r.requestId);
    const auto* request = std::get_if<protocol::SimplifyRequest>(&r.message);
    if (request == nullptr) return Status(ErrorCode::kInternal, "impostor request with impostors off");
    const protocol::SimplifyResult result = service.simplify(*request);
    if (!result.status.ok()) return result.status;
    if (result.kind == protocol::RepresentationKind::kHybrid) {
      ++served.hybridResults;
      EXPECT_EQ(result.kappa, kappa);
    } else {
      ++served.meshResults;
    }
    THINLOD_RETURN_IF_ERROR(core.onSimplifyResult(result));
  }
  return Status();
}

struct RunResult {
  std::size_t hybridsShown = 0;  // objects shown as hybrids in the last update's state
  std::size_t meshesShown = 0;
  double maxFrontendUnits = 0.0;  // the core's count after each update
  double maxHeldUnits = 0.0;      // summed from the operations sent
  double lastPlanAccuracy = 0.0;
};

RunResult runRow(double budget, double kappa, const std::string& scheduler = "accuracy-curve") {
  RunResult out;
  const std::string path = writeScene();
  scene::SceneLoadOptions load;
  Result<scene::Scene> loaded = scene::loadSceneFile(path, load);
  EXPECT_TRUE(loaded.ok()) << loaded.status().toString();
  if (!loaded.ok()) return out;
  CoreOptions options;
  options.config.maxSpeed = 0.1;
  options.budget.maxTriangles = budget;
  options.simpleImpostorRadii = 0.0;
  options.meshedImpostorRadii = 0.0;
  options.hybridKappa = kappa;
  options.scheduler = scheduler;
  Result<std::unique_ptr<BackboneCore>> created =
      BackboneCore::create(std::move(loaded).value(), path, options);
  EXPECT_TRUE(created.ok()) << created.status().toString();
  if (!created.ok()) return out;
  BackboneCore& core = **created;

  simplifier::ServiceOptions serviceOptions;
  serviceOptions.sceneRoot = scratchDir();
  serviceOptions.curve.error.samplesPerMesh = 10000;  // test speed; same for both kinds
  simplifier::SimplifierService service(serviceOptions);
  Served served;
  Status status = serve(core, service, kappa, served);  // startup curves
  EXPECT_TRUE(status.ok()) << status.toString();
  EXPECT_EQ(core.curvesPending(), 0u);

  // objectId -> kind and primitive units the frontend holds (from the
  // updates' operations alone, not from the core's own count).
  std::map<std::uint64_t, protocol::RepresentationKind> held;
  std::map<std::uint64_t, double> heldUnits;
  for (std::uint64_t step = 0; step < 4; ++step) {
    EXPECT_TRUE(core.beginPose(poseLookingDownZ(step)).ok());
    status = serve(core, service, kappa, served);
    EXPECT_TRUE(status.ok()) << status.toString();
    const PoseOutcome outcome = core.finishPose();
    EXPECT_TRUE(outcome.planned) << outcome.planError.toString();
    for (const auto& op : outcome.update.operations) {
      if (op.type == protocol::SceneOperation::Type::kAddOrReplace) {
        held[op.objectId] = op.representation.kind;
        heldUnits[op.objectId] =
            op.representation.triangleCount +
            (op.representation.kind == protocol::RepresentationKind::kHybrid
                 ? op.representation.pointCount / kappa
                 : 0.0);
        if (op.representation.kind == protocol::RepresentationKind::kHybrid) {
          EXPECT_GT(op.representation.pointCount + op.representation.triangleCount, 0u);
        }
      } else if (op.type == protocol::SceneOperation::Type::kRemove) {
        held.erase(op.objectId);
        heldUnits.erase(op.objectId);
      }
    }
    double units = 0.0;
    for (const auto& [id, u] : heldUnits) units += u;
    out.maxHeldUnits = std::max(out.maxHeldUnits, units);
    out.maxFrontendUnits = std::max(out.maxFrontendUnits, outcome.frontendTriangles);
    out.lastPlanAccuracy = outcome.row.targetAccuracy;
  }
  for (const auto& [id, kind] : held) {
    out.hybridsShown += kind == protocol::RepresentationKind::kHybrid;
    out.meshesShown += kind == protocol::RepresentationKind::kMesh;
  }
  EXPECT_EQ(service.stats().hybridGraphBuilds, kappa > 0.0 ? 1u : 0u)
      << "one graph for the one shared mesh";
  return out;
}

TEST(HybridSchedule, CoarseBudgetOnTheMultiManifoldRowPicksHybridsWithinTheBudget) {
  // 8 x 19,200 triangles at 2,000 units: about 250 an object, where the
  // progressive mesh of 60 closed parts is near its floor.
  constexpr double kBudget = 2000.0;
  const RunResult hybrid = runRow(kBudget, kKappa);
  EXPECT_GT(hybrid.hybridsShown, 0u) << "the scheduler chose no hybrid";
  EXPECT_LE(hybrid.maxFrontendUnits, kBudget + 1e-6);
  EXPECT_LE(hybrid.maxHeldUnits, kBudget + 1e-6);
  EXPECT_GT(hybrid.maxHeldUnits, 0.5 * kBudget) << "the budget is used, not avoided";
  // The same row without hybrids reaches a lower planned accuracy.
  const RunResult meshes = runRow(kBudget, 0.0);
  std::printf("hybrid run: %zu hybrids, %zu meshes shown, max units %.1f (held %.1f), accuracy "
              "%.2f; mesh run: %zu meshes, max units %.1f, accuracy %.2f\n",
              hybrid.hybridsShown, hybrid.meshesShown, hybrid.maxFrontendUnits,
              hybrid.maxHeldUnits, hybrid.lastPlanAccuracy, meshes.meshesShown,
              meshes.maxFrontendUnits, meshes.lastPlanAccuracy);
  EXPECT_EQ(meshes.hybridsShown, 0u);
  EXPECT_LE(meshes.maxFrontendUnits, kBudget + 1e-6);
  EXPECT_LE(meshes.maxHeldUnits, kBudget + 1e-6);
  EXPECT_GT(hybrid.lastPlanAccuracy, meshes.lastPlanAccuracy);
}

// Every other method of the catalogue that takes a polygon budget sees the
// hybrid option among an object's candidates (it is one more option with its
// curve) and holds the same budget in primitive units. Whether it chooses
// hybrids is its own judgement; at this budget each of them does.
class HybridScheduleEveryMethod : public ::testing::TestWithParam<const char*> {};

TEST_P(HybridScheduleEveryMethod, HoldsTheBudgetInPrimitiveUnitsAndChoosesHybrids) {
  constexpr double kBudget = 2000.0;
  const RunResult run = runRow(kBudget, kKappa, GetParam());
  std::printf("%s: %zu hybrids, %zu meshes shown, max units %.1f (held %.1f)\n", GetParam(),
              run.hybridsShown, run.meshesShown, run.maxFrontendUnits, run.maxHeldUnits);
  EXPECT_LE(run.maxFrontendUnits, kBudget + 1e-6);
  EXPECT_LE(run.maxHeldUnits, kBudget + 1e-6);
  EXPECT_GT(run.hybridsShown + run.meshesShown, 0u) << "nothing shown";
  EXPECT_GT(run.hybridsShown, 0u) << GetParam() << " chose no hybrid";
}

INSTANTIATE_TEST_SUITE_P(Catalogue, HybridScheduleEveryMethod,
                         ::testing::Values("greedy-fs93", "aslod", "span-of-level-changed",
                                           "active-set"),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           std::string name = info.param;
                           for (char& c : name) {
                             if (c == '-') c = '_';
                           }
                           return name;
                         });

}  // namespace
}  // namespace thinlod
