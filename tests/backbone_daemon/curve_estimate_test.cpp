// estimatedMeshCurve (backbone/src/daemon/curve_estimate.h): its shape, and
// that it is pessimistic about triangles against the measured curves of the
// shared models.
#include "curve_estimate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "thinlod/common/mesh/primitives.h"

namespace thinlod::backbone_daemon {
namespace {

struct MeasuredModel {
  const char* name;
  double fullTriangles;
  std::vector<AccuracySample> levels;  // {accuracy, triangles} as measured (raw 1 / max(d, 1e-4))
};

// Measured 2026-12-02 with
//   thinlod-simplifier curve /work/shared/models/NAME --no-bytes --json --levels 12 --samples 30000
// (the service's curve settings: 12 levels, 30k samples per direction);
// levels as (triangles, accuracy) of the JSON's "levels".
std::vector<MeasuredModel> measuredModels() {
  auto model = [](const char* name, double full, std::vector<std::pair<double, double>> levels) {
    MeasuredModel m{name, full, {}};
    for (auto [triangles, accuracy] : levels) m.levels.push_back({accuracy, triangles});
    return m;
  };
  return {
      model("cheburashka", 13334,
            {{4, 2.18132},
             {8, 4.17998},
             {16, 4.17998},
             {36, 7.83513},
             {76, 11.2379},
             {160, 17.1439},
             {334, 43.5578},
             {698, 59.4759},
             {1458, 141.73},
             {3050, 298.757},
             {6378, 707.338},
             {13334, 10000}}),
      model("cow", 5804,
            {{12, 2.27151},
             {20, 4.11268},
             {36, 5.03504},
             {64, 8.82749},
             {114, 11.9813},
             {198, 20.1644},
             {350, 25.8223},
             {612, 68.6192},
             {1074, 107.374},
             {1886, 107.374},
             {3308, 407.149},
             {5804, 10000}}),
      model("fandisk", 12946,
            {{4, 2.73693},
             {8, 4.14651},
             {16, 7.51178},
             {36, 12.5198},
             {76, 26.0912},
             {158, 91.9126},
             {328, 315.217},
             {684, 1095.9},
             {1428, 2609.16},
             {2978, 10000},
             {6208, 10000},
             {12946, 10000}}),
      model("horse", 96966,
            {{4, 2.41596},
             {10, 2.91371},
             {24, 3.38115},
             {62, 9.25428},
             {156, 22.0015},
             {394, 48.4893},
             {984, 115.231},
             {2466, 193.394},
             {6178, 193.394},
             {15468, 357.526},
             {38728, 357.526},
             {96966, 10000}}),
      model("nefertiti", 99938,
            {{4, 1.99041},
             {10, 5.43473},
             {24, 7.32141},
             {62, 14.9849},
             {158, 29.5508},
             {398, 48.4871},
             {1002, 93.334},
             {2514, 186.84},
             {6314, 336.505},
             {15854, 910.317},
             {39804, 1702.51},
             {99938, 10000}}),
      model("spot", 5856,
            {{4, 2.26949},
             {8, 2.98713},
             {14, 4.5568},
             {28, 5.45102},
             {56, 8.20926},
             {110, 20.3086},
             {212, 28.6639},
             {414, 62.4808},
             {802, 72.8866},
             {1556, 128.024},
             {3018, 406.504},
             {5856, 10000}}),
      model("stanford-bunny", 69451,
            {{27, 1.97216},
             {55, 3.90463},
             {113, 13.4989},
             {230, 26.3521},
             {468, 51.4905},
             {957, 75.2845},
             {1957, 148.542},
             {3994, 306.261},
             {8157, 558.485},
             {16657, 931.147},
             {34013, 1869.48},
             {69451, 10000}}),
      model("suzanne", 968,
            {{20, 3.65421},
             {28, 3.7779},
             {40, 9.51342},
             {58, 8.89105},
             {82, 16.92},
             {116, 22.8067},
             {166, 27.1898},
             {236, 34.7072},
             {336, 34.8484},
             {478, 56.4166},
             {679, 105.463},
             {967, 10000}}),
      model("teapot", 6320,
            {{19, 2.80112},
             {31, 8.40676},
             {55, 16.1545},
             {93, 16.627},
             {156, 21.5009},
             {266, 34.1567},
             {450, 59.2932},
             {764, 79.3391},
             {1297, 187.711},
             {2198, 230.369},
             {3727, 823.411},
             {6320, 10000}}),
      model("woody", 1267,
            {{1, 2.28908},
             {2, 2.93456},
             {4, 3.34768},
             {7, 4.40353},
             {13, 11.4099},
             {26, 52.939},
             {49, 140.937},
             {94, 707.11},
             {181, 10000},
             {346, 10000},
             {661, 10000},
             {1267, 10000}}),
  };
}

// What the simplifier service delivers from those levels: each level is
// credited the worst error of it and every finer level, and the Draco
// quantization may add 10 % of the error (accuracy / 1.1). Returns the
// fewest triangles delivering at least `a` (the full mesh reaches anything).
double deliveredStaircase(const MeasuredModel& m, double a) {
  double cheapest = m.fullTriangles;
  for (std::size_t i = 0; i < m.levels.size(); ++i) {
    double credit = std::numeric_limits<double>::infinity();
    for (std::size_t j = i; j < m.levels.size(); ++j)
      credit = std::min(credit, m.levels[j].accuracy);
    if (credit / 1.1 >= a) cheapest = std::min(cheapest, m.levels[i].resources);
  }
  return cheapest;
}

TEST(CurveEstimate, ShapeIsLinearThenTheFullMesh) {
  Result<AccuracyCurve> curve = estimatedMeshCurve(69451.0);
  ASSERT_TRUE(curve.ok()) << curve.status().toString();
  EXPECT_DOUBLE_EQ(curve->minAccuracy(), 1.0);
  EXPECT_DOUBLE_EQ(curve->maxAccuracy(), kExactRelativeAccuracy);
  EXPECT_DOUBLE_EQ(curve->resourcesFor(0.5), 40.0);  // left of the domain: its start
  EXPECT_DOUBLE_EQ(curve->resourcesFor(1.0), 40.0);
  EXPECT_DOUBLE_EQ(curve->resourcesFor(10.0), 400.0);
  EXPECT_DOUBLE_EQ(curve->resourcesFor(49.0), 1960.0);
  EXPECT_DOUBLE_EQ(curve->resourcesFor(50.0), 69451.0);  // the full mesh from 50 on
  EXPECT_DOUBLE_EQ(curve->resourcesFor(kExactRelativeAccuracy), 69451.0);
  EXPECT_EQ(curve->resourcesFor(2.0 * kExactRelativeAccuracy),
            std::numeric_limits<double>::infinity());
  // The budget inversion the scheduler uses: 400 triangles buy a = 10.
  EXPECT_NEAR(*curve->maxAccuracyWithin(400.0), 10.0, 1e-9);
}

TEST(CurveEstimate, SmallMeshesReachTheirFullMeshOnTheLine) {
  // 968 triangles: k a reaches them at a = 24.2, flat from there.
  Result<AccuracyCurve> suzanne = estimatedMeshCurve(968.0);
  ASSERT_TRUE(suzanne.ok());
  EXPECT_DOUBLE_EQ(suzanne->resourcesFor(20.0), 800.0);
  EXPECT_DOUBLE_EQ(suzanne->resourcesFor(24.2), 968.0);
  EXPECT_DOUBLE_EQ(suzanne->resourcesFor(40.0), 968.0);
  // Fewer triangles than the line's start: one flat piece.
  Result<AccuracyCurve> tiny = estimatedMeshCurve(12.0);
  ASSERT_TRUE(tiny.ok());
  EXPECT_DOUBLE_EQ(tiny->resourcesFor(1.0), 12.0);
  EXPECT_DOUBLE_EQ(tiny->resourcesFor(kExactRelativeAccuracy), 12.0);
}

TEST(CurveEstimate, InvalidInputIsRefused) {
  EXPECT_EQ(estimatedMeshCurve(0.0).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(estimatedMeshCurve(std::nan("")).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(estimatedMeshCurve(std::numeric_limits<double>::infinity()).status().code(),
            ErrorCode::kInvalidArgument);
  MeshCurveEstimate bad;
  bad.trianglesPerAccuracy = -1.0;
  EXPECT_FALSE(estimatedMeshCurve(100.0, bad).ok());
  bad = MeshCurveEstimate{};
  bad.fullMeshAbove = 0.5;  // below the domain start
  EXPECT_FALSE(estimatedMeshCurve(100.0, bad).ok());
}

TEST(CurveEstimate, PessimisticAgainstEveryMeasuredSharedModel) {
  // Invariant: at every accuracy the estimate costs at least the triangles
  // the simplifier needs to deliver it (sampled densely, and just above each
  // measured level where the staircase steps up).
  for (const MeasuredModel& m : measuredModels()) {
    Result<AccuracyCurve> estimate = estimatedMeshCurve(m.fullTriangles);
    ASSERT_TRUE(estimate.ok()) << m.name;
    std::vector<double> accuracies;
    for (double a = 1.0; a <= 1e4; a *= 1.01) accuracies.push_back(a);
    for (const AccuracySample& level : m.levels) {
      accuracies.push_back(level.accuracy / 1.1);
      accuracies.push_back(std::nextafter(level.accuracy / 1.1, 1e300));
    }
    for (double a : accuracies) {
      if (a < 1.0) continue;
      EXPECT_GE(estimate->resourcesFor(a), deliveredStaircase(m, a))
          << m.name << " at relative accuracy " << a;
    }
  }
}

TEST(CurveEstimate, NeverAboveTheFullMeshAndMonotoneOverRandomSizes) {
  // Extreme magnitudes: 1 to 10^8 triangles.
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> logSize(0.0, 8.0);
  for (int i = 0; i < 500; ++i) {
    const double full = std::max(1.0, std::round(std::pow(10.0, logSize(random))));
    Result<AccuracyCurve> curve = estimatedMeshCurve(full);
    ASSERT_TRUE(curve.ok()) << full;
    double previous = 0.0;
    for (double a = 1.0; a <= kExactRelativeAccuracy; a *= 1.3) {
      const double r = curve->resourcesFor(a);
      ASSERT_GE(r, previous) << full << " at " << a;
      ASSERT_LE(r, full) << full << " at " << a;
      ASSERT_GE(r, 1.0);
      previous = r;
    }
    EXPECT_EQ(curve->resourcesFor(kExactRelativeAccuracy), full);
  }
}

}  // namespace
}  // namespace thinlod::backbone_daemon
