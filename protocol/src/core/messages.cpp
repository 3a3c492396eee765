#include "thinlod/protocol/messages.h"

#include <cstdio>
#include <type_traits>

namespace thinlod::protocol {

const char* roleName(Role role) {
  switch (role) {
    case Role::kUnknown:
      return "unknown";
    case Role::kBackbone:
      return "backbone";
    case Role::kSimplifier:
      return "simplifier";
    case Role::kFrontend:
      return "frontend";
    case Role::kTool:
      return "tool";
  }
  return "invalid-role";
}

const char* messageName(const Message& message) {
  static constexpr const char* kNames[] = {"Hello",           "HelloReply",      "ViewerPose",
                                           "SceneUpdate",     "SimplifyRequest", "SimplifyResult",
                                           "ImpostorRequest", "ImpostorResult",  "FrameStats",
                                           "Heartbeat",       "Shutdown"};
  static_assert(std::size(kNames) == std::variant_size_v<Message>, "one name per message");
  return kNames[message.index()];
}

namespace {
bool sameStatus(const Status& a, const Status& b) {
  return a.code() == b.code() && a.message() == b.message();
}
bool sameCurve(const std::vector<AccuracySample>& a, const std::vector<AccuracySample>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].accuracy != b[i].accuracy || a[i].resources != b[i].resources) return false;
  }
  return true;
}
bool sameFrameCost(const std::optional<FrameCostConstants>& a,
                   const std::optional<FrameCostConstants>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return a->initSeconds == b->initSeconds && a->finalSeconds == b->finalSeconds &&
         a->setupSeconds == b->setupSeconds && a->triangleSeconds == b->triangleSeconds &&
         a->pixelSeconds == b->pixelSeconds && a->additive == b->additive;
}
}  // namespace

