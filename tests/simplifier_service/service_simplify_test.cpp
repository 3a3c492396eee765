// SimplifierService: SimplifyRequests on the paper room (no GL).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "service_test_util.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier {
namespace {

using namespace testing_util;

IndexedMesh decode(const protocol::Bytes& bytes) {
  Result<IndexedMesh> mesh = codec::decodeMesh(bytes.data(), bytes.size());
  EXPECT_TRUE(mesh.ok()) << mesh.status().toString();
  return mesh.ok() ? std::move(mesh).value() : IndexedMesh();
}

void expectMonotone(const std::vector<AccuracySample>& curve) {
  for (std::size_t i = 1; i < curve.size(); ++i) {
    EXPECT_GT(curve[i].accuracy, curve[i - 1].accuracy) << "sample " << i;
    EXPECT_GT(curve[i].resources, curve[i - 1].resources) << "sample " << i;
  }
}

TEST(SimplifierServiceMesh, CowComesBackWithTheRequestedTriangleCount) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult result = service.simplify(triangles(kCow, 500));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.requestId, 100 + kCow);
  EXPECT_EQ(result.objectId, kCow);
  // A collapse removes one or two triangles: the order passes through 500 or 499.
  EXPECT_LE(result.triangleCount, 500u);
  EXPECT_GE(result.triangleCount, 499u);
  const IndexedMesh mesh = decode(result.mesh);
  EXPECT_EQ(mesh.triangleCount(), result.triangleCount);
  // Content frame: the cow.obj extent (x from -4.45 to 6.0), not world.
  EXPECT_GT(mesh.bounds().diagonal(), 10.0f);
  EXPECT_GT(result.accuracy, 1.0);
  EXPECT_TRUE(result.curve.empty());
}

TEST(SimplifierServiceMesh, AnotherCountReusesTheProgressiveMesh) {
  SimplifierService service(roomOptions());
  ASSERT_TRUE(service.simplify(triangles(kCow, 300)).status.ok());
  const protocol::SimplifyResult second = service.simplify(triangles(kCow, 3000));
  ASSERT_TRUE(second.status.ok()) << second.status.toString();
  EXPECT_GE(second.triangleCount, 2999u);
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 1u);
  EXPECT_EQ(service.stats().sceneLoads, 1u);
  EXPECT_EQ(service.stats().curvesMeasured + service.stats().curvesFromDisk, 1u);
}

TEST(SimplifierServiceMesh, MoreTrianglesNeverReportLessAccuracy) {
  SimplifierService service(roomOptions());
  double previous = 0.0;
  for (std::uint32_t count : {50u, 200u, 800u, 3000u, 100000u}) {
    const protocol::SimplifyResult result = service.simplify(triangles(kCow, count));
    ASSERT_TRUE(result.status.ok()) << result.status.toString();
    EXPECT_GE(result.accuracy, previous) << count;
    previous = result.accuracy;
  }
  // The full cow (5804 triangles) for an oversized request.
  EXPECT_EQ(service.simplify(triangles(kCow, 100000)).triangleCount, 5804u);
}

TEST(SimplifierServiceMesh, CurveSamplesAreMonotoneAndBounded) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult result = service.simplify(triangles(kCow, 400, 6));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  ASSERT_GE(result.curve.size(), 2u);
  EXPECT_LE(result.curve.size(), 6u);
  expectMonotone(result.curve);
  EXPECT_EQ(result.curve.back().resources, 5804.0);
}

TEST(SimplifierServiceMesh, ReportedAccuracyMatchesTheCurveAtItsSamples) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult withCurve = service.simplify(triangles(kCow, 100, 64));
  ASSERT_TRUE(withCurve.status.ok());
  for (const AccuracySample& sample : withCurve.curve) {
    const protocol::SimplifyResult level =
        service.simplify(triangles(kCow, static_cast<std::uint32_t>(sample.resources)));
    ASSERT_TRUE(level.status.ok());
    EXPECT_EQ(level.triangleCount, static_cast<std::uint32_t>(sample.resources));
    EXPECT_DOUBLE_EQ(level.accuracy, sample.accuracy);
  }
}

TEST(SimplifierServiceMesh, AccuracyTargetGivesTheCheapestLevelReachingIt) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult withCurve = service.simplify(triangles(kCow, 100, 64));
  ASSERT_TRUE(withCurve.status.ok());
  ASSERT_GE(withCurve.curve.size(), 3u);
  const AccuracySample middle = withCurve.curve[withCurve.curve.size() / 2];
  const AccuracySample below = withCurve.curve[withCurve.curve.size() / 2 - 1];
  // Just above the cheaper sample's accuracy: the middle sample is the cheapest reaching it.
  const protocol::SimplifyResult result = service.simplify(accuracy(kCow, below.accuracy * 1.0001));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_GE(result.accuracy, below.accuracy * 1.0001);
  EXPECT_EQ(result.triangleCount, static_cast<std::uint32_t>(middle.resources));
}

