// Skinning: skeletons, keyframe clips and ASLOD's two-bone deformation
// (Schmalstieg & Fuhrmann, section 5; docs/animation.md).
//
// Contract:
// - Skeleton: bones ordered parents first (parent < index, -1 for a root);
//   restLocal is the bone's transform relative to its parent when no clip
//   drives it; inverseBind maps the skin's mesh space into the bone's space
//   at bind time. validate() checks order, finiteness and invertible
//   (non-singular) rest transforms.
// - VertexSkin: the paper's rule, a vertex depends on exactly one or two
//   bones: P = (1 - s) T_A P_A + s T_B P_B, with P_X = inverseBind_X * P
//   and T_X the bone's current global transform; boneA == boneB (s = 0)
//   is a rigid vertex.
// - AnimationClip: per-bone channels of position, rotation (unit
//   quaternion) and scale keys, times in seconds, strictly increasing, in
//   [0, duration]. Between keys: linear (positions, scales), slerp
//   (rotations); before the first / after the last key the key's value.
//   A channel with no keys of a component keeps the rest transform's one.
// - samplePose: loops (kLoop: t mod duration) or clamps (kClamp).
// - deform writes only the listed vertices (ASLOD 5.4: only the vertices of
//   the current levels are deformed); the others of `out` are untouched.
// - Pure functions, no I/O; inputs from files are validated first
//   (Skeleton::validate, validateSkin, AnimationClip::validate).
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod::anim {

struct Bone {
  std::string name;
  int parent = -1;
  glm::mat4 restLocal{1.0f};
  glm::mat4 inverseBind{1.0f};
};

struct Skeleton {
  std::vector<Bone> bones;
  Status validate(const std::string& what) const;
};

struct VertexSkin {
  std::uint32_t boneA = 0;
  std::uint32_t boneB = 0;
  float weightB = 0.0f;  // s in [0, 1]; 0 when boneA == boneB
  bool rigid() const { return boneA == boneB || weightB == 0.0f; }
};

// One VertexSkin per vertex, bones < skeleton size, weights finite in [0, 1].
Status validateSkin(const std::vector<VertexSkin>& skin, std::size_t vertexCount,
                    std::size_t boneCount, const std::string& what);

struct VectorKey {
  double time = 0.0;
  glm::vec3 value{0.0f};
};
struct RotationKey {
  double time = 0.0;
  glm::quat value{1.0f, 0.0f, 0.0f, 0.0f};
};
struct BoneChannel {
  std::uint32_t bone = 0;
  std::vector<VectorKey> positions;
  std::vector<RotationKey> rotations;
  std::vector<VectorKey> scales;
};

struct AnimationClip {
  std::string name;
  double duration = 0.0;  // seconds, > 0
  std::vector<BoneChannel> channels;
  // Bones in range and each bone driven by at most one channel, finite keys,
  // times strictly increasing within [0, duration], rotations of unit length
  // (within 1e-3; normalised on sampling), scales non-zero.
  Status validate(const Skeleton& skeleton, const std::string& what) const;
};

enum class ClipWrap : std::uint8_t { kLoop, kClamp };

// Local transforms of every bone at `seconds` (rest for undriven bones).
std::vector<glm::mat4> samplePose(const Skeleton& skeleton, const AnimationClip& clip,
                                  double seconds, ClipWrap wrap);
// The rest pose's local transforms.
std::vector<glm::mat4> restPose(const Skeleton& skeleton);
// Global transform of every bone (parents first), then times inverseBind:
// the matrices deform() multiplies mesh-space positions with.
std::vector<glm::mat4> skinningMatrices(const Skeleton& skeleton,
                                        const std::vector<glm::mat4>& localPose);

// out[v] for every v in `vertices` (all when empty); out must hold
// positions.size() entries.
void deform(const std::vector<glm::vec3>& positions, const std::vector<VertexSkin>& skin,
            const std::vector<glm::mat4>& matrices, const std::vector<std::uint32_t>& vertices,
            std::vector<glm::vec3>& out);

// ASLOD 5.2: connected vertices with the same dependency (one bone: rigid;
// a pair of bones: deformable) form one region. Vertices are connected by the
// mesh's edges. Returns a region label per vertex, labels dense from 0, in
// order of each region's lowest vertex.
struct SkinRegions {
  std::vector<std::uint32_t> labelOfVertex;
  struct Region {
    std::uint32_t boneA = 0, boneB = 0;  // boneA == boneB: rigid
    std::size_t vertices = 0;
  };
  std::vector<Region> regions;
};
SkinRegions partitionBySkin(const IndexedMesh& mesh, const std::vector<VertexSkin>& skin);

// ASLOD 5.5: weights of a deformable region from path lengths along its
// edges. `inRegion` marks the region's vertices; `borderA` / `borderB` the
// vertices it shares with the regions of bone A and bone B. Returns, per
// vertex of the region, s = dA / (dA + dB) with dX the shortest edge-path
// length (Dijkstra) to border X: 0 on border A, 1 on border B. Vertices of
// the region that reach neither border keep s = 0.5; vertices outside keep 0.
// Errors: sizes that do not match the mesh, an empty border.
Result<std::vector<float>> pathLengthWeights(const IndexedMesh& mesh,
                                             const std::vector<bool>& inRegion,
                                             const std::vector<std::uint32_t>& borderA,
                                             const std::vector<std::uint32_t>& borderB);

// The bones a skin names, ascending (`bones`), and the skin with each bone
// replaced by its index in that list (`skin`): what a renderer indexes per
// vertex, so a frame's bone poses need one matrix per palette entry only.
struct SkinPalette {
  std::vector<std::uint32_t> bones;
  std::vector<VertexSkin> skin;
};
SkinPalette compactSkin(const std::vector<VertexSkin>& skin);

// The palette's matrices at `seconds` of the clip: skinningMatrices of
// samplePose, entry i for bone palette.bones[i] (all bones < skeleton size:
// validate the skin first).
std::vector<glm::mat4> paletteMatricesAt(const Skeleton& skeleton, const AnimationClip& clip,
                                         const SkinPalette& palette, double seconds, ClipWrap wrap);

// Largest distance of any vertex from its stored (bind) position over the
// whole clip, sampled at `steps` + 1 evenly spaced times in [0, duration]
// (steps >= 1): how far the deformed mesh reaches from the mesh as stored.
// Measured, not proven, as sampledMaxDisplacement. +infinity when a deformed
// position is not finite.
double sampledMaxDeviationFromBind(const Skeleton& skeleton, const AnimationClip& clip,
                                   const std::vector<glm::vec3>& positions,
                                   const std::vector<VertexSkin>& skin, std::size_t steps);

// One weld key per vertex (simplifier BuildOptions::weldKeys): equal for
// vertices whose skins deform them alike (same bones and weight; a rigid
// vertex's unused second bone and weight ignored), different otherwise
// (a 64-bit hash: a collision could only let two such vertices weld).
std::vector<std::uint64_t> skinWeldKeys(const std::vector<VertexSkin>& skin);

// An upper bound of the spectral norm ||l||_2 (how far l can stretch a
// vector): the square root of the largest absolute row sum of l^T l
// (Gershgorin), exact for rotations, tight for similarities.
double spectralNormBound(const glm::dmat3& l);

// The largest spectralNormBound of a palette bone's skinning matrix (its
// linear part) at `steps` + 1 evenly spaced times in [0, duration] (steps >=
// 1): a bind-space displacement of length q (a quantization step) moves at
// most this factor times q at a pose, as a skinned vertex's displacement is
// a convex combination of its bones' images of it. Sampled like
// sampledMaxDeviationFromBind, so measured, not proven, between samples.
// +infinity when a matrix is not finite.
double sampledMaxSkinningScale(const Skeleton& skeleton, const AnimationClip& clip,
                               const SkinPalette& palette, std::size_t steps);

// The relative accuracy (Pasman & Jansen's a = L / error) a representation
// keeps while its object moves (docs/animation.md, "Served"): credited
// `restAccuracy` against the bind-pose reference length L, with every point
// of the level and of the full mesh at most m from its bind position
// (motionRatio = 2 m / L), the deformed level is within L / restAccuracy + 2m
// of the deformed full mesh (a point of a triangle moves by a convex
// combination of its corners' motions), and the reference sphere grown by m
// has diameter L + 2m: a' = (1 + motionRatio) / (1 / restAccuracy +
// motionRatio). restAccuracy > 0, motionRatio >= 0; 0 gives restAccuracy.
double animatedRelativeAccuracy(double restAccuracy, double motionRatio);

// Largest displacement of any vertex from its position at t0 over [t0, t1],
// with the clip sampled every `step` seconds (and at t1): a measured motion
// bound for the planned lifetime, not a proof (fast motion between samples
// can exceed it; the step bounds how much).
double sampledMaxDisplacement(const Skeleton& skeleton, const AnimationClip& clip,
                              const std::vector<glm::vec3>& positions,
                              const std::vector<VertexSkin>& skin, double t0, double t1,
                              double step, ClipWrap wrap);

}  // namespace thinlod::anim
