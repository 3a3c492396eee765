#include "validate.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include "thinlod/protocol/codec.h"

namespace thinlod::protocol::detail {
namespace {

constexpr float kPi = 3.14159265358979f;

std::string describe(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "+inf" : "-inf";
  return std::to_string(value);
}

Status checkFinite(const FieldPath& path, double value) {
  if (!std::isfinite(value))
    return invalidField(path, "is " + describe(value) + ", must be finite");
  return Status();
}

Status checkNonNegative(const FieldPath& path, double value) {
  THINLOD_RETURN_IF_ERROR(checkFinite(path, value));
  if (value < 0.0) return invalidField(path, "is " + describe(value) + ", must be >= 0");
  return Status();
}

Status checkVec3(const FieldPath& path, const glm::vec3& v) {
  static const char* kAxes[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) THINLOD_RETURN_IF_ERROR(checkFinite(path.child(kAxes[i]), v[i]));
  return Status();
}

Status checkUnitQuaternion(const FieldPath& path, const glm::quat& q) {
  for (int i = 0; i < 4; ++i) THINLOD_RETURN_IF_ERROR(checkFinite(path, q[i]));
  const double norm =
      std::sqrt(double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z + double(q.w) * q.w);
  if (std::fabs(norm - 1.0) > kUnitQuaternionTolerance) {
    return invalidField(path, "has length " + describe(norm) + ", must be a unit quaternion");
  }
  return Status();
}

Status checkFov(const FieldPath& path, float fov) {
  THINLOD_RETURN_IF_ERROR(checkFinite(path, fov));
  if (!(fov > 0.0f && fov < kPi))
    return invalidField(path, "is " + describe(fov) + ", must be in (0, pi)");
  return Status();
}

Status checkText(const FieldPath& path, const std::string& text, std::size_t maxBytes) {
  if (text.size() > maxBytes) {
    return tooLarge(
        path, "is " + std::to_string(text.size()) + " bytes, limit " + std::to_string(maxBytes));
  }
  if (text.find('\0') != std::string::npos) return invalidField(path, "contains a NUL byte");
  return Status();
}

// A peer's name goes into every daemon's log (event=worker_joined name="..."):
// printable ASCII without quotes or backslashes, so it cannot end a quoted
// log field or start a forged log line.
Status checkName(const FieldPath& path, const std::string& name) {
  if (name.empty()) return invalidField(path, "is empty");
  THINLOD_RETURN_IF_ERROR(checkText(path, name, kMaxNameBytes));
  for (const char c : name) {
    if (c < 0x20 || c > 0x7e || c == '"' || c == '\\') {
      return invalidField(path, "holds byte " + std::to_string(static_cast<unsigned char>(c)) +
                                    ", allowed are printable ASCII without \" and \\");
    }
  }
  return Status();
}

Status checkRequestId(const FieldPath& path, std::uint64_t id) {
  if (id == 0) return invalidField(path, "is 0 (request ids start at 1)");
  return Status();
}

Status checkCount(const FieldPath& path, std::size_t count, std::size_t limit) {
  if (count > limit) {
    return tooLarge(path,
                    "has " + std::to_string(count) + " elements, limit " + std::to_string(limit));
  }
  return Status();
}

Status checkStatus(const FieldPath& path, const Status& status) {
  // The code is range-checked by errorCodeFromWire on decode; check it here
  // too so encode() never writes a byte the peer would reject.
  if (!errorCodeFromWire(static_cast<std::uint8_t>(status.code())).ok()) {
    return invalidField(path.child("code"), "is not a known ErrorCode");
  }
  return checkText(path.child("message"), status.message(), kMaxTextBytes);
}

bool validRole(Role role) {
  return static_cast<unsigned>(role) <= static_cast<unsigned>(Role::kTool);
}
bool validKind(RepresentationKind kind) {
  return static_cast<unsigned>(kind) <= static_cast<unsigned>(RepresentationKind::kHybrid);
}
bool validCodec(TextureCodec codec) {
  return static_cast<unsigned>(codec) <= static_cast<unsigned>(TextureCodec::kZstd);
}

Status checkConicRange(const FieldPath& path, const ConicRange& range) {
  THINLOD_RETURN_IF_ERROR(checkVec3(path.child("center"), range.center));
  THINLOD_RETURN_IF_ERROR(checkNonNegative(path.child("distance_min"), range.distanceMin));
  const FieldPath maxPath = path.child("distance_max");
  if (std::isnan(range.distanceMax) || range.distanceMax == -INFINITY) {
    return invalidField(maxPath,
                        "is " + describe(range.distanceMax) + ", must be a number or +inf");
  }
  if (range.distanceMax < range.distanceMin) {
    return invalidField(maxPath, "is " + describe(range.distanceMax) + ", below distance_min " +
                                     describe(range.distanceMin));
  }
  THINLOD_RETURN_IF_ERROR(checkVec3(path.child("direction"), range.direction));
  const FieldPath anglePath = path.child("half_angle");
  THINLOD_RETURN_IF_ERROR(checkFinite(anglePath, range.halfAngle));
  if (range.halfAngle < 0.0f || range.halfAngle > kPi) {
    return invalidField(anglePath, "is " + describe(range.halfAngle) + ", must be in [0, pi]");
  }
  if (range.halfAngle < kPi) {
    const float length =
        std::sqrt(range.direction.x * range.direction.x + range.direction.y * range.direction.y +
                  range.direction.z * range.direction.z);
    if (std::fabs(length - 1.0f) > 1e-3f) {
      return invalidField(path.child("direction"),
                          "has length " + describe(length) + ", must be a unit vector");
    }
  }
  return Status();
}

Status checkTexture(const FieldPath& path, const Texture& texture) {
  if (!validCodec(texture.codec))
    return invalidField(path.child("codec"), "is not a known TextureCodec");
  if (texture.codec == TextureCodec::kNone) {
    if (texture.width != 0 || texture.height != 0 || !texture.data.empty()) {
      return invalidField(path, "codec None must have width = height = 0 and no data");
    }
    return Status();
  }
  if (texture.width == 0 || texture.height == 0) {
    return invalidField(path, "is " + std::to_string(texture.width) + "x" +
                                  std::to_string(texture.height) + ", both sides must be >= 1");
  }
  if (texture.width > kMaxTextureDimension || texture.height > kMaxTextureDimension) {
    return tooLarge(path, "is " + std::to_string(texture.width) + "x" +
                              std::to_string(texture.height) + ", limit " +
                              std::to_string(kMaxTextureDimension) + " per side");
  }
  if (texture.data.empty()) return invalidField(path.child("data"), "is empty");
  if (texture.codec == TextureCodec::kRawRgba8) {
    const std::uint64_t expected = std::uint64_t(texture.width) * texture.height * 4u;
    if (texture.data.size() != expected) {
      return invalidField(path.child("data"), "RawRgba8 data is " +
                                                  std::to_string(texture.data.size()) +
                                                  " bytes, expected " + std::to_string(expected));
    }
  }
  return Status();
}

// Points only in hybrid representations, at most kMaxPointCount.
Status checkPointCount(const FieldPath& path, RepresentationKind kind, std::uint32_t points) {
  if (points != 0 && kind != RepresentationKind::kHybrid) {
    return invalidField(path, std::string("is ") + std::to_string(points) +
                                  ", must be 0 for kind " + representationKindName(kind));
  }
  if (points > kMaxPointCount) {
    return tooLarge(path,
                    "is " + std::to_string(points) + ", limit " + std::to_string(kMaxPointCount));
  }
  return Status();
}

// kappa of a hybrid request or result (or a SceneUpdate's units_kappa, checked
// as a hybrid's): 0 (request: the default; update: no hybrids) or in [1, kMaxKappa].
Status checkKappa(const FieldPath& path, RepresentationKind kind, double kappa, bool allowZero) {
  THINLOD_RETURN_IF_ERROR(checkFinite(path, kappa));
  if (kind != RepresentationKind::kHybrid) {
    if (kappa != 0.0)
      return invalidField(path, "is " + describe(kappa) + ", must be 0 unless Hybrid");
    return Status();
  }
  if ((allowZero && kappa == 0.0) || (kappa >= 1.0 && kappa <= kMaxKappa)) return Status();
  return invalidField(path, "is " + describe(kappa) + ", must be in [1, " + describe(kMaxKappa) +
                                "]" + (allowZero ? " or 0" : ""));
}

Status checkRepresentation(const FieldPath& path, const Representation& rep) {
  if (!validKind(rep.kind))
    return invalidField(path.child("kind"), "is not a known RepresentationKind");
  const bool needsMesh = rep.kind != RepresentationKind::kSimpleImpostor;
  const bool needsTexture =
      rep.kind != RepresentationKind::kMesh && rep.kind != RepresentationKind::kHybrid;
  if (needsMesh && rep.mesh.empty()) {
    return invalidField(path.child("mesh"), std::string("is empty, required for kind ") +
                                                representationKindName(rep.kind));
  }
  THINLOD_RETURN_IF_ERROR(checkTexture(path.child("texture"), rep.texture));
  if (needsTexture && rep.texture.codec == TextureCodec::kNone) {
    return invalidField(path.child("texture"), std::string("is missing, required for kind ") +
                                                   representationKindName(rep.kind));
  }
  if (rep.textureId != 0 && needsTexture) {
    return invalidField(path.child("texture_id"), std::string("is set for kind ") +
                                                      representationKindName(rep.kind) +
                                                      ", which carries its own texture");
  }
  if (rep.textureId != 0 && rep.texture.codec != TextureCodec::kNone) {
    return invalidField(path.child("texture_id"), "is set together with an inline texture");
  }
  const FieldPath transformPath = path.child("transform");
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r)
      THINLOD_RETURN_IF_ERROR(checkFinite(transformPath, rep.transform[c][r]));
  }
  THINLOD_RETURN_IF_ERROR(checkConicRange(path.child("validity"), rep.validity));
  THINLOD_RETURN_IF_ERROR(checkNonNegative(path.child("accuracy"), rep.accuracy));
  if (rep.triangleCount > kMaxTriangleCount) {
    return tooLarge(
        path.child("triangle_count"),
        "is " + std::to_string(rep.triangleCount) + ", limit " + std::to_string(kMaxTriangleCount));
  }
  THINLOD_RETURN_IF_ERROR(checkPointCount(path.child("point_count"), rep.kind, rep.pointCount));
  return Status();
}

