// SimplifierService: ImpostorRequests on the paper room (offscreen GL).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

#include "service_test_util.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/conic_range.h"
#include "thinlod/simplifier/impostor_level.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier {
namespace {

using namespace testing_util;

// The room's entrance viewpoint: the cow is about 3 m ahead.
const glm::vec3 kEntrance{2.0f, 1.1f, 3.5f};

protocol::ImpostorRequest impostorOf(
    std::uint64_t object, protocol::RepresentationKind kind, std::uint32_t size = 128,
    protocol::TextureCodec codec = protocol::TextureCodec::kRawRgba8) {
  protocol::ImpostorRequest request;
  request.requestId = 9000 + object;
  request.objectIds = {object};
  request.eye = kEntrance;
  request.textureWidth = size;
  request.textureHeight = size;
  request.kind = kind;
  request.accuracyBound = 2e-3;
  request.textureCodec = codec;
  return request;
}

ServiceOptions withDefaultScene() {
  ServiceOptions options = roomOptions();
  options.defaultScenePath = roomScene();
  return options;
}

double coverage(const protocol::Texture& texture) {
  EXPECT_EQ(texture.codec, protocol::TextureCodec::kRawRgba8);
  std::size_t covered = 0;
  for (std::size_t i = 3; i < texture.data.size(); i += 4) covered += texture.data[i] != 0;
  return static_cast<double>(covered) / static_cast<double>(texture.width * texture.height);
}

bool borderEmpty(const protocol::Texture& texture) {
  const std::uint32_t w = texture.width;
  for (std::uint32_t i = 0; i < w; ++i) {
    for (std::uint32_t j : {0u, w - 1}) {
      if (texture.data[(j * w + i) * 4 + 3] != 0 || texture.data[(i * w + j) * 4 + 3] != 0) {
        return false;
      }
    }
  }
  return true;
}

ConicRange fromWire(const protocol::ConicRange& wire) {
  Result<ConicRange> range =
      ConicRange::make(glm::dvec3(wire.center), wire.distanceMin, wire.distanceMax,
                       glm::dvec3(wire.direction), wire.halfAngle);
  EXPECT_TRUE(range.ok()) << range.status().toString();
  return range.ok() ? *range : ConicRange::nowhere();
}

IndexedMesh decode(const protocol::Bytes& bytes) {
  Result<IndexedMesh> mesh = codec::decodeMesh(bytes.data(), bytes.size());
  EXPECT_TRUE(mesh.ok()) << mesh.status().toString();
  return mesh.ok() ? std::move(mesh).value() : IndexedMesh();
}

// The cow's world bounds from the scene file, with a little slack.
bool nearCow(const glm::vec3& p) {
  return p.x > 1.5f && p.x < 2.6f && p.y > -0.15f && p.y < 0.65f && p.z > 0.3f && p.z < 0.8f;
}

TEST(SimplifierServiceImpostor, SimpleImpostorOfTheCow) {
  SimplifierService service(withDefaultScene());
  const protocol::ImpostorResult result =
      service.renderImpostor(impostorOf(kCow, protocol::RepresentationKind::kSimpleImpostor));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.requestId, 9000 + kCow);
  EXPECT_EQ(result.objectIds, std::vector<std::uint64_t>{kCow});
  const protocol::Representation& rep = result.representation;
  EXPECT_EQ(rep.kind, protocol::RepresentationKind::kSimpleImpostor);
  EXPECT_EQ(rep.transform, glm::mat4(1.0f));
  ASSERT_EQ(rep.texture.width, 128u);
  ASSERT_EQ(rep.texture.data.size(), 128u * 128u * 4u);
  // The framing hugs the cow: a side view of a 0.8 x 0.49 m cow fills a good
  // part of the square, never its 1-texel border.
  const double covered = coverage(rep.texture);
  EXPECT_GT(covered, 0.2);
  EXPECT_LT(covered, 0.9);
  EXPECT_TRUE(borderEmpty(rep.texture));
  // The quad, in world space at the cow.
  const IndexedMesh quad = decode(rep.mesh);
  EXPECT_EQ(rep.triangleCount, 2u);
  EXPECT_EQ(quad.triangleCount(), 2u);
  for (const glm::vec3& p : quad.positions)
    EXPECT_TRUE(nearCow(p)) << p.x << " " << p.y << " " << p.z;
  EXPECT_TRUE(fromWire(rep.validity).containsPoint(glm::dvec3(kEntrance)));
  // About (cow size) / (2 texels): the quad is ~0.8 m over 128 texels.
  EXPECT_GT(rep.accuracy, 30.0);
  EXPECT_LT(rep.accuracy, 128.0);
}

