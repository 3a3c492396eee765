// A stand-in for the simplifier in the BackboneCore tests: answers requests
// with small, valid results whose accuracies follow simple models (analytic
// tessellations for primitives, a(t) = 3 sqrt(t) for meshes, a parallax cone
// for impostors), and a model of the frontend that applies SceneUpdates.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <glm/geometric.hpp>
#include <map>
#include <string>
#include <vector>

#include "backbone_core.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::backbone_daemon::testing {

inline std::string paperRoomPath() {
  return std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl";
}
inline std::string modelsDir() { return std::string(THINLOD_SHARED_DIR) + "/models"; }

inline Result<std::unique_ptr<BackboneCore>> paperRoomCore(const CoreOptions& options) {
  scene::SceneLoadOptions load;
  load.meshSearchPaths = {modelsDir()};
  Result<scene::Scene> loaded = scene::loadSceneFile(paperRoomPath(), load);
  if (!loaded.ok()) return loaded.status();
  return BackboneCore::create(std::move(loaded).value(), paperRoomPath(), options);
}

inline CoreOptions polygonBudget(double triangles) {
  CoreOptions options;
  options.config.maxSpeed = 0.1;
  options.budget.maxTriangles = triangles;
  return options;
}

class FakeSimplifier {
 public:
  explicit FakeSimplifier(const BackboneCore& core) : core_(core) {}

  // Triangles delivered = min(target, full) * inflation (a simplifier that
  // does not keep its promises).
  double inflation = 1.0;
  std::size_t texturebytes = 6000;
  double meshBytesPerTriangle = 1.5;
  // Mesh results say their accuracies were measured under the object's
  // motion (SimplifyResult::motionIncluded), as the simplifier does for a
  // skinned object.
  bool motionIncluded = false;

  static double meshAccuracy(double triangles) { return 3.0 * std::sqrt(triangles); }

  const scene::SceneObject& object(std::uint64_t id) const {
    return core_.sceneObjects().at(static_cast<std::size_t>(id - 1));
  }

  protocol::SimplifyResult simplify(const protocol::SimplifyRequest& request) const {
    protocol::SimplifyResult result;
    result.requestId = request.requestId;
    result.objectId = request.objectId;
    const scene::SceneObject& o = object(request.objectId);
    const double full = double(o.fullMesh->triangleCount());
    double triangles = std::min<double>(request.targetTriangles, full);
    double accuracy = 0.0;
    if (o.shape->geometry.kind == scene::GeometryKind::kPrimitive) {
      const PrimitiveShape& shape = o.shape->geometry.primitive;
      const TessellationParams p = chooseTessellation(shape, static_cast<int>(triangles));
      triangles = tessellationTriangles(shape, p);
      accuracy = tessellationAccuracy(shape, p) / 1.05;  // quantization
    } else {
      accuracy = meshAccuracy(triangles);
      if (request.curvePoints > 0) {
        for (double t = 50.0; t < full; t *= 2.0) result.curve.push_back({meshAccuracy(t), t});
        result.curve.push_back({meshAccuracy(full), full});
      }
    }
    triangles = std::max(1.0, std::floor(triangles * inflation));
    result.triangleCount = static_cast<std::uint32_t>(triangles);
    result.accuracy = accuracy;
    result.motionIncluded = motionIncluded;
    result.mesh.assign(static_cast<std::size_t>(300 + meshBytesPerTriangle * triangles), 0x5a);
    return result;
  }

  protocol::ImpostorResult impostor(const protocol::ImpostorRequest& request) const {
    protocol::ImpostorResult result;
    result.requestId = request.requestId;
    result.objectIds = request.objectIds;
    // The reference sphere of a group is enclosingSphere of its objects'
    // world spheres (relative_accuracy.h), its box their union.
    std::vector<BoundingSphere> spheres;
    Bounds box;
    for (std::uint64_t id : request.objectIds) {
      spheres.push_back(object(id).worldSphere);
      box.extend(object(id).worldBounds.min);
      box.extend(object(id).worldBounds.max);
    }
    const BoundingSphere sphere = enclosingSphere(spheres);
    protocol::Representation& rep = result.representation;
    rep.kind = request.kind;
    rep.triangleCount = request.kind == protocol::RepresentationKind::kSimpleImpostor ? 2 : 48;
    rep.mesh.assign(200, 0x11);
    rep.texture.codec = protocol::TextureCodec::kPng;
    rep.texture.width = request.textureWidth;
    rep.texture.height = request.textureHeight;
    rep.texture.data.assign(texturebytes, 0x22);
    // size / 2.8 of the world box diagonal, in the reference length L = 2r
    // (relative_accuracy.h) as the real simplifier reports it.
    rep.accuracy = double(request.textureWidth) / 2.8 *
                   (2.0 * double(sphere.radius) / double(box.diagonal()));
    // Parallax: a viewer at distance D turned by phi sees an error of about
    // diameter * sin(phi) / D.
    const glm::vec3 center = sphere.center;
    const glm::vec3 toEye = request.eye - center;
    const float distance = glm::length(toEye);
    const double diameter = 2.0 * sphere.radius;
    const double sine = std::min(1.0, request.accuracyBound * distance / diameter);
    rep.validity.center = center;
    rep.validity.distanceMin = 0.5f * distance;
    rep.validity.distanceMax = std::numeric_limits<float>::infinity();
    rep.validity.direction = toEye / distance;
    rep.validity.halfAngle = static_cast<float>(std::asin(sine));
    return result;
  }