// Bone poses: counts within the limits, object ids unique, every matrix
// finite and affine (the wire carries the top three rows only).
Status checkBonePoses(const FieldPath& path, const std::vector<BonePose>& poses) {
  THINLOD_RETURN_IF_ERROR(checkCount(path.child("bone_poses"), poses.size(), kMaxBonePoses));
  std::vector<std::uint64_t> ids;
  ids.reserve(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const FieldPath posePath = path.element("bone_poses", i);
    const BonePose& pose = poses[i];
    THINLOD_RETURN_IF_ERROR(
        checkCount(posePath.child("matrices"), pose.matrices.size(), kMaxBonesPerPose));
    for (std::size_t k = 0; k < pose.matrices.size(); ++k) {
      const FieldPath matrixPath = posePath.element("matrices", k);
      const glm::mat4& m = pose.matrices[k];
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) THINLOD_RETURN_IF_ERROR(checkFinite(matrixPath, m[c][r]));
        if (m[c][3] != (c == 3 ? 1.0f : 0.0f))
          return invalidField(matrixPath, "is not affine (its bottom row must be 0 0 0 1)");
      }
    }
    ids.push_back(pose.objectId);
  }
  std::sort(ids.begin(), ids.end());
  const auto duplicate = std::adjacent_find(ids.begin(), ids.end());
  if (duplicate != ids.end()) {
    return invalidField(path.child("bone_poses"),
                        "object " + std::to_string(*duplicate) + " has two poses");
  }
  return Status();
}

