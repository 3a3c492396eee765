// A generated articulated figure for the skinned-level tests and report
// (docs/animation.md): a three-segment limb (a tube along +x from 0 to 3,
// capped at both ends) on a chain of three bones at x = 0, 1, 2. Vertices
// nearer than `joint` to a joint are deformable on the joint's two bones,
// with ASLOD path-length weights (pathLengthWeights); the others are rigid
// on their segment's bone. The clip "wave" (2 s) moves the root (translation
// and a roll about x) and bends both joints about different axes at
// different rates, so every region moves and no two move alike.
#pragma once

#include <cstddef>
#include <cstdint>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/skinning.h"

namespace thinlod::anim::testing {

struct ArticulatedFigure {
  IndexedMesh mesh;
  Skeleton skeleton;
  std::vector<VertexSkin> skin;
  AnimationClip clip;
};

struct FigureShape {
  int ringsPerUnit = 20;  // rings of vertices per unit of length
  int around = 24;        // vertices per ring
  float radius = 0.25f;
  float joint = 0.25f;        // half length of a joint's deformable region
  float scale = 1.0f;         // every length (mesh, bones, clip translations) times this
  float bendDegrees = 70.0f;  // the joints' largest bend
  float rootTravel = 0.5f;    // the root's largest translation (before scale)
};

ArticulatedFigure makeArticulatedFigure(const FigureShape& shape = {});

}  // namespace thinlod::anim::testing
