// SimplifierService: hybrid (triangles + disc points) SimplifyRequests on the
// paper room's cow (no GL), and the measured ladders kept in the curve cache
// directory across services (processes).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "service_test_util.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/protocol/codec.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier {
namespace {

using namespace testing_util;

protocol::SimplifyRequest hybridAccuracy(std::uint64_t object, double accuracy, double kappa,
                                         std::uint16_t curvePoints) {
  protocol::SimplifyRequest request = triangles(object, 1, curvePoints);
  request.target = protocol::SimplifyRequest::Target::kAccuracy;
  request.targetAccuracy = accuracy;
  request.representation = protocol::RepresentationKind::kHybrid;
  request.kappa = kappa;
  return request;
}

HybridGeometry decodeGeometry(const protocol::Bytes& bytes) {
  Result<HybridGeometry> g = codec::decodeHybrid(bytes.data(), bytes.size());
  EXPECT_TRUE(g.ok()) << g.status().toString();
  return g.ok() ? std::move(g).value() : HybridGeometry();
}

TEST(SimplifierServiceHybrid, CowCutReachesTheAccuracyAndCarriesPoints) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult result = service.simplify(hybridAccuracy(kCow, 20.0, 10.0, 16));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.kind, protocol::RepresentationKind::kHybrid);
  EXPECT_EQ(result.kappa, 10.0);
  EXPECT_GE(result.accuracy, 20.0);
  const HybridGeometry g = decodeGeometry(result.mesh);
  EXPECT_EQ(g.triangles.triangleCount(), result.triangleCount);
  EXPECT_EQ(g.points.size(), result.pointCount);
  EXPECT_GT(result.pointCount, 0u) << "a coarse cow cut at kappa 10 keeps points";
  EXPECT_TRUE(protocol::validate(protocol::Message(result)).ok());
  // Curve: strictly increasing, resources in primitive units, and the
  // delivered cut lies on or above it (its units buy at least the curve's
  // accuracy at those units).
  ASSERT_GE(result.curve.size(), 2u);
  for (std::size_t i = 1; i < result.curve.size(); ++i) {
    EXPECT_GT(result.curve[i].accuracy, result.curve[i - 1].accuracy);
    EXPECT_GT(result.curve[i].resources, result.curve[i - 1].resources);
  }
  const double units = result.triangleCount + result.pointCount / result.kappa;
  EXPECT_LE(result.curve.front().resources, units + 1e-9);
}

TEST(SimplifierServiceHybrid, FinerAccuracyCostsMoreUnitsAndTheGraphIsReused) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult coarse = service.simplify(hybridAccuracy(kCow, 10.0, 3.0, 0));
  const protocol::SimplifyResult fine = service.simplify(hybridAccuracy(kCow, 200.0, 3.0, 0));
  ASSERT_TRUE(coarse.status.ok()) << coarse.status.toString();
  ASSERT_TRUE(fine.status.ok()) << fine.status.toString();
  EXPECT_GE(fine.accuracy, 200.0);
  EXPECT_LT(coarse.triangleCount + coarse.pointCount / 3.0,
            fine.triangleCount + fine.pointCount / 3.0);
  EXPECT_EQ(service.stats().hybridGraphBuilds, 1u);
  // Another kappa is another graph.
  ASSERT_TRUE(service.simplify(hybridAccuracy(kCow, 10.0, 8.0, 0)).status.ok());
  EXPECT_EQ(service.stats().hybridGraphBuilds, 2u);
}

TEST(SimplifierServiceHybrid, UnitTargetIsNotExceeded) {
  SimplifierService service(roomOptions());
  protocol::SimplifyRequest request = triangles(kCow, 400);
  request.representation = protocol::RepresentationKind::kHybrid;
  const protocol::SimplifyResult result = service.simplify(request);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.kappa, service.options().hybridKappa);
  EXPECT_LE(result.triangleCount + result.pointCount / result.kappa, 400.0 + 1e-9);
}

TEST(SimplifierServiceHybrid, PrimitivesAndBadKappaAreRefused) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult sphere =
      service.simplify(hybridAccuracy(kSphereLeft, 10.0, 3.0, 0));
  EXPECT_EQ(sphere.status.code(), ErrorCode::kUnsupported);
  const protocol::SimplifyResult badKappa = service.simplify(hybridAccuracy(kCow, 10.0, 0.5, 0));
  EXPECT_EQ(badKappa.status.code(), ErrorCode::kInvalidArgument);
  protocol::SimplifyRequest impostorKind = triangles(kCow, 100);
  impostorKind.representation = protocol::RepresentationKind::kSimpleImpostor;
  EXPECT_EQ(service.simplify(impostorKind).status.code(), ErrorCode::kInvalidArgument);
}

// A fresh curve cache directory of its own; progress lines go to `log`.
ServiceOptions freshCacheOptions(const std::string& name, std::vector<std::string>* log) {
  ServiceOptions options = roomOptions();
  options.curveCacheDir = scratchDir() + "/hybrid-" + name;
  std::filesystem::remove_all(options.curveCacheDir);
  if (log != nullptr) options.progress = [log](const std::string& line) { log->push_back(line); };
  return options;
}

std::vector<std::filesystem::path> ladderFiles(const std::string& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().filename().string().rfind("hybrid-", 0) == 0) files.push_back(entry.path());
  }
  return files;
}