Status checkObjectIds(const FieldPath& path, const std::vector<std::uint64_t>& ids,
                      bool allowEmpty) {
  THINLOD_RETURN_IF_ERROR(checkCount(path, ids.size(), kMaxObjectIdsPerRequest));
  if (!allowEmpty && ids.empty()) return invalidField(path, "is empty");
  return Status();
}

// --- one function per message ---

Status check(const FieldPath& path, const Hello& m) {
  if (m.minVersion == 0 || m.minVersion > m.maxVersion) {
    return invalidField(path.child("min_version"),
                        "version range [" + std::to_string(m.minVersion) + ", " +
                            std::to_string(m.maxVersion) + "] is empty or starts at 0");
  }
  if (!validRole(m.role) || m.role == Role::kUnknown) {
    return invalidField(path.child("role"), "must be backbone, simplifier, frontend or tool");
  }
  THINLOD_RETURN_IF_ERROR(checkName(path.child("name"), m.name));
  THINLOD_RETURN_IF_ERROR(
      checkCount(path.child("capabilities"), m.capabilities.size(), kMaxCapabilities));
  for (std::size_t i = 0; i < m.capabilities.size(); ++i) {
    THINLOD_RETURN_IF_ERROR(checkName(path.element("capabilities", i), m.capabilities[i]));
  }
  if (m.capacity > kMaxWorkerCapacity) {
    return tooLarge(path.child("capacity"), "is " + std::to_string(m.capacity) + ", limit " +
                                                std::to_string(kMaxWorkerCapacity));
  }
  THINLOD_RETURN_IF_ERROR(checkText(path.child("scene_file"), m.sceneFile, kMaxPathBytes));
  if (m.frameCost) {
    const Status usable = validateCalibratedFrameCost(*m.frameCost);
    if (!usable.ok()) return invalidField(path.child("frame_cost"), usable.message());
  }
  THINLOD_RETURN_IF_ERROR(checkCount(path.child("held"), m.held.size(), kMaxHeldRepresentations));
  if (!m.held.empty() && m.role != Role::kFrontend)
    return invalidField(path.child("held"), "is for frontends only");
  for (std::size_t i = 0; i < m.held.size(); ++i) {
    const HeldRepresentation& h = m.held[i];
    const FieldPath at = path.element("held", i);
    if (h.objectId == 0) return invalidField(at.child("object_id"), "is 0");
    // Ascending and unique: one held representation per object.
    if (i > 0 && h.objectId <= m.held[i - 1].objectId)
      return invalidField(at.child("object_id"),
                          "is " + std::to_string(h.objectId) +
                              ": ids must be unique and ascending (previous " +
                              std::to_string(m.held[i - 1].objectId) + ")");
    if (!validKind(h.kind))
      return invalidField(at.child("kind"), "is not a known RepresentationKind");
    if (h.triangleCount > kMaxTriangleCount)
      return tooLarge(at.child("triangle_count"), "is " + std::to_string(h.triangleCount) +
                                                      ", limit " +
                                                      std::to_string(kMaxTriangleCount));
    THINLOD_RETURN_IF_ERROR(checkPointCount(at.child("point_count"), h.kind, h.pointCount));
  }
  return Status();
}

