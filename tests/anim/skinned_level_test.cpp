// Skinned levels (simplifier/skinned_level.h): TOM skins, levels deformed
// vertex by vertex, and the error bound of a level under animation checked
// against the error measured at 4x denser poses, on the generated
// articulated figure and on assimp-testmodels' Testwuson.X.
#include "thinlod/simplifier/skinned_level.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <set>

#include "articulated_figure.h"
#include "thinlod/common/scene/skinned_import.h"

namespace thinlod::simplifier {
namespace {

using anim::ClipWrap;
using anim::VertexSkin;
using anim::testing::ArticulatedFigure;
using anim::testing::FigureShape;
using anim::testing::makeArticulatedFigure;

const std::string kModels = "/usr/share/assimp/models";

ProgressiveMesh buildPm(const IndexedMesh& mesh) {
  Result<ProgressiveMesh> pm = ProgressiveMesh::build(mesh);
  EXPECT_TRUE(pm.ok()) << pm.status().toString();
  return pm.ok() ? std::move(*pm) : ProgressiveMesh{};
}

std::vector<glm::vec3> deformed(const std::vector<glm::vec3>& positions,
                                const std::vector<VertexSkin>& skin, const anim::Skeleton& skeleton,
                                const anim::AnimationClip& clip, double t) {
  std::vector<glm::vec3> out(positions.size());
  anim::deform(
      positions, skin,
      anim::skinningMatrices(skeleton, anim::samplePose(skeleton, clip, t, ClipWrap::kLoop)), {},
      out);
  return out;
}

// The largest error at `count` evenly spaced poses over [t0, t1] (ends
// included), measured directly (deformedLevelErrorAt).
double denseError(const IndexedMesh& full, const std::vector<VertexSkin>& fullSkin,
                  const anim::Skeleton& skeleton, const anim::AnimationClip& clip,
                  const IndexedMesh& level, const std::vector<VertexSkin>& levelSkin, double t0,
                  double t1, std::size_t count, const SurfaceErrorOptions& surface) {
  double worst = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    const double t = t0 + (t1 - t0) * static_cast<double>(i) / static_cast<double>(count - 1);
    Result<double> e = deformedLevelErrorAt(full, fullSkin, skeleton, clip, level, levelSkin, t,
                                            ClipWrap::kLoop, surface);
    EXPECT_TRUE(e.ok()) << e.status().toString();
    if (e.ok()) worst = std::max(worst, *e);
  }
  return worst;
}

TEST(SkinnedLevel, TomSkinOfTheIdentityLevelMatchesTheInputSkins) {
  const ArticulatedFigure f = makeArticulatedFigure();
  ASSERT_TRUE(anim::validateSkin(f.skin, f.mesh.vertexCount(), 3, "figure").ok());
  const ProgressiveMesh pm = buildPm(f.mesh);
  Result<std::vector<VertexSkin>> skin = tomSkin(pm, f.mesh, f.skin, f.skeleton.bones.size());
  ASSERT_TRUE(skin.ok()) << skin.status().toString();
  ASSERT_EQ(skin->size(), pm.vertexCount());
  // The figure has no duplicate vertices: every input vertex is one TOM vertex.
  ASSERT_EQ(pm.vertexCount(), f.mesh.vertexCount());
  const IndexedMesh identity = pm.extract(pm.maxTriangles());
  ASSERT_EQ(identity.vertexCount(), f.mesh.vertexCount());
  std::set<std::uint32_t> sources;
  std::size_t deformable = 0;
  for (std::uint32_t v = 0; v < skin->size(); ++v) {
    const std::uint32_t source = pm.sourceVertexOf(v);
    sources.insert(source);
    EXPECT_EQ((*skin)[v].boneA, f.skin[source].boneA) << v;
    EXPECT_EQ((*skin)[v].boneB, f.skin[source].boneB) << v;
    EXPECT_EQ((*skin)[v].weightB, f.skin[source].weightB) << v;
    EXPECT_EQ(identity.positions[v], f.mesh.positions[source]) << v;
    deformable += (*skin)[v].rigid() ? 0 : 1;
  }
  EXPECT_EQ(sources.size(), f.mesh.vertexCount()) << "sourceVertexOf is a permutation here";
  EXPECT_GT(deformable, 0u);
}

TEST(SkinnedLevel, DeformedLevelWithAllVerticesIsTheDeformedFullMesh) {
  const ArticulatedFigure f = makeArticulatedFigure();
  const ProgressiveMesh pm = buildPm(f.mesh);
  const std::vector<VertexSkin> skin = *tomSkin(pm, f.mesh, f.skin, 3);
  const IndexedMesh identity = pm.extract(pm.maxTriangles());
  // The identity level's triangles are the input's, through sourceVertexOf.
  const auto canonical = [](std::array<std::uint32_t, 3> t) {
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
  };
  std::set<std::array<std::uint32_t, 3>> input, level;
  for (std::size_t t = 0; t < f.mesh.indices.size(); t += 3) {
    input.insert(canonical({f.mesh.indices[t], f.mesh.indices[t + 1], f.mesh.indices[t + 2]}));
  }
  for (std::size_t t = 0; t < identity.indices.size(); t += 3) {
    level.insert(canonical({pm.sourceVertexOf(identity.indices[t]),
                            pm.sourceVertexOf(identity.indices[t + 1]),
                            pm.sourceVertexOf(identity.indices[t + 2])}));
  }
  EXPECT_EQ(level, input);
  for (const double t : {0.0, 0.35, 1.0, 1.7}) {
    const std::vector<glm::vec3> whole = deformed(f.mesh.positions, f.skin, f.skeleton, f.clip, t);
    const std::vector<glm::vec3> ofLevel =
        deformed(identity.positions, skin, f.skeleton, f.clip, t);
    for (std::uint32_t v = 0; v < ofLevel.size(); ++v) {
      ASSERT_EQ(ofLevel[v], whole[pm.sourceVertexOf(v)]) << "t " << t << " vertex " << v;
    }
  }
  // The same surface at every pose: the bound says so without sampling.
  Result<AnimatedLevelError> bound =
      deformedLevelBound(f.mesh, f.skin, f.skeleton, f.clip, identity, skin);
  ASSERT_TRUE(bound.ok()) << bound.status().toString();
  EXPECT_TRUE(bound->identical);
  EXPECT_EQ(bound->bound, 0.0);
  EXPECT_EQ(bound->poses, 0u);
}

TEST(SkinnedLevel, ACoarseLevelDeformsOnlyItsOwnVerticesAndThoseMoveLikeTheFullMesh) {
  const ArticulatedFigure f = makeArticulatedFigure();
  const ProgressiveMesh pm = buildPm(f.mesh);
  const std::vector<VertexSkin> skin = *tomSkin(pm, f.mesh, f.skin, 3);
  const std::size_t target = pm.maxTriangles() / 10;
  const IndexedMesh level = pm.extract(target);
  EXPECT_EQ(level.vertexCount(), pm.vertexCountAt(target));
  EXPECT_LT(level.vertexCount() * 5, f.mesh.vertexCount());
  const std::vector<glm::vec3> whole = deformed(f.mesh.positions, f.skin, f.skeleton, f.clip, 0.8);
  // deform() over the level's positions with the TOM skin touches the level's
  // vertices only (the first vertexCountAt(n) TOM vertices).
  const std::vector<glm::vec3> ofLevel = deformed(level.positions, skin, f.skeleton, f.clip, 0.8);
  ASSERT_EQ(ofLevel.size(), level.vertexCount());
  for (std::uint32_t v = 0; v < ofLevel.size(); ++v) {
    EXPECT_EQ(ofLevel[v], whole[pm.sourceVertexOf(v)]) << v;
  }
}

// Small enough for the sanitizer subset (deploy/test); the report
// (bench_skinned_level) runs the defaults.
AnimatedErrorOptions testOptions() {
  AnimatedErrorOptions options;
  options.initialPoses = 5;
  options.maxPoses = 17;
  options.motionSteps = 4;
  options.surface.samplesPerMesh = 2000;
  return options;
}

// bound >= the error at 4x as many evenly spaced poses as the bound measured,
// and, once converged, within its tolerance of the largest measured error.
void expectBoundCoversDensePoses(const IndexedMesh& full, const std::vector<VertexSkin>& fullSkin,
                                 const anim::Skeleton& skeleton, const anim::AnimationClip& clip,
                                 const ProgressiveMesh& pm, const std::vector<VertexSkin>& skin,
                                 double fraction, const AnimatedErrorOptions& options,
                                 const std::string& what) {
  const auto target = static_cast<std::size_t>(fraction * static_cast<double>(pm.maxTriangles()));
  const IndexedMesh level = pm.extract(target);
  Result<AnimatedLevelError> bound =
      deformedLevelBound(full, fullSkin, skeleton, clip, level, skin, options);
  ASSERT_TRUE(bound.ok()) << bound.status().toString();
  EXPECT_FALSE(bound->identical) << what;
  EXPECT_GT(bound->bound, 0.0) << what;
  EXPECT_GE(bound->bound, bound->maxAtPoses) << what;
  ASSERT_GE(bound->poses, options.initialPoses) << what;
  EXPECT_LE(bound->poses, options.maxPoses) << what;
  const double t1 = options.t1 < 0 ? clip.duration : options.t1;
  const double dense = denseError(full, fullSkin, skeleton, clip, level, skin, options.t0, t1,
                                  4 * bound->poses, options.surface);
  EXPECT_GE(bound->bound, dense) << what << ": " << bound->poses << " poses";
  if (bound->converged) {
    EXPECT_LE(bound->bound, std::max((1.0 + options.relativeTolerance) * bound->maxAtPoses,
                                     options.absoluteTolerance * bound->diagonal) *
                                (1.0 + 1e-12))
        << what;
  }
}

TEST(SkinnedLevel, BoundCoversDensePosesOnTheArticulatedFigure) {
  const ArticulatedFigure f = makeArticulatedFigure({10, 12});
  const ProgressiveMesh pm = buildPm(f.mesh);
  const std::vector<VertexSkin> skin = *tomSkin(pm, f.mesh, f.skin, 3);
  for (const double fraction : {0.5, 0.1}) {
    expectBoundCoversDensePoses(f.mesh, f.skin, f.skeleton, f.clip, pm, skin, fraction,
                                testOptions(), "figure " + std::to_string(fraction));
  }
}

TEST(SkinnedLevel, BoundCoversDensePosesOnTestwuson) {
  const std::string path = kModels + "/X/Testwuson.X";
  ASSERT_TRUE(std::filesystem::exists(path))
      << path << " is missing: deploy/setup installs the Debian package assimp-testmodels";
  Result<scene::SkinnedModel> model = scene::importSkinnedModel(path);
  ASSERT_TRUE(model.ok()) << model.status().toString();
  ASSERT_FALSE(model->clips.empty());
  const ProgressiveMesh pm = buildPm(model->mesh);
  Result<std::vector<VertexSkin>> skin =
      tomSkin(pm, model->mesh, model->skin, model->skeleton.bones.size());
  ASSERT_TRUE(skin.ok()) << skin.status().toString();
  AnimatedErrorOptions options = testOptions();
  options.surface.samplesPerMesh = 1000;  // + every vertex and edge points
  options.maxPoses = 9;                   // under the sanitizers this test is the subset's slowest
  for (const double fraction : {0.5, 0.1}) {
    expectBoundCoversDensePoses(model->mesh, model->skin, model->skeleton, model->clips[0], pm,
                                *skin, fraction, options, "Testwuson " + std::to_string(fraction));
  }
}

TEST(SkinnedLevel, AWindowOfOneInstantIsThatPosesError) {
  const ArticulatedFigure f = makeArticulatedFigure({6, 8});
  const ProgressiveMesh pm = buildPm(f.mesh);
  const std::vector<VertexSkin> skin = *tomSkin(pm, f.mesh, f.skin, 3);
  const IndexedMesh level = pm.extract(pm.maxTriangles() / 4);
  AnimatedErrorOptions options = testOptions();
  options.t0 = options.t1 = 0.9;
  Result<AnimatedLevelError> bound =
      deformedLevelBound(f.mesh, f.skin, f.skeleton, f.clip, level, skin, options);
  ASSERT_TRUE(bound.ok()) << bound.status().toString();
  EXPECT_EQ(bound->poses, 1u);
  Result<double> direct = deformedLevelErrorAt(f.mesh, f.skin, f.skeleton, f.clip, level, skin, 0.9,
                                               ClipWrap::kLoop, options.surface);
  ASSERT_TRUE(direct.ok());
  EXPECT_GT(*direct, 0.0);
  EXPECT_EQ(bound->bound, *direct);
  EXPECT_EQ(bound->maxAtPoses, *direct);
  EXPECT_EQ(bound->worstTime, 0.9);
}

TEST(SkinnedLevel, RandomFiguresAtExtremeMagnitudes) {
  std::mt19937 random(18);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int trial = 0; trial < 6; ++trial) {
    FigureShape shape;
    shape.ringsPerUnit = 4 + static_cast<int>(unit(random) * 8.0f);
    shape.around = 6 + static_cast<int>(unit(random) * 10.0f);
    shape.radius = 0.05f + 0.4f * unit(random);
    shape.joint = 0.15f + 0.3f * unit(random);
    // 1e-12 to 1e12 in six steps: both extremes are run.
    shape.scale = std::pow(10.0f, -12.0f + 24.0f * static_cast<float>(trial) / 5.0f);
    shape.bendDegrees = 170.0f * unit(random);
    shape.rootTravel = 3.0f * unit(random);
    const ArticulatedFigure f = makeArticulatedFigure(shape);
    const std::string what =
        "trial " + std::to_string(trial) + " scale " + std::to_string(shape.scale);
    ASSERT_TRUE(f.clip.validate(f.skeleton, what).ok());
    const ProgressiveMesh pm = buildPm(f.mesh);
    Result<std::vector<VertexSkin>> skin = tomSkin(pm, f.mesh, f.skin, 3);
    ASSERT_TRUE(skin.ok()) << skin.status().toString();
    AnimatedErrorOptions options = testOptions();
    options.surface.samplesPerMesh = 1000;
    options.t0 = 2.0 * unit(random);
    options.t1 = options.t0 + 0.1 + 1.9 * unit(random);
    const double fraction = 0.05 + 0.6 * unit(random);
    expectBoundCoversDensePoses(f.mesh, f.skin, f.skeleton, f.clip, pm, *skin, fraction, options,
                                what);
    if (HasFatalFailure()) return;
  }
}

