// Regions in the running system (issue 18; docs/regions.md, "In the running
// system"): a terrain Inline with `regions 4`, the real BackboneCore and the
// real SimplifierService in-process (no sockets, the hybrid_schedule_test
// pattern), impostors off. The scene makes 4 objects, the backbone 4 leaves
// with their own measured curves, the simplifier keeps every region's
// border, and the frontend's held levels (decoded from the SceneUpdates'
// operations) assemble into a crack-free terrain in which the regions near
// the viewer hold more triangles than the far ones, under several schedulers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <glm/gtc/quaternion.hpp>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "backbone_core.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/simplifier/service.h"

namespace thinlod {
namespace {

using backbone_daemon::BackboneCore;
using backbone_daemon::CoreOptions;
using backbone_daemon::OutgoingRequest;
using backbone_daemon::PoseOutcome;

// A terrain strip in the x-z plane (y up): x in [-2, 2], z in [-16, 0],
// 0.25 m squares. The partition cuts the longest axis, so the 4 regions are
// strips across z: region 0 farthest from a viewer at z > 0 looking down -z,
// region 3 nearest.
constexpr int kNx = 17;
constexpr int kNz = 65;
constexpr float kSpacing = 0.25f;
constexpr float kX0 = -2.0f;
constexpr float kZ0 = -16.0f;

float height(float x, float z) {
  return 0.3f * std::sin(1.3f * x) * std::cos(0.7f * z) + 0.1f * std::sin(3.1f * x + 1.7f * z);
}

IndexedMesh terrain() {
  IndexedMesh mesh;
  for (int j = 0; j < kNz; ++j) {
    for (int i = 0; i < kNx; ++i) {
      const float x = kX0 + float(i) * kSpacing, z = kZ0 + float(j) * kSpacing;
      mesh.positions.emplace_back(x, height(x, z), z);
    }
  }
  for (int j = 0; j + 1 < kNz; ++j) {
    for (int i = 0; i + 1 < kNx; ++i) {
      const std::uint32_t a = std::uint32_t(j * kNx + i), b = a + 1, c = a + kNx, d = c + 1;
      // Counter-clockwise seen from above (+y).
      mesh.indices.insert(mesh.indices.end(), {a, c, d, a, d, b});
    }
  }
  return mesh;
}

std::string scratchDir() {
  static const std::string dir = [] {
    const std::filesystem::path path = std::filesystem::path(THINLOD_BINARY_DIR) / "test-tmp" /
                                       ("regions-live-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    return path.string();
  }();
  return dir;
}

std::string writeScene() {
  const std::string dir = scratchDir();
  EXPECT_TRUE(saveMeshFile(terrain(), dir + "/strip.ply", true).ok());
  const std::string path = dir + "/strip-regions.wrl";
  std::ofstream(path) << "#VRML V2.0 utf8\n"
                         "DirectionalLight { direction 0.3 -1 -0.5 }\n"
                         "Shape { appearance Appearance { material Material { diffuseColor 0.5 "
                         "0.7 0.4 } }\n"
                         "        geometry Inline { url \"strip.ply\" regions 4 } }\n";
  return path;
}

// Low over the near end, looking down -z along the strip.
protocol::ViewerPose pose(std::uint64_t sequence) {
  protocol::ViewerPose p;
  p.sequence = sequence;
  p.timestampNs = static_cast<std::int64_t>(sequence) * 100'000'000;
  p.position = glm::vec3(0.0f, 1.2f, 1.0f - 0.02f * float(sequence));
  p.orientation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  p.fovY = 0.9f;
  return p;
}

// What an assembled terrain does wrong (all zero: crack-free, manifold,
// covering the strip exactly once).
struct CrackCheck {
  std::size_t triangles = 0;
  std::size_t unknownVertices = 0;     // not at a grid vertex
  std::size_t degenerate = 0;          // a grid vertex twice
  std::size_t duplicateDirected = 0;   // a directed edge on two triangles
  std::size_t edgesOnMoreThanTwo = 0;  // non-manifold
  std::size_t openEdgesInside = 0;     // an edge on one triangle off the outer border: a crack
  // A grid vertex decoded to different floats by two parts (their Draco
  // grids differ): a sliver between regions however small.
  std::size_t splitVertices = 0;
  std::size_t turnedOver = 0;  // a triangle facing down (negative area seen in x-z)
  double areaError = 0.0;      // |projected area - strip area| / strip area
  std::size_t violations() const {
    return unknownVertices + degenerate + duplicateDirected + edgesOnMoreThanTwo + openEdgesInside +
           splitVertices + turnedOver + (areaError > 1e-4 ? 1 : 0);
  }
};

CrackCheck checkCracks(const std::vector<IndexedMesh>& parts) {
  CrackCheck out;
  std::map<std::pair<int, int>, int> directed;
  std::map<int, glm::vec3> decodedAt;  // grid vertex -> the floats the first part decoded
  std::set<int> split;
  double area = 0.0;
  for (const IndexedMesh& mesh : parts) {
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
      ++out.triangles;
      int id[3];
      glm::vec2 p[3];
      bool known = true;
      for (int k = 0; k < 3; ++k) {
        const glm::vec3& v = mesh.positions[mesh.indices[3 * t + k]];
        // Every level vertex is an input vertex (vertex substitution); Draco
        // moves it by far less than a quarter square.
        const int i = int(std::lround((v.x - kX0) / kSpacing));
        const int j = int(std::lround((v.z - kZ0) / kSpacing));
        const glm::vec2 grid(kX0 + float(i) * kSpacing, kZ0 + float(j) * kSpacing);
        if (i < 0 || i >= kNx || j < 0 || j >= kNz ||
            glm::length(glm::vec2(v.x, v.z) - grid) > 0.25f * kSpacing) {
          known = false;
        }
        id[k] = j * kNx + i;
        p[k] = grid;
        const auto [at, fresh] = decodedAt.emplace(id[k], v);
        if (!fresh && at->second != v) split.insert(id[k]);
      }
      if (!known) {
        ++out.unknownVertices;
        continue;
      }
      if (id[0] == id[1] || id[1] == id[2] || id[0] == id[2]) {
        ++out.degenerate;
        continue;
      }
      // Signed area in (x, -z): counter-clockwise from above is positive.
      const double signedArea =
          0.5 * ((p[1].x - p[0].x) * -(p[2].y - p[0].y) - (p[2].x - p[0].x) * -(p[1].y - p[0].y));
      // Zero: a vertical sliver on the rim (three kept rim vertices on one
      // side of the strip), not a fold.
      if (signedArea < -1e-9) ++out.turnedOver;
      area += signedArea;
      for (int k = 0; k < 3; ++k) ++directed[{id[k], id[(k + 1) % 3]}];
    }
  }
  auto onBorder = [](int a, int b) {
    const int ia = a % kNx, ja = a / kNx, ib = b % kNx, jb = b / kNx;
    return (ia == 0 && ib == 0) || (ia == kNx - 1 && ib == kNx - 1) || (ja == 0 && jb == 0) ||
           (ja == kNz - 1 && jb == kNz - 1);
  };
  for (const auto& [edge, count] : directed) {
    if (count > 1) ++out.duplicateDirected;
    const int uses =
        count +
        (directed.count({edge.second, edge.first}) ? directed.at({edge.second, edge.first}) : 0);
    if (uses > 2) ++out.edgesOnMoreThanTwo;
    if (uses == 1 && !onBorder(edge.first, edge.second)) ++out.openEdgesInside;
  }
  out.splitVertices = split.size();
  const double strip = double(kNx - 1) * double(kNz - 1) * double(kSpacing) * kSpacing;
  out.areaError = std::abs(area - strip) / strip;
  return out;
}

struct Run {
  std::size_t leaves = 0;
  std::size_t regionRequests = 0;             // SimplifyRequests for region objects
  std::size_t regionRequestsKeeping = 0;      // ... with keepBoundary
  std::map<std::uint64_t, IndexedMesh> held;  // object id -> decoded level at the frontend
  std::vector<double> curveTop;               // per leaf: its curve's resources at full accuracy
  std::vector<double> fullTriangles;          // per leaf: its region's triangles
  double maxFrontendTriangles = 0.0;
};

Status serve(BackboneCore& core, simplifier::SimplifierService& service, Run& run) {
  for (const OutgoingRequest& r : core.takeRequests()) {
    core.requestSubmitted(r.requestId);
    const auto* request = std::get_if<protocol::SimplifyRequest>(&r.message);
    if (request == nullptr) return Status(ErrorCode::kInternal, "impostor request, impostors off");
    ++run.regionRequests;
    run.regionRequestsKeeping += request->keepBoundary ? 1 : 0;
    const protocol::SimplifyResult result = service.simplify(*request);
    if (!result.status.ok()) return result.status;
    THINLOD_RETURN_IF_ERROR(core.onSimplifyResult(result));
  }
  return Status();
}

Run runStrip(const std::string& scheduler, double budget) {
  Run run;
  const std::string path = writeScene();
  Result<scene::Scene> loaded = scene::loadSceneFile(path, {});
  EXPECT_TRUE(loaded.ok()) << loaded.status().toString();
  if (!loaded.ok()) return run;
  CoreOptions options;
  options.config.maxSpeed = 0.1;
  options.budget.maxTriangles = budget;
  options.simpleImpostorRadii = 0.0;
  options.meshedImpostorRadii = 0.0;
  options.scheduler = scheduler;
  Result<std::unique_ptr<BackboneCore>> created =
      BackboneCore::create(std::move(loaded).value(), path, options);
  EXPECT_TRUE(created.ok()) << created.status().toString();
  if (!created.ok()) return run;
  BackboneCore& core = **created;
  run.leaves = core.objects().size();
  for (const auto& record : core.objects()) {
    EXPECT_EQ(record.object->regionCount, 4u) << "object " << record.id;
    run.fullTriangles.push_back(record.fullTriangles);
  }

  simplifier::ServiceOptions serviceOptions;
  serviceOptions.sceneRoot = scratchDir();
  serviceOptions.curve.error.samplesPerMesh = 4000;  // test speed
  simplifier::SimplifierService service(serviceOptions);
  Status status = serve(core, service, run);  // startup curves
  EXPECT_TRUE(status.ok()) << status.toString();
  EXPECT_EQ(core.curvesPending(), 0u);
  EXPECT_TRUE(core.objectsWithoutMeasuredCurve().empty());
  const backbone::SchedulingScene& scheduling = core.schedulingScene();
  for (const backbone::SceneObject& object : scheduling.objects) {
    double top = 0.0;
    for (std::uint32_t o = object.firstOption; o < object.firstOption + object.optionCount; ++o) {
      const AccuracyCurve& curve = scheduling.options[o].relativeTriangles;
      if (!curve.segments().empty()) top = std::max(top, curve.resourcesFor(curve.maxAccuracy()));
    }
    run.curveTop.push_back(top);
  }

  for (std::uint64_t step = 0; step < 5; ++step) {
    EXPECT_TRUE(core.beginPose(pose(step)).ok());
    status = serve(core, service, run);
    EXPECT_TRUE(status.ok()) << status.toString();
    const PoseOutcome outcome = core.finishPose();
    EXPECT_TRUE(outcome.planned) << outcome.planError.toString();
    for (const auto& op : outcome.update.operations) {
      if (op.type == protocol::SceneOperation::Type::kAddOrReplace) {
        EXPECT_EQ(op.representation.kind, protocol::RepresentationKind::kMesh);
        Result<IndexedMesh> mesh =
            codec::decodeMesh(op.representation.mesh.data(), op.representation.mesh.size());
        EXPECT_TRUE(mesh.ok()) << mesh.status().toString();
        if (mesh.ok()) run.held[op.objectId] = std::move(mesh).value();
      } else if (op.type == protocol::SceneOperation::Type::kRemove) {
        run.held.erase(op.objectId);
      }
    }
    run.maxFrontendTriangles = std::max(run.maxFrontendTriangles, outcome.frontendTriangles);
  }
  return run;
}

void expectRegionsLive(const std::string& scheduler) {
  constexpr double kBudget = 1200.0;  // of 2,048 triangles in all
  const Run run = runStrip(scheduler, kBudget);
  EXPECT_EQ(run.leaves, 4u);
  // Every request was a mesh request for a region object, with the flag.
  EXPECT_GT(run.regionRequests, 4u);
  EXPECT_EQ(run.regionRequestsKeeping, run.regionRequests);
  // Own curves: each measured on its own region (about 512 triangles each at
  // full resolution: the partition balances vertices, not triangles).
  ASSERT_EQ(run.curveTop.size(), 4u);
  double full = 0.0;
  for (std::size_t k = 0; k < run.curveTop.size(); ++k) {
    EXPECT_GT(run.curveTop[k], 0.0);
    EXPECT_LE(run.curveTop[k], run.fullTriangles[k] + 1e-9);
    full += run.fullTriangles[k];
  }
  EXPECT_EQ(full, 2048.0) << "the regions' triangles are the terrain's";
  // All four held (a region the plan drops would open a hole at the frontend).
  ASSERT_EQ(run.held.size(), 4u) << scheduler;
  std::vector<std::size_t> triangles;
  std::vector<IndexedMesh> parts;
  for (const auto& [id, mesh] : run.held) {
    triangles.push_back(mesh.triangleCount());
    parts.push_back(mesh);
  }
  // Ids 1..4 are regions 0..3, far to near.
  EXPECT_GT(triangles[3], triangles[0]) << scheduler << ": nearest vs farthest";
  EXPECT_GT(triangles[2] + triangles[3], triangles[0] + triangles[1])
      << scheduler << ": near half vs far half";
  EXPECT_LE(run.maxFrontendTriangles, kBudget + 1e-6);
  const CrackCheck check = checkCracks(parts);
  EXPECT_EQ(check.violations(), 0u)
      << scheduler << ": unknown " << check.unknownVertices << " degenerate " << check.degenerate
      << " duplicate directed " << check.duplicateDirected << " non-manifold "
      << check.edgesOnMoreThanTwo << " open inside " << check.openEdgesInside << " split "
      << check.splitVertices << " turned over " << check.turnedOver << " area error "
      << check.areaError;
  EXPECT_LT(check.triangles, 2048u) << "the levels are simplified";
  std::ostringstream line;
  for (std::size_t t : triangles) line << t << " ";
  ::testing::Test::RecordProperty("triangles_far_to_near_" + scheduler, line.str());
  std::printf("%s: triangles far to near %s(total %zu)\n", scheduler.c_str(), line.str().c_str(),
              check.triangles);
}

// The crack check has teeth: the regions' coarsest levels from the same
// service crack without the flag and do not with it.
TEST(RegionsLive, CoarsestLevelsCrackOnlyWithoutKeepBoundary) {
  const std::string path = writeScene();
  simplifier::ServiceOptions serviceOptions;
  serviceOptions.sceneRoot = scratchDir();
  serviceOptions.curve.error.samplesPerMesh = 4000;
  simplifier::SimplifierService service(serviceOptions);
  for (bool keep : {false, true}) {
    std::vector<IndexedMesh> parts;
    for (std::uint64_t id = 1; id <= 4; ++id) {
      protocol::SimplifyRequest request;
      request.requestId = id;
      request.objectId = id;
      request.sourcePath = path;
      request.targetTriangles = 1;
      request.keepBoundary = keep;
      const protocol::SimplifyResult result = service.simplify(request);
      ASSERT_TRUE(result.status.ok()) << result.status.toString();
      Result<IndexedMesh> mesh = codec::decodeMesh(result.mesh.data(), result.mesh.size());
      ASSERT_TRUE(mesh.ok());
      parts.push_back(std::move(mesh).value());
    }
    const CrackCheck check = checkCracks(parts);
    if (keep) {
      EXPECT_EQ(check.violations(), 0u) << "open inside " << check.openEdgesInside;
    } else {
      EXPECT_GT(check.openEdgesInside, 0u) << "free borders should open cracks";
    }
  }
}

TEST(RegionsLive, AccuracyCurveSchedulerNearRegionsGetMoreTrianglesWithoutCracks) {
  expectRegionsLive("accuracy-curve");
}

TEST(RegionsLive, GreedySchedulerNearRegionsGetMoreTrianglesWithoutCracks) {
  expectRegionsLive("greedy-fs93");
}

TEST(RegionsLive, AslodSchedulerNearRegionsGetMoreTrianglesWithoutCracks) {
  expectRegionsLive("aslod");
}

}  // namespace
}  // namespace thinlod