Status check(const FieldPath& path, const HelloReply& m) {
  if (!validRole(m.role)) return invalidField(path.child("role"), "is not a known Role");
  THINLOD_RETURN_IF_ERROR(checkText(path.child("name"), m.name, kMaxNameBytes));
  THINLOD_RETURN_IF_ERROR(checkStatus(path.child("error"), m.status));
  if (m.accepted) {
    if (!m.status.ok()) return invalidField(path.child("error"), "must be absent when accepted");
    if (m.version == 0) return invalidField(path.child("version"), "is 0 in an accepted reply");
    if (m.heartbeatIntervalMs == 0) {
      return invalidField(path.child("heartbeat_interval_ms"), "is 0 in an accepted reply");
    }
  } else if (m.status.ok()) {
    return invalidField(path.child("error"), "must say why the Hello was not accepted");
  }
  return Status();
}

Status check(const FieldPath& path, const ViewerPose& m) {
  THINLOD_RETURN_IF_ERROR(checkVec3(path.child("position"), m.position));
  THINLOD_RETURN_IF_ERROR(checkUnitQuaternion(path.child("orientation"), m.orientation));
  THINLOD_RETURN_IF_ERROR(checkFov(path.child("fov_y"), m.fovY));
  if (m.viewportWidth > kMaxViewportDimension || m.viewportHeight > kMaxViewportDimension) {
    return tooLarge(path.child("viewport"), "is " + std::to_string(m.viewportWidth) + "x" +
                                                std::to_string(m.viewportHeight) + ", limit " +
                                                std::to_string(kMaxViewportDimension));
  }
  return Status();
}

