// ProgressiveMesh on textured meshes with uv seams (BuildOptions::preserveSeams):
// the two sides of a seam stay paired at every resolution, chart borders stay
// where they were in uv space, and seam ends and chart corners never move.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <map>
#include <set>
#include <tuple>

#include "qem_test_meshes.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::simplifier {
namespace {

using qemtest::ChartedSphere;
using qemtest::makeChartedSphere;
using qemtest::makeGrid;

ProgressiveMesh buildOrDie(const IndexedMesh& mesh, const BuildOptions& options = {}) {
  Result<ProgressiveMesh> pm = ProgressiveMesh::build(mesh, options);
  EXPECT_TRUE(pm.ok()) << pm.status().toString();
  return pm.ok() ? std::move(pm.value()) : ProgressiveMesh();
}

using Place = std::array<float, 3>;
Place placeOf(const glm::vec3& p) { return {p.x, p.y, p.z}; }

// Edges between places (positions), with the number of triangles on each:
// a mesh whose seams are intact is closed here even though its vertex
// edges along the seams are borders.
std::map<std::pair<Place, Place>, int> placeEdgeCounts(const IndexedMesh& mesh) {
  std::map<std::pair<Place, Place>, int> counts;
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      Place a = placeOf(mesh.positions[mesh.indices[t + k]]);
      Place b = placeOf(mesh.positions[mesh.indices[t + (k + 1) % 3]]);
      if (b < a) std::swap(a, b);
      ++counts[{a, b}];
    }
  }
  return counts;
}

// Place edges not used by exactly two triangles (an open or torn seam
// shows up here).
int tornPlaceEdges(const IndexedMesh& mesh) {
  int torn = 0;
  for (const auto& [edge, count] : placeEdgeCounts(mesh)) torn += count != 2 ? 1 : 0;
  return torn;
}

// Input vertex with the same position and uv as each output vertex (the
// progressive mesh substitutes vertices, it never invents one).
std::vector<std::uint32_t> sourceVertices(const IndexedMesh& out, const IndexedMesh& in) {
  std::map<std::tuple<float, float, float, float, float>, std::uint32_t> index;
  for (std::uint32_t v = 0; v < in.vertexCount(); ++v) {
    const glm::vec3& p = in.positions[v];
    index.emplace(std::make_tuple(p.x, p.y, p.z, in.uvs[v].x, in.uvs[v].y), v);
  }
  std::vector<std::uint32_t> source;
  for (std::uint32_t v = 0; v < out.vertexCount(); ++v) {
    const glm::vec3& p = out.positions[v];
    auto it = index.find(std::make_tuple(p.x, p.y, p.z, out.uvs[v].x, out.uvs[v].y));
    source.push_back(it == index.end() ? UINT32_MAX : it->second);
  }
  return source;
}

// Which sides of its island rectangle a uv lies on (bit 0: left, 1: right,
// 2: bottom, 3: top); 0 inside.
unsigned islandSides(const ChartedSphere& sphere, std::uint32_t chart, const glm::vec2& uv) {
  const float cell = 1.0f / static_cast<float>(sphere.atlasColumns);
  const glm::vec2 lo(static_cast<float>(chart % sphere.atlasColumns) * cell + sphere.padding,
                     static_cast<float>(chart / sphere.atlasColumns) * cell + sphere.padding);
  const glm::vec2 hi = lo + glm::vec2(cell - 2.0f * sphere.padding);
  constexpr float kTolerance = 1e-6f;
  unsigned sides = 0;
  if (std::abs(uv.x - lo.x) <= kTolerance) sides |= 1u;
  if (std::abs(uv.x - hi.x) <= kTolerance) sides |= 2u;
  if (std::abs(uv.y - lo.y) <= kTolerance) sides |= 4u;
  if (std::abs(uv.y - hi.y) <= kTolerance) sides |= 8u;
  return sides;
}

double uvArea(const IndexedMesh& mesh, std::size_t t) {
  const glm::vec2 a = mesh.uvs[mesh.indices[t]];
  const glm::vec2 e1 = mesh.uvs[mesh.indices[t + 1]] - a, e2 = mesh.uvs[mesh.indices[t + 2]] - a;
  return 0.5 * static_cast<double>(e1.x * e2.y - e1.y * e2.x);
}

class ChartedSphereSeams : public ::testing::TestWithParam<double> {};

