// Hybrid (triangles + disc points) link frames: round trips within the
// quantization bound, both parts optional, header/part validation, and the
// memory-safety sweep (every prefix, random corruptions with the checksum
// resealed so Draco sees the damage). Fuzz entry: fuzz/codec_hybrid_frame.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <random>
#include <vector>

#include "test_meshes.h"
#include "thinlod/common/codec/encoding.h"

namespace thinlod::codec {
namespace {

using Bytes = std::vector<std::uint8_t>;

DiscPoints randomPoints(std::size_t n, std::uint32_t seed, bool normals) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  DiscPoints points;
  for (std::size_t i = 0; i < n; ++i) {
    points.centres.emplace_back(u(rng), u(rng), 0.5f * u(rng));
    if (normals) {
      glm::vec3 nrm(u(rng), u(rng), u(rng) + 2.0f);
      points.normals.push_back(glm::normalize(nrm));
    }
    points.radii.push_back(0.01f + 0.05f * (u(rng) + 1.0f));
    points.colors.push_back({static_cast<std::uint8_t>(i * 13), static_cast<std::uint8_t>(i * 7),
                             static_cast<std::uint8_t>(255 - i), 255});
  }
  return points;
}

HybridGeometry geometry(std::size_t points, bool normals = true) {
  HybridGeometry g;
  g.triangles = thinlod::testing::makeIcosphere(2, 1.0f);
  g.points = randomPoints(points, 7, normals);
  return g;
}

void resealFrame(Bytes& frame) {
  const std::uint32_t payload = static_cast<std::uint32_t>(frame.size() - kFrameHeaderBytes);
  for (int i = 0; i < 4; ++i) frame[16 + i] = static_cast<std::uint8_t>(payload >> (8 * i));
  const std::uint64_t sum = frameChecksum(frame.data() + kFrameHeaderBytes, payload);
  for (int i = 0; i < 8; ++i) frame[24 + i] = static_cast<std::uint8_t>(sum >> (8 * i));
}

// Each original point has a decoded point with the same radius and colour
// within `bound` of its centre (Draco reorders points).
void expectPointsMatch(const DiscPoints& original, const DiscPoints& decoded, double bound) {
  ASSERT_EQ(decoded.size(), original.size());
  std::vector<bool> used(decoded.size(), false);
  for (std::size_t i = 0; i < original.size(); ++i) {
    std::size_t best = decoded.size();
    double bestDistance = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < decoded.size(); ++j) {
      if (used[j] || decoded.radii[j] != original.radii[i] ||
          decoded.colors[j] != original.colors[i]) {
        continue;
      }
      const double d = glm::length(glm::dvec3(decoded.centres[j] - original.centres[i]));
      if (d < bestDistance) bestDistance = d, best = j;
    }
    ASSERT_LT(best, decoded.size()) << "point " << i << " lost its radius/colour";
    EXPECT_LE(bestDistance, bound * (1.0 + 1e-5) + 1e-7) << "point " << i;
    used[best] = true;
    if (!original.normals.empty()) {
      EXPECT_GT(glm::dot(decoded.normals[best], original.normals[i]), 0.99f);
    }
  }
}

