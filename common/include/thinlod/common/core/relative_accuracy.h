// Relative accuracy: the one reference length every module uses
// (docs/protocol.md, "Relative accuracy"; Pasman & Jansen 2002, section 3.1:
// distortion as a fraction of the object's size).
//
// Contract:
// - An object's reference sphere is a bounding sphere of its full geometry in
//   its content frame: referenceSphere(mesh) for a mesh (IndexedMesh::
//   boundingSphere, Ritter, over every position), primitiveReferenceSphere
//   (mesh/primitives.h) for an analytic primitive. scene::collectSceneObjects
//   stores it per object (SceneObject::contentSphere) so that all daemons,
//   loading the same scene file, compute the same floats.
// - In world the sphere is mapped by the object's transform: centre
//   transformed, radius times the transform's largest stretch
//   (scene::maxScale). This mapped sphere is the scheduler's leaf sphere.
// - The reference length L is the reference sphere's diameter 2r (content
//   units in the content frame, metres in world). A representation of
//   several objects (an impostor of a group) refers to enclosingSphere of
//   their world reference spheres; of one object, to that object's sphere.
// - Relative accuracy a = 1/d, d = e / L, e = the representation's largest
//   geometric error (symmetric Hausdorff) in the same frame as L.
//   Frame invariance: e_world <= stretch * e_content and L_world = stretch *
//   L_content, so a relative accuracy measured in the content frame never
//   overstates the world one (equal under similarities). No module converts
//   relative accuracies between frames or between representation kinds.
// - Absolute accuracy (rad^-1) at distance D: a * D / L (angular error
//   e / D <= L / (a D)). Callers keep D > 0 (the scheduler clamps it with
//   minimalDistance).
// - Any enclosing sphere's diameter bounds the mesh's extent along every axis,
//   so L also bounds Draco's position quantization step range (codec).
// - Pure functions, no I/O, thread-safe. Non-positive or non-finite lengths
//   give 0 or +infinity as stated per function; callers validate inputs from
//   outside first.
#pragma once

#include <glm/mat4x4.hpp>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"

namespace thinlod {

// The reference sphere of a mesh object (content frame). Empty mesh: radius 0.
BoundingSphere referenceSphere(const IndexedMesh& contentMesh);

// `contentSphere` mapped to world by `contentToWorld`, whose largest stretch
// (scene::maxScale(contentToWorld)) is `stretch` >= 0.
BoundingSphere mapReferenceSphere(const BoundingSphere& contentSphere,
                                  const glm::mat4& contentToWorld, double stretch);

// One sphere: itself. Several: centred on the box around them, the smallest
// radius around that centre that holds them all (rounded up). None: radius 0.
BoundingSphere enclosingSphere(const std::vector<BoundingSphere>& spheres);

// L = 2 r, in double.
double referenceLength(const BoundingSphere& sphere);

// d = error / L: the relative error of a representation whose largest
// geometric error is `error` (same units as L). L <= 0: +infinity.
double relativeError(double error, double referenceLength);

// a * D / L (rad^-1). L <= 0: 0.
double absoluteAccuracy(double relativeAccuracy, double distance, double referenceLength);

// The largest angular error (rad) a representation of relative accuracy `a`
// makes at distance D: L / (a D). a <= 0 or D <= 0: +infinity.
double angularError(double relativeAccuracy, double distance, double referenceLength);

}  // namespace thinlod