Status check(const FieldPath& path, const SceneUpdate& m) {
  THINLOD_RETURN_IF_ERROR(checkNonNegative(path.child("target_accuracy"), m.targetAccuracy));
  THINLOD_RETURN_IF_ERROR(
      checkKappa(path.child("units_kappa"), RepresentationKind::kHybrid, m.unitsKappa, true));
  THINLOD_RETURN_IF_ERROR(checkCount(path.child("textures"), m.textures.size(), kMaxSharedTextures));
  std::vector<std::uint64_t> textureIds;
  textureIds.reserve(m.textures.size());
  for (std::size_t i = 0; i < m.textures.size(); ++i) {
    const SharedTexture& t = m.textures[i];
    const FieldPath texturePath = path.element("textures", i);
    if (t.textureId == 0) return invalidField(texturePath.child("texture_id"), "is 0");
    THINLOD_RETURN_IF_ERROR(checkTexture(texturePath.child("texture"), t.texture));
    if (t.texture.codec == TextureCodec::kNone)
      return invalidField(texturePath.child("texture"), "is missing");
    textureIds.push_back(t.textureId);
  }
  std::sort(textureIds.begin(), textureIds.end());
  const auto duplicateTexture = std::adjacent_find(textureIds.begin(), textureIds.end());
  if (duplicateTexture != textureIds.end()) {
    return invalidField(path.child("textures"),
                        "lists texture id " + std::to_string(*duplicateTexture) + " twice");
  }
  THINLOD_RETURN_IF_ERROR(
      checkCount(path.child("operations"), m.operations.size(), kMaxSceneOperations));
  static const Representation kNoRepresentation;
  std::vector<std::uint64_t> ids;
  ids.reserve(m.operations.size());
  for (std::size_t i = 0; i < m.operations.size(); ++i) {
    const SceneOperation& op = m.operations[i];
    const FieldPath opPath = path.element("operations", i);
    switch (op.type) {
      case SceneOperation::Type::kAddOrReplace:
        THINLOD_RETURN_IF_ERROR(
            checkRepresentation(opPath.child("representation"), op.representation));
        break;
      case SceneOperation::Type::kRemove:
        if (!(op.representation == kNoRepresentation)) {
          return invalidField(opPath.child("representation"), "must be absent in a Remove");
        }
        break;
      default:
        return invalidField(opPath.child("type"), "is not a known SceneOpType");
    }
    ids.push_back(op.objectId);
  }
  std::sort(ids.begin(), ids.end());
  const auto duplicate = std::adjacent_find(ids.begin(), ids.end());
  if (duplicate != ids.end()) {
    return invalidField(path.child("operations"),
                        "object " + std::to_string(*duplicate) + " appears twice in one batch");
  }
  return checkBonePoses(path, m.bonePoses);
}

Status check(const FieldPath& path, const FrameStats& m) {
  THINLOD_RETURN_IF_ERROR(checkFinite(path.child("snr_db"), m.snrDb));
  if (!m.hasSnr && m.snrDb != 0.0)
    return invalidField(path.child("snr_db"), "must be 0 when has_snr is false");
  THINLOD_RETURN_IF_ERROR(checkNonNegative(path.child("render_ms"), m.renderMs));
  THINLOD_RETURN_IF_ERROR(
      checkCount(path.child("rejected_plans"), m.rejectedPlans.size(), kMaxRejectedPlans));
  if (m.earlyPolygons > m.polygons)
    return invalidField(path.child("early_polygons"), "must be at most polygons");
  return Status();
}

