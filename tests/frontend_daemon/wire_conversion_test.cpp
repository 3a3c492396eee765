// Wire SceneUpdate -> frontend SceneBatch: decoded whole or rejected whole.
#include "wire_conversion.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <random>

#include "daemon_test_util.h"
#include "thinlod/frontend/frontend_scene.h"

namespace thinlod::frontend::daemon {
namespace {

using protocol::TextureCodec;
using testing::addOp;
using testing::encodeOrDie;
using testing::gradientTexture;
using testing::impostorRepresentation;
using testing::meshRepresentation;
using testing::quadMesh;
using testing::sphereMesh;
using testing::wireTexture;

const glm::mat4 kPlaced = glm::translate(glm::mat4(1.0f), glm::vec3(1.0f, 0.5f, -2.0f));

TEST(WireConversion, MeshDecodesWithTransformTrianglesAndSceneColour) {
  const IndexedMesh sphere = sphereMesh(0.3f, 16, 8);
  MeshColors colours{{7, glm::vec4(0.85f, 0.25f, 0.2f, 1.0f)}};
  ConversionOptions options;
  options.meshColors = &colours;
  auto rep = convertRepresentation(meshRepresentation(sphere, kPlaced), 7, options, "op");
  ASSERT_TRUE(rep.ok()) << rep.status().toString();
  EXPECT_EQ(rep->kind, RepresentationKind::kMesh);
  ASSERT_NE(rep->mesh, nullptr);
  EXPECT_EQ(rep->mesh->triangleCount(), sphere.triangleCount());
  EXPECT_EQ(rep->texture, nullptr);
  EXPECT_EQ(rep->transform, kPlaced);
  EXPECT_EQ(rep->color, glm::vec4(0.85f, 0.25f, 0.2f, 1.0f));
  // Draco moves vertices by at most its quantisation bound.
  const double bound = codec::positionErrorBound(sphere, codec::MeshEncodeOptions{}.positionBits);
  const Bounds decoded = rep->mesh->bounds();
  EXPECT_NEAR(decoded.max.x, 0.3f, bound + 1e-6);
  EXPECT_NEAR(decoded.min.y, -0.3f, bound + 1e-6);
}

TEST(WireConversion, MeshOfAnUnlistedObjectIsWhite) {
  MeshColors colours{{7, glm::vec4(0.5f)}};
  ConversionOptions options;
  options.meshColors = &colours;
  auto rep = convertRepresentation(meshRepresentation(sphereMesh(1.0f, 8, 4)), 8, options, "op");
  ASSERT_TRUE(rep.ok()) << rep.status().toString();
  EXPECT_EQ(rep->color, glm::vec4(1.0f));
}

TEST(WireConversion, MeshedImpostorDecodesTextureAndStaysWhite) {
  MeshColors colours{{3, glm::vec4(0.1f, 0.2f, 0.3f, 1.0f)}};
  ConversionOptions options;
  options.meshColors = &colours;
  const RgbaImage expected = gradientTexture(32, 32);
  for (TextureCodec codec : {TextureCodec::kPng, TextureCodec::kZstd, TextureCodec::kRawRgba8}) {
    SCOPED_TRACE(static_cast<int>(codec));
    auto rep = convertRepresentation(impostorRepresentation(codec), 3, options, "op");
    ASSERT_TRUE(rep.ok()) << rep.status().toString();
    EXPECT_EQ(rep->kind, RepresentationKind::kMeshedImpostor);
    EXPECT_EQ(rep->generation, 3u);
    EXPECT_EQ(rep->color, glm::vec4(1.0f));
    ASSERT_NE(rep->texture, nullptr);
    EXPECT_EQ(rep->texture->width, 32);
    EXPECT_EQ(rep->texture->height, 32);
    EXPECT_EQ(rep->texture->pixels, expected.pixels);  // lossless codecs
    ASSERT_NE(rep->mesh, nullptr);
    EXPECT_FALSE(rep->mesh->uvs.empty());
  }
}

TEST(WireConversion, JpegImpostorDecodesWithinItsLoss) {
  auto rep = convertRepresentation(impostorRepresentation(TextureCodec::kJpeg), 1, {}, "op");
  ASSERT_TRUE(rep.ok()) << rep.status().toString();
  const RgbaImage expected = gradientTexture(32, 32);
  ASSERT_EQ(rep->texture->pixels.size(), expected.pixels.size());
  int worst = 0;
  for (std::size_t i = 0; i < expected.pixels.size(); ++i) {
    worst = std::max(worst, std::abs(int(rep->texture->pixels[i]) - int(expected.pixels[i])));
  }
  EXPECT_LE(worst, 24);  // q85 on a smooth gradient
}

TEST(WireConversion, SimpleImpostorWithoutMeshGetsTheUnitQuad) {
  protocol::Representation wire;
  wire.kind = protocol::RepresentationKind::kSimpleImpostor;
  wire.texture = wireTexture(gradientTexture(16, 8), TextureCodec::kPng);
  wire.triangleCount = 2;
  wire.transform = kPlaced;
  auto rep = convertRepresentation(wire, 1, {}, "op");
  ASSERT_TRUE(rep.ok()) << rep.status().toString();
  EXPECT_EQ(rep->mesh, nullptr);  // the scene substitutes unitQuadMesh()
  EXPECT_EQ(rep->texture->width, 16);
  EXPECT_EQ(rep->texture->height, 8);
  FrontendScene scene;
  SceneBatch batch;
  batch.operations.push_back({SceneOperation::Type::kAddOrReplace, 1, *rep});
  EXPECT_TRUE(scene.enqueue(std::move(batch)).ok());
}

TEST(WireConversion, CorruptedDracoBytesAreRejected) {
  protocol::Representation wire = meshRepresentation(sphereMesh(1.0f, 12, 6));
  // Flip payload bytes after the 32-byte frame header: the checksum catches it.
  for (std::size_t i = codec::kFrameHeaderBytes; i < wire.mesh.size(); i += 7) wire.mesh[i] ^= 0x5a;
  auto rep = convertRepresentation(wire, 4, {}, "update 9, operation 0 (object 4)");
  ASSERT_FALSE(rep.ok());
  EXPECT_NE(rep.status().message().find("update 9, operation 0 (object 4): mesh:"),
            std::string::npos)
      << rep.status().message();
}

TEST(WireConversion, TruncatedMeshBytesFailAndRandomCorruptionNeverYieldsAnotherMesh) {
  const protocol::Representation valid = meshRepresentation(sphereMesh(1.0f, 10, 5));
  for (std::size_t size = 0; size < valid.mesh.size(); size += 13) {
    protocol::Representation wire = valid;
    wire.mesh.resize(size);
    EXPECT_FALSE(convertRepresentation(wire, 1, {}, "op").ok()) << size;
  }
  std::mt19937 random(1234);
  for (int trial = 0; trial < 200; ++trial) {
    protocol::Representation wire = valid;
    wire.mesh[random() % wire.mesh.size()] ^= static_cast<std::uint8_t>(1 + random() % 255);
    // Header corruption may be caught by any check; payload corruption by the
    // checksum. Either way: an error, never a crash, never a different mesh.
    auto rep = convertRepresentation(wire, 1, {}, "op");
    if (rep.ok()) {
      EXPECT_EQ(rep->mesh->triangleCount(), valid.triangleCount);
    }
  }
}

TEST(WireConversion, TextureSizeMismatchIsRejected) {
  protocol::Representation wire = impostorRepresentation(TextureCodec::kPng, 32);
  wire.texture.width = 64;  // the frame holds 32x32
  wire.texture.height = 64;
  auto rep = convertRepresentation(wire, 2, {}, "op");
  ASSERT_FALSE(rep.ok());
  EXPECT_EQ(rep.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(rep.status().message().find("decoded size 32x32 does not match the announced 64x64"),
            std::string::npos)
      << rep.status().message();
}

TEST(WireConversion, RawTextureWithWrongByteCountIsRejected) {
  protocol::Representation wire = impostorRepresentation(TextureCodec::kRawRgba8, 8);
  wire.texture.data.pop_back();
  auto rep = convertRepresentation(wire, 2, {}, "op");
  ASSERT_FALSE(rep.ok());
  EXPECT_NE(rep.status().message().find("RawRgba8 data is 255 bytes, expected 256"),
            std::string::npos)
      << rep.status().message();
}

TEST(WireConversion, TextureFrameOfAnotherCodecIsRejected) {
  protocol::Representation wire = impostorRepresentation(TextureCodec::kPng);
  wire.texture.codec = TextureCodec::kZstd;  // bytes are still a PNG frame
  auto rep = convertRepresentation(wire, 2, {}, "op");
  ASSERT_FALSE(rep.ok());
  EXPECT_NE(rep.status().message().find("does not match the wire codec"), std::string::npos)
      << rep.status().message();
}

TEST(WireConversion, ImpostorWithoutTextureIsRejected) {
  for (auto kind : {protocol::RepresentationKind::kSimpleImpostor,
                    protocol::RepresentationKind::kMeshedImpostor}) {
    protocol::Representation wire = impostorRepresentation(TextureCodec::kPng);
    wire.kind = kind;
    wire.texture = protocol::Texture{};
    auto rep = convertRepresentation(wire, 2, {}, "op");
    ASSERT_FALSE(rep.ok());
    EXPECT_NE(rep.status().message().find("has no texture"), std::string::npos)
        << rep.status().message();
  }
}

TEST(WireConversion, TriangleCountMustMatchTheMesh) {
  protocol::Representation wire = meshRepresentation(sphereMesh(1.0f, 8, 4));
  wire.triangleCount += 1;
  auto rep = convertRepresentation(wire, 1, {}, "op");
  ASSERT_FALSE(rep.ok());
  EXPECT_NE(rep.status().message().find("triangles, the representation announces"),
            std::string::npos);
}

TEST(WireConversion, MeshKindsNeedMeshBytes) {
  protocol::Representation wire = meshRepresentation(sphereMesh(1.0f, 8, 4));
  wire.mesh.clear();
  EXPECT_FALSE(convertRepresentation(wire, 1, {}, "op").ok());
  wire = impostorRepresentation(TextureCodec::kPng);
  wire.mesh.clear();
  EXPECT_FALSE(convertRepresentation(wire, 1, {}, "op").ok());
}

TEST(WireConversion, TexturedImpostorMeshWithoutUvsIsRejected) {
  protocol::Representation wire = impostorRepresentation(TextureCodec::kPng);
  IndexedMesh noUvs = quadMesh();
  noUvs.uvs.clear();
  wire.mesh = encodeOrDie(noUvs);
  auto rep = convertRepresentation(wire, 1, {}, "op");
  ASSERT_FALSE(rep.ok());
  EXPECT_NE(rep.status().message().find("has no uvs"), std::string::npos);
}

TEST(WireConversion, UpdateKeepsPlanOrderAndRemovals) {
  protocol::SceneUpdate update;
  update.plan = 12;
  update.frame = 30;
  update.operations.push_back(addOp(1, meshRepresentation(sphereMesh(1.0f, 8, 4))));
  protocol::SceneOperation remove;
  remove.type = protocol::SceneOperation::Type::kRemove;
  remove.objectId = 2;
  update.operations.push_back(remove);
  update.operations.push_back(addOp(3, impostorRepresentation(TextureCodec::kZstd)));
  auto batch = convertUpdate(update, {});
  ASSERT_TRUE(batch.ok()) << batch.status().toString();
  EXPECT_EQ(batch->plan, 12u);
  ASSERT_EQ(batch->operations.size(), 3u);
  EXPECT_EQ(batch->operations[0].id, 1u);
  EXPECT_EQ(batch->operations[1].type, SceneOperation::Type::kRemove);
  EXPECT_EQ(batch->operations[1].id, 2u);
  EXPECT_EQ(batch->operations[2].representation.kind, RepresentationKind::kMeshedImpostor);
  EXPECT_EQ(payloadBytes(update), update.operations[0].representation.mesh.size() +
                                      update.operations[2].representation.mesh.size() +
                                      update.operations[2].representation.texture.data.size());
}

TEST(WireConversion, OneBadOperationRejectsTheWholeUpdateAndNothingIsApplied) {
  FrontendScene scene;
  // The scene holds object 1 from an earlier update.
  auto first = convertUpdate(
      [] {
        protocol::SceneUpdate u;
        u.plan = 1;
        u.operations.push_back(addOp(1, meshRepresentation(sphereMesh(1.0f, 8, 4))));
        return u;
      }(),
      {});
  ASSERT_TRUE(first.ok());
  ASSERT_TRUE(scene.enqueue(std::move(first).value()).ok());
  for (const PendingUpload& upload : scene.planUploads(~std::size_t{0})) {
    ASSERT_TRUE(scene.markUploaded(upload.key).ok());
  }
  scene.commitReady();
  const std::size_t heldPolygons = scene.polygons();

  // Replace 1 (valid), add 2 (valid), add 3 as an impostor without a texture.
  protocol::SceneUpdate update;
  update.plan = 2;
  update.frame = 5;
  update.operations.push_back(addOp(1, meshRepresentation(sphereMesh(1.0f, 16, 8))));
  update.operations.push_back(addOp(2, impostorRepresentation(TextureCodec::kPng)));
  protocol::Representation untextured = impostorRepresentation(TextureCodec::kPng);
  untextured.texture = protocol::Texture{};
  update.operations.push_back(addOp(3, untextured));
  auto batch = convertUpdate(update, {});
  ASSERT_FALSE(batch.ok());
  EXPECT_NE(
      batch.status().message().find(
          "SceneUpdate plan 2 frame 5, operation 2 (object 3): MeshedImpostor has no texture"),
      std::string::npos)
      << batch.status().message();

  // The caller has nothing to submit: the scene is as it was.
  EXPECT_EQ(scene.pendingBatches(), 0u);
  EXPECT_EQ(scene.polygons(), heldPolygons);
  EXPECT_EQ(scene.objects().size(), 1u);
  EXPECT_EQ(scene.lastAppliedPlan(), 1u);
}

TEST(FrameStatsOfARecord, CopiesTheRecordAndSendsOnlyAFiniteSnr) {
  FrameRecord record;
  record.frame = 9;
  record.plan = 4;
  record.polygons = 348;
  record.linkBytes = 1234;
  record.renderMs = 2.5;
  record.quality.snrDb = 11.0;
  protocol::FrameStats stats = toFrameStats(record, 42, {7, 8});
  EXPECT_EQ(stats.frame, 9u);
  EXPECT_EQ(stats.plan, 4u);
  EXPECT_EQ(stats.timestampNs, 42);
  EXPECT_EQ(stats.polygons, 348u);
  EXPECT_EQ(stats.linkBytes, 1234u);
  EXPECT_FLOAT_EQ(stats.renderMs, 2.5f);
  EXPECT_TRUE(stats.hasSnr);
  EXPECT_EQ(stats.snrDb, 11.0);
  EXPECT_EQ(stats.rejectedPlans, (std::vector<std::uint64_t>{7, 8}));
  for (double snr : {std::numeric_limits<double>::infinity(),
                     -std::numeric_limits<double>::infinity(), FrameRecord::kMissing}) {
    record.quality.snrDb = snr;
    stats = toFrameStats(record, 0, {});
    EXPECT_FALSE(stats.hasSnr);
    EXPECT_EQ(stats.snrDb, 0.0);
  }
  record.renderMs = FrameRecord::kMissing;
  record.polygons = std::size_t{1} << 40;
  stats = toFrameStats(record, 0, {});
  EXPECT_EQ(stats.renderMs, 0.0f);
  EXPECT_EQ(stats.polygons, std::numeric_limits<std::uint32_t>::max());  // saturated
}

}  // namespace
}  // namespace thinlod::frontend::daemon
