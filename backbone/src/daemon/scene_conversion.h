// Scene graph -> SchedulingScene tree (the scheduler's flat input).
//
// Contract:
// - Object numbering is scene::collectSceneObjects (id = 1 + index); the
//   scheduling object k is the scene object with id k + 1 (externalId = id).
// - Tree: node 0 is a Group holding every object that is not inside an LOD.
//   Each scene LOD becomes an LOD node whose children are one Group per
//   level (childRanges = the level's ConicRange mapped to world space: centre
//   transformed, distances times maxScale, direction by the linear part);
//   a level's objects and nested LODs hang under its Group. Transform and
//   Group nodes of the scene are transparent (their shapes attach to the
//   nearest enclosing level or the root).
// - Imposter nodes (SimpleImposter, MeshedImposter, SimplifiedPolygon; paper
//   section 3.6, "replace their children with a single simplification") are
//   one representation of their whole subtree (docs/backbone.md, "Imposter
//   nodes"); an imposter node inside another one's subtree is transparent:
//   * one object below it: that object is one leaf whose options are its
//     full representation (the mesh kinds) and the node's kind only
//     (SimplifiedPolygon: the mesh kinds only);
//   * several objects below a SimpleImposter / MeshedImposter: an LOD node
//     whose level 0 is a Group of the objects (mesh kinds only) and whose
//     level 1 is one *cluster* leaf with the node's impostor of all of them
//     (ObjectRecord::members; its wire id is numbered above every object id,
//     objects.size() + 1 + k for the k-th cluster in pre-order);
//   * an LOD below a SimpleImposter / MeshedImposter of several objects:
//     the node is transparent (an LOD's levels are alternatives);
//   * several objects below a SimplifiedPolygon: its objects keep their own
//     leaves with the mesh kinds only (no merged mesh yet: every one is
//     simplified to the same target);
//   * an LOD whose every level is the same Shape under the same transform,
//     as itself or as the one object of an imposter node (the paper's
//     Figure 10), is ONE leaf (the first level's object id) whose options
//     are the levels' kinds, each valid in its level's range (world); the
//     other levels' object ids get no leaf.
// - A region Shape (an Inline's `regions N`) is N objects of one instance:
//   N leaves side by side, each with its region's sphere and its own curve
//   (docs/regions.md, "In the running system"); below an imposter node they
//   count as N objects, inside an LOD level they do not collapse (Figure 10).
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
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <optional>
#include <vector>

#include "thinlod/backbone/scheduling_scene.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/scene/scene.h"
#include "thinlod/common/scene/scene_objects.h"

namespace thinlod::backbone_daemon {

// A representation kind the scene allows for a record (section 3.6).
struct KindOffer {
  bool offered = true;
  // World range from an LOD level (a Figure 10 level with a ConicRange);
  // unset: the kind's default (everywhere for meshes, the impostor radii of
  // CoreOptions for impostors).
  std::optional<ConicRange> range;
  // The scene names this kind explicitly (an imposter node): offered even
  // when CoreOptions switches the kind's default off.
  bool explicitNode = false;
  // The node's autocenter / autosize FALSE (paper Figure 9): the impostor's
  // fixed centre (world) and width x height (world metres; 0 0: automatic),
  // sent in the ImpostorRequest.
  std::optional<glm::vec3> frameCenter;
  glm::vec2 frameSize{0.0f};
};

struct ObjectRecord {
  std::uint64_t id = 0;  // wire object id
  const scene::SceneObject* object = nullptr;
  std::uint32_t leafNode = 0;  // index into SchedulingScene::nodes
  bool primitive = false;
  double fullTriangles = 0.0;     // the object's original geometry
  backbone::Sphere bounds;        // world
  double diameter = 0.0;          // 2 * bounds.radius: the world reference length L
  double worldBoxDiagonal = 0.0;  // world bbox diagonal: the impostor quad's expected width
  // What the scene lets this record be: a plain Shape offers every kind.
  KindOffer mesh, meshedImpostor, simpleImpostor;
  // The scene object ids a representation of this record stands for (an
  // ImpostorRequest's objectIds): {id}, or a cluster's objects.
  std::vector<std::uint64_t> members;
  bool cluster = false;  // a representation of several objects (id above the objects')
  const scene::ImposterNode* imposterNode = nullptr;  // the node it comes from, if any
};

struct ConvertedScene {
  backbone::SchedulingScene scheduling;  // options empty, objects[k].optionCount = 0
  std::vector<ObjectRecord> records;     // records[k] <-> scheduling.objects[k]
  std::uint32_t lodNodes = 0;            // LOD nodes of the scene that became LOD nodes
  std::uint32_t clusters = 0;            // cluster leaves (several objects, one impostor)
  std::uint32_t collapsedLods = 0;       // LODs of one Shape that became one leaf (Figure 10)
  std::uint32_t imposterLeaves = 0;      // imposter nodes over one object (one leaf)
};

// `objects` must come from collectSceneObjects(scene) (pointers into scene).
Result<ConvertedScene> convertScene(const scene::Scene& scene,
                                    const std::vector<scene::SceneObject>& objects);

// A scene-frame ConicRange mapped by `contentToWorld` (see above).
ConicRange rangeToWorld(const ConicRange& range, const glm::mat4& contentToWorld);

}  // namespace thinlod::backbone_daemon