TEST_P(ChartedSphereSeams, SidesStayPairedAndChartBordersStayOnThemselves) {
  const ChartedSphere sphere = makeChartedSphere(2, 12, 0.08f);
  const IndexedMesh& input = sphere.mesh;
  ASSERT_EQ(tornPlaceEdges(input), 0) << "the fixture is closed by place";
  const ProgressiveMesh pm = buildOrDie(input);
  const std::size_t target =
      static_cast<std::size_t>(GetParam() * static_cast<double>(input.triangleCount()));
  const IndexedMesh out = pm.extract(target);
  SCOPED_TRACE(std::to_string(out.triangleCount()) + " triangles of " +
               std::to_string(input.triangleCount()));
  ASSERT_LE(out.triangleCount(), std::max<std::size_t>(target, pm.minTriangles()));
  ASSERT_GT(out.triangleCount(), 0u);
  ASSERT_EQ(out.uvs.size(), out.positions.size());

  // 1. The sides of every seam are still paired: closed by place.
  EXPECT_EQ(tornPlaceEdges(out), 0);

  // 2. Every vertex is an input vertex with its own uv.
  const std::vector<std::uint32_t> source = sourceVertices(out, input);
  for (std::uint32_t v = 0; v < out.vertexCount(); ++v) {
    ASSERT_NE(source[v], UINT32_MAX) << "vertex " << v << " is not an input (position, uv)";
  }

  // 3. Every triangle stays inside one chart, and every border edge of a
  //    chart (vertex edge with one triangle) runs along one side of the
  //    chart's island: the uv chart boundary is a sub-polyline of the
  //    input's, deviation 0 (tolerance 1e-6 uv).
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> vertexEdges;
  std::vector<double> areaPerChart(6 * 2 * 2, 0.0);
  for (std::size_t t = 0; t < out.indices.size(); t += 3) {
    const std::uint32_t chart = sphere.chartOf[source[out.indices[t]]];
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(sphere.chartOf[source[out.indices[t + k]]], chart) << "triangle " << t / 3;
      std::uint32_t a = out.indices[t + k], b = out.indices[t + (k + 1) % 3];
      if (b < a) std::swap(a, b);
      ++vertexEdges[{a, b}];
    }
    const double area = uvArea(out, t);
    EXPECT_GT(area, 0.0) << "triangle " << t / 3 << " folds over in uv space";
    areaPerChart[chart] += area;
  }
  int borderEdges = 0;
  for (const auto& [edge, count] : vertexEdges) {
    if (count != 1) continue;
    ++borderEdges;
    const std::uint32_t chart = sphere.chartOf[source[edge.first]];
    const unsigned common = islandSides(sphere, chart, out.uvs[edge.first]) &
                            islandSides(sphere, chart, out.uvs[edge.second]);
    EXPECT_NE(common, 0u) << "border edge " << edge.first << "-" << edge.second
                          << " leaves its chart's border";
  }
  EXPECT_GT(borderEdges, 0);
  // Border unchanged, no fold-over: each chart still covers its whole island.
  const double cell = 1.0 / sphere.atlasColumns;
  const double island = (cell - 2.0 * sphere.padding) * (cell - 2.0 * sphere.padding);
  for (double area : areaPerChart) EXPECT_NEAR(area, island, 1e-4 * island);

  // 4. Texels stay nearer their place than with the seams welded: the
  //    texture displacement (how far from its place on the input a texel
  //    is drawn) against the same count welded by position alone. It is
  //    not bounded by the geometric error: collapses inside a chart bend
  //    its piecewise-linear uv map, so texels slide along the surface.
  BuildOptions weldedOptions;
  weldedOptions.preserveSeams = false;
  const IndexedMesh welded = buildOrDie(input, weldedOptions).extract(target);
  UvErrorOptions options;
  options.samples = 20000;
  Result<UvError> error = measureUvError(input, out, options);
  Result<UvError> weldedError = measureUvError(input, welded, options);
  ASSERT_TRUE(error.ok() && weldedError.ok()) << error.status().toString();
  SurfaceErrorOptions geometric;
  geometric.samplesPerMesh = 20000;
  Result<SurfaceError> distance = measureSurfaceError(input, out, geometric);
  ASSERT_TRUE(distance.ok());
  std::cout << "[ seams ] " << out.triangleCount() << " triangles: Hausdorff " << distance->max()
            << ", texture displacement mean " << error->meanDisplacement << " p95 "
            << error->p95Displacement << " max " << error->maxDisplacement << " (welded: mean "
            << weldedError->meanDisplacement << " max " << weldedError->maxDisplacement
            << "), uv distance p95 " << error->p95Uv << " max " << error->maxUv << "\n";
  EXPECT_GE(error->maxDisplacement, distance->maxBackward * (1.0 - 1e-6))
      << "a texel's place is on the input surface";
  EXPECT_LT(error->meanDisplacement, 0.25 * weldedError->meanDisplacement);
  EXPECT_LT(error->maxDisplacement, 0.25 * weldedError->maxDisplacement);
}

