#include "thinlod/simplifier/mesh_curve.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "test_meshes.h"
#include "thinlod/common/core/relative_accuracy.h"

namespace thinlod::simplifier {
namespace {

using thinlod::testing::makeIcosphere;
using thinlod::testing::maxSagitta;

constexpr float kRadius = 1.0f;
constexpr int kFinestLevel = 4;  // 5120 triangles

MeshCurveOptions quickOptions() {
  MeshCurveOptions options;
  options.error.samplesPerMesh = 4000;
  options.levels = 8;
  options.maxSegments = 3;
  return options;
}

// The icosphere family as a "progressive mesh": the finest sphere level whose
// triangle count fits. Counts extractions so cache hits can be checked.
struct IcosphereLadder {
  int* calls;
  IndexedMesh operator()(std::size_t target) const {
    ++*calls;
    int level = 0;
    while (level < kFinestLevel && 20u * (1u << (2 * (level + 1))) <= target) ++level;
    return makeIcosphere(level, kRadius);
  }
};

// min{ r_k : a_k >= a } over the measured levels (infinity if none).
double staircase(const std::vector<CurveLevel>& levels, double a, bool bytes) {
  double best = INFINITY;
  for (const CurveLevel& l : levels) {
    const double la = bytes ? l.encodedAccuracy : l.accuracy;
    const double lr =
        bytes ? static_cast<double>(l.encodedBytes) : static_cast<double>(l.triangles);
    if (la >= a) best = std::min(best, lr);
  }
  return best;
}

void expectMonotoneAndConservative(const AccuracyCurve& curve,
                                   const std::vector<CurveLevel>& levels, bool bytes) {
  ASSERT_FALSE(curve.empty());
  const double lo = curve.minAccuracy(), hi = curve.maxAccuracy();
  double previous = -1.0;
  for (int i = 0; i <= 400; ++i) {
    const double a = lo + (hi - lo) * i / 400.0;
    const double r = curve.resourcesFor(a);
    EXPECT_GE(r, previous) << "not monotone at a=" << a;
    previous = r;
    // Conservative: never fewer resources than the cheapest measured level
    // that reaches at least this accuracy.
    EXPECT_GE(r, staircase(levels, a, bytes) * (1 - 1e-12)) << "a=" << a;
  }
  for (const CurveLevel& l : levels) {
    const double a = bytes ? l.encodedAccuracy : l.accuracy;
    EXPECT_GE(curve.resourcesFor(a), staircase(levels, a, bytes) * (1 - 1e-12));
  }
}

TEST(GeometricLadder, SpansTheRangeGeometrically) {
  const std::vector<std::size_t> ladder = geometricLadder(100, 100000, 4);
  ASSERT_EQ(ladder, (std::vector<std::size_t>{100, 1000, 10000, 100000}));
  EXPECT_EQ(geometricLadder(5, 8, 12), (std::vector<std::size_t>{5, 6, 7, 8}));
  EXPECT_TRUE(geometricLadder(0, 10, 4).empty());
  EXPECT_TRUE(geometricLadder(11, 10, 4).empty());
}

TEST(MeshCurve, IcosphereLevelsMatchTheirSagitta) {
  int calls = 0;
  const IndexedMesh original = makeIcosphere(kFinestLevel, kRadius);
  Result<MeshCurves> curves = measureMeshCurves(original, 20, original.triangleCount(),
                                                IcosphereLadder{&calls}, quickOptions());
  ASSERT_TRUE(curves.ok()) << curves.status().toString();
  ASSERT_EQ(curves->levels.size(), 5u);  // sphere levels 0..4
  const double reference = referenceLength(referenceSphere(original));
  for (std::size_t i = 0; i + 1 < curves->levels.size(); ++i) {
    const CurveLevel& l = curves->levels[i];
    const IndexedMesh sphere = makeIcosphere(static_cast<int>(i), kRadius);
    // Against the finest sphere: coarse sagitta minus the finest's own.
    const double expected =
        (maxSagitta(sphere, kRadius) - maxSagitta(original, kRadius)) / reference;
    EXPECT_EQ(l.triangles, sphere.triangleCount());
    EXPECT_NEAR(l.relativeMaxError, expected,
                0.03 * expected + maxSagitta(original, kRadius) / reference);
    EXPECT_NEAR(l.accuracy, 1.0 / l.relativeMaxError, 1e-9 * l.accuracy);
  }
  // The full mesh measures 0 (up to rounding) and is floored.
  EXPECT_LT(curves->levels.back().relativeMaxError, 1e-12);
  EXPECT_DOUBLE_EQ(curves->levels.back().accuracy, 1.0 / quickOptions().minRelativeError);
}

// A flat textured grid (uv = position / size) whose coarser "levels" are
// coarser grids of the same square with their uvs shifted by 0.01: no
// geometric error at all, every texel drawn 0.01 * size from its place.
struct ShiftedUvLadder {
  static IndexedMesh grid(int cells, float shift) {
    IndexedMesh m = thinlod::testing::makeGrid(cells, 2.0f, 0.0f);
    for (const glm::vec3& p : m.positions) {
      m.uvs.emplace_back(p.x / 2.0f + shift, p.y / 2.0f);
    }
    return m;
  }
  IndexedMesh operator()(std::size_t target) const {
    int cells = 16;
    while (cells > 1 && static_cast<std::size_t>(2 * cells * cells) > target) --cells;
    return grid(cells, cells == 16 ? 0.0f : 0.01f);
  }
};

TEST(MeshCurve, TexturedLevelsAreCreditedWithTheirTexelDisplacement) {
  const IndexedMesh original = ShiftedUvLadder::grid(16, 0.0f);
  const double reference = referenceLength(referenceSphere(original));
  MeshCurveOptions options = quickOptions();
  options.measureEncodedBytes = false;
  Result<MeshCurves> curves =
      measureMeshCurves(original, 2, original.triangleCount(), ShiftedUvLadder{}, options);
  ASSERT_TRUE(curves.ok()) << curves.status().toString();
  for (std::size_t i = 0; i + 1 < curves->levels.size(); ++i) {
    const CurveLevel& l = curves->levels[i];
    SCOPED_TRACE(l.triangles);
    EXPECT_LT(l.relativeHausdorffError, 1e-6);
    // 0.01 uv x 2 units per uv: 0.02 units, but no farther than the square
    // reaches (most samples: the shift leaves the texture on one side only).
    EXPECT_NEAR(l.relativeTextureError, 0.02 / reference, 1e-4 / reference);
    EXPECT_DOUBLE_EQ(l.relativeMaxError, l.relativeTextureError);
    EXPECT_NEAR(l.accuracy, 1.0 / l.relativeMaxError, 1e-9 * l.accuracy);
  }
  EXPECT_LT(curves->levels.back().relativeTextureError, 1e-9);  // the full mesh: rounding only
  // Switched off: the geometric error alone (0, floored).
  options.textureCredit = false;
  Result<MeshCurves> plain =
      measureMeshCurves(original, 2, original.triangleCount(), ShiftedUvLadder{}, options);
  ASSERT_TRUE(plain.ok());
  for (const CurveLevel& l : plain->levels) {
    EXPECT_EQ(l.relativeTextureError, 0.0);
    EXPECT_DOUBLE_EQ(l.accuracy, 1.0 / options.minRelativeError);
  }
}

TEST(MeshCurve, TriangleAndByteCurvesAreMonotoneAndConservative) {
  int calls = 0;
  const IndexedMesh original = makeIcosphere(kFinestLevel, kRadius);
  Result<MeshCurves> curves = measureMeshCurves(original, 20, original.triangleCount(),
                                                IcosphereLadder{&calls}, quickOptions());
  ASSERT_TRUE(curves.ok()) << curves.status().toString();
  expectMonotoneAndConservative(curves->triangles, curves->levels, false);
  expectMonotoneAndConservative(curves->bytes, curves->levels, true);
  EXPECT_LE(curves->triangles.segments().size(), 3u);
}

TEST(MeshCurve, CoarserLevelsGetFewerPositionBitsAndBytes) {
  int calls = 0;
  const IndexedMesh original = makeIcosphere(kFinestLevel, kRadius);
  Result<MeshCurves> curves = measureMeshCurves(original, 20, original.triangleCount(),
                                                IcosphereLadder{&calls}, quickOptions());
  ASSERT_TRUE(curves.ok()) << curves.status().toString();
  for (std::size_t i = 1; i < curves->levels.size(); ++i) {
    const CurveLevel& coarse = curves->levels[i - 1];
    const CurveLevel& fine = curves->levels[i];
    EXPECT_LE(coarse.positionBits, fine.positionBits);
    EXPECT_LT(coarse.encodedBytes, fine.encodedBytes);
    // Quantization costs at most budgetFraction of the level's accuracy.
    EXPECT_GE(fine.encodedAccuracy,
              fine.accuracy / (1.0 + quickOptions().quantizationBudgetFraction));
    EXPECT_LE(fine.encodedAccuracy, fine.accuracy);
  }
}

TEST(MeshCurve, EveryCurvePointIsBackedByAMeasuredLevel) {
  // The guarantee the backbone relies on: if the curve says r resources
  // reach accuracy a, some measured level with <= r resources reached >= a.
  int calls = 0;
  const IndexedMesh original = makeIcosphere(kFinestLevel, kRadius);
  Result<MeshCurves> curves = measureMeshCurves(original, 20, original.triangleCount(),
                                                IcosphereLadder{&calls}, quickOptions());
  ASSERT_TRUE(curves.ok()) << curves.status().toString();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const AccuracyCurve& c = curves->triangles;
  for (int i = 0; i < 1000; ++i) {
    const double a = c.minAccuracy() + (c.maxAccuracy() - c.minAccuracy()) * u(rng);
    const double r = c.resourcesFor(a);
    bool backed = false;
    for (const CurveLevel& l : curves->levels) backed |= l.triangles <= r && l.accuracy >= a;
    ASSERT_TRUE(backed) << "a=" << a << " r=" << r;
  }
}

TEST(MeshCurve, ProgressiveMeshOfTheCowGivesConservativeCurves) {
  Result<IndexedMesh> cow =
      thinlod::testing::readObjPositions(thinlod::testing::sharedModelPath("cow.obj"));
  ASSERT_TRUE(cow.ok()) << cow.status().toString();
  Result<ProgressiveMesh> pm = ProgressiveMesh::build(*cow);
  ASSERT_TRUE(pm.ok()) << pm.status().toString();
  MeshCurveOptions options = quickOptions();
  options.levels = 10;
  Result<MeshCurves> curves = measureMeshCurves(*cow, *pm, options);
  ASSERT_TRUE(curves.ok()) << curves.status().toString();
  ASSERT_GE(curves->levels.size(), 8u);
  EXPECT_EQ(curves->levels.back().triangles, pm->maxTriangles());
  // Accuracy grows with triangles overall (Hausdorff error is not strictly
  // monotone in the collapse order, so compare the ends).
  EXPECT_GT(curves->levels.back().accuracy, 10 * curves->levels.front().accuracy);
  expectMonotoneAndConservative(curves->triangles, curves->levels, false);
  expectMonotoneAndConservative(curves->bytes, curves->levels, true);
}

// Levels measured on several threads: every field of every level and both
// curves are the same (==) as measured on one, on a plain and a textured
// mesh; the progress callback hears every level once, counting up.
TEST(MeshCurve, AnyThreadCountGivesTheSameCurves) {
  Result<IndexedMesh> cow =
      thinlod::testing::readObjPositions(thinlod::testing::sharedModelPath("cow.obj"));
  ASSERT_TRUE(cow.ok()) << cow.status().toString();
  Result<ProgressiveMesh> pm = ProgressiveMesh::build(*cow);
  ASSERT_TRUE(pm.ok()) << pm.status().toString();
  const IndexedMesh textured = ShiftedUvLadder::grid(16, 0.0f);
  const auto sameCurves = [](const MeshCurves& a, const MeshCurves& b) {
    ASSERT_EQ(a.levels.size(), b.levels.size());
    for (std::size_t i = 0; i < a.levels.size(); ++i) {
      const CurveLevel& x = a.levels[i];
      const CurveLevel& y = b.levels[i];
      EXPECT_EQ(x.requestedTriangles, y.requestedTriangles);
      EXPECT_EQ(x.triangles, y.triangles);
      EXPECT_EQ(x.relativeMaxError, y.relativeMaxError);
      EXPECT_EQ(x.relativeHausdorffError, y.relativeHausdorffError);
      EXPECT_EQ(x.relativeTextureError, y.relativeTextureError);
      EXPECT_EQ(x.relativeMeanError, y.relativeMeanError);
      EXPECT_EQ(x.accuracy, y.accuracy);
      EXPECT_EQ(x.encodedBytes, y.encodedBytes);
      EXPECT_EQ(x.encodedAccuracy, y.encodedAccuracy);
    }
    EXPECT_EQ(serializeMeshCurves(a, "k"), serializeMeshCurves(b, "k"));
  };
  MeshCurveOptions one = quickOptions();
  one.levels = 10;
  one.threads = 1;
  Result<MeshCurves> serial = measureMeshCurves(*cow, *pm, one);
  ASSERT_TRUE(serial.ok()) << serial.status().toString();
  MeshCurveOptions uvOne = one;
  uvOne.measureEncodedBytes = false;
  Result<MeshCurves> uvSerial =
      measureMeshCurves(textured, 2, textured.triangleCount(), ShiftedUvLadder{}, uvOne);
  ASSERT_TRUE(uvSerial.ok()) << uvSerial.status().toString();
  for (int threads : {0, 2, 3, 16}) {
    SCOPED_TRACE(threads);
    MeshCurveOptions many = one;
    many.threads = threads;
    std::vector<std::size_t> heard;
    std::size_t heardTotal = 0;
    many.levelMeasured = [&](const CurveLevel&, std::size_t done, std::size_t total) {
      heard.push_back(done);
      heardTotal = total;
    };
    Result<MeshCurves> parallel = measureMeshCurves(*cow, *pm, many);
    ASSERT_TRUE(parallel.ok()) << parallel.status().toString();
    sameCurves(*serial, *parallel);
    ASSERT_EQ(heard.size(), serial->levels.size());
    EXPECT_EQ(heardTotal, serial->levels.size());
    for (std::size_t i = 0; i < heard.size(); ++i) EXPECT_EQ(heard[i], i + 1);

    MeshCurveOptions uvMany = uvOne;
    uvMany.threads = threads;
    Result<MeshCurves> uvParallel =
        measureMeshCurves(textured, 2, textured.triangleCount(), ShiftedUvLadder{}, uvMany);
    ASSERT_TRUE(uvParallel.ok()) << uvParallel.status().toString();
    sameCurves(*uvSerial, *uvParallel);
  }
  MeshCurveOptions bad = one;
  bad.threads = -1;
  EXPECT_EQ(measureMeshCurves(*cow, *pm, bad).status().code(), ErrorCode::kInvalidArgument);
}

// A failing level on another thread is reported like a serial failure.
TEST(MeshCurve, AFailingLevelFailsTheParallelMeasurement) {
  const IndexedMesh sphere = makeIcosphere(2, kRadius);
  auto tooMany = [&](std::size_t) { return sphere; };
  MeshCurveOptions options = quickOptions();
  options.threads = 4;
  Result<MeshCurves> curves = measureMeshCurves(sphere, 20, 320, tooMany, options);
  EXPECT_EQ(curves.status().code(), ErrorCode::kInternal);
}

TEST(MeshCurve, InvalidInputsAreRejected) {
  int calls = 0;
  const IndexedMesh sphere = makeIcosphere(2, kRadius);
  EXPECT_EQ(measureMeshCurves(IndexedMesh{}, 20, 320, IcosphereLadder{&calls}).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(measureMeshCurves(sphere, 0, 320, IcosphereLadder{&calls}).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(measureMeshCurves(sphere, 20, 320, ExtractTriangles{}).status().code(),
            ErrorCode::kInvalidArgument);
  MeshCurveOptions options = quickOptions();
  options.levels = 1;
  EXPECT_EQ(measureMeshCurves(sphere, 20, 320, IcosphereLadder{&calls}, options).status().code(),
            ErrorCode::kInvalidArgument);
}

TEST(MeshCurve, ExtractionReturningTooManyTrianglesIsInternalError) {
  const IndexedMesh sphere = makeIcosphere(2, kRadius);
  auto tooMany = [&](std::size_t) { return sphere; };
  Result<MeshCurves> curves = measureMeshCurves(sphere, 20, 320, tooMany, quickOptions());
  EXPECT_EQ(curves.status().code(), ErrorCode::kInternal);
}

class MeshCurveCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    directory_ = std::filesystem::temp_directory_path() /
                 ("thinlod-curve-cache-" + std::to_string(::getpid()) + "-" +
                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(directory_);
  }
  void TearDown() override { std::filesystem::remove_all(directory_); }

  Result<MeshCurves> run(MeshCurveCache& cache, int& calls) {
    return cache.getOrMeasure(original_, "icosphere-ladder", 20, original_.triangleCount(),
                              IcosphereLadder{&calls}, quickOptions());
  }
  std::filesystem::path onlyFile() const {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(directory_)) files.push_back(e.path());
    EXPECT_EQ(files.size(), 1u);
    return files.empty() ? std::filesystem::path() : files.front();
  }
  std::string read(const std::filesystem::path& p) const {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  void write(const std::filesystem::path& p, const std::string& text) const {
    std::ofstream(p, std::ios::trunc) << text;
  }

  std::filesystem::path directory_;
  IndexedMesh original_ = makeIcosphere(3, kRadius);
};

TEST_F(MeshCurveCacheTest, SecondRunHitsTheCacheWithoutExtracting) {
  MeshCurveCache cache(directory_);
  int calls = 0;
  Result<MeshCurves> first = run(cache, calls);
  ASSERT_TRUE(first.ok()) << first.status().toString();
  EXPECT_GT(calls, 0);
  EXPECT_EQ(cache.stats().misses, 1);
  calls = 0;
  Result<MeshCurves> second = run(cache, calls);
  ASSERT_TRUE(second.ok()) << second.status().toString();
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(cache.stats().hits, 1);
  ASSERT_EQ(second->levels.size(), first->levels.size());
  for (std::size_t i = 0; i < first->levels.size(); ++i) {
    EXPECT_EQ(second->levels[i].triangles, first->levels[i].triangles);
    EXPECT_EQ(second->levels[i].accuracy, first->levels[i].accuracy);
    EXPECT_EQ(second->levels[i].encodedBytes, first->levels[i].encodedBytes);
  }
  for (const CurveLevel& l : first->levels) {
    EXPECT_NEAR(second->triangles.resourcesFor(l.accuracy),
                first->triangles.resourcesFor(l.accuracy), 1e-9 * l.triangles);
  }
}

TEST_F(MeshCurveCacheTest, CorruptFileIsRecomputedAndRewritten) {
  MeshCurveCache cache(directory_);
  int calls = 0;
  ASSERT_TRUE(run(cache, calls).ok());
  const std::filesystem::path file = onlyFile();
  write(file, "{\"format\": \"thinlod-mesh-curves\", \"version\": 1, \"key\": ");  // truncated
  calls = 0;
  ASSERT_TRUE(run(cache, calls).ok());
  EXPECT_GT(calls, 0);
  EXPECT_EQ(cache.stats().rejected, 1);
  calls = 0;
  ASSERT_TRUE(run(cache, calls).ok());  // the rewritten file is good again
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(cache.stats().hits, 1);
}

TEST_F(MeshCurveCacheTest, OldVersionIsRecomputed) {
  MeshCurveCache cache(directory_);
  int calls = 0;
  ASSERT_TRUE(run(cache, calls).ok());
  const std::filesystem::path file = onlyFile();
  std::string text = read(file);
  const std::string current = "\"version\": " + std::to_string(kMeshCurveFormatVersion);
  ASSERT_NE(text.find(current), std::string::npos);
  text.replace(text.find(current), current.size(), "\"version\": 0");
  EXPECT_EQ(parseMeshCurves(text, file.stem().string()).status().code(),
            ErrorCode::kVersionMismatch);
  write(file, text);
  calls = 0;
  ASSERT_TRUE(run(cache, calls).ok());
  EXPECT_GT(calls, 0);
  EXPECT_EQ(cache.stats().rejected, 1);
}

TEST_F(MeshCurveCacheTest, OverPromisingCurveInTheFileIsRejected) {
  MeshCurveCache cache(directory_);
  int calls = 0;
  Result<MeshCurves> measured = run(cache, calls);
  ASSERT_TRUE(measured.ok());
  // A structurally valid curve that is cheaper than the measurements.
  MeshCurves tampered = *measured;
  const double lo = tampered.triangles.minAccuracy(), hi = tampered.triangles.maxAccuracy();
  tampered.triangles = *AccuracyCurve::fromTriples({{lo, 1.0, 0.0}}, hi);
  const std::string key = onlyFile().stem().string();
  EXPECT_EQ(parseMeshCurves(serializeMeshCurves(tampered, key), key).status().code(),
            ErrorCode::kParseError);
  write(onlyFile(), serializeMeshCurves(tampered, key));
  calls = 0;
  ASSERT_TRUE(run(cache, calls).ok());
  EXPECT_GT(calls, 0);
  EXPECT_EQ(cache.stats().rejected, 1);
}

TEST_F(MeshCurveCacheTest, FileWithAnotherKeyIsNotTrusted) {
  MeshCurveCache cache(directory_);
  int calls = 0;
  Result<MeshCurves> measured = run(cache, calls);
  ASSERT_TRUE(measured.ok());
  const std::string text = serializeMeshCurves(*measured, "0123");
  EXPECT_EQ(parseMeshCurves(text, "4567").status().code(), ErrorCode::kParseError);
  EXPECT_TRUE(parseMeshCurves(text, "0123").ok());
}

TEST_F(MeshCurveCacheTest, KeyChangesWithMeshProducerAndOptions) {
  const MeshCurveOptions options = quickOptions();
  const std::string base = meshCurveCacheKey(original_, "qem", 20, 1280, options);
  EXPECT_EQ(base.size(), 32u);
  EXPECT_EQ(base, meshCurveCacheKey(original_, "qem", 20, 1280, options));
  EXPECT_NE(base, meshCurveCacheKey(original_, "qem boundaries=0", 20, 1280, options));
  EXPECT_NE(base, meshCurveCacheKey(original_, "qem", 21, 1280, options));
  MeshCurveOptions other = options;
  other.error.seed = 2;
  EXPECT_NE(base, meshCurveCacheKey(original_, "qem", 20, 1280, other));
  IndexedMesh moved = original_;
  moved.positions[7].x += 1e-6f;
  EXPECT_NE(base, meshCurveCacheKey(moved, "qem", 20, 1280, options));
}

TEST_F(MeshCurveCacheTest, DefaultDirectoryFollowsTheEnvironment) {
  const char* saved = std::getenv("THINLOD_CACHE_DIR");
  const std::string savedValue = saved ? saved : "";
  ::setenv("THINLOD_CACHE_DIR", directory_.c_str(), 1);
  EXPECT_EQ(MeshCurveCache::defaultDirectory(), directory_);
  ::unsetenv("THINLOD_CACHE_DIR");
  EXPECT_EQ(MeshCurveCache::defaultDirectory(), std::filesystem::path("build/cache/curves"));
  if (saved) ::setenv("THINLOD_CACHE_DIR", savedValue.c_str(), 1);
}

TEST_F(MeshCurveCacheTest, UnwritableDirectoryStillReturnsTheCurves) {
  write(directory_, "a file where the directory should be");
  MeshCurveCache cache(directory_ / "curves");
  int calls = 0;
  Result<MeshCurves> curves = run(cache, calls);
  ASSERT_TRUE(curves.ok()) << curves.status().toString();
  EXPECT_EQ(cache.stats().writeFailures, 1);
}

}  // namespace
}  // namespace thinlod::simplifier