TEST(SimplifierServiceMesh, UnreachableAccuracyGivesTheFullMesh) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult result = service.simplify(accuracy(kCow, 1e9));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.triangleCount, 5804u);
  EXPECT_LT(result.accuracy, 1e9);
}

TEST(SimplifierServiceMesh, CurvesComeFromTheDiskCacheInALaterService) {
  ServiceOptions options = roomOptions();
  options.curveCacheDir = scratchDir() + "/curves";
  options.curve.error.samplesPerMesh = 5000;
  {
    SimplifierService first(options);
    ASSERT_TRUE(first.simplify(triangles(kCow, 500)).status.ok());
    EXPECT_EQ(first.stats().curvesMeasured, 1u);
  }
  SimplifierService second(options);
  ASSERT_TRUE(second.simplify(triangles(kCow, 500)).status.ok());
  EXPECT_EQ(second.stats().curvesFromDisk, 1u);
  EXPECT_EQ(second.stats().curvesMeasured, 0u);
}

TEST(SimplifierServiceMesh, WorksWithoutACurveCacheDirectory) {
  ServiceOptions options = roomOptions();
  options.curveCacheDir.clear();
  options.curve.error.samplesPerMesh = 5000;  // only speed matters here
  SimplifierService service(options);
  const protocol::SimplifyResult result = service.simplify(triangles(kCow, 1000));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(service.stats().curvesMeasured, 1u);
}

TEST(SimplifierServiceMesh, SourceMeshRequestsAreSimplifiedToo) {
  Result<LoadedMesh> cow = loadMeshFile(modelsDir() + "/cow.obj");
  ASSERT_TRUE(cow.ok()) << cow.status().toString();
  Result<std::vector<std::uint8_t>> bytes = codec::encodeMesh(cow->mesh);
  ASSERT_TRUE(bytes.ok());
  ServiceOptions options = roomOptions();
  options.curve.error.samplesPerMesh = 5000;  // a new mesh (Draco moved it): keep it quick
  SimplifierService service(options);
  protocol::SimplifyRequest request = triangles(77, 250, 4);
  request.sourcePath.clear();
  request.sourceMesh = *bytes;
  const protocol::SimplifyResult result = service.simplify(request);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.objectId, 77u);
  EXPECT_LE(result.triangleCount, 250u);
  EXPECT_EQ(decode(result.mesh).triangleCount(), result.triangleCount);
  expectMonotone(result.curve);
  ASSERT_TRUE(service.simplify(request).status.ok());
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 1u);
}

// --- Primitives ---

TEST(SimplifierServicePrimitive, SphereUsesTheAnalyticTessellation) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult result = service.simplify(triangles(kSphereLeft, 200, 8));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_LE(result.triangleCount, 200u);
  const IndexedMesh mesh = decode(result.mesh);
  EXPECT_EQ(mesh.triangleCount(), result.triangleCount);
  // Sphere radius 0.3 in its content frame.
  EXPECT_NEAR(mesh.bounds().max.y, 0.3f, 0.01f);
  const PrimitiveShape sphere = PrimitiveShape::sphere(0.3f);
  const double analytic = tessellationAccuracy(sphere, chooseTessellation(sphere, 200));
  // Quantization costs at most the budgeted 10 %.
  EXPECT_LE(result.accuracy, analytic);
  EXPECT_GE(result.accuracy, analytic / 1.1 * 0.999);
  EXPECT_GE(result.curve.size(), 2u);
  EXPECT_LE(result.curve.size(), 8u);
  expectMonotone(result.curve);
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 0u);
}

TEST(SimplifierServicePrimitive, CylinderReachesAnAccuracyTarget) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult result = service.simplify(accuracy(kColumn, 300.0));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_GE(result.accuracy, 300.0);
  const protocol::SimplifyResult coarser = service.simplify(accuracy(kColumn, 30.0));
  ASSERT_TRUE(coarser.status.ok());
  EXPECT_LT(coarser.triangleCount, result.triangleCount);
}

// --- Errors: every one answers a result with a status; the service keeps working ---

TEST(SimplifierServiceErrors, PathOutsideTheRootIsRejected) {
  SimplifierService service(roomOptions());
  protocol::SimplifyRequest request = triangles(kCow, 100);
  request.sourcePath = "/etc/passwd";
  protocol::SimplifyResult result = service.simplify(request);
  EXPECT_EQ(result.status.code(), ErrorCode::kInvalidArgument);
  EXPECT_TRUE(result.mesh.empty());
  request.sourcePath = sceneRoot() + "/../../CMakeLists.txt";
  EXPECT_EQ(service.simplify(request).status.code(), ErrorCode::kInvalidArgument);
  EXPECT_TRUE(service.simplify(triangles(kCow, 100)).status.ok());
  EXPECT_EQ(service.stats().failedRequests, 2u);
}

