// The hybrid multiresolution graph and its cuts: input validation, graph
// invariants (kappa limit, monotone errors, units removed), randomized cut
// properties (fixed seeds), and the verified bound: the sampled two-sided
// Hausdorff distance of random cuts never exceeds the cut's stored bound, on
// the bunny and on a generated multi-manifold model.
#include "thinlod/simplifier/hybrid_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <glm/geometric.hpp>
#include <limits>
#include <random>
#include <set>

#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::simplifier {
namespace {

IndexedMesh loadBunny() {
  Result<LoadedMesh> loaded =
      loadMeshFile(std::string(THINLOD_SHARED_DIR) + "/models/stanford-bunny.obj");
  EXPECT_TRUE(loaded.ok()) << loaded.status().toString();
  IndexedMesh m;
  if (!loaded.ok()) return m;
  m.positions = loaded->mesh.positions;
  m.indices = loaded->mesh.indices;
  return m;
}

// Square [0,1]^2 with a bump, cells x cells quads: an open sheet (border).
IndexedMesh makeBumpyGrid(int cells) {
  IndexedMesh m;
  for (int y = 0; y <= cells; ++y) {
    for (int x = 0; x <= cells; ++x) {
      const float fx = static_cast<float>(x) / cells, fy = static_cast<float>(y) / cells;
      const float z =
          0.2f * std::exp(-20.0f * ((fx - 0.5f) * (fx - 0.5f) + (fy - 0.4f) * (fy - 0.4f)));
      m.positions.emplace_back(fx, fy, z);
    }
  }
  auto id = [cells](int x, int y) { return static_cast<std::uint32_t>(y * (cells + 1) + x); };
  for (int y = 0; y < cells; ++y) {
    for (int x = 0; x < cells; ++x) {
      m.indices.insert(m.indices.end(), {id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      m.indices.insert(m.indices.end(), {id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  }
  return m;
}

HybridOptions options(double kappa, double tau, bool points = true) {
  HybridOptions o;
  o.kappa = kappa;
  o.tau = tau;
  o.enablePoints = points;
  return o;
}

// Every upward path from every input triangle meets exactly one primitive of
// the cut: nothing missing, nothing covered twice (a triangle and its
// replacement never both in the cut). Computed from the primitives alone.
::testing::AssertionResult coversOnce(const HybridGraph& g, const HybridCut& cut) {
  const auto& prims = g.primitives();
  const auto& nodes = g.nodes();
  const std::uint32_t source = g.sourceNode();
  std::vector<std::int8_t> clean(prims.size(), -1), exact(prims.size(), -1);
  // clean(p): no primitive strictly above p is in the cut.
  std::function<bool(std::uint32_t)> aboveClean = [&](std::uint32_t p) -> bool {
    if (clean[p] >= 0) return clean[p] != 0;
    bool ok = true;
    const std::uint32_t c = prims[p].consumer;
    if (c != source) {
      for (std::uint32_t i = nodes[c].producedBegin; i < nodes[c].producedEnd && ok; ++i) {
        const std::uint32_t q = g.producedList()[i];
        ok = !cut.contains(q) && aboveClean(q);
      }
    }
    clean[p] = ok ? 1 : 0;
    return ok;
  };
  std::function<bool(std::uint32_t)> exactlyOnce = [&](std::uint32_t p) -> bool {
    if (exact[p] >= 0) return exact[p] != 0;
    bool ok;
    if (cut.contains(p)) {
      ok = aboveClean(p);
    } else {
      const std::uint32_t c = prims[p].consumer;
      ok = c != source;
      for (std::uint32_t i = nodes[c].producedBegin; ok && i < nodes[c].producedEnd; ++i) {
        ok = exactlyOnce(g.producedList()[i]);
      }
    }
    exact[p] = ok ? 1 : 0;
    return ok;
  };
  const HybridNode& drain = nodes[HybridGraph::kDrain];
  for (std::uint32_t i = drain.producedBegin; i < drain.producedEnd; ++i) {
    if (!exactlyOnce(g.producedList()[i])) {
      return ::testing::AssertionFailure()
             << "input primitive " << g.producedList()[i] << " is missing or covered twice";
    }
  }
  // The applied flags agree with the primitives.
  for (std::uint32_t p : cut.primitives()) {
    if (!cut.applied(prims[p].producer) || cut.applied(prims[p].consumer)) {
      return ::testing::AssertionFailure() << "primitive " << p << " inconsistent with nodes";
    }
  }
  return ::testing::AssertionSuccess();
}

std::set<std::uint32_t> appliedSet(const HybridGraph& g, const HybridCut& cut) {
  std::set<std::uint32_t> s;
  for (std::uint32_t n = 0; n < g.nodes().size(); ++n) {
    if (cut.applied(n)) s.insert(n);
  }
  return s;
}

std::set<std::uint32_t> cutSet(const HybridCut& cut) {
  return {cut.primitives().begin(), cut.primitives().end()};
}

TEST(HybridGraph, RejectsBadInput) {
  IndexedMesh empty;
  EXPECT_EQ(buildHybridGraph(empty).status().code(), ErrorCode::kInvalidArgument);
  IndexedMesh nan = makeBumpyGrid(2);
  nan.positions[1].x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(buildHybridGraph(nan).status().code(), ErrorCode::kInvalidArgument);
  IndexedMesh badIndex = makeBumpyGrid(2);
  badIndex.indices[4] = 1000;
  EXPECT_EQ(buildHybridGraph(badIndex).status().code(), ErrorCode::kInvalidArgument);
  IndexedMesh degenerate;
  degenerate.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  degenerate.indices = {0, 1, 2, 0, 0, 1};
  EXPECT_EQ(buildHybridGraph(degenerate).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(buildHybridGraph(makeBumpyGrid(2), options(3.0, 0.0)).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(buildHybridGraph(makeBumpyGrid(2), options(std::nan(""), 1.0)).status().code(),
            ErrorCode::kInvalidArgument);
}

void checkGraphInvariants(const HybridGraph& g, bool points) {
  const auto& nodes = g.nodes();
  const auto& prims = g.primitives();
  ASSERT_GE(nodes.size(), 2u);
  EXPECT_EQ(nodes.front().kind, HybridNodeKind::kDrain);
  EXPECT_EQ(nodes.back().kind, HybridNodeKind::kSource);
  const auto maxPoints = static_cast<std::size_t>(std::floor(g.kappa()));
  for (std::uint32_t n = 1; n + 1 < nodes.size(); ++n) {
    const HybridNode& node = nodes[n];
    EXPECT_GT(g.unitsRemovedBy(n), 0.0) << "node " << n;
    for (std::uint32_t i = node.consumedBegin; i < node.consumedEnd; ++i) {
      const HybridPrimitive& c = prims[g.consumedList()[i]];
      EXPECT_EQ(c.consumer, n);
      EXPECT_GE(node.error, nodes[c.producer].error) << "error not monotone at node " << n;
      const HybridNode& child = nodes[c.producer];
      EXPECT_LE(glm::length(child.sphereCentre - node.sphereCentre) + child.sphereRadius,
                node.sphereRadius * (1.0 + 1e-12));
    }
    for (std::uint32_t i = node.producedBegin; i < node.producedEnd; ++i) {
      const HybridPrimitive& p = prims[g.producedList()[i]];
      EXPECT_EQ(p.producer, n);
      EXPECT_LE(p.error, node.error);
    }
    const std::size_t produced = node.producedEnd - node.producedBegin;
    if (node.kind == HybridNodeKind::kPointReplacement) {
      EXPECT_EQ(node.consumedEnd - node.consumedBegin, 1u);
      EXPECT_GE(produced, 1u);
      EXPECT_LE(produced, maxPoints);
      EXPECT_LT(static_cast<double>(produced), g.kappa());
    }
    if (node.kind == HybridNodeKind::kPointMerge) {
      EXPECT_EQ(produced, 1u);
      EXPECT_GE(node.consumedEnd - node.consumedBegin, 2u);
      EXPECT_LE(node.consumedEnd - node.consumedBegin, 8u);
    }
  }
  const HybridNode& source = nodes.back();
  if (points) {
    // Everything ends in one root point.
    ASSERT_EQ(source.consumedEnd - source.consumedBegin, 1u);
    EXPECT_EQ(prims[g.consumedList()[source.consumedBegin]].kind, HybridPrimitiveKind::kPoint);
  } else {
    EXPECT_TRUE(g.points().empty());
  }
  const auto steps = g.unitsVersusError();
  ASSERT_FALSE(steps.empty());
  EXPECT_DOUBLE_EQ(steps.front().units, static_cast<double>(g.stats().inputTriangles));
  for (std::size_t i = 1; i < steps.size(); ++i) {
    EXPECT_GT(steps[i].error, steps[i - 1].error);
    EXPECT_LT(steps[i].units, steps[i - 1].units);
  }
}

TEST(HybridGraph, InvariantsOnSmallModels) {
  const std::vector<IndexedMesh> meshes = {makeBumpyGrid(12), generateScatteredParts(1, 3, 4),
                                           generateScatteredParts(40, 1, 9)};
  for (const IndexedMesh& mesh : meshes) {
    for (double kappa : {1.0, 2.5, 3.0, 10.0}) {
      for (double tau : {1.0, 5.0}) {
        Result<HybridGraph> g = buildHybridGraph(mesh, options(kappa, tau));
        ASSERT_TRUE(g.ok()) << g.status().toString();
        checkGraphInvariants(*g, kappa > 1.0);
      }
    }
    Result<HybridGraph> g = buildHybridGraph(mesh, options(3.0, 1.0, false));
    ASSERT_TRUE(g.ok());
    checkGraphInvariants(*g, false);
    EXPECT_EQ(g->stats().pointReplacements, 0u);
  }
}

TEST(HybridGraph, PointsInterpolateVertexColours) {
  // One part, one colour: every point keeps it.
  Result<HybridGraph> g = buildHybridGraph(generateScatteredParts(1, 1, 3), options(3.0, 5.0));
  ASSERT_TRUE(g.ok());
  ASSERT_FALSE(g->points().empty());
  const auto colour = g->vertexColors().front();
  for (const HybridPoint& p : g->points()) {
    EXPECT_EQ(p.color, colour);
  }
}

TEST(HybridCut, RandomCutsAreConsistentMonotoneAndIncremental) {
  const std::vector<IndexedMesh> meshes = {makeBumpyGrid(16), generateScatteredParts(60, 1, 21)};
  std::uint64_t seed = 100;
  for (const IndexedMesh& mesh : meshes) {
    for (double kappa : {3.0, 10.0}) {
      Result<HybridGraph> built = buildHybridGraph(mesh, options(kappa, 5.0));
      ASSERT_TRUE(built.ok());
      const HybridGraph& g = *built;
      const auto steps = g.unitsVersusError();
      const double top = steps.back().error;
      std::mt19937_64 rng(seed++);
      HybridCut incremental(g);
      // A random walk of thresholds, up and down.
      for (int k = 0; k < 25; ++k) {
        const double threshold =
            top * std::pow(10.0, -4.0 * static_cast<double>(rng() % 1000) / 1000.0);
        incremental.adaptToError(threshold);
        HybridCut scratch(g);
        scratch.adaptToError(threshold);
        EXPECT_EQ(cutSet(incremental), cutSet(scratch));
        EXPECT_TRUE(coversOnce(g, incremental));
        EXPECT_LE(incremental.errorBound(), threshold);
        // Exactly the nodes with error <= threshold are applied.
        for (std::uint32_t n = 1; n + 1 < g.nodes().size(); ++n) {
          ASSERT_EQ(incremental.applied(n), g.nodes()[n].error <= threshold);
        }
        // Units equal the curve's step at the threshold.
        double expected = steps.front().units;
        for (const auto& s : steps) {
          if (s.error <= threshold) expected = s.units;
        }
        EXPECT_NEAR(incremental.units(), expected, 1e-9 * expected);
      }
      // Monotone in the threshold: nested applied sets, units non-increasing.
      std::vector<double> thresholds;
      for (int k = 0; k < 30; ++k)
        thresholds.push_back(top * static_cast<double>(rng() % 10000) / 10000.0);
      std::sort(thresholds.begin(), thresholds.end());
      HybridCut cut(g);
      std::set<std::uint32_t> previous = appliedSet(g, cut);
      double previousUnits = cut.units();
      for (double t : thresholds) {
        cut.adaptToError(t);
        const std::set<std::uint32_t> now = appliedSet(g, cut);
        EXPECT_TRUE(std::includes(now.begin(), now.end(), previous.begin(), previous.end()));
        EXPECT_LE(cut.units(), previousUnits);
        previous = now;
        previousUnits = cut.units();
      }
      cut.adaptToError(std::numeric_limits<double>::max());
      EXPECT_EQ(cut.primitives().size(), 1u);  // the root point
      cut.adaptToError(0.0);
      EXPECT_TRUE(coversOnce(g, cut));
    }
  }
}

TEST(HybridCut, ScreenSpaceCutsRespectTheToleranceAndAreMonotone) {
  Result<HybridGraph> built = buildHybridGraph(generateScatteredParts(60, 1, 5), options(3.0, 1.0));
  ASSERT_TRUE(built.ok());
  const HybridGraph& g = *built;
  std::mt19937_64 rng(77);
  HybridCut incremental(g);
  for (int k = 0; k < 12; ++k) {
    HybridView view;
    view.eye = glm::dvec3(static_cast<double>(rng() % 1000) / 250.0 - 2.0, 0.5,
                          -1.0 - static_cast<double>(rng() % 100) / 50.0);
    view.pixelsPerRadian = 800.0;
    view.nearDistance = 0.01;
    double previousUnits = std::numeric_limits<double>::infinity();
    for (double tolerance : {0.5, 1.0, 3.0, 10.0, 50.0}) {
      incremental.adaptToScreen(view, tolerance);
      HybridCut scratch(g);
      scratch.adaptToScreen(view, tolerance);
      EXPECT_EQ(cutSet(incremental), cutSet(scratch));
      EXPECT_TRUE(coversOnce(g, incremental));
      EXPECT_LE(incremental.units(), previousUnits);
      previousUnits = incremental.units();
      // Every cut primitive's error, seen from the eye at its producer's
      // sphere, is within the tolerance.
      for (std::uint32_t p : incremental.primitives()) {
        const HybridPrimitive& prim = g.primitives()[p];
        if (prim.producer == HybridGraph::kDrain) continue;
        const HybridNode& node = g.nodes()[prim.producer];
        const double z = std::max(glm::length(node.sphereCentre - view.eye) - node.sphereRadius,
                                  view.nearDistance);
        EXPECT_LE(prim.error * view.pixelsPerRadian / z, tolerance * (1.0 + 1e-12));
      }
    }
  }
}

TEST(HybridAccuracyCurve, IsConservativeAndMonotone) {
  Result<HybridGraph> g = buildHybridGraph(generateScatteredParts(30, 1, 8), options(3.0, 1.0));
  ASSERT_TRUE(g.ok());
  Result<AccuracyCurve> curve = hybridAccuracyCurve(*g, 1e-4, 8);
  ASSERT_TRUE(curve.ok()) << curve.status().toString();
  for (const HybridCurveStep& s : g->unitsVersusError()) {
    const double a = g->diagonal() / std::max(s.error, 1e-4 * g->diagonal());
    // The curve never promises an accuracy for fewer units than measured.
    EXPECT_GE(curve->resourcesFor(a), s.units * (1.0 - 1e-9));
  }
  EXPECT_EQ(hybridAccuracyCurve(*g, 0.0).status().code(), ErrorCode::kInvalidArgument);
}

// The measured ladder: increasing units ending at the input, each rung a
// step of the graph's curve with its cut's own sampled error (measured again
// here from scratch), never above the rung's stored bound.
TEST(HybridMeasuredLevels, RungsAreStepsWithTheirCutsMeasuredError) {
  const IndexedMesh parts = generateScatteredParts(30, 1, 8);
  Result<HybridGraph> g = buildHybridGraph(parts, options(3.0, 1.0));
  ASSERT_TRUE(g.ok());
  SurfaceErrorOptions eo;
  eo.samplesPerMesh = 5000;
  Result<std::vector<HybridMeasuredLevel>> levels = measureHybridLevels(parts, *g, 6, eo);
  ASSERT_TRUE(levels.ok()) << levels.status().toString();
  ASSERT_GE(levels->size(), 3u);
  EXPECT_LE(levels->size(), 7u) << "6 rungs and the input at most";
  const std::vector<HybridCurveStep> steps = g->unitsVersusError();
  EXPECT_EQ(levels->back().step.units, steps.front().units) << "the last rung is the input";
  EXPECT_EQ(levels->front().step.units, steps.back().units) << "the first the coarsest cut";
  HybridCut incremental(*g);  // adapted rung to rung, as measureHybridLevels does
  for (std::size_t i = 0; i < levels->size(); ++i) {
    const HybridMeasuredLevel& level = (*levels)[i];
    if (i > 0) {
      EXPECT_GT(level.step.units, (*levels)[i - 1].step.units);
    }
    HybridCut fresh(*g);
    fresh.adaptToError(level.step.error);
    incremental.adaptToError(level.step.error);
    EXPECT_DOUBLE_EQ(fresh.units(), level.step.units);
    EXPECT_EQ(cutSet(incremental), cutSet(fresh));
    Result<SurfaceError> again = measureHybridSurfaceError(parts, incremental.triangleMesh(),
                                                           incremental.pointList(), eo);
    ASSERT_TRUE(again.ok());
    EXPECT_DOUBLE_EQ(again->max(), level.measuredError);
    EXPECT_LE(level.measuredError, fresh.errorBound() + 1e-6 * g->diagonal());
  }
  EXPECT_EQ(measureHybridLevels(parts, *g, 0, eo).status().code(), ErrorCode::kInvalidArgument);
}

// The verified bound: sampled Hausdorff of random cuts <= stored bound.
void checkBoundsHold(const IndexedMesh& mesh, const HybridOptions& o, std::uint64_t seed,
                     int cuts) {
  Result<HybridGraph> built = buildHybridGraph(mesh, o);
  ASSERT_TRUE(built.ok()) << built.status().toString();
  const HybridGraph& g = *built;
  std::mt19937_64 rng(seed);
  SurfaceErrorOptions eo;
  eo.samplesPerMesh = 20000;
  eo.seed = seed;
  HybridCut cut(g);
  // Rounding of float inputs in double arithmetic: far below any bound.
  const double slack = 1e-6 * g.diagonal();
  // The source's sphere holds the whole model: views from just outside it.
  const HybridNode& all = g.nodes().back();
  for (int k = 0; k < cuts; ++k) {
    const double relative = std::pow(10.0, -3.5 + 3.0 * static_cast<double>(rng() % 1000) / 1000.0);
    if (k % 3 == 2) {
      // A view-dependent cut: fine near the eye, coarse far away.
      HybridView view;
      view.eye = all.sphereCentre + glm::dvec3(1.2 * all.sphereRadius, 0.3 * all.sphereRadius, 0.0);
      view.pixelsPerRadian = 1000.0;
      view.nearDistance = 0.01 * all.sphereRadius;
      cut.adaptToScreen(view, 1000.0 * relative);
    } else {
      cut.adaptToError(relative * g.diagonal());
    }
    const IndexedMesh triangles = cut.triangleMesh();
    const std::vector<HybridPoint> points = cut.pointList();
    Result<SurfaceError> measured = measureHybridSurfaceError(mesh, triangles, points, eo);
    ASSERT_TRUE(measured.ok()) << measured.status().toString();
    EXPECT_LE(measured->max(), cut.errorBound() + slack)
        << "relative threshold " << relative << ", " << cut.triangleCount() << " triangles, "
        << cut.pointCount() << " points";
    if (points.empty()) {
      // Triangles only: the project's own sampled surface error agrees.
      Result<SurfaceError> plain = measureSurfaceError(mesh, triangles, eo);
      ASSERT_TRUE(plain.ok());
      EXPECT_LE(plain->max(), cut.errorBound() + slack);
    }
  }
}

TEST(HybridBounds, HoldOnTheBunny) {
  const IndexedMesh bunny = loadBunny();
  ASSERT_GT(bunny.triangleCount(), 60000u);
  checkBoundsHold(bunny, options(3.0, 5.0), 1, 5);
  checkBoundsHold(bunny, options(3.0, 1.0, false), 2, 4);
}

TEST(HybridBounds, HoldOnAMultiManifoldModel) {
  const IndexedMesh parts = generateScatteredParts(300, 1, 13);
  checkBoundsHold(parts, options(3.0, 1.0), 3, 6);
  checkBoundsHold(parts, options(10.0, 5.0), 4, 6);
  checkBoundsHold(parts, options(3.0, 1.0, false), 5, 4);
}

TEST(HybridBounds, HoldOnAnOpenSheet) {
  checkBoundsHold(makeBumpyGrid(30), options(3.0, 5.0), 6, 8);
}

TEST(HybridSurfaceError, DiscDistanceIsExact) {
  IndexedMesh square = makeBumpyGrid(1);
  for (auto& p : square.positions) p.z = 0.0f;
  HybridPoint disc;
  disc.centre = glm::dvec3(0.5, 0.5, 0.3);
  disc.radius = 0.25;
  IndexedMesh none;
  Result<SurfaceError> e = measureHybridSurfaceError(square, none, {disc}, {});
  ASSERT_TRUE(e.ok());
  // Disc -> square: every disc point is 0.3 above the square.
  EXPECT_NEAR(e->maxBackward, 0.3, 1e-9);
  // Square corner (0,0,0) -> disc rim: in-plane 0.5*sqrt(2) - 0.25, height 0.3.
  const double inPlane = 0.5 * std::sqrt(2.0) - 0.25;
  EXPECT_NEAR(e->maxForward, std::sqrt(inPlane * inPlane + 0.09), 1e-9);
  EXPECT_EQ(measureHybridSurfaceError(square, none, {}, {}).status().code(),
            ErrorCode::kInvalidArgument);
  disc.normal = glm::dvec3(0.0);
  EXPECT_EQ(measureHybridSurfaceError(square, none, {disc}, {}).status().code(),
            ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::simplifier
