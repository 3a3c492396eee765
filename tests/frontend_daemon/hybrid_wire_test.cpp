// Wire Hybrid representation -> frontend: decoded triangles and discs whose
// counts match the announced ones, or an error.
#include <gtest/gtest.h>

#include "daemon_test_util.h"
#include "thinlod/common/codec/encoding.h"
#include "wire_conversion.h"

namespace thinlod::frontend::daemon {
namespace {

protocol::Representation hybridWire(bool withTriangles, std::size_t points) {
  HybridGeometry g;
  if (withTriangles) g.triangles = testing::sphereMesh(1.0f, 8, 4);
  for (std::size_t i = 0; i < points; ++i) {
    g.points.centres.emplace_back(0.1f * i, 0.0f, 1.5f);
    g.points.normals.emplace_back(0.0f, 0.0f, 1.0f);
    g.points.radii.push_back(0.05f);
    g.points.colors.push_back({200, 100, 50, 255});
  }
  Result<std::vector<std::uint8_t>> frame = codec::encodeHybrid(g);
  EXPECT_TRUE(frame.ok()) << frame.status().toString();
  protocol::Representation wire;
  wire.kind = protocol::RepresentationKind::kHybrid;
  wire.mesh = frame.ok() ? *frame : std::vector<std::uint8_t>{};
  wire.triangleCount = withTriangles ? static_cast<std::uint32_t>(g.triangles.triangleCount()) : 0;
  wire.pointCount = static_cast<std::uint32_t>(points);
  return wire;
}

TEST(HybridWireConversion, TrianglesAndDiscsDecode) {
  auto rep = convertRepresentation(hybridWire(true, 12), 5, {}, "op");
  ASSERT_TRUE(rep.ok()) << rep.status().toString();
  EXPECT_EQ(rep->kind, RepresentationKind::kHybrid);
  ASSERT_NE(rep->mesh, nullptr);
  ASSERT_NE(rep->points, nullptr);
  EXPECT_EQ(rep->points->size(), 12u);
  EXPECT_TRUE(rep->points->validate("points").ok());
  EXPECT_EQ(rep->texture, nullptr);
}

TEST(HybridWireConversion, PointsOnlyHasNoMesh) {
  auto rep = convertRepresentation(hybridWire(false, 7), 5, {}, "op");
  ASSERT_TRUE(rep.ok()) << rep.status().toString();
  EXPECT_EQ(rep->mesh, nullptr);
  ASSERT_NE(rep->points, nullptr);
  EXPECT_EQ(rep->points->size(), 7u);
}

TEST(HybridWireConversion, WrongCountsAndMeshFramesAreRejected) {
  protocol::Representation wire = hybridWire(true, 12);
  wire.pointCount = 11;
  EXPECT_EQ(convertRepresentation(wire, 5, {}, "op").status().code(), ErrorCode::kInvalidArgument);
  wire = hybridWire(true, 12);
  wire.triangleCount += 1;
  EXPECT_EQ(convertRepresentation(wire, 5, {}, "op").status().code(), ErrorCode::kInvalidArgument);
  // A plain mesh frame is not a hybrid frame.
  Result<std::vector<std::uint8_t>> mesh = codec::encodeMesh(testing::sphereMesh(1.0f, 8, 4));
  ASSERT_TRUE(mesh.ok());
  wire.mesh = *mesh;
  EXPECT_EQ(convertRepresentation(wire, 5, {}, "op").status().code(), ErrorCode::kParseError);
  wire.mesh.clear();
  EXPECT_EQ(convertRepresentation(wire, 5, {}, "op").status().code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::frontend::daemon