TEST(HybridEncoding, RoundTripsTrianglesAndPointsWithinTheQuantizationBound) {
  const HybridGeometry input = geometry(300);
  MeshEncodeOptions options;
  options.positionBits = 11;
  Result<Bytes> frame = encodeHybrid(input, options);
  ASSERT_TRUE(frame.ok()) << frame.status().toString();
  Result<HybridGeometry> decoded = decodeHybrid(frame->data(), frame->size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  EXPECT_EQ(decoded->triangles.triangleCount(), input.triangles.triangleCount());
  EXPECT_TRUE(decoded->triangles.validate("decoded").ok());
  expectPointsMatch(input.points, decoded->points, pointPositionErrorBound(input.points, 11));
}

TEST(HybridEncoding, PointsOnlyAndTrianglesOnlyFramesRoundTrip) {
  HybridGeometry pointsOnly;
  pointsOnly.points = randomPoints(50, 3, false);
  Result<Bytes> a = encodeHybrid(pointsOnly);
  ASSERT_TRUE(a.ok()) << a.status().toString();
  Result<HybridGeometry> da = decodeHybrid(a->data(), a->size());
  ASSERT_TRUE(da.ok()) << da.status().toString();
  EXPECT_EQ(da->triangles.triangleCount(), 0u);
  EXPECT_TRUE(da->points.normals.empty());
  expectPointsMatch(pointsOnly.points, da->points, pointPositionErrorBound(pointsOnly.points, 14));

  HybridGeometry trianglesOnly = geometry(0);
  Result<Bytes> b = encodeHybrid(trianglesOnly);
  ASSERT_TRUE(b.ok()) << b.status().toString();
  Result<HybridGeometry> db = decodeHybrid(b->data(), b->size());
  ASSERT_TRUE(db.ok()) << db.status().toString();
  EXPECT_EQ(db->triangles.triangleCount(), trianglesOnly.triangles.triangleCount());
  EXPECT_TRUE(db->points.empty());
}

TEST(HybridEncoding, SinglePointAndCoincidentPointsSurvive) {
  HybridGeometry g;
  g.points = randomPoints(1, 5, true);
  Result<Bytes> one = encodeHybrid(g);
  ASSERT_TRUE(one.ok()) << one.status().toString();
  Result<HybridGeometry> d1 = decodeHybrid(one->data(), one->size());
  ASSERT_TRUE(d1.ok()) << d1.status().toString();
  expectPointsMatch(g.points, d1->points, 1e-6);

  g.points = randomPoints(20, 5, true);
  for (glm::vec3& c : g.points.centres) c = glm::vec3(3.0f, -2.0f, 1e4f);  // zero extent
  Result<Bytes> same = encodeHybrid(g);
  ASSERT_TRUE(same.ok()) << same.status().toString();
  Result<HybridGeometry> d2 = decodeHybrid(same->data(), same->size());
  ASSERT_TRUE(d2.ok()) << d2.status().toString();
  expectPointsMatch(g.points, d2->points, 1e-6 * 1e4);
}

TEST(HybridEncoding, RejectsInvalidGeometry) {
  HybridGeometry empty;
  EXPECT_EQ(encodeHybrid(empty).status().code(), ErrorCode::kInvalidArgument);
  HybridGeometry g = geometry(10);
  g.points.radii[3] = 0.0f;
  EXPECT_EQ(encodeHybrid(g).status().code(), ErrorCode::kInvalidArgument);
  g = geometry(10);
  g.points.radii[2] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(encodeHybrid(g).status().code(), ErrorCode::kInvalidArgument);
  g = geometry(10);
  g.points.centres[1].y = std::numeric_limits<float>::infinity();
  EXPECT_EQ(encodeHybrid(g).status().code(), ErrorCode::kInvalidArgument);
  g = geometry(10);
  g.points.colors.pop_back();
  EXPECT_EQ(encodeHybrid(g).status().code(), ErrorCode::kInvalidArgument);
  g = geometry(10);
  MeshEncodeOptions bad;
  bad.positionBits = 30;
  EXPECT_EQ(encodeHybrid(g, bad).status().code(), ErrorCode::kInvalidArgument);
  g.triangles = IndexedMesh();
  EXPECT_EQ(encodeHybrid(g, bad).status().code(), ErrorCode::kInvalidArgument);
}

TEST(HybridEncoding, RejectsAMeshFrameAndForeignHeaders) {
  Result<Bytes> mesh = encodeMesh(thinlod::testing::makeIcosphere(1, 1.0f));
  ASSERT_TRUE(mesh.ok());
  EXPECT_EQ(decodeHybrid(mesh->data(), mesh->size()).status().code(), ErrorCode::kParseError);

  Result<Bytes> frame = encodeHybrid(geometry(40));
  ASSERT_TRUE(frame.ok());
  Bytes badCodec = *frame;
  badCodec[6] = 9;
  EXPECT_EQ(decodeHybrid(badCodec.data(), badCodec.size()).status().code(),
            ErrorCode::kUnsupported);
  Bytes badAttributes = *frame;
  badAttributes[20] = 6;
  EXPECT_EQ(decodeHybrid(badAttributes.data(), badAttributes.size()).status().code(),
            ErrorCode::kUnsupported);
  Bytes version = *frame;
  version[4] = 77;
  EXPECT_EQ(decodeHybrid(version.data(), version.size()).status().code(),
            ErrorCode::kVersionMismatch);

  DecodeLimits limits;
  limits.maxPoints = 39;
  EXPECT_EQ(decodeHybrid(frame->data(), frame->size(), limits).status().code(),
            ErrorCode::kResourceExhausted);

  // Header counts that disagree with the parts (checksum resealed).
  Bytes morePoints = *frame;
  morePoints[8] = 41;
  EXPECT_EQ(decodeHybrid(morePoints.data(), morePoints.size()).status().code(),
            ErrorCode::kParseError);
  Bytes noTriangles = *frame;
  for (int i = 12; i < 16; ++i) noTriangles[i] = 0;
  EXPECT_EQ(decodeHybrid(noTriangles.data(), noTriangles.size()).status().code(),
            ErrorCode::kParseError);
  Bytes hugeMeshPart = *frame;
  hugeMeshPart[kFrameHeaderBytes + 3] = 0x7f;
  resealFrame(hugeMeshPart);
  EXPECT_EQ(decodeHybrid(hugeMeshPart.data(), hugeMeshPart.size()).status().code(),
            ErrorCode::kParseError);
}

TEST(HybridEncoding, EveryPrefixAndRandomCorruptionIsAnErrorOrValid) {
  Result<Bytes> frame = encodeHybrid(geometry(120));
  ASSERT_TRUE(frame.ok());
  for (std::size_t n = 0; n < frame->size(); ++n) {
    EXPECT_FALSE(decodeHybrid(frame->data(), n).ok()) << "prefix " << n;
  }
  std::mt19937 rng(1234);
  int decodedOk = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    Bytes damaged = *frame;
    const int flips = 1 + static_cast<int>(rng() % 8);
    for (int f = 0; f < flips; ++f) {
      const std::size_t at = kFrameHeaderBytes + rng() % (damaged.size() - kFrameHeaderBytes);
      damaged[at] = static_cast<std::uint8_t>(rng());
    }
    resealFrame(damaged);
    Result<HybridGeometry> decoded = decodeHybrid(damaged.data(), damaged.size());
    if (decoded.ok()) {
      ++decodedOk;
      EXPECT_TRUE(decoded->triangles.validate("decoded").ok());
      EXPECT_TRUE(decoded->points.validate("decoded").ok());
      EXPECT_EQ(decoded->points.size(), 120u);
    }
  }
  // Not an assertion on Draco's robustness, only that the sweep ran.
  RecordProperty("decodedAfterCorruption", decodedOk);
}

}  // namespace
}  // namespace thinlod::codec