// An imposter node's fixed size (paper Figure 9, autosize FALSE): the quad
// has that size; one that cuts the cow off credits the cut (a lower
// accuracy), one larger than the cow spreads it over fewer texels.
TEST(SimplifierServiceImpostor, AFixedFrameSizesTheQuadAndCreditsWhatItCutsOff) {
  SimplifierService service(withDefaultScene());
  const protocol::ImpostorRequest automatic =
      impostorOf(kCow, protocol::RepresentationKind::kSimpleImpostor);
  protocol::ImpostorRequest small = automatic;
  small.frameWidth = 0.4f;
  small.frameHeight = 0.25f;
  protocol::ImpostorRequest large = automatic;
  large.frameCenter = glm::vec3(2.06f, 0.25f, 0.55f);
  large.frameWidth = 2.0f;
  large.frameHeight = 2.0f;
  const protocol::ImpostorResult a = service.renderImpostor(automatic);
  const protocol::ImpostorResult s = service.renderImpostor(small);
  const protocol::ImpostorResult l = service.renderImpostor(large);
  ASSERT_TRUE(a.status.ok() && s.status.ok() && l.status.ok())
      << s.status.toString() << l.status.toString();
  auto width = [](const protocol::Representation& rep) {
    const IndexedMesh quad = decode(rep.mesh);
    float lo = 1e9f, hi = -1e9f;
    for (const glm::vec3& p : quad.positions) {
      lo = std::min(lo, p.x);
      hi = std::max(hi, p.x);
    }
    return hi - lo;  // the cow is seen from +z: the quad's width lies along x
  };
  EXPECT_NEAR(width(s.representation), 0.4f, 0.02f);
  EXPECT_NEAR(width(l.representation), 2.0f, 0.05f);
  // Cut off: about (0.8 - 0.4) / 2 m of the cow is missing from each side.
  EXPECT_LT(s.representation.accuracy, 0.5 * a.representation.accuracy);
  // Larger than the cow: no cut, coarser texels.
  EXPECT_LT(l.representation.accuracy, a.representation.accuracy);
  EXPECT_GT(l.representation.accuracy, 0.1 * a.representation.accuracy);
  EXPECT_LT(coverage(l.representation.texture), coverage(a.representation.texture));
}

// The daemon renders the cow from a coarser level (impostor_level.h): the
// texture stays within the stated tolerance of the full-mesh capture, the
// level is extracted once, and the reported accuracy D / (2 s + e) counts
// the level's error e <= s (so it lies in [2/3, 1) of the full one's).
TEST(SimplifierServiceImpostor, RendersFromALevelAndCountsItsError) {
  for (protocol::RepresentationKind kind : {protocol::RepresentationKind::kSimpleImpostor,
                                            protocol::RepresentationKind::kMeshedImpostor}) {
    SimplifierService levels(withDefaultScene());
    ServiceOptions fullOptions = withDefaultScene();
    fullOptions.impostorFromLevels = false;
    SimplifierService full(fullOptions);
    const protocol::ImpostorRequest request = impostorOf(kCow, kind, 256);
    const protocol::ImpostorResult fromLevel = levels.renderImpostor(request);
    const protocol::ImpostorResult fromFull = full.renderImpostor(request);
    ASSERT_TRUE(fromLevel.status.ok()) << fromLevel.status.toString();
    ASSERT_TRUE(fromFull.status.ok()) << fromFull.status.toString();
    EXPECT_EQ(levels.stats().impostorLevelsExtracted, 1u);
    EXPECT_EQ(full.stats().impostorLevelsExtracted, 0u);
    // Again: the kept level (and its GPU copy) is reused, the texture identical.
    const protocol::ImpostorResult again = levels.renderImpostor(request);
    ASSERT_TRUE(again.status.ok());
    EXPECT_EQ(levels.stats().impostorLevelsExtracted, 1u);
    EXPECT_EQ(again.representation.texture.data, fromLevel.representation.texture.data);

    RgbaImage a(256, 256);
    RgbaImage b(256, 256);
    a.pixels = fromFull.representation.texture.data;
    b.pixels = fromLevel.representation.texture.data;
    auto diff = compareImpostorTextures(a, b);
    ASSERT_TRUE(diff.ok()) << diff.status().toString();
    EXPECT_LE(diff->meanAbs, 1.0);
    EXPECT_LE(diff->coverageMismatch, diff->coveredEither / 50);  // <= 2 %
    const double ratio = fromLevel.representation.accuracy / fromFull.representation.accuracy;
    EXPECT_LT(ratio, 1.0);
    EXPECT_GE(ratio, 2.0 / 3.0 - 1e-9);
  }
}