bool operator==(const ConicRange& a, const ConicRange& b) {
  return a.center == b.center && a.distanceMin == b.distanceMin && a.distanceMax == b.distanceMax &&
         a.direction == b.direction && a.halfAngle == b.halfAngle;
}
bool operator==(const Texture& a, const Texture& b) {
  return a.codec == b.codec && a.width == b.width && a.height == b.height && a.data == b.data;
}
bool operator==(const Representation& a, const Representation& b) {
  return a.representationId == b.representationId && a.generation == b.generation &&
         a.kind == b.kind && a.mesh == b.mesh && a.texture == b.texture &&
         a.transform == b.transform && a.validity == b.validity && a.accuracy == b.accuracy &&
         a.triangleCount == b.triangleCount && a.pointCount == b.pointCount &&
         a.textureId == b.textureId;
}
bool operator==(const SharedTexture& a, const SharedTexture& b) {
  return a.textureId == b.textureId && a.texture == b.texture;
}
bool operator==(const HeldRepresentation& a, const HeldRepresentation& b) {
  return a.objectId == b.objectId && a.representationId == b.representationId &&
         a.kind == b.kind && a.triangleCount == b.triangleCount && a.pointCount == b.pointCount;
}
bool operator==(const Hello& a, const Hello& b) {
  return a.minVersion == b.minVersion && a.maxVersion == b.maxVersion && a.role == b.role &&
         a.name == b.name && a.instanceId == b.instanceId && a.capabilities == b.capabilities &&
         a.capacity == b.capacity && a.sceneFingerprint == b.sceneFingerprint &&
         a.sceneFile == b.sceneFile && sameFrameCost(a.frameCost, b.frameCost) &&
         a.held == b.held;
}
bool operator==(const HelloReply& a, const HelloReply& b) {
  return a.accepted == b.accepted && a.version == b.version && a.role == b.role &&
         a.name == b.name && a.heartbeatIntervalMs == b.heartbeatIntervalMs &&
         sameStatus(a.status, b.status);
}
bool operator==(const ViewerPose& a, const ViewerPose& b) {
  return a.timestampNs == b.timestampNs && a.sequence == b.sequence && a.position == b.position &&
         a.orientation == b.orientation && a.fovY == b.fovY && a.viewportWidth == b.viewportWidth &&
         a.viewportHeight == b.viewportHeight;
}
bool operator==(const SceneOperation& a, const SceneOperation& b) {
  return a.type == b.type && a.objectId == b.objectId && a.representation == b.representation;
}
bool operator==(const BonePose& a, const BonePose& b) {
  return a.objectId == b.objectId && a.matrices == b.matrices;
}
bool operator==(const SceneUpdate& a, const SceneUpdate& b) {
  return a.plan == b.plan && a.frame == b.frame && a.targetAccuracy == b.targetAccuracy &&
         a.operations == b.operations && a.textures == b.textures && a.bonePoses == b.bonePoses &&
         a.unitsKappa == b.unitsKappa;
}
bool operator==(const FrameStats& a, const FrameStats& b) {
  return a.frame == b.frame && a.plan == b.plan && a.timestampNs == b.timestampNs &&
         a.polygons == b.polygons && a.linkBytes == b.linkBytes && a.hasSnr == b.hasSnr &&
         a.snrDb == b.snrDb && a.renderMs == b.renderMs && a.rejectedPlans == b.rejectedPlans &&
         a.earlyPolygons == b.earlyPolygons;
}
bool operator==(const SimplifyRequest& a, const SimplifyRequest& b) {
  return a.requestId == b.requestId && a.objectId == b.objectId && a.sourcePath == b.sourcePath &&
         a.sourceMesh == b.sourceMesh && a.target == b.target &&
         a.targetTriangles == b.targetTriangles && a.targetAccuracy == b.targetAccuracy &&
         a.curvePoints == b.curvePoints && a.sceneFingerprint == b.sceneFingerprint &&
         a.representation == b.representation && a.kappa == b.kappa &&
         a.keepBoundary == b.keepBoundary;
}
bool operator==(const SimplifyResult& a, const SimplifyResult& b) {
  return a.requestId == b.requestId && a.objectId == b.objectId && sameStatus(a.status, b.status) &&
         a.mesh == b.mesh && a.triangleCount == b.triangleCount && a.accuracy == b.accuracy &&
         sameCurve(a.curve, b.curve) && a.kind == b.kind && a.pointCount == b.pointCount &&
         a.kappa == b.kappa && a.motionIncluded == b.motionIncluded;
}
bool operator==(const ImpostorRequest& a, const ImpostorRequest& b) {
  return a.requestId == b.requestId && a.objectIds == b.objectIds && a.eye == b.eye &&
         a.orientation == b.orientation && a.fovY == b.fovY && a.textureWidth == b.textureWidth &&
         a.textureHeight == b.textureHeight && a.kind == b.kind &&
         a.accuracyBound == b.accuracyBound && a.textureCodec == b.textureCodec &&
         a.sceneFingerprint == b.sceneFingerprint && a.frameCenter == b.frameCenter &&
         a.frameWidth == b.frameWidth && a.frameHeight == b.frameHeight;
}
bool operator==(const ImpostorResult& a, const ImpostorResult& b) {
  return a.requestId == b.requestId && a.objectIds == b.objectIds &&
         sameStatus(a.status, b.status) && a.representation == b.representation;
}
bool operator==(const Heartbeat& a, const Heartbeat& b) {
  return a.timestampNs == b.timestampNs && a.sequence == b.sequence;
}
bool operator==(const Shutdown& a, const Shutdown& b) { return a.reason == b.reason; }

std::string fingerprintText(std::uint64_t fingerprint) {
  char text[19];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(fingerprint));
  return text;
}

Status checkSameScene(const char* ourRole, std::uint64_t ourFingerprint, const std::string& ourFile,
                      const char* theirRole, std::uint64_t theirFingerprint,
                      const std::string& theirFile) {
  if (ourFingerprint == 0 || theirFingerprint == 0 || ourFingerprint == theirFingerprint)
    return Status();
  return Status(ErrorCode::kInvalidArgument,
                std::string("scene mismatch: the ") + ourRole + " loaded " + ourFile +
                    " (fingerprint " + fingerprintText(ourFingerprint) + "), the " + theirRole +
                    " loaded " + (theirFile.empty() ? std::string("an unnamed scene") : theirFile) +
                    " (fingerprint " + fingerprintText(theirFingerprint) +
                    "): start every daemon with the same scene file and models");
}

}  // namespace thinlod::protocol
