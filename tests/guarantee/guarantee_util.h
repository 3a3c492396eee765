// Shared by the guarantee tests and guarantee_report: a protocol
// Representation decoded into what the frontend draws, the full-quality
// reference of a scene object, and one guarantee check of a representation
// from one eye (guarantee_check.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <memory>
#include <string>
#include <vector>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/protocol/messages.h"
#include "thinlod/simplifier/guarantee_check.h"

namespace thinlod::guarantee {

// What the frontend draws for one Representation (world space via transform).
struct Shown {
  protocol::RepresentationKind kind = protocol::RepresentationKind::kMesh;
  IndexedMesh mesh;
  glm::mat4 transform{1.0f};
  RgbaImage texture;  // impostors only
  bool textured = false;
};

inline Result<Shown> decodeShown(const protocol::Representation& rep) {
  Shown shown;
  shown.kind = rep.kind;
  shown.transform = rep.transform;
  Result<IndexedMesh> mesh = codec::decodeMesh(rep.mesh.data(), rep.mesh.size());
  if (!mesh.ok()) return mesh.status();
  shown.mesh = std::move(mesh).value();
  if (rep.kind != protocol::RepresentationKind::kMesh) {
    if (rep.texture.codec == protocol::TextureCodec::kRawRgba8) {
      shown.texture.width = static_cast<int>(rep.texture.width);
      shown.texture.height = static_cast<int>(rep.texture.height);
      shown.texture.pixels = rep.texture.data;
    } else {
      Result<RgbaImage> texture =
          codec::decodeTexture(rep.texture.data.data(), rep.texture.data.size());
      if (!texture.ok()) return texture.status();
      shown.texture = std::move(texture).value();
    }
    shown.textured = true;
  }
  return shown;
}

// The full-quality object: its full mesh, or for a primitive the finest
// tessellation the simplifier serves (error about 1e-5 of L).
struct Reference {
  std::shared_ptr<const IndexedMesh> mesh;  // content frame
  glm::mat4 objectToWorld{1.0f};
  glm::vec3 center{0.0f};  // world reference sphere
  double length = 0.0;     // L
  double reach = 0.0;      // radius around center holding every vertex (world)
};

inline double reachOf(const IndexedMesh& mesh, const glm::mat4& model, const glm::vec3& center) {
  double reach = 0.0;
  for (const glm::vec3& p : mesh.positions) {
    const glm::vec3 w(model * glm::vec4(p, 1.0f));
    reach = std::max(reach, static_cast<double>(glm::length(w - center)));
  }
  return reach;
}

inline Reference referenceOf(const scene::SceneObject& object) {
  Reference ref;
  ref.objectToWorld = object.objectToWorld;
  ref.center = glm::vec3(object.worldSphere.center);
  ref.length = referenceLength(object.worldSphere);
  const scene::Geometry& geometry = object.shape->geometry;
  if (geometry.kind == scene::GeometryKind::kPrimitive) {
    const PrimitiveShape& shape = geometry.primitive;
    ref.mesh = std::make_shared<IndexedMesh>(tessellate(shape, chooseTessellation(shape, 65536)));
  } else {
    ref.mesh = object.fullMesh;
  }
  ref.reach = reachOf(*ref.mesh, ref.objectToWorld, ref.center);
  return ref;
}

struct Check {
  simplifier::GuaranteeVerdict verdict;
  simplifier::SilhouetteDistance distance;
  int pixels = 0;
};

// One check of `shown` against `ref` from `eye`, the shown representation
// credited with relative accuracy `credited`. The camera resolves an eighth
// of the stated error per pixel (at most 1024 pixels).
inline Result<Check> checkFrom(simplifier::CoverageRenderer& renderer, const Reference& ref,
                               const Shown& shown, double credited, const glm::vec3& eye) {
  const double reach = std::max(ref.reach, reachOf(shown.mesh, shown.transform, ref.center)) * 1.02;
  const double gap = std::max(0.1, glm::length(eye - ref.center) - 0.5 * ref.length);
  const double stated = credited > 0.0 ? ref.length / (credited * gap) : 1.0;
  Result<simplifier::CheckCamera> camera =
      simplifier::makeCheckCamera(eye, ref.center, reach, std::max(stated / 8.0, 1e-6));
  if (!camera.ok()) return camera.status();
  simplifier::CoveragePart refPart{ref.mesh.get(), ref.objectToWorld, nullptr};
  simplifier::CoveragePart shownPart{&shown.mesh, shown.transform,
                                     shown.textured ? &shown.texture : nullptr};
  Result<simplifier::CoverageMask> refMask = renderer.render({refPart}, *camera);
  if (!refMask.ok()) return refMask.status();
  Result<simplifier::CoverageMask> shownMask = renderer.render({shownPart}, *camera);
  if (!shownMask.ok()) return shownMask.status();
  Result<simplifier::SilhouetteDistance> distance =
      simplifier::silhouetteDistance(*refMask, *shownMask);
  if (!distance.ok()) return distance.status();
  Check check;
  check.distance = *distance;
  check.pixels = camera->pixels;
  check.verdict =
      simplifier::judgeGuarantee(*distance, *camera, eye, ref.center, ref.length, credited);
  return check;
}

}  // namespace thinlod::guarantee
