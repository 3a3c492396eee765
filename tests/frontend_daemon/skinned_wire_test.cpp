// Wire -> frontend for animated objects (docs/animation.md, "Served"): a
// skinned mesh frame becomes Representation::skin, the update's bone poses
// ride in the batch, and a skin on another kind refuses the update.
#include <gtest/gtest.h>

#include "articulated_figure.h"
#include "thinlod/common/codec/encoding.h"
#include "wire_conversion.h"

namespace thinlod::frontend::daemon {
namespace {

protocol::SceneUpdate skinnedUpdate(protocol::RepresentationKind kind) {
  anim::testing::FigureShape shape;
  shape.ringsPerUnit = 4;
  shape.around = 8;
  const anim::testing::ArticulatedFigure f = anim::testing::makeArticulatedFigure(shape);
  Result<std::vector<std::uint8_t>> frame = codec::encodeSkinnedMesh(f.mesh, f.skin);
  EXPECT_TRUE(frame.ok()) << frame.status().toString();
  protocol::SceneUpdate update;
  update.plan = 3;
  update.frame = 3;
  protocol::SceneOperation op;
  op.objectId = 7;
  op.representation.kind = kind;
  op.representation.mesh = frame.ok() ? *frame : std::vector<std::uint8_t>{};
  op.representation.triangleCount = static_cast<std::uint32_t>(f.mesh.triangleCount());
  if (kind != protocol::RepresentationKind::kMesh) {
    op.representation.texture.codec = protocol::TextureCodec::kRawRgba8;
    op.representation.texture.width = 2;
    op.representation.texture.height = 2;
    op.representation.texture.data.assign(16, 200);
  }
  update.operations.push_back(op);
  protocol::BonePose pose;
  pose.objectId = 7;
  pose.matrices = anim::skinningMatrices(f.skeleton, anim::restPose(f.skeleton));
  update.bonePoses.push_back(pose);
  return update;
}

TEST(SkinnedWireConversion, SkinAndPosesReachTheBatch) {
  const protocol::SceneUpdate update = skinnedUpdate(protocol::RepresentationKind::kMesh);
  Result<SceneBatch> batch = convertUpdate(update, {});
  ASSERT_TRUE(batch.ok()) << batch.status().toString();
  ASSERT_EQ(batch->operations.size(), 1u);
  const Representation& rep = batch->operations[0].representation;
  ASSERT_NE(rep.skin, nullptr);
  ASSERT_NE(rep.mesh, nullptr);
  EXPECT_EQ(rep.skin->size(), rep.mesh->vertexCount());
  ASSERT_EQ(batch->bonePoses.size(), 1u);
  EXPECT_EQ(batch->bonePoses[0].first, 7u);
  EXPECT_EQ(batch->bonePoses[0].second, update.bonePoses[0].matrices);
  // Pose bytes count as payload: 48 a matrix.
  EXPECT_GE(payloadBytes(update), update.operations[0].representation.mesh.size() +
                                      48 * update.bonePoses[0].matrices.size());
}

TEST(SkinnedWireConversion, ASkinOnAnImpostorRefusesTheUpdate) {
  Result<SceneBatch> batch =
      convertUpdate(skinnedUpdate(protocol::RepresentationKind::kMeshedImpostor), {});
  ASSERT_FALSE(batch.ok());
  EXPECT_NE(batch.status().message().find("carries a skin"), std::string::npos)
      << batch.status().toString();
}

}  // namespace
}  // namespace thinlod::frontend::daemon
