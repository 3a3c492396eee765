// The on-disk cache of measured hybrid ladders (hybrid_curve_cache.h): keys
// change with everything the ladder depends on, a stored ladder reads back
// exactly, and every damaged, stale or forged file is refused (then measured
// again by the cache) instead of reaching the scheduler.
#include "thinlod/simplifier/hybrid_curve_cache.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>

namespace thinlod::simplifier {
namespace {

using Json = nlohmann::json;
constexpr int kLevels = 6;

HybridOptions hybridOptions(double kappa) {
  HybridOptions o;
  o.kappa = kappa;
  return o;
}

SurfaceErrorOptions errorOptions() {
  SurfaceErrorOptions o;
  o.samplesPerMesh = 2000;
  return o;
}

// A small multi-manifold model, its graph and its measured ladder.
struct Fixture {
  IndexedMesh mesh = generateScatteredParts(12, 1, 8);
  HybridGraph graph;
  std::vector<HybridMeasuredLevel> levels;
  std::string key;
  std::string text;
  Fixture() {
    Result<HybridGraph> built = buildHybridGraph(mesh, hybridOptions(3.0));
    EXPECT_TRUE(built.ok()) << built.status().toString();
    graph = std::move(built).value();
    Result<std::vector<HybridMeasuredLevel>> measured =
        measureHybridLevels(mesh, graph, kLevels, errorOptions());
    EXPECT_TRUE(measured.ok()) << measured.status().toString();
    levels = std::move(measured).value();
    key = hybridCurveCacheKey(mesh, hybridOptions(3.0), kLevels, errorOptions());
    text = serializeHybridLevels(levels, key);
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

Result<std::vector<HybridMeasuredLevel>> parse(const std::string& text) {
  return parseHybridLevels(text, fixture().key, fixture().graph, kLevels);
}

// The fixture's document with `edit` applied.
std::string edited(const std::function<void(Json&)>& edit) {
  Json document = Json::parse(fixture().text);
  edit(document);
  return document.dump();
}

std::string scratchDir(const std::string& name) {
  const std::filesystem::path path = std::filesystem::path(THINLOD_BINARY_DIR) / "test-tmp" /
                                     ("hybrid-cache-" + std::to_string(::getpid())) / name;
  std::filesystem::remove_all(path);
  std::filesystem::create_directories(path);
  return path.string();
}

TEST(HybridCurveCache, StoredLadderReadsBackExactly) {
  const Fixture& f = fixture();
  ASSERT_GE(f.levels.size(), 3u);
  Result<std::vector<HybridMeasuredLevel>> back = parse(f.text);
  ASSERT_TRUE(back.ok()) << back.status().toString();
  ASSERT_EQ(back->size(), f.levels.size());
  for (std::size_t i = 0; i < f.levels.size(); ++i) {
    EXPECT_EQ((*back)[i].step.error, f.levels[i].step.error);
    EXPECT_EQ((*back)[i].step.units, f.levels[i].step.units);
    EXPECT_EQ((*back)[i].step.triangles, f.levels[i].step.triangles);
    EXPECT_EQ((*back)[i].step.points, f.levels[i].step.points);
    EXPECT_EQ((*back)[i].measuredError, f.levels[i].measuredError);
  }
}

TEST(HybridCurveCache, KeyChangesWithEverythingTheLadderDependsOn) {
  const Fixture& f = fixture();
  EXPECT_EQ(f.key, hybridCurveCacheKey(f.mesh, hybridOptions(3.0), kLevels, errorOptions()));
  EXPECT_EQ(f.key.size(), 32u);
  std::set<std::string> keys{f.key};
  const auto distinct = [&](const std::string& key, const char* what) {
    EXPECT_TRUE(keys.insert(key).second) << what << " does not change the key";
  };
  distinct(hybridCurveCacheKey(f.mesh, hybridOptions(10.0), kLevels, errorOptions()), "kappa");
  distinct(hybridCurveCacheKey(f.mesh, hybridOptions(1.5), kLevels, errorOptions()), "kappa");
  HybridOptions o = hybridOptions(3.0);
  o.tau = 5.0;
  distinct(hybridCurveCacheKey(f.mesh, o, kLevels, errorOptions()), "tau");
  o = hybridOptions(3.0);
  o.enablePoints = false;
  distinct(hybridCurveCacheKey(f.mesh, o, kLevels, errorOptions()), "enablePoints");
  o = hybridOptions(3.0);
  o.sampleDistanceTolerance = 1e-4;
  distinct(hybridCurveCacheKey(f.mesh, o, kLevels, errorOptions()), "sample distance tolerance");
  o = hybridOptions(3.0);
  o.octreeMaxDepth = 12;
  distinct(hybridCurveCacheKey(f.mesh, o, kLevels, errorOptions()), "octree depth");
  distinct(hybridCurveCacheKey(f.mesh, hybridOptions(3.0), kLevels + 1, errorOptions()), "levels");
  SurfaceErrorOptions e = errorOptions();
  e.samplesPerMesh += 1;
  distinct(hybridCurveCacheKey(f.mesh, hybridOptions(3.0), kLevels, e), "samples");
  e = errorOptions();
  e.seed = 2;
  distinct(hybridCurveCacheKey(f.mesh, hybridOptions(3.0), kLevels, e), "seed");
  e = errorOptions();
  e.includeVerticesAndEdges = false;
  distinct(hybridCurveCacheKey(f.mesh, hybridOptions(3.0), kLevels, e), "vertex samples");
  IndexedMesh moved = f.mesh;
  moved.positions[0].x += 1e-3f;
  distinct(hybridCurveCacheKey(moved, hybridOptions(3.0), kLevels, errorOptions()), "mesh");
  IndexedMesh coloured = f.mesh;
  coloured.colors.assign(coloured.positions.size(), {255, 255, 255, 255});
  distinct(hybridCurveCacheKey(coloured, hybridOptions(3.0), kLevels, errorOptions()), "colours");
}

TEST(HybridCurveCache, WrongVersionFormatOrKeyIsRefused) {
  const Result<std::vector<HybridMeasuredLevel>> version =
      parse(edited([](Json& d) { d["version"] = kHybridCurveFormatVersion + 1; }));
  EXPECT_EQ(version.status().code(), ErrorCode::kVersionMismatch);
  EXPECT_EQ(parse(edited([](Json& d) { d["format"] = "thinlod-mesh-curves"; })).status().code(),
            ErrorCode::kParseError);
  EXPECT_EQ(parse(edited([](Json& d) { d["key"] = std::string(32, '0'); })).status().code(),
            ErrorCode::kParseError);
  EXPECT_EQ(parse(edited([](Json& d) { d.erase("rungs"); })).status().code(),
            ErrorCode::kParseError);
  EXPECT_EQ(parse("[]").status().code(), ErrorCode::kParseError);
  EXPECT_EQ(parse("").status().code(), ErrorCode::kParseError);
}

TEST(HybridCurveCache, EveryTruncationIsRefused) {
  const std::string& text = fixture().text;
  for (std::size_t n = 0; n < text.size(); ++n) {
    // The only prefix that is still the whole document: trailing whitespace.
    if (text.find_first_not_of(" \n", n) == std::string::npos) continue;
    EXPECT_FALSE(parse(text.substr(0, n)).ok()) << "prefix of " << n << " bytes accepted";
  }
}

TEST(HybridCurveCache, NonFiniteNegativeOrImpossibleErrorsAreRefused) {
  const auto rung1 = [](const char* field, Json value) {
    return edited([=](Json& d) { d["rungs"][1][field] = value; });
  };
  // NaN is written as null by JSON writers; 1e999 parses to infinity.
  EXPECT_FALSE(parse(rung1("measuredError", nullptr)).ok());
  std::string infinite = fixture().text;
  Json d = Json::parse(infinite);
  d["rungs"][1]["measuredError"] = 0.5;
  infinite = d.dump();
  infinite.replace(infinite.find("0.5"), 3, "1e999");
  EXPECT_FALSE(parse(infinite).ok());
  EXPECT_FALSE(parse(rung1("measuredError", -1e-9)).ok());
  EXPECT_FALSE(parse(rung1("measuredError", "0.1")).ok());
  // A sampled distance above the rung's guaranteed bound cannot be measured.
  const double bound = fixture().levels[1].step.error;
  EXPECT_FALSE(parse(rung1("measuredError", bound * 1.5 + 1e-3 * fixture().graph.diagonal())).ok());
  EXPECT_FALSE(parse(rung1("error", nullptr)).ok());
  EXPECT_FALSE(parse(rung1("units", -3.0)).ok());
  EXPECT_FALSE(parse(rung1("triangles", -1)).ok());
  EXPECT_FALSE(parse(rung1("points", 1.5)).ok());
}

TEST(HybridCurveCache, RungsThatAreNotTheGraphsAreRefused) {
  const Fixture& f = fixture();
  // Reordered (units no longer increasing), a rung dropped, one added, a
  // threshold or a count moved: none is the ladder this graph gives.
  EXPECT_FALSE(parse(edited([](Json& d) { std::swap(d["rungs"][0], d["rungs"][1]); })).ok());
  EXPECT_FALSE(parse(edited([](Json& d) { d["rungs"].erase(0); })).ok());
  EXPECT_FALSE(parse(edited([](Json& d) { d["rungs"].push_back(d["rungs"].back()); })).ok());
  EXPECT_FALSE(parse(edited([](Json& d) {
                 d["rungs"][0]["error"] = d["rungs"][0]["error"].get<double>() * 1.01;
               })).ok());
  EXPECT_FALSE(parse(edited([](Json& d) {
                 d["rungs"][0]["units"] = d["rungs"][0]["units"].get<double>() - 1.0;
               })).ok());
  EXPECT_FALSE(parse(edited([](Json& d) {
                 d["rungs"][0]["points"] = d["rungs"][0]["points"].get<std::size_t>() + 1;
               })).ok());
  EXPECT_FALSE(parse(edited([](Json& d) { d["rungs"] = Json::array(); })).ok());
  Json many = Json::parse(f.text);
  for (int i = 0; i < 100; ++i) many["rungs"].push_back(many["rungs"][0]);
  EXPECT_FALSE(parse(many.dump()).ok());
  // The right key but another graph (a stale build of the graph code that
  // kept kHybridGraphVersion): its steps differ, the file is refused.
  Result<HybridGraph> other = buildHybridGraph(f.mesh, hybridOptions(10.0));
  ASSERT_TRUE(other.ok());
  EXPECT_FALSE(parseHybridLevels(f.text, f.key, *other, kLevels).ok());
}

TEST(HybridCurveCache, RandomCorruptionsAreRefusedOrValid) {
  const std::string& text = fixture().text;
  std::mt19937 rng(16);
  int accepted = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    std::string damaged = text;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < flips; ++k) {
      damaged[rng() % damaged.size()] = static_cast<char>(rng() % 256);
    }
    Result<std::vector<HybridMeasuredLevel>> r = parse(damaged);
    if (!r.ok()) continue;
    // Accepted (e.g. whitespace hit, a digit beyond what round-trips in a
    // measured error): it must still pass every check.
    ++accepted;
    EXPECT_TRUE(validateHybridLevels(*r, fixture().graph, kLevels).ok());
  }
  EXPECT_LT(accepted, 1500);
}

TEST(HybridCurveCache, SecondCacheReadsWhatTheFirstMeasured) {
  const Fixture& f = fixture();
  const std::string dir = scratchDir("hit");
  HybridCurveCache first(dir);
  Result<std::vector<HybridMeasuredLevel>> measured =
      first.getOrMeasure(f.mesh, f.graph, hybridOptions(3.0), kLevels, errorOptions());
  ASSERT_TRUE(measured.ok()) << measured.status().toString();
  EXPECT_EQ(first.stats().misses, 1);
  EXPECT_EQ(first.stats().hits, 0);
  EXPECT_EQ(first.stats().writeFailures, 0);
  EXPECT_TRUE(std::filesystem::exists(first.fileFor(f.key)));

  HybridCurveCache second(dir);
  Result<std::vector<HybridMeasuredLevel>> read =
      second.getOrMeasure(f.mesh, f.graph, hybridOptions(3.0), kLevels, errorOptions());
  ASSERT_TRUE(read.ok()) << read.status().toString();
  EXPECT_EQ(second.stats().hits, 1);
  EXPECT_EQ(second.stats().misses, 0);
  ASSERT_EQ(read->size(), measured->size());
  for (std::size_t i = 0; i < read->size(); ++i) {
    EXPECT_EQ((*read)[i].measuredError, (*measured)[i].measuredError);
    EXPECT_EQ((*read)[i].step.units, (*measured)[i].step.units);
  }
}

TEST(HybridCurveCache, DamagedFileIsMeasuredAgainAndReplaced) {
  const Fixture& f = fixture();
  const std::string dir = scratchDir("damaged");
  const std::filesystem::path path = HybridCurveCache(dir).fileFor(f.key);
  const std::vector<std::pair<const char*, std::string>> damages = {
      {"truncated", f.text.substr(0, f.text.size() / 2)},
      {"wrong version", edited([](Json& d) { d["version"] = 0; })},
      {"impossible error", edited([](Json& d) { d["rungs"][0]["measuredError"] = 1e30; })},
      {"empty", ""},
  };
  for (const auto& [what, bytes] : damages) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
    HybridCurveCache cache(dir);
    Result<std::vector<HybridMeasuredLevel>> r =
        cache.getOrMeasure(f.mesh, f.graph, hybridOptions(3.0), kLevels, errorOptions());
    ASSERT_TRUE(r.ok()) << what << ": " << r.status().toString();
    EXPECT_EQ(cache.stats().rejected, 1) << what;
    EXPECT_EQ(cache.stats().hits, 0) << what;
    EXPECT_NE(cache.lastRejection().find(path.string()), std::string::npos) << what;
    EXPECT_EQ(r->size(), f.levels.size()) << what;
    for (std::size_t i = 0; i < r->size(); ++i) {
      EXPECT_EQ((*r)[i].measuredError, f.levels[i].measuredError) << what << " (deterministic)";
    }
    // Rewritten: the next process reads it.
    HybridCurveCache next(dir);
    ASSERT_TRUE(
        next.getOrMeasure(f.mesh, f.graph, hybridOptions(3.0), kLevels, errorOptions()).ok());
    EXPECT_EQ(next.stats().hits, 1) << what;
  }
  // A directory where the file should be: refused (not readable), measured,
  // the write fails and is counted; the measured ladder is still returned.
  std::filesystem::remove(path);
  std::filesystem::create_directories(path / "sub");
  HybridCurveCache blocked(dir);
  ASSERT_TRUE(
      blocked.getOrMeasure(f.mesh, f.graph, hybridOptions(3.0), kLevels, errorOptions()).ok());
  EXPECT_EQ(blocked.stats().rejected, 1);
  EXPECT_EQ(blocked.stats().writeFailures, 1);
}

}  // namespace
}  // namespace thinlod::simplifier
