// Synthetic scheduling scenes for tests and benchmarks (deterministic).
//
// Contract:
// - Objects are spheres placed uniformly in a cube of side worldSize (m)
//   centred at the origin, radii log-uniform in [minRadius, maxRadius].
//   Each object gets the enabled options with plausible relative curves
//   (docs/scheduling.md, "Synthetic scenes"): simplified mesh (always),
//   original mesh (a point), meshed impostor (usable from 4 radii away),
//   simple impostor (a point, usable from 10 radii away). Triangles are
//   log-uniform per object; link bytes = 1.5 B/triangle + 500 B for meshes,
//   6000 B textures for impostors.
// - A share lodShare of objects becomes an LOD node with two levels: the
//   object itself (range: everywhere) and a coarse stand-in object with one
//   simple-impostor-like point (range: from 6 radii on).
// - Leaves are grouped spatially (Morton order) into groups of `fanout`,
//   recursively, so the tree has O(log n) depth. Node order is preorder.
// - Same options and seed -> identical scene. The result passes
//   validateScene(); contentVersion is 1 and subtree versions are filled.
#pragma once

#include <cstdint>

#include "thinlod/backbone/scheduling_scene.h"

namespace thinlod::backbone {

struct SyntheticSceneOptions {
  std::uint64_t seed = 1;
  std::size_t objects = 100;
  double worldSize = 100.0;
  double minRadius = 0.25;
  double maxRadius = 2.0;
  std::uint32_t fanout = 8;
  double minTriangles = 200.0;
  double maxTriangles = 20000.0;
  bool originalMesh = true;
  bool meshedImpostor = true;
  bool simpleImpostor = true;
  double lodShare = 0.0;
};

Result<SchedulingScene> makeSyntheticScene(const SyntheticSceneOptions& options);

}  // namespace thinlod::backbone