Status check(const FieldPath& path, const SimplifyRequest& m) {
  THINLOD_RETURN_IF_ERROR(checkRequestId(path.child("request_id"), m.requestId));
  const bool hasPath = !m.sourcePath.empty();
  const bool hasMesh = !m.sourceMesh.empty();
  if (hasPath == hasMesh)
    return invalidField(path, "needs exactly one of source_path and source_mesh");
  THINLOD_RETURN_IF_ERROR(checkText(path.child("source_path"), m.sourcePath, kMaxPathBytes));
  switch (m.target) {
    case SimplifyRequest::Target::kTriangles:
      if (m.targetTriangles == 0 || m.targetTriangles > kMaxTriangleCount) {
        return invalidField(path.child("target_triangles"),
                            "is " + std::to_string(m.targetTriangles) + ", must be in [1, " +
                                std::to_string(kMaxTriangleCount) + "]");
      }
      break;
    case SimplifyRequest::Target::kAccuracy:
      THINLOD_RETURN_IF_ERROR(checkFinite(path.child("target_accuracy"), m.targetAccuracy));
      if (m.targetAccuracy <= 0.0) {
        return invalidField(path.child("target_accuracy"),
                            "is " + describe(m.targetAccuracy) + ", must be > 0");
      }
      break;
    default:
      return invalidField(path.child("target"), "is not a known SimplifyTarget");
  }
  if (m.curvePoints > kMaxCurveSamples) {
    return tooLarge(path.child("curve_points"), "is " + std::to_string(m.curvePoints) + ", limit " +
                                                    std::to_string(kMaxCurveSamples));
  }
  if (m.representation != RepresentationKind::kMesh &&
      m.representation != RepresentationKind::kHybrid) {
    return invalidField(path.child("representation"), "must be Mesh or Hybrid");
  }
  THINLOD_RETURN_IF_ERROR(checkKappa(path.child("kappa"), m.representation, m.kappa, true));
  if (m.keepBoundary && m.representation != RepresentationKind::kMesh)
    return invalidField(path.child("keep_boundary"), "applies to Mesh only");
  return Status();
}

Status check(const FieldPath& path, const SimplifyResult& m) {
  THINLOD_RETURN_IF_ERROR(checkRequestId(path.child("request_id"), m.requestId));
  THINLOD_RETURN_IF_ERROR(checkStatus(path.child("error"), m.status));
  THINLOD_RETURN_IF_ERROR(checkCount(path.child("curve"), m.curve.size(), kMaxCurveSamples));
  if (!m.status.ok()) {
    if (!m.mesh.empty() || !m.curve.empty() || m.triangleCount != 0 || m.accuracy != 0.0 ||
        m.pointCount != 0 || m.kappa != 0.0 || m.motionIncluded) {
      return invalidField(path,
                          "an error result must carry no mesh, curve, triangles, points, kappa, "
                          "accuracy or motion_included");
    }
    return Status();
  }
  if (m.mesh.empty()) return invalidField(path.child("mesh"), "is empty in a successful result");
  if (m.kind != RepresentationKind::kMesh && m.kind != RepresentationKind::kHybrid) {
    return invalidField(path.child("kind"), "must be Mesh or Hybrid");
  }
  THINLOD_RETURN_IF_ERROR(checkPointCount(path.child("point_count"), m.kind, m.pointCount));
  THINLOD_RETURN_IF_ERROR(checkKappa(path.child("kappa"), m.kind, m.kappa, false));
  if (m.motionIncluded && m.kind != RepresentationKind::kMesh)
    return invalidField(path.child("motion_included"), "applies to Mesh only");
  THINLOD_RETURN_IF_ERROR(checkNonNegative(path.child("accuracy"), m.accuracy));
  if (m.triangleCount > kMaxTriangleCount) {
    return tooLarge(
        path.child("triangle_count"),
        "is " + std::to_string(m.triangleCount) + ", limit " + std::to_string(kMaxTriangleCount));
  }
  for (std::size_t i = 0; i < m.curve.size(); ++i) {
    const FieldPath samplePath = path.element("curve", i);
    THINLOD_RETURN_IF_ERROR(checkNonNegative(samplePath.child("accuracy"), m.curve[i].accuracy));
    THINLOD_RETURN_IF_ERROR(checkNonNegative(samplePath.child("resources"), m.curve[i].resources));
  }
  return Status();
}