TEST(SkinnedLevel, InvalidInputsAreRejected) {
  const ArticulatedFigure f = makeArticulatedFigure({6, 8});
  const ProgressiveMesh pm = buildPm(f.mesh);
  const std::vector<VertexSkin> skin = *tomSkin(pm, f.mesh, f.skin, 3);
  const IndexedMesh level = pm.extract(pm.maxTriangles() / 2);
  const auto code = [&](const IndexedMesh& full, const std::vector<VertexSkin>& fullSkin,
                        const anim::Skeleton& skeleton, const anim::AnimationClip& clip,
                        const IndexedMesh& lvl, const std::vector<VertexSkin>& lvlSkin,
                        const AnimatedErrorOptions& options) {
    return deformedLevelBound(full, fullSkin, skeleton, clip, lvl, lvlSkin, options)
        .status()
        .code();
  };
  const AnimatedErrorOptions ok = testOptions();
  ASSERT_EQ(code(f.mesh, f.skin, f.skeleton, f.clip, level, skin, ok), ErrorCode::kOk);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

  IndexedMesh nanFull = f.mesh;
  nanFull.positions[3].y = kNaN;
  EXPECT_EQ(code(nanFull, f.skin, f.skeleton, f.clip, level, skin, ok),
            ErrorCode::kInvalidArgument);
  IndexedMesh nanLevel = level;
  nanLevel.positions[0].x = std::numeric_limits<float>::infinity();
  EXPECT_EQ(code(f.mesh, f.skin, f.skeleton, f.clip, nanLevel, skin, ok),
            ErrorCode::kInvalidArgument);
  IndexedMesh badIndex = level;
  badIndex.indices[1] = static_cast<std::uint32_t>(level.vertexCount());
  EXPECT_EQ(code(f.mesh, f.skin, f.skeleton, f.clip, badIndex, skin, ok),
            ErrorCode::kInvalidArgument);
  IndexedMesh noTriangles = level;
  noTriangles.indices.clear();
  EXPECT_EQ(code(f.mesh, f.skin, f.skeleton, f.clip, noTriangles, skin, ok),
            ErrorCode::kInvalidArgument);

  std::vector<VertexSkin> shortSkin(f.skin.begin(), f.skin.end() - 1);
  EXPECT_EQ(code(f.mesh, shortSkin, f.skeleton, f.clip, level, skin, ok),
            ErrorCode::kInvalidArgument);
  std::vector<VertexSkin> badBone = skin;
  badBone[0].boneB = 3;
  badBone[0].weightB = 0.5f;
  EXPECT_EQ(code(f.mesh, f.skin, f.skeleton, f.clip, level, badBone, ok),
            ErrorCode::kInvalidArgument);
  std::vector<VertexSkin> nanWeight = f.skin;
  nanWeight[5].weightB = kNaN;
  EXPECT_EQ(code(f.mesh, nanWeight, f.skeleton, f.clip, level, skin, ok),
            ErrorCode::kInvalidArgument);
  const std::vector<VertexSkin> tooFewForLevel(skin.begin(), skin.begin() + 2);
  EXPECT_EQ(code(f.mesh, f.skin, f.skeleton, f.clip, level, tooFewForLevel, ok),
            ErrorCode::kInvalidArgument);

  anim::AnimationClip nanClip = f.clip;
  nanClip.channels[0].positions[1].value.x = kNaN;
  EXPECT_EQ(code(f.mesh, f.skin, f.skeleton, nanClip, level, skin, ok),
            ErrorCode::kInvalidArgument);
  anim::Skeleton nanSkeleton = f.skeleton;
  nanSkeleton.bones[1].inverseBind[3][0] = kNaN;
  EXPECT_EQ(code(f.mesh, f.skin, nanSkeleton, f.clip, level, skin, ok),
            ErrorCode::kInvalidArgument);
  // Finite but huge: the deformed positions overflow float.
  anim::Skeleton huge = f.skeleton;
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) huge.bones[0].restLocal[c][r] = c == r ? 2e38f : 0.0f;
  }
  ASSERT_TRUE(huge.validate("huge").ok());
  anim::AnimationClip still = f.clip;
  still.channels.erase(still.channels.begin());  // bone 0 keeps its huge rest
  const Result<AnimatedLevelError> overflow =
      deformedLevelBound(f.mesh, f.skin, huge, still, level, skin, ok);
  ASSERT_FALSE(overflow.ok());
  EXPECT_NE(overflow.status().message().find("not finite when deformed"), std::string::npos)
      << overflow.status().toString();

  for (const auto& [t0, t1] : std::vector<std::pair<double, double>>{
           {std::nan(""), 1.0}, {0.0, std::numeric_limits<double>::infinity()}, {1.5, 1.0}}) {
    AnimatedErrorOptions window = ok;
    window.t0 = t0;
    window.t1 = t1;
    EXPECT_EQ(code(f.mesh, f.skin, f.skeleton, f.clip, level, skin, window),
              ErrorCode::kInvalidArgument)
        << t0 << " " << t1;
  }
  for (int which = 0; which < 6; ++which) {
    AnimatedErrorOptions bad = ok;
    if (which == 0) bad.initialPoses = 1;
    if (which == 1) bad.maxPoses = bad.initialPoses - 1;
    if (which == 2) bad.motionSteps = 0;
    if (which == 3) bad.relativeTolerance = -0.1;
    if (which == 4) bad.absoluteTolerance = std::nan("");
    if (which == 5) bad.surface.samplesPerMesh = 0;
    EXPECT_EQ(code(f.mesh, f.skin, f.skeleton, f.clip, level, skin, bad),
              ErrorCode::kInvalidArgument)
        << which;
  }
  EXPECT_EQ(deformedLevelErrorAt(f.mesh, f.skin, f.skeleton, f.clip, level, skin, std::nan(""),
                                 ClipWrap::kLoop)
                .status()
                .code(),
            ErrorCode::kInvalidArgument);

  // tomSkin: the skin must be the input's, and the PM the input's.
  EXPECT_EQ(tomSkin(pm, f.mesh, shortSkin, 3).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(tomSkin(pm, f.mesh, f.skin, 2).status().code(), ErrorCode::kInvalidArgument);
  IndexedMesh smaller;
  smaller.positions.assign(f.mesh.positions.begin(), f.mesh.positions.begin() + 10);
  const std::vector<VertexSkin> smallerSkin(10);
  const Result<std::vector<VertexSkin>> foreign = tomSkin(pm, smaller, smallerSkin, 3);
  ASSERT_FALSE(foreign.ok());
  EXPECT_NE(foreign.status().message().find("another mesh"), std::string::npos)
      << foreign.status().toString();
}

}  // namespace
}  // namespace thinlod::simplifier