bool logged(const std::vector<std::string>& log, const std::string& a, const std::string& b) {
  for (const std::string& line : log) {
    if (line.find(a) != std::string::npos && line.find(b) != std::string::npos) return true;
  }
  return false;
}

void expectSameAnswer(const protocol::SimplifyResult& a, const protocol::SimplifyResult& b) {
  EXPECT_EQ(a.accuracy, b.accuracy);
  EXPECT_EQ(a.triangleCount, b.triangleCount);
  EXPECT_EQ(a.pointCount, b.pointCount);
  EXPECT_EQ(a.mesh, b.mesh);
  ASSERT_EQ(a.curve.size(), b.curve.size());
  for (std::size_t i = 0; i < a.curve.size(); ++i) {
    EXPECT_EQ(a.curve[i].accuracy, b.curve[i].accuracy);
    EXPECT_EQ(a.curve[i].resources, b.curve[i].resources);
  }
}

TEST(SimplifierServiceHybrid, SecondServiceReadsTheLadderInsteadOfMeasuring) {
  const ServiceOptions options = freshCacheOptions("second", nullptr);
  protocol::SimplifyResult measured;
  {
    SimplifierService first(options);
    measured = first.simplify(hybridAccuracy(kCow, 20.0, 3.0, 16));
    ASSERT_TRUE(measured.status.ok()) << measured.status.toString();
    EXPECT_EQ(first.stats().hybridCurvesMeasured, 1u);
    EXPECT_EQ(first.stats().hybridCurvesFromDisk, 0u);
  }
  ASSERT_EQ(ladderFiles(options.curveCacheDir).size(), 1u);
  std::vector<std::string> log;
  ServiceOptions withLog = options;
  withLog.progress = [&log](const std::string& line) { log.push_back(line); };
  SimplifierService second(withLog);
  const protocol::SimplifyResult read = second.simplify(hybridAccuracy(kCow, 20.0, 3.0, 16));
  ASSERT_TRUE(read.status.ok()) << read.status.toString();
  EXPECT_EQ(second.stats().hybridCurvesMeasured, 0u) << "the ladder was measured again";
  EXPECT_EQ(second.stats().hybridCurvesFromDisk, 1u);
  EXPECT_EQ(second.stats().hybridGraphBuilds, 1u) << "the graph itself is rebuilt";
  EXPECT_TRUE(logged(log, "event=hybrid_curve_from_disk", "kappa=3"));
  expectSameAnswer(measured, read);
}

TEST(SimplifierServiceHybrid, DamagedLadderFileIsMeasuredAgainWithTheReasonLogged) {
  const ServiceOptions options = freshCacheOptions("damaged", nullptr);
  protocol::SimplifyResult measured;
  {
    SimplifierService first(options);
    measured = first.simplify(hybridAccuracy(kCow, 20.0, 3.0, 16));
    ASSERT_TRUE(measured.status.ok()) << measured.status.toString();
  }
  const std::vector<std::filesystem::path> files = ladderFiles(options.curveCacheDir);
  ASSERT_EQ(files.size(), 1u);
  std::filesystem::resize_file(files[0], std::filesystem::file_size(files[0]) / 2);

  std::vector<std::string> log;
  ServiceOptions withLog = options;
  withLog.progress = [&log](const std::string& line) { log.push_back(line); };
  {
    SimplifierService second(withLog);
    const protocol::SimplifyResult again = second.simplify(hybridAccuracy(kCow, 20.0, 3.0, 16));
    ASSERT_TRUE(again.status.ok()) << again.status.toString();
    EXPECT_EQ(second.stats().hybridCurvesMeasured, 1u);
    EXPECT_EQ(second.stats().hybridCurvesFromDisk, 0u);
    EXPECT_TRUE(logged(log, "event=hybrid_curve_cache_rejected", files[0].string()))
        << "no rejection line naming the file";
    expectSameAnswer(measured, again);
  }
  // Measured again and written back: a third service reads it.
  SimplifierService third(options);
  ASSERT_TRUE(third.simplify(hybridAccuracy(kCow, 20.0, 3.0, 16)).status.ok());
  EXPECT_EQ(third.stats().hybridCurvesFromDisk, 1u);
  EXPECT_EQ(third.stats().hybridCurvesMeasured, 0u);
}

TEST(SimplifierServiceHybrid, AnotherKappaIsAnotherLadderFile) {
  const ServiceOptions options = freshCacheOptions("kappa", nullptr);
  {
    SimplifierService first(options);
    ASSERT_TRUE(first.simplify(hybridAccuracy(kCow, 20.0, 3.0, 16)).status.ok());
    ASSERT_TRUE(first.simplify(hybridAccuracy(kCow, 20.0, 8.0, 16)).status.ok());
    EXPECT_EQ(first.stats().hybridCurvesMeasured, 2u);
  }
  EXPECT_EQ(ladderFiles(options.curveCacheDir).size(), 2u);
  SimplifierService second(options);
  const protocol::SimplifyResult eight = second.simplify(hybridAccuracy(kCow, 20.0, 8.0, 16));
  ASSERT_TRUE(eight.status.ok());
  EXPECT_EQ(eight.kappa, 8.0);
  EXPECT_EQ(second.stats().hybridCurvesFromDisk, 1u);
  EXPECT_EQ(second.stats().hybridCurvesMeasured, 0u);
}

}  // namespace
}  // namespace thinlod::simplifier