INSTANTIATE_TEST_SUITE_P(Ratios, ChartedSphereSeams, ::testing::Values(0.5, 0.1, 0.01));

TEST(ProgressiveMeshSeams, WeldingByPositionAloneTearsTheTextureThatSeamsKeep) {
  // What the progressive mesh did before preserveSeams: welded every place
  // into one vertex with the first side's uv, so triangles on the other
  // sides of a seam interpolate across the atlas.
  const ChartedSphere sphere = makeChartedSphere(2, 12, 0.08f);
  BuildOptions welded;
  welded.preserveSeams = false;
  const ProgressiveMesh plain = buildOrDie(sphere.mesh, welded);
  const ProgressiveMesh seams = buildOrDie(sphere.mesh);
  EXPECT_LT(plain.vertexCount(), seams.vertexCount());
  EXPECT_EQ(seams.vertexCount(), sphere.mesh.vertexCount()) << "no vertex welded away";
  UvErrorOptions options;
  options.samples = 20000;
  for (std::size_t target : {sphere.mesh.triangleCount(), sphere.mesh.triangleCount() / 10}) {
    Result<UvError> plainError = measureUvError(sphere.mesh, plain.extract(target), options);
    Result<UvError> seamError = measureUvError(sphere.mesh, seams.extract(target), options);
    ASSERT_TRUE(plainError.ok() && seamError.ok());
    EXPECT_GT(plainError->meanUv, 10.0 * seamError->meanUv)
        << target << ": plain " << plainError->meanUv << " seams " << seamError->meanUv;
  }
  // At full resolution the kept seams lose nothing.
  Result<UvError> full = measureUvError(sphere.mesh, seams.extract(sphere.mesh.triangleCount()));
  ASSERT_TRUE(full.ok());
  EXPECT_LT(full->maxUv, 1e-5);
}

TEST(ProgressiveMeshSeams, TessellatedSphereKeepsItsMeridianSeamAndPoles) {
  // The primitive sphere: one meridian seam (u = 0 and u = 1 at one place)
  // and a fan of pole vertices, one per segment, all at one place.
  const IndexedMesh sphere = tessellate(PrimitiveShape::sphere(1.0f), TessellationParams{64, 32});
  const ProgressiveMesh pm = buildOrDie(sphere);
  for (double ratio : {0.1, 0.01}) {
    const IndexedMesh out =
        pm.extract(static_cast<std::size_t>(ratio * static_cast<double>(sphere.triangleCount())));
    SCOPED_TRACE(out.triangleCount());
    EXPECT_EQ(tornPlaceEdges(out), 0);
    // No triangle spans the seam (its uvs would run across the texture).
    for (std::size_t t = 0; t < out.indices.size(); t += 3) {
      for (int k = 0; k < 3; ++k) {
        const float du =
            std::abs(out.uvs[out.indices[t + k]].x - out.uvs[out.indices[t + (k + 1) % 3]].x);
        EXPECT_LT(du, 0.5f) << "triangle " << t / 3 << " crosses the seam";
      }
    }
    // Both poles are still there.
    int poles = 0;
    for (const glm::vec3& p : out.positions) poles += std::abs(std::abs(p.y) - 1.0f) < 1e-6f;
    EXPECT_GE(poles, 2);
  }
}