TEST(SimplifierServiceImpostor, MeshedImpostorOfTheCow) {
  ServiceOptions options = withDefaultScene();
  options.meshedImpostorTriangles = 48;
  SimplifierService service(options);
  const protocol::ImpostorResult result =
      service.renderImpostor(impostorOf(kCow, protocol::RepresentationKind::kMeshedImpostor));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  const protocol::Representation& rep = result.representation;
  EXPECT_EQ(rep.kind, protocol::RepresentationKind::kMeshedImpostor);
  const IndexedMesh mesh = decode(rep.mesh);
  EXPECT_EQ(mesh.triangleCount(), rep.triangleCount);
  EXPECT_GT(rep.triangleCount, 4u);
  EXPECT_LE(rep.triangleCount, 48u);
  for (const glm::vec3& p : mesh.positions)
    EXPECT_TRUE(nearCow(p)) << p.x << " " << p.y << " " << p.z;
  EXPECT_EQ(mesh.uvs.size(), mesh.positions.size());
  EXPECT_GT(coverage(rep.texture), 0.2);
  const ConicRange validity = fromWire(rep.validity);
  EXPECT_TRUE(validity.containsPoint(glm::dvec3(kEntrance)));
  // A meshed impostor stays valid over a wider cone than a simple one.
  const protocol::ImpostorResult simple =
      service.renderImpostor(impostorOf(kCow, protocol::RepresentationKind::kSimpleImpostor));
  ASSERT_TRUE(simple.status.ok());
  EXPECT_GT(validity.alpha(), fromWire(simple.representation.validity).alpha());
}

TEST(SimplifierServiceImpostor, SphereImpostorsBothKinds) {
  SimplifierService service(withDefaultScene());
  for (auto kind : {protocol::RepresentationKind::kSimpleImpostor,
                    protocol::RepresentationKind::kMeshedImpostor}) {
    const protocol::ImpostorResult result =
        service.renderImpostor(impostorOf(kSphereRight, kind, 64));
    ASSERT_TRUE(result.status.ok()) << result.status.toString();
    // A sphere fills pi/4 of its square framing (less the padding).
    EXPECT_NEAR(coverage(result.representation.texture), 0.74, 0.06);
    EXPECT_TRUE(fromWire(result.representation.validity).containsPoint(glm::dvec3(kEntrance)));
  }
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 0u);  // primitives are tessellated
}

TEST(SimplifierServiceImpostor, SeveralObjectsInOneImpostor) {
  SimplifierService service(withDefaultScene());
  protocol::ImpostorRequest request =
      impostorOf(kSphereLeft, protocol::RepresentationKind::kSimpleImpostor);
  request.objectIds = {kSphereLeft, kColumn};
  const protocol::ImpostorResult result = service.renderImpostor(request);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.objectIds, request.objectIds);
  EXPECT_GT(coverage(result.representation.texture), 0.1);
}

TEST(SimplifierServiceImpostor, TextureCodecsDecode) {
  SimplifierService service(withDefaultScene());
  for (auto codec : {protocol::TextureCodec::kPng, protocol::TextureCodec::kZstd}) {
    const protocol::ImpostorResult result = service.renderImpostor(
        impostorOf(kCow, protocol::RepresentationKind::kSimpleImpostor, 64, codec));
    ASSERT_TRUE(result.status.ok()) << result.status.toString();
    const protocol::Texture& texture = result.representation.texture;
    EXPECT_EQ(texture.codec, codec);
    Result<RgbaImage> decoded = codec::decodeTexture(texture.data.data(), texture.data.size());
    ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
    EXPECT_EQ(decoded->width, 64);
    EXPECT_EQ(decoded->height, 64);
  }
}