TEST(SimplifierServiceErrors, SymlinkLeadingOutOfTheRootIsRejected) {
  const std::filesystem::path root = std::filesystem::path(scratchDir()) / "root";
  std::filesystem::create_directories(root);
  std::filesystem::remove(root / "room.wrl");
  std::filesystem::create_symlink(roomScene(), root / "room.wrl");
  ServiceOptions options = roomOptions();
  options.sceneRoot = root.string();
  SimplifierService service(options);
  protocol::SimplifyRequest request = triangles(kCow, 100);
  request.sourcePath = (root / "room.wrl").string();
  EXPECT_EQ(service.simplify(request).status.code(), ErrorCode::kInvalidArgument);
}

TEST(SimplifierServiceErrors, MissingSceneIsNotFound) {
  SimplifierService service(roomOptions());
  protocol::SimplifyRequest request = triangles(kCow, 100);
  request.sourcePath = sceneRoot() + "/no-such-room.wrl";
  EXPECT_EQ(service.simplify(request).status.code(), ErrorCode::kNotFound);
}

TEST(SimplifierServiceErrors, NoRootConfiguredRejectsEveryPath) {
  ServiceOptions options = roomOptions();
  options.sceneRoot.clear();
  SimplifierService service(options);
  EXPECT_EQ(service.simplify(triangles(kCow, 100)).status.code(), ErrorCode::kInvalidArgument);
}

TEST(SimplifierServiceErrors, UnknownObjectIsNotFound) {
  SimplifierService service(roomOptions());
  EXPECT_EQ(service.simplify(triangles(5, 100)).status.code(), ErrorCode::kNotFound);
  EXPECT_EQ(service.simplify(triangles(0, 100)).status.code(), ErrorCode::kNotFound);
  EXPECT_EQ(service.simplify(triangles(~0ull, 100)).status.code(), ErrorCode::kNotFound);
}

TEST(SimplifierServiceErrors, AbsurdTargetsAreRejected) {
  SimplifierService service(roomOptions());
  EXPECT_FALSE(service.simplify(triangles(kCow, 0)).status.ok());
  EXPECT_FALSE(service.simplify(triangles(kCow, 0xffffffffu)).status.ok());
  EXPECT_FALSE(service.simplify(accuracy(kCow, 0.0)).status.ok());
  EXPECT_FALSE(service.simplify(accuracy(kCow, -3.0)).status.ok());
  EXPECT_FALSE(service.simplify(accuracy(kCow, std::nan(""))).status.ok());
  EXPECT_FALSE(
      service.simplify(accuracy(kCow, std::numeric_limits<double>::infinity())).status.ok());
  protocol::SimplifyRequest tooManyPoints = triangles(kCow, 100, 5000);
  EXPECT_FALSE(service.simplify(tooManyPoints).status.ok());
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 0u);
}

TEST(SimplifierServiceErrors, SourceMustBeExactlyOneOfPathAndMesh) {
  SimplifierService service(roomOptions());
  protocol::SimplifyRequest both = triangles(kCow, 100);
  both.sourceMesh = {1, 2, 3};
  EXPECT_EQ(service.simplify(both).status.code(), ErrorCode::kInvalidArgument);
  protocol::SimplifyRequest neither = triangles(kCow, 100);
  neither.sourcePath.clear();
  EXPECT_EQ(service.simplify(neither).status.code(), ErrorCode::kInvalidArgument);
}

TEST(SimplifierServiceErrors, GarbageSourceMeshIsRejected) {
  SimplifierService service(roomOptions());
  protocol::SimplifyRequest request = triangles(kCow, 100);
  request.sourcePath.clear();
  request.sourceMesh.assign(200, 0xab);
  const protocol::SimplifyResult result = service.simplify(request);
  EXPECT_FALSE(result.status.ok());
  EXPECT_TRUE(result.mesh.empty());
  EXPECT_TRUE(result.curve.empty());
}

TEST(SimplifierServiceErrors, UnparsableSceneIsReportedWithItsLocation) {
  const std::filesystem::path root = std::filesystem::path(scratchDir()) / "bad-root";
  std::filesystem::create_directories(root);
  std::ofstream(root / "broken.wrl") << "#VRML V2.0 utf8\nTransform { children [ Shape {\n";
  ServiceOptions options = roomOptions();
  options.sceneRoot = root.string();
  SimplifierService service(options);
  protocol::SimplifyRequest request = triangles(1, 100);
  request.sourcePath = (root / "broken.wrl").string();
  const protocol::SimplifyResult result = service.simplify(request);
  EXPECT_EQ(result.status.code(), ErrorCode::kParseError) << result.status.toString();
}

}  // namespace
}  // namespace thinlod::simplifier
