// Skinning (core/skinning.h): clip sampling, ASLOD two-bone deformation,
// skin regions, path-length weights, the sampled motion bound.
#include "thinlod/common/core/skinning.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace thinlod::anim {
namespace {

constexpr float kPi = 3.14159265358979f;

// A tube along +x from 0 to 2 (rings of 8 vertices every 0.1), two bones:
// bone 0 at the origin, bone 1 at x = 1 (child of bone 0). Vertices with
// x < 0.7 are rigid on bone 0, x > 1.3 rigid on bone 1, the rest deformable
// with weights from pathLengthWeights (set by the caller).
struct Figure {
  IndexedMesh mesh;
  Skeleton skeleton;
  std::vector<VertexSkin> skin;
  std::vector<bool> deformable;
  std::vector<std::uint32_t> borderA, borderB;
};

Figure makeArm() {
  Figure f;
  const int rings = 21, around = 8;
  for (int r = 0; r < rings; ++r) {
    for (int a = 0; a < around; ++a) {
      const float angle = 2.0f * kPi * static_cast<float>(a) / around;
      f.mesh.positions.emplace_back(0.1f * static_cast<float>(r), 0.2f * std::cos(angle),
                                    0.2f * std::sin(angle));
    }
  }
  for (int r = 0; r + 1 < rings; ++r) {
    for (int a = 0; a < around; ++a) {
      const auto v = [&](int rr, int aa) {
        return static_cast<std::uint32_t>(rr * around + (aa % around));
      };
      f.mesh.indices.insert(f.mesh.indices.end(), {v(r, a), v(r + 1, a), v(r + 1, a + 1)});
      f.mesh.indices.insert(f.mesh.indices.end(), {v(r, a), v(r + 1, a + 1), v(r, a + 1)});
    }
  }
  Bone root;
  root.name = "upper";
  Bone child;
  child.name = "lower";
  child.parent = 0;
  child.restLocal = glm::translate(glm::mat4(1.0f), glm::vec3(1, 0, 0));
  child.inverseBind = glm::inverse(child.restLocal);  // global rest of bone 1
  f.skeleton.bones = {root, child};
  f.deformable.assign(f.mesh.vertexCount(), false);
  for (std::uint32_t v = 0; v < f.mesh.vertexCount(); ++v) {
    const float x = f.mesh.positions[v].x;
    VertexSkin s;
    if (x < 0.65f) {
      s = {0, 0, 0.0f};
      if (x > 0.55f) f.borderA.push_back(v);
    } else if (x > 1.35f) {
      s = {1, 1, 0.0f};
      if (x < 1.45f) f.borderB.push_back(v);
    } else {
      s = {0, 1, 0.5f};
      f.deformable[v] = true;
    }
    f.skin.push_back(s);
  }
  return f;
}

AnimationClip bendClip(float degrees) {
  AnimationClip clip;
  clip.name = "bend";
  clip.duration = 1.0;
  BoneChannel channel;
  channel.bone = 1;
  channel.rotations = {{0.0, glm::quat(1, 0, 0, 0)},
                       {1.0, glm::angleAxis(degrees * kPi / 180.0f, glm::vec3(0, 0, 1))}};
  clip.channels.push_back(channel);
  return clip;
}

TEST(Skinning, RestPoseReproducesTheMesh) {
  const Figure f = makeArm();
  ASSERT_TRUE(f.skeleton.validate("arm").ok());
  ASSERT_TRUE(validateSkin(f.skin, f.mesh.vertexCount(), 2, "arm").ok());
  std::vector<glm::vec3> out(f.mesh.vertexCount());
  deform(f.mesh.positions, f.skin, skinningMatrices(f.skeleton, restPose(f.skeleton)), {}, out);
  for (std::size_t v = 0; v < out.size(); ++v) {
    EXPECT_NEAR(glm::length(out[v] - f.mesh.positions[v]), 0.0f, 1e-6f) << v;
  }
}

TEST(Skinning, RigidVerticesFollowTheirBoneRigidly) {
  const Figure f = makeArm();
  const AnimationClip clip = bendClip(90.0f);
  ASSERT_TRUE(clip.validate(f.skeleton, "bend").ok());
  std::vector<glm::vec3> out(f.mesh.vertexCount());
  deform(f.mesh.positions, f.skin,
         skinningMatrices(f.skeleton, samplePose(f.skeleton, clip, 1.0, ClipWrap::kClamp)), {},
         out);
  for (std::uint32_t v = 0; v < out.size(); ++v) {
    const glm::vec3 p = f.mesh.positions[v];
    if (f.skin[v].boneA == 0 && f.skin[v].rigid()) {
      EXPECT_NEAR(glm::length(out[v] - p), 0.0f, 1e-6f) << v;
    } else if (f.skin[v].boneA == 1 && f.skin[v].rigid()) {
      // 90 degrees about z at the joint (1, 0, 0): (x, y, z) -> (1 - y, x - 1, z).
      const glm::vec3 expected(1.0f - p.y, p.x - 1.0f, p.z);
      EXPECT_NEAR(glm::length(out[v] - expected), 0.0f, 1e-5f) << v;
    }
  }
}

TEST(Skinning, DeformWritesOnlyTheListedVertices) {
  const Figure f = makeArm();
  const std::vector<glm::mat4> matrices = skinningMatrices(
      f.skeleton, samplePose(f.skeleton, bendClip(60.0f), 1.0, ClipWrap::kClamp));
  const glm::vec3 sentinel(-7.0f);
  std::vector<glm::vec3> out(f.mesh.vertexCount(), sentinel);
  const std::vector<std::uint32_t> listed{0, 5, 160};
  deform(f.mesh.positions, f.skin, matrices, listed, out);
  std::vector<glm::vec3> all(f.mesh.vertexCount());
  deform(f.mesh.positions, f.skin, matrices, {}, all);
  for (std::uint32_t v = 0; v < out.size(); ++v) {
    const bool isListed = v == 0 || v == 5 || v == 160;
    if (isListed) {
      EXPECT_EQ(out[v], all[v]);
    } else {
      EXPECT_EQ(out[v], sentinel);
    }
  }
}

TEST(Skinning, TwoBoneVertexIsTheLinearBlendOfBothBones) {
  const Figure f = makeArm();
  const std::vector<glm::mat4> m = skinningMatrices(
      f.skeleton, samplePose(f.skeleton, bendClip(90.0f), 1.0, ClipWrap::kClamp));
  std::vector<VertexSkin> skin = f.skin;
  const std::uint32_t v = 10 * 8;  // ring at x = 1.0
  skin[v] = {0, 1, 0.25f};
  std::vector<glm::vec3> out(f.mesh.vertexCount());
  deform(f.mesh.positions, skin, m, {v}, out);
  const glm::vec4 p(f.mesh.positions[v], 1.0f);
  const glm::vec3 expected = 0.75f * glm::vec3(m[0] * p) + 0.25f * glm::vec3(m[1] * p);
  EXPECT_NEAR(glm::length(out[v] - expected), 0.0f, 1e-6f);
}

TEST(Skinning, ClipInterpolatesLinearlyAndBySlerpAndWraps) {
  Skeleton skeleton;
  skeleton.bones.resize(1);
  AnimationClip clip;
  clip.duration = 2.0;
  BoneChannel c;
  c.bone = 0;
  c.positions = {{0.0, glm::vec3(0)}, {2.0, glm::vec3(4, 0, 0)}};
  c.rotations = {{0.0, glm::quat(1, 0, 0, 0)},
                 {2.0, glm::angleAxis(kPi / 2.0f, glm::vec3(0, 1, 0))}};
  clip.channels = {c};
  ASSERT_TRUE(clip.validate(skeleton, "clip").ok());
  const glm::mat4 mid = samplePose(skeleton, clip, 1.0, ClipWrap::kClamp)[0];
  EXPECT_NEAR(mid[3].x, 2.0f, 1e-6f);
  // Slerp halfway: 45 degrees about y, so +x maps to (cos 45, 0, -sin 45).
  const glm::vec3 x = glm::vec3(mid * glm::vec4(1, 0, 0, 0));
  EXPECT_NEAR(x.x, std::cos(kPi / 4.0f), 1e-5f);
  EXPECT_NEAR(x.z, -std::sin(kPi / 4.0f), 1e-5f);
  // Loop: t = 3 is t = 1; clamp: t = 3 is the last key, t = -1 the first.
  EXPECT_NEAR(samplePose(skeleton, clip, 3.0, ClipWrap::kLoop)[0][3].x, 2.0f, 1e-6f);
  EXPECT_NEAR(samplePose(skeleton, clip, 3.0, ClipWrap::kClamp)[0][3].x, 4.0f, 1e-6f);
  EXPECT_NEAR(samplePose(skeleton, clip, -1.0, ClipWrap::kClamp)[0][3].x, 0.0f, 1e-6f);
}

TEST(Skinning, ChannelWithoutAComponentKeepsTheRestOne) {
  Skeleton skeleton;
  skeleton.bones.resize(1);
  skeleton.bones[0].restLocal = glm::translate(glm::mat4(1.0f), glm::vec3(0, 3, 0));
  AnimationClip clip;
  clip.duration = 1.0;
  BoneChannel c;
  c.bone = 0;
  c.rotations = {{0.0, glm::angleAxis(kPi, glm::vec3(0, 0, 1))}};
  clip.channels = {c};
  const glm::mat4 m = samplePose(skeleton, clip, 0.5, ClipWrap::kLoop)[0];
  EXPECT_NEAR(m[3].y, 3.0f, 1e-6f);           // rest translation kept
  EXPECT_NEAR(m[0].x, -1.0f, 1e-6f);          // rotated by pi about z
}

TEST(Skinning, ValidationNamesTheProblem) {
  Skeleton skeleton;
  skeleton.bones.resize(2);
  skeleton.bones[1].parent = 1;  // itself: not before it
  EXPECT_EQ(skeleton.validate("s").code(), ErrorCode::kInvalidArgument);
  skeleton.bones[1].parent = 0;
  skeleton.bones[1].restLocal[3].x = std::nanf("");
  EXPECT_NE(skeleton.validate("s").message().find("non-finite"), std::string::npos);
  skeleton.bones[1].restLocal = glm::mat4(0.0f);
  EXPECT_NE(skeleton.validate("s").message().find("singular"), std::string::npos);
  skeleton.bones[1].restLocal = glm::mat4(1.0f);
  ASSERT_TRUE(skeleton.validate("s").ok());

  EXPECT_FALSE(validateSkin({{0, 2, 0.5f}}, 1, 2, "skin").ok());   // bone out of range
  EXPECT_FALSE(validateSkin({{0, 1, 1.5f}}, 1, 2, "skin").ok());   // weight > 1
  EXPECT_FALSE(validateSkin({{0, 1, std::nanf("")}}, 1, 2, "skin").ok());
  EXPECT_FALSE(validateSkin({}, 1, 2, "skin").ok());               // size

  AnimationClip clip;
  clip.duration = 1.0;
  BoneChannel c;
  c.bone = 0;
  c.positions = {{0.5, glm::vec3(0)}, {0.5, glm::vec3(1)}};  // repeated time
  clip.channels = {c};
  EXPECT_NE(clip.validate(skeleton, "c").message().find("strictly increasing"), std::string::npos);
  clip.channels[0].positions = {{0.5, glm::vec3(0)}, {1.5, glm::vec3(1)}};
  EXPECT_NE(clip.validate(skeleton, "c").message().find("outside"), std::string::npos);
  clip.channels[0].positions.clear();
  clip.channels[0].rotations = {{0.0, glm::quat(2, 0, 0, 0)}};
  EXPECT_NE(clip.validate(skeleton, "c").message().find("unit quaternion"), std::string::npos);
  clip.channels[0].rotations.clear();
  clip.channels[0].scales = {{0.0, glm::vec3(1, 0, 1)}};
  EXPECT_FALSE(clip.validate(skeleton, "c").ok());
  clip.channels[0].scales.clear();
  clip.channels.push_back(clip.channels[0]);  // bone 0 twice
  EXPECT_NE(clip.validate(skeleton, "c").message().find("two channels"), std::string::npos);
  clip.channels = {c};
  clip.channels[0].bone = 5;
  EXPECT_FALSE(clip.validate(skeleton, "c").ok());
  clip.duration = 0.0;
  EXPECT_FALSE(clip.validate(skeleton, "c").ok());
}

TEST(Skinning, PartitionFindsRigidAndDeformableRegions) {
  const Figure f = makeArm();
  const SkinRegions regions = partitionBySkin(f.mesh, f.skin);
  ASSERT_EQ(regions.regions.size(), 3u);
  EXPECT_EQ(regions.regions[0].boneA, 0u);  // the region of vertex 0 comes first
  EXPECT_EQ(regions.regions[0].boneB, 0u);
  EXPECT_EQ(regions.regions[1].boneA, 0u);  // deformable (0, 1)
  EXPECT_EQ(regions.regions[1].boneB, 1u);
  EXPECT_EQ(regions.regions[2].boneA, 1u);
  std::size_t total = 0;
  for (const auto& r : regions.regions) total += r.vertices;
  EXPECT_EQ(total, f.mesh.vertexCount());
  // Two separate rigid pieces on the same bone are two regions.
  Figure two = makeArm();
  for (std::uint32_t v = 0; v < two.mesh.vertexCount(); ++v) {
    if (two.skin[v].boneA == 1 && two.skin[v].rigid()) two.skin[v] = {0, 0, 0.0f};
  }
  EXPECT_EQ(partitionBySkin(two.mesh, two.skin).regions.size(), 3u);
}

TEST(Skinning, PathLengthWeightsRunFromZeroToOneAlongTheJoint) {
  const Figure f = makeArm();
  Result<std::vector<float>> weights =
      pathLengthWeights(f.mesh, f.deformable, f.borderA, f.borderB);
  ASSERT_TRUE(weights.ok()) << weights.status().toString();
  for (const std::uint32_t v : f.borderA) EXPECT_EQ((*weights)[v], 0.0f);
  for (const std::uint32_t v : f.borderB) EXPECT_EQ((*weights)[v], 1.0f);
  // Along one line of the tube (a = 0), the weight grows with x, and is
  // the path-length ratio: (x - 0.6) / 0.8 for the straight edges.
  float previous = -1.0f;
  for (int r = 7; r <= 13; ++r) {
    const float w = (*weights)[static_cast<std::size_t>(r * 8)];
    EXPECT_GT(w, previous) << r;
    EXPECT_NEAR(w, (0.1f * static_cast<float>(r) - 0.6f) / 0.8f, 1e-4f) << r;
    previous = w;
  }
  EXPECT_FALSE(pathLengthWeights(f.mesh, f.deformable, {}, f.borderB).ok());
  EXPECT_FALSE(pathLengthWeights(f.mesh, {true}, f.borderA, f.borderB).ok());
  EXPECT_FALSE(pathLengthWeights(f.mesh, f.deformable, {100000}, f.borderB).ok());
}

TEST(Skinning, SampledDisplacementBoundsTheMotion) {
  const Figure f = makeArm();
  const AnimationClip clip = bendClip(90.0f);
  // The tip ring (x = 2, radius 0.2) is 1 to ~1.02 from the joint: after 90
  // degrees its chord is sqrt(2) * distance.
  const double bound =
      sampledMaxDisplacement(f.skeleton, clip, f.mesh.positions, f.skin, 0.0, 1.0, 0.05,
                             ClipWrap::kClamp);
  const double far = std::sqrt(1.0 + 0.2 * 0.2);
  EXPECT_GE(bound, std::sqrt(2.0) * 1.0 - 1e-5);
  EXPECT_LE(bound, std::sqrt(2.0) * far + 1e-5);
  // Nothing moves in a window where the clip holds still (clamped past the end).
  EXPECT_NEAR(sampledMaxDisplacement(f.skeleton, clip, f.mesh.positions, f.skin, 1.0, 3.0, 0.1,
                                     ClipWrap::kClamp),
              0.0, 1e-6);
}

}  // namespace
}  // namespace thinlod::anim