TEST(ProgressiveMeshSeams, TheClosedEndOfASeamNeverMoves) {
  // A slit in uv space: on a 16 x 16 grid the vertices of x = 0.5, y < 0.5
  // are split (left and right sides get uvs 0.1 apart); the slit ends at
  // (0.5, 0.5), where the sides join again.
  IndexedMesh grid = makeGrid(16);
  for (const glm::vec3& p : grid.positions) grid.uvs.emplace_back(p.x, p.y);
  IndexedMesh slit = grid;
  const std::uint32_t side = 17;  // vertices per row
  std::map<std::uint32_t, std::uint32_t> rightCopy;
  for (std::uint32_t y = 0; y < 8; ++y) {
    const std::uint32_t v = y * side + 8;
    rightCopy[v] = static_cast<std::uint32_t>(slit.positions.size());
    slit.positions.push_back(grid.positions[v]);
    slit.uvs.push_back(grid.uvs[v] + glm::vec2(0.1f, 0.0f));
  }
  // Triangles right of the slit use the copies.
  for (std::size_t t = 0; t < slit.indices.size(); t += 3) {
    float cx = 0.0f;
    for (int k = 0; k < 3; ++k) cx += grid.positions[grid.indices[t + k]].x / 3.0f;
    if (cx < 0.5f) continue;
    for (int k = 0; k < 3; ++k) {
      auto it = rightCopy.find(slit.indices[t + k]);
      if (it != rightCopy.end()) slit.indices[t + k] = it->second;
    }
  }
  const ProgressiveMesh pm = buildOrDie(slit);
  EXPECT_EQ(pm.vertexCount(), slit.vertexCount());
  for (std::size_t target : {std::size_t{50}, std::size_t{10}}) {
    const IndexedMesh out = pm.extract(target);
    SCOPED_TRACE(out.triangleCount());
    bool tip = false;
    for (const glm::vec3& p : out.positions) tip = tip || (p.x == 0.5f && p.y == 0.5f);
    EXPECT_TRUE(tip) << "the end of the slit moved";
    // Seam edges are still paired: every place edge on the slit (x = 0.5,
    // y < 0.5, inside the sheet) has two triangles.
    for (const auto& [edge, count] : placeEdgeCounts(out)) {
      const bool onSlit = edge.first[0] == 0.5f && edge.second[0] == 0.5f &&
                          edge.first[1] <= 0.5f && edge.second[1] <= 0.5f;
      if (onSlit && edge.first[1] > 0.0f) {
        EXPECT_EQ(count, 2);
      }
    }
    // And no triangle mixes the sides: one with the left side of a slit
    // place (uv = position) lies left of the slit, one with the right side
    // (uv shifted by 0.1) right of it.
    for (std::size_t t = 0; t < out.indices.size(); t += 3) {
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = out.indices[t + k];
        if (!(out.positions[v].x == 0.5f && out.positions[v].y < 0.5f)) continue;
        const bool right = out.uvs[v].x - out.positions[v].x > 0.05f;
        for (int j = 0; j < 3; ++j) {
          const float x = out.positions[out.indices[t + j]].x;
          if (right) {
            EXPECT_GE(x, 0.5f) << "triangle " << t / 3 << " mixes the slit's sides";
          } else {
            EXPECT_LE(x, 0.5f) << "triangle " << t / 3 << " mixes the slit's sides";
          }
        }
      }
    }
  }
}

TEST(ProgressiveMeshSeams, OnlyVerticesWithEqualAttributesAreWelded) {
  // Two triangles sharing an edge through four vertices: the shared corners
  // appear twice, once with equal uvs (welded) and once with other uvs.
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 0}, {1, 1}, {0.5f, 1}};
  m.indices = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(buildOrDie(m).vertexCount(), 5u);  // corner 3 welds onto 1, corner 5 stays apart
  BuildOptions byPosition;
  byPosition.preserveSeams = false;
  EXPECT_EQ(buildOrDie(m, byPosition).vertexCount(), 4u);
  // Colours split too.
  IndexedMesh c = m;
  c.uvs.clear();
  c.colors = {{0, 0, 0, 255}, {9, 9, 9, 255}, {0, 0, 0, 255},
              {9, 9, 9, 255}, {0, 0, 0, 255}, {1, 0, 0, 255}};
  EXPECT_EQ(buildOrDie(c).vertexCount(), 5u);
}

// BuildOptions::weldKeys (a skinned mesh's skins): coincident vertices whose
// keys differ stay apart, as seam sides, with or without preserveSeams;
// equal keys weld as before; a key per vertex or none.
TEST(ProgressiveMeshSeams, VerticesWithDifferentWeldKeysStayApart) {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(buildOrDie(m).vertexCount(), 4u);
  BuildOptions keyed;
  keyed.weldKeys = {7, 8, 9, 8, 7, 3};  // corner 3 welds onto 1, corner 5 stays apart
  EXPECT_EQ(buildOrDie(m, keyed).vertexCount(), 5u);
  keyed.preserveSeams = false;
  EXPECT_EQ(buildOrDie(m, keyed).vertexCount(), 5u);
  const ProgressiveMesh pm = buildOrDie(m, keyed);
  const IndexedMesh full = pm.extract(pm.maxTriangles());
  EXPECT_EQ(full.triangleCount(), 2u);
  // The two vertices at (0, 1, 0) are both there, at exactly that place.
  int atCorner = 0;
  for (const glm::vec3& p : full.positions) atCorner += p == glm::vec3(0, 1, 0);
  EXPECT_EQ(atCorner, 2);
  keyed.weldKeys.pop_back();
  Result<ProgressiveMesh> wrongSize = ProgressiveMesh::build(m, keyed);
  EXPECT_EQ(wrongSize.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(wrongSize.status().message().find("weld keys"), std::string::npos);
}

}  // namespace
}  // namespace thinlod::simplifier
