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
// - Relative accuracies have one reference length everywhere
//   (thinlod/common/core/relative_accuracy.h, docs/protocol.md): the leaf
//   sphere is the object's world reference sphere (SceneObject::worldSphere)
//   and its diameter the L that the simplifier's mesh, primitive and
//   impostor accuracies refer to, so they are used as they arrive.
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
  double fullTriangles = 0.0;     // the object's original geometry
  backbone::Sphere bounds;        // world
  double diameter = 0.0;          // 2 * bounds.radius: the world reference length L
  double worldBoxDiagonal = 0.0;  // world bbox diagonal: the impostor quad's expected width
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