 private:
  const BackboneCore& core_;
};

// Submits every queued request (under its own id, as the WorkerPool does)
// and returns them.
inline std::vector<OutgoingRequest> submitAll(BackboneCore& core) {
  std::vector<OutgoingRequest> requests = core.takeRequests();
  for (const OutgoingRequest& r : requests) core.requestSubmitted(r.requestId);
  return requests;
}

// The id on the wire: the request's one id.
inline std::uint64_t wireIdOf(const OutgoingRequest& r) { return r.requestId; }

// Answers requests (already submitted) through the core's result handlers.
inline void answer(BackboneCore& core, const FakeSimplifier& fake,
                   const std::vector<OutgoingRequest>& requests) {
  for (const OutgoingRequest& r : requests) {
    if (const auto* s = std::get_if<protocol::SimplifyRequest>(&r.message)) {
      protocol::SimplifyRequest wire = *s;
      wire.requestId = wireIdOf(r);
      EXPECT_TRUE(core.onSimplifyResult(fake.simplify(wire)).ok());
    } else {
      protocol::ImpostorRequest wire = std::get<protocol::ImpostorRequest>(r.message);
      wire.requestId = wireIdOf(r);
      EXPECT_TRUE(core.onImpostorResult(fake.impostor(wire)).ok());
    }
  }
}

// Requests on their way to a simulated simplifier: (due pose, request).
using InFlightRequests = std::deque<std::pair<int, OutgoingRequest>>;

// Drops the requests the core cancelled, then answers those due by `step`.
inline void answerDue(BackboneCore& core, const FakeSimplifier& fake, InFlightRequests& inFlight,
                      int step) {
  for (std::uint64_t wire : core.takeCancellations()) {
    inFlight.erase(std::remove_if(inFlight.begin(), inFlight.end(),
                                  [&](const auto& f) { return wireIdOf(f.second) == wire; }),
                   inFlight.end());
  }
  std::vector<OutgoingRequest> due;
  for (auto it = inFlight.begin(); it != inFlight.end();) {
    if (it->first <= step) {
      due.push_back(std::move(it->second));
      it = inFlight.erase(it);
    } else {
      ++it;
    }
  }
  answer(core, fake, due);
}

inline protocol::ViewerPose poseAt(std::uint64_t sequence, double seconds, glm::vec3 position,
                                   glm::vec3 target, float fovY = 0.785398f) {
  protocol::ViewerPose pose;
  pose.sequence = sequence;
  pose.timestampNs = static_cast<std::int64_t>(std::llround(seconds * 1e9));
  pose.position = position;
  const glm::vec3 forward = glm::normalize(target - position);
  // Camera looks down -z: rotation taking -z to forward, +y up.
  const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
  const glm::vec3 up = glm::cross(right, forward);
  const glm::mat3 rotation(right, up, -forward);
  pose.orientation = glm::normalize(glm::quat_cast(rotation));
  pose.fovY = fovY;
  pose.viewportWidth = 640;
  pose.viewportHeight = 480;
  return pose;
}

// What the frontend holds after applying updates (object id -> triangles),
// and what it says in its Hello (Hello.held, as
// frontend/src/daemon/wire_conversion.h heldRepresentations builds it).
struct FrontendModel {
  std::map<std::uint64_t, std::uint32_t> triangles;
  std::map<std::uint64_t, protocol::HeldRepresentation> held;
  void apply(const protocol::SceneUpdate& update) {
    for (const protocol::SceneOperation& op : update.operations) {
      if (op.type == protocol::SceneOperation::Type::kRemove) {
        triangles.erase(op.objectId);
        held.erase(op.objectId);
      } else {
        triangles[op.objectId] = op.representation.triangleCount;
        protocol::HeldRepresentation& h = held[op.objectId];
        h.objectId = op.objectId;
        h.representationId = op.representation.representationId;
        h.kind = op.representation.kind;
        h.triangleCount = op.representation.triangleCount;
        h.pointCount = op.representation.pointCount;
      }
    }
  }
  double total() const {
    double sum = 0.0;
    for (const auto& entry : triangles) sum += entry.second;
    return sum;
  }
  protocol::Hello hello() const {
    protocol::Hello hello;
    hello.role = protocol::Role::kFrontend;
    hello.name = "frontend@test";
    for (const auto& [id, h] : held) hello.held.push_back(h);
    return hello;
  }
};

}  // namespace thinlod::backbone_daemon::testing
