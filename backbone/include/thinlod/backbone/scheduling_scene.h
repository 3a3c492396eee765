// SchedulingScene: the scheduler's own flat input (not the scene graph).
//
// Contract:
// - A tree of nodes in flat arrays; nodes[0] is the root. Group nodes render
//   all children (curves add), LOD nodes render one child (lower envelope),
//   leaves are objects with representation options. Children of node n are
//   children[n.firstChild, n.firstChild + n.childCount); every child index is
//   larger than its parent's, every non-root node has exactly one parent,
//   depth <= kMaxSceneDepth. childRanges[i] is the LOD range of children[i]
//   (a level is eligible when it contains the whole predicted region).
// - bounds are world-space spheres (metres), radius > 0; a child's sphere
//   lies inside its parent's. Accuracy curves of options are RELATIVE
//   (1 / distortion as a fraction of the object's diameter 2*radius);
//   resources: triangles and encoded bytes.
// - Versions: contentVersion changes whenever a node's own inputs change
//   (bounds, ranges, options, copies); subtreeVersion must change whenever
//   anything in the subtree changes. The scheduler reuses cached curves of a
//   subtree while its subtreeVersion is unchanged, so a stale subtreeVersion
//   gives stale plans. updateSubtreeVersions() recomputes them in O(n).
// - validateScene() checks indices, tree shape, finiteness and non-empty
//   curves and names the offending node/option; Scheduler::plan requires a
//   scene that passed it (the daemon validates after every edit).
#pragma once

#include <cstdint>
#include <vector>

#include "thinlod/backbone/validity_range.h"
#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/core/status.h"

namespace thinlod::backbone {

inline constexpr int kMaxSceneDepth = 256;

enum class OptionKind : std::uint8_t {
  kOriginalMesh = 0,
  kSimplifiedMesh = 1,
  kMeshedImpostor = 2,
  kSimpleImpostor = 3,
  // Triangles + disc points (docs/hybrid.md): scheduled like a simplified
  // mesh, its resources primitive units = triangles + points / kappa.
  kHybrid = 4,
};
const char* optionKindName(OptionKind kind);

// One generated representation that exists somewhere (frontend or backbone).
struct RepresentationCopy {
  bool present = false;
  std::uint64_t id = 0;           // request id that produced it (0: preloaded)
  double relativeAccuracy = 0.0;  // what it reaches, relative to the object's diameter
  double triangles = 0.0;
  double encodedBytes = 0.0;
  ValidityRange validity;  // viewpoints from which relativeAccuracy holds
};

struct RepresentationOption {
  OptionKind kind = OptionKind::kSimplifiedMesh;
  // A newly generated representation: relative accuracy -> triangles and ->
  // encoded bytes. A fixed representation is a point curve.
  AccuracyCurve relativeTriangles;
  AccuracyCurve relativeLinkBytes;
  // Where this kind may be used at all (e.g. impostors only from afar).
  ValidityRange validity;
  RepresentationCopy atFrontend;  // displayed copy: keeping it costs no link
  RepresentationCopy atBackbone;  // generated but not at the frontend: send it
};

struct SceneObject {
  std::uint32_t firstOption = 0;  // into SchedulingScene::options
  std::uint32_t optionCount = 0;
  std::uint64_t externalId = 0;  // the daemon's id, opaque here
};

enum class SceneNodeKind : std::uint8_t { kGroup = 0, kLod = 1, kLeaf = 2 };

struct SceneNode {
  SceneNodeKind kind = SceneNodeKind::kGroup;
  Sphere bounds;
  std::uint32_t firstChild = 0;  // group, LOD
  std::uint32_t childCount = 0;
  std::uint32_t object = 0;  // leaf: into SchedulingScene::objects
  std::uint64_t contentVersion = 0;
  std::uint64_t subtreeVersion = 0;
};

struct SchedulingScene {
  std::vector<SceneNode> nodes;
  std::vector<std::uint32_t> children;
  std::vector<ValidityRange> childRanges;  // parallel to children
  std::vector<SceneObject> objects;
  std::vector<RepresentationOption> options;
};

Status validateScene(const SchedulingScene& scene);
// subtreeVersion = hash(contentVersion, children's subtreeVersion).
void updateSubtreeVersions(SchedulingScene& scene);

}  // namespace thinlod::backbone
