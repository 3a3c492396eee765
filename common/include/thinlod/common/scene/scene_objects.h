// Scene objects: the drawable leaves of a scene graph, numbered the same way
// by all three daemons so that an object id on the wire means one Shape.
//
// Contract:
// - collectSceneObjects() walks flattenInstances() (pre-order over all
//   roots): each Shape instance with drawable geometry becomes one object,
//   id = 1 + its position among them. A Shape USEd twice is two objects. The
//   numbering depends only on the scene file, so daemons that load the same
//   file agree on every id.
// - fullMesh is the Shape's best geometry in its own (content) frame: the
//   loaded mesh file or IndexedFaceSet as is, a primitive tessellated at
//   `primitiveTriangles` (its "original"). objectToWorld maps that frame to
//   world; worldBounds are the transformed mesh's bounds.
// - contentSphere is the object's reference sphere of relative accuracy
//   (core/relative_accuracy.h): primitiveReferenceSphere for a primitive,
//   referenceSphere(fullMesh) otherwise. worldSphere is it mapped by
//   objectToWorld (mapReferenceSphere with maxScale); it encloses the object
//   and is the scheduler's leaf sphere, its diameter the world L.
// - An animated object (Geometry::animation) moves within its clip's motion
//   bound m of its stored (bind) mesh: its contentSphere is the reference
//   sphere grown by m and its worldBounds by m (times maxScale), so both
//   enclose it at every (sampled) pose. Relative accuracies measured against
//   the bind mesh's sphere convert to this one by anim::animatedRelativeAccuracy
//   (docs/animation.md, "Served").
// - Regions: a mesh-file Shape with Geometry::regionCount N (an Inline's
//   `regions N`) becomes N consecutive objects, one per region of
//   splitMeshIntoRegions (mesh/mesh_regions.h): fullMesh is the region's
//   owned triangles (vertices renumbered), same shape (appearance) and
//   transform; spheres and bounds are the region's. Every instance of the
//   Shape shares the N meshes. A split that fails (a region owning no
//   triangle) is kInvalidArgument naming the Inline's file:line:column.
// - Pointers refer into the Scene, which must outlive the objects.
// - Errors: a mesh-file Shape whose mesh was not resolved -> kNotFound naming
//   the url; an invalid primitive -> kInvalidArgument.
// - Pure apart from the tessellation work; thread-safe for a const Scene.
#pragma once

#include <cstdint>
#include <glm/mat4x4.hpp>
#include <memory>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/scene/scene.h"

namespace thinlod::scene {

struct SceneObject {
  std::uint64_t id = 0;
  const ShapeNode* shape = nullptr;
  int instance = -1;  // index into flattenInstances(scene)
  glm::mat4 objectToWorld{1.0f};
  std::shared_ptr<const IndexedMesh> fullMesh;  // content frame
  Bounds worldBounds;
  BoundingSphere contentSphere;  // reference sphere, content frame
  BoundingSphere worldSphere;    // contentSphere mapped to world
  // A region object (an Inline's `regions N`): region index in [0, regionCount)
  // and N; regionCount 0 for every other object.
  std::uint32_t region = 0;
  std::uint32_t regionCount = 0;
};

struct SceneObjectOptions {
  int primitiveTriangles = 4096;  // tessellation of a primitive's "original"
};

Result<std::vector<SceneObject>> collectSceneObjects(const Scene& scene,
                                                     const SceneObjectOptions& options = {});

// True when the object is drawn with a texture: its shape names a texture
// file and its full mesh carries uvs. The one test of the backbone's texture
// table (scene_textures) and of the kinds that carry no uvs (hybrids).
bool isTextured(const SceneObject& object);

// The object with `id`, or nullptr.
const SceneObject* findSceneObject(const std::vector<SceneObject>& objects, std::uint64_t id);

}  // namespace thinlod::scene