Status check(const FieldPath& path, const ImpostorRequest& m) {
  THINLOD_RETURN_IF_ERROR(checkRequestId(path.child("request_id"), m.requestId));
  THINLOD_RETURN_IF_ERROR(checkObjectIds(path.child("object_ids"), m.objectIds, false));
  THINLOD_RETURN_IF_ERROR(checkVec3(path.child("eye"), m.eye));
  THINLOD_RETURN_IF_ERROR(checkUnitQuaternion(path.child("orientation"), m.orientation));
  THINLOD_RETURN_IF_ERROR(checkFov(path.child("fov_y"), m.fovY));
  if (m.textureWidth == 0 || m.textureHeight == 0) {
    return invalidField(path.child("texture_size"), "has a zero side");
  }
  if (m.textureWidth > kMaxTextureDimension || m.textureHeight > kMaxTextureDimension) {
    return tooLarge(path.child("texture_size"),
                    "is " + std::to_string(m.textureWidth) + "x" + std::to_string(m.textureHeight) +
                        ", limit " + std::to_string(kMaxTextureDimension) + " per side");
  }
  if (!validKind(m.kind) || m.kind == RepresentationKind::kMesh) {
    return invalidField(path.child("kind"), "must be SimpleImpostor or MeshedImpostor");
  }
  THINLOD_RETURN_IF_ERROR(checkNonNegative(path.child("accuracy_bound"), m.accuracyBound));
  if (!validCodec(m.textureCodec) || m.textureCodec == TextureCodec::kNone) {
    return invalidField(path.child("texture_codec"), "must be a known codec other than None");
  }
  if (m.frameCenter) THINLOD_RETURN_IF_ERROR(checkVec3(path.child("frame_center"), *m.frameCenter));
  if (!std::isfinite(m.frameWidth) || !std::isfinite(m.frameHeight) || m.frameWidth < 0.0f ||
      m.frameHeight < 0.0f || ((m.frameWidth > 0.0f) != (m.frameHeight > 0.0f))) {
    return invalidField(path.child("frame_size"),
                        "must be two finite positive sizes or 0 0 (framed from the objects)");
  }
  return Status();
}

Status check(const FieldPath& path, const ImpostorResult& m) {
  THINLOD_RETURN_IF_ERROR(checkRequestId(path.child("request_id"), m.requestId));
  THINLOD_RETURN_IF_ERROR(checkObjectIds(path.child("object_ids"), m.objectIds, true));
  THINLOD_RETURN_IF_ERROR(checkStatus(path.child("error"), m.status));
  if (!m.status.ok()) {
    static const Representation kNoRepresentation;
    if (!(m.representation == kNoRepresentation)) {
      return invalidField(path.child("representation"), "must be absent in an error result");
    }
    return Status();
  }
  const FieldPath repPath = path.child("representation");
  THINLOD_RETURN_IF_ERROR(checkRepresentation(repPath, m.representation));
  if (m.representation.kind == RepresentationKind::kMesh) {
    return invalidField(repPath.child("kind"), "must be an impostor kind");
  }
  return Status();
}

Status check(const FieldPath&, const Heartbeat&) { return Status(); }

Status check(const FieldPath& path, const Shutdown& m) {
  return checkText(path.child("reason"), m.reason, kMaxTextBytes);
}

}  // namespace

Status validateMessage(const FieldPath& path, const Message& message) {
  return std::visit([&](const auto& m) { return check(path, m); }, message);
}

}  // namespace thinlod::protocol::detail