TEST(SimplifierServiceImpostor, JpegFallsBackToPngForTransparentTextures) {
  SimplifierService service(withDefaultScene());
  const protocol::ImpostorResult result = service.renderImpostor(impostorOf(
      kCow, protocol::RepresentationKind::kSimpleImpostor, 64, protocol::TextureCodec::kJpeg));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.representation.texture.codec, protocol::TextureCodec::kPng);
}

TEST(SimplifierServiceImpostor, SmallerTexturesSupportLessAccuracy) {
  SimplifierService service(withDefaultScene());
  const protocol::ImpostorResult big =
      service.renderImpostor(impostorOf(kCow, protocol::RepresentationKind::kSimpleImpostor, 256));
  const protocol::ImpostorResult small =
      service.renderImpostor(impostorOf(kCow, protocol::RepresentationKind::kSimpleImpostor, 32));
  ASSERT_TRUE(big.status.ok());
  ASSERT_TRUE(small.status.ok());
  EXPECT_GT(big.representation.accuracy, 4.0 * small.representation.accuracy);
}

TEST(SimplifierServiceImpostor, UsesTheLastSceneWithoutADefault) {
  SimplifierService service(roomOptions());
  const protocol::ImpostorRequest request =
      impostorOf(kSphereLeft, protocol::RepresentationKind::kSimpleImpostor);
  EXPECT_EQ(service.renderImpostor(request).status.code(), ErrorCode::kUnavailable);
  ASSERT_TRUE(service.simplify(triangles(kSphereLeft, 100)).status.ok());
  EXPECT_TRUE(service.renderImpostor(request).status.ok());
}

TEST(SimplifierServiceImpostorErrors, BadRequestsGetErrorResults) {
  SimplifierService service(withDefaultScene());
  using Kind = protocol::RepresentationKind;
  auto code = [&](const protocol::ImpostorRequest& request) {
    const protocol::ImpostorResult result = service.renderImpostor(request);
    EXPECT_TRUE(result.representation.mesh.empty());
    return result.status.code();
  };
  protocol::ImpostorRequest request = impostorOf(kCow, Kind::kSimpleImpostor);
  request.kind = Kind::kMesh;
  EXPECT_EQ(code(request), ErrorCode::kInvalidArgument);
  request = impostorOf(99, Kind::kSimpleImpostor);
  EXPECT_EQ(code(request), ErrorCode::kNotFound);
  request = impostorOf(kCow, Kind::kSimpleImpostor);
  request.objectIds = {kCow, kCow};
  EXPECT_EQ(code(request), ErrorCode::kInvalidArgument);
  request = impostorOf(kCow, Kind::kSimpleImpostor);
  request.objectIds.clear();
  EXPECT_EQ(code(request), ErrorCode::kInvalidArgument);
  request = impostorOf(kCow, Kind::kSimpleImpostor);
  request.textureHeight = 64;
  EXPECT_EQ(code(request), ErrorCode::kUnsupported);
  request = impostorOf(kCow, Kind::kSimpleImpostor, 4);
  EXPECT_EQ(code(request), ErrorCode::kInvalidArgument);
  request = impostorOf(kCow, Kind::kSimpleImpostor, 8192);
  EXPECT_EQ(code(request), ErrorCode::kResourceExhausted);
  request = impostorOf(kCow, Kind::kSimpleImpostor);
  request.accuracyBound = 0.0;
  EXPECT_EQ(code(request), ErrorCode::kInvalidArgument);
  request.accuracyBound = std::nan("");
  EXPECT_FALSE(service.renderImpostor(request).status.ok());
  request = impostorOf(kCow, Kind::kSimpleImpostor);
  request.eye = glm::vec3(2.0f, 0.25f, 0.55f);  // inside the cow
  EXPECT_EQ(code(request), ErrorCode::kInvalidArgument);
  request.eye = glm::vec3(NAN, 0.0f, 0.0f);
  EXPECT_FALSE(service.renderImpostor(request).status.ok());
  request = impostorOf(kCow, Kind::kSimpleImpostor);
  request.textureCodec = protocol::TextureCodec::kNone;
  EXPECT_FALSE(service.renderImpostor(request).status.ok());
  // Still serving.
  EXPECT_TRUE(service.renderImpostor(impostorOf(kCow, Kind::kSimpleImpostor)).status.ok());
}

}  // namespace
}  // namespace thinlod::simplifier
