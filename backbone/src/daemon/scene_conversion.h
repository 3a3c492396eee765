// Scene graph -> SchedulingScene tree (the scheduler's flat input).
//
// Contract:
// - Object numbering is scene::collectSceneObjects (id = 1 + index); the
//   scheduling object k is the scene object with id k + 1 (externalId = id).
// - Tree: node 0 is a Group holding every object that is not inside an LOD.
//   Each scene LOD becomes an LOD node whose children are one Group per
//   level (childRanges = the level's ConicRange mapped to world space: centre
//   transformed, distances times maxScale, direction by the linear part);
//   a level's objects and nested LODs hang under its Group. Transform, Group
//   and imposter nodes of the scene are transparent (their shapes attach to
//   the nearest enclosing level or the root).
// - Leaf bounds are the objects' world bounding spheres; a parent's sphere
//   encloses its children's (validateScene holds). Level groups without any
//   object get a tiny sphere at their parent's centre (they render nothing).
// - Relative accuracies: the scheduler's are relative to the leaf sphere's
//   diameter 2r. The simplifier's mesh accuracies are relative to the
//   content-frame bbox diagonal (primitives: primitiveDiameter), impostor
//   accuracies to the world bbox diagonal. meshToScheduler / impostorToScheduler
//   convert them so that the scheduler never overstates: a world distortion
//   is at most maxScale * (content distortion).
// - Options are not filled here (the core adds them). Pure: no I/O.
#pragma once

#include <cstdint>
#include <vector>

#include "thinlod/backbone/scheduling_scene.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/scene/scene.h"
#include "thinlod/common/scene/scene_objects.h"

namespace thinlod::backbone_daemon {

struct ObjectRecord {
  std::uint64_t id = 0;  // wire object id
  const scene::SceneObject* object = nullptr;
  std::uint32_t leafNode = 0;  // index into SchedulingScene::nodes
  bool primitive = false;
  double fullTriangles = 0.0;        // the object's original geometry
  backbone::Sphere bounds;           // world
  double diameter = 0.0;             // 2 * bounds.radius (scheduler's relative size)
  double contentDiameter = 0.0;      // what the simplifier's mesh accuracies refer to
  double worldBoxDiagonal = 0.0;     // what the simplifier's impostor accuracies refer to
  double meshToScheduler = 1.0;      // a_scheduler = a_simplifier_mesh * this
  double impostorToScheduler = 1.0;  // a_scheduler = a_simplifier_impostor * this
};

struct ConvertedScene {
  backbone::SchedulingScene scheduling;  // options empty, objects[k].optionCount = 0
  std::vector<ObjectRecord> records;     // records[k] <-> scheduling.objects[k]
  std::uint32_t lodNodes = 0;
};

// `objects` must come from collectSceneObjects(scene) (pointers into scene).
Result<ConvertedScene> convertScene(const scene::Scene& scene,
                                    const std::vector<scene::SceneObject>& objects);

// A scene-frame ConicRange mapped by `contentToWorld` (see above).
ConicRange rangeToWorld(const ConicRange& range, const glm::mat4& contentToWorld);

}  // namespace thinlod::backbone_daemon
