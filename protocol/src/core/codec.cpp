// FlatBuffers <-> plain structs. Order of checks in decode (codec.h):
// size limit, identifier, envelope header (version), full Verifier, then
// conversion with count limits, then the shared semantic checks.
#include "thinlod/protocol/codec.h"

#include <cstring>
#include <glm/gtc/type_ptr.hpp>
#include <type_traits>

#include "field_path.h"
#include "thinlod_wire_generated.h"
#include "validate.h"

namespace thinlod::protocol {
namespace {

namespace fb = flatbuffers;
namespace w = thinlod::wire;
using detail::FieldPath;
using detail::invalidField;
using detail::tooLarge;

constexpr char kIdentifier[] = "TLOD";
// Smallest possible FlatBuffer with an identifier: root offset + identifier.
constexpr std::size_t kMinMessageBytes = 8;

static_assert(static_cast<int>(w::ErrorCode::MAX) == static_cast<int>(ErrorCode::kInternal),
              "wire ErrorCode and thinlod::ErrorCode must have the same values");
static_assert(static_cast<int>(w::Role::MAX) == static_cast<int>(Role::kTool));
static_assert(static_cast<int>(w::RepresentationKind::MAX) ==
              static_cast<int>(RepresentationKind::kHybrid));
static_assert(static_cast<int>(w::TextureCodec::MAX) == static_cast<int>(TextureCodec::kZstd));

// ---------------------------------------------------------------- encode

w::Vec3 toWire(const glm::vec3& v) { return w::Vec3(v.x, v.y, v.z); }
w::Quat toWire(const glm::quat& q) { return w::Quat(q.x, q.y, q.z, q.w); }
w::Mat4 toWire(const glm::mat4& m) {
  return w::Mat4(fb::span<const float, 16>(glm::value_ptr(m), 16));
}
// The top three rows; validate() has checked the bottom row is 0 0 0 1.
w::BoneMatrix toWireBoneMatrix(const glm::mat4& m) {
  float rows[12];
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 3; ++r) rows[c * 3 + r] = m[c][r];
  }
  return w::BoneMatrix(fb::span<const float, 12>(rows, 12));
}
w::ConicRange toWire(const ConicRange& c) {
  return w::ConicRange(toWire(c.center), c.distanceMin, c.distanceMax, toWire(c.direction),
                       c.halfAngle);
}

fb::Offset<fb::Vector<std::uint8_t>> bytesOrNull(fb::FlatBufferBuilder& b, const Bytes& bytes) {
  if (bytes.empty()) return 0;
  return b.CreateVector(bytes.data(), bytes.size());
}
fb::Offset<fb::String> stringOrNull(fb::FlatBufferBuilder& b, const std::string& s) {
  if (s.empty()) return 0;
  return b.CreateString(s);
}
fb::Offset<w::Error> errorOrNull(fb::FlatBufferBuilder& b, const Status& status) {
  if (status.ok()) return 0;
  auto message = stringOrNull(b, status.message());
  return w::CreateError(b, static_cast<w::ErrorCode>(errorCodeToWire(status.code())), message);
}

fb::Offset<w::Texture> build(fb::FlatBufferBuilder& b, const Texture& t) {
  if (t.codec == TextureCodec::kNone) return 0;
  auto data = bytesOrNull(b, t.data);
  return w::CreateTexture(b, static_cast<w::TextureCodec>(t.codec), t.width, t.height, data);
}

fb::Offset<w::Representation> build(fb::FlatBufferBuilder& b, const Representation& r) {
  auto mesh = bytesOrNull(b, r.mesh);
  fb::Offset<w::Texture> texture = build(b, r.texture);
  const w::Mat4 transform = toWire(r.transform);
  const w::ConicRange validity = toWire(r.validity);
  return w::CreateRepresentation(b, r.representationId, r.generation,
                                 static_cast<w::RepresentationKind>(r.kind), mesh, texture,
                                 &transform, &validity, r.accuracy, r.triangleCount, r.pointCount,
                                 r.textureId);
}

fb::Offset<fb::Vector<std::uint64_t>> idsOrNull(fb::FlatBufferBuilder& b,
                                                const std::vector<std::uint64_t>& ids) {
  if (ids.empty()) return 0;
  return b.CreateVector(ids);
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const Hello& m) {
  auto name = stringOrNull(b, m.name);
  fb::Offset<fb::Vector<fb::Offset<fb::String>>> caps = 0;
  if (!m.capabilities.empty()) caps = b.CreateVectorOfStrings(m.capabilities);
  auto sceneFile = stringOrNull(b, m.sceneFile);
  fb::Offset<w::FrameCost> frameCost = 0;
  if (const auto& c = m.frameCost)
    frameCost = w::CreateFrameCost(b, c->initSeconds, c->finalSeconds, c->setupSeconds,
                                   c->triangleSeconds, c->pixelSeconds, c->additive);
  fb::Offset<fb::Vector<fb::Offset<w::HeldRepresentation>>> held = 0;
  if (!m.held.empty()) {
    std::vector<fb::Offset<w::HeldRepresentation>> items;
    items.reserve(m.held.size());
    for (const HeldRepresentation& h : m.held)
      items.push_back(w::CreateHeldRepresentation(b, h.objectId, h.representationId,
                                                  static_cast<w::RepresentationKind>(h.kind),
                                                  h.triangleCount, h.pointCount));
    held = b.CreateVector(items);
  }
  auto t = w::CreateHello(b, m.minVersion, m.maxVersion, static_cast<w::Role>(m.role), name,
                          m.instanceId, caps, m.capacity, m.sceneFingerprint, sceneFile, frameCost,
                          held);
  return {w::Body::Hello, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const HelloReply& m) {
  auto name = stringOrNull(b, m.name);
  auto error = errorOrNull(b, m.status);
  auto t = w::CreateHelloReply(b, m.accepted, m.version, static_cast<w::Role>(m.role), name,
                               m.heartbeatIntervalMs, error);
  return {w::Body::HelloReply, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const ViewerPose& m) {
  const w::Vec3 position = toWire(m.position);
  const w::Quat orientation = toWire(m.orientation);
  auto t = w::CreateViewerPose(b, m.timestampNs, m.sequence, &position, &orientation, m.fovY,
                               m.viewportWidth, m.viewportHeight);
  return {w::Body::ViewerPose, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const SceneUpdate& m) {
  std::vector<fb::Offset<w::SceneOp>> ops;
  ops.reserve(m.operations.size());
  for (const SceneOperation& op : m.operations) {
    fb::Offset<w::Representation> rep = 0;
    if (op.type == SceneOperation::Type::kAddOrReplace) rep = build(b, op.representation);
    ops.push_back(w::CreateSceneOp(b, static_cast<w::SceneOpType>(op.type), op.objectId, rep));
  }
  auto opsVector = ops.empty() ? 0 : b.CreateVector(ops);
  std::vector<fb::Offset<w::SharedTexture>> textures;
  textures.reserve(m.textures.size());
  for (const SharedTexture& t : m.textures)
    textures.push_back(w::CreateSharedTexture(b, t.textureId, build(b, t.texture)));
  auto texturesVector = textures.empty() ? 0 : b.CreateVector(textures);
  std::vector<fb::Offset<w::BonePose>> poses;
  poses.reserve(m.bonePoses.size());
  for (const BonePose& pose : m.bonePoses) {
    std::vector<w::BoneMatrix> matrices;
    matrices.reserve(pose.matrices.size());
    for (const glm::mat4& matrix : pose.matrices) matrices.push_back(toWireBoneMatrix(matrix));
    poses.push_back(w::CreateBonePose(b, pose.objectId, b.CreateVectorOfStructs(matrices)));
  }
  auto posesVector = poses.empty() ? 0 : b.CreateVector(poses);
  auto t = w::CreateSceneUpdate(b, m.plan, m.frame, m.targetAccuracy, opsVector, texturesVector,
                                posesVector, m.unitsKappa);
  return {w::Body::SceneUpdate, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const SimplifyRequest& m) {
  auto path = stringOrNull(b, m.sourcePath);
  auto mesh = bytesOrNull(b, m.sourceMesh);
  auto t = w::CreateSimplifyRequest(
      b, m.requestId, m.objectId, path, mesh, static_cast<w::SimplifyTarget>(m.target),
      m.targetTriangles, m.targetAccuracy, m.curvePoints, m.sceneFingerprint,
      static_cast<w::RepresentationKind>(m.representation), m.kappa, m.keepBoundary);
  return {w::Body::SimplifyRequest, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const SimplifyResult& m) {
  auto error = errorOrNull(b, m.status);
  auto mesh = bytesOrNull(b, m.mesh);
  fb::Offset<fb::Vector<const w::AccuracySample*>> curve = 0;
  if (!m.curve.empty()) {
    std::vector<w::AccuracySample> samples;
    samples.reserve(m.curve.size());
    for (const AccuracySample& s : m.curve) samples.emplace_back(s.accuracy, s.resources);
    curve = b.CreateVectorOfStructs(samples);
  }
  auto t = w::CreateSimplifyResult(b, m.requestId, m.objectId, error, mesh, m.triangleCount,
                                   m.accuracy, curve, static_cast<w::RepresentationKind>(m.kind),
                                   m.pointCount, m.kappa, m.motionIncluded);
  return {w::Body::SimplifyResult, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const ImpostorRequest& m) {
  auto ids = idsOrNull(b, m.objectIds);
  const w::Vec3 eye = toWire(m.eye);
  const w::Quat orientation = toWire(m.orientation);
  const w::Vec3 frameCenter = toWire(m.frameCenter.value_or(glm::vec3(0.0f)));
  auto t = w::CreateImpostorRequest(b, m.requestId, ids, &eye, &orientation, m.fovY, m.textureWidth,
                                    m.textureHeight, static_cast<w::RepresentationKind>(m.kind),
                                    m.accuracyBound, static_cast<w::TextureCodec>(m.textureCodec),
                                    m.sceneFingerprint, m.frameCenter ? &frameCenter : nullptr,
                                    m.frameWidth, m.frameHeight);
  return {w::Body::ImpostorRequest, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const ImpostorResult& m) {
  auto ids = idsOrNull(b, m.objectIds);
  auto error = errorOrNull(b, m.status);
  fb::Offset<w::Representation> rep = 0;
  if (m.status.ok()) rep = build(b, m.representation);
  auto t = w::CreateImpostorResult(b, m.requestId, ids, error, rep);
  return {w::Body::ImpostorResult, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const FrameStats& m) {
  auto rejected = idsOrNull(b, m.rejectedPlans);
  auto t = w::CreateFrameStats(b, m.frame, m.plan, m.timestampNs, m.polygons, m.linkBytes, m.hasSnr,
                               m.snrDb, m.renderMs, rejected, m.earlyPolygons);
  return {w::Body::FrameStats, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const Heartbeat& m) {
  auto t = w::CreateHeartbeat(b, m.timestampNs, m.sequence);
  return {w::Body::Heartbeat, t.Union()};
}

std::pair<w::Body, fb::Offset<void>> build(fb::FlatBufferBuilder& b, const Shutdown& m) {
  auto reason = stringOrNull(b, m.reason);
  auto t = w::CreateShutdown(b, reason);
  return {w::Body::Shutdown, t.Union()};
}

Status buildEnvelope(fb::FlatBufferBuilder& builder, const Message& message) {
  const FieldPath root{nullptr, messageName(message)};
  THINLOD_RETURN_IF_ERROR(detail::validateMessage(root, message));
  builder.Clear();
  const auto [type, body] = std::visit([&](const auto& m) { return build(builder, m); }, message);
  auto envelope = w::CreateEnvelope(builder, kProtocolVersion, type, body);
  builder.Finish(envelope, kIdentifier);
  if (builder.GetSize() > kMaxMessageBytes) {
    return Status(ErrorCode::kResourceExhausted,
                  std::string(messageName(message)) + ": encodes to " +
                      std::to_string(builder.GetSize()) + " bytes, limit " +
                      std::to_string(kMaxMessageBytes));
  }
  return Status();
}

// ---------------------------------------------------------------- decode

glm::vec3 fromWire(const w::Vec3& v) { return {v.x(), v.y(), v.z()}; }
glm::quat fromWire(const w::Quat& q) { return glm::quat(q.w(), q.x(), q.y(), q.z()); }
glm::mat4 fromWire(const w::Mat4& m) {
  glm::mat4 out;
  float* dst = glm::value_ptr(out);
  for (int i = 0; i < 16; ++i) dst[i] = m.m()->Get(i);
  return out;
}
ConicRange fromWire(const w::ConicRange& c) {
  ConicRange out;
  out.center = fromWire(c.center());
  out.distanceMin = c.distance_min();
  out.distanceMax = c.distance_max();
  out.direction = fromWire(c.direction());
  out.halfAngle = c.half_angle();
  return out;
}

Bytes toBytes(const fb::Vector<std::uint8_t>* v) {
  if (v == nullptr) return {};
  return Bytes(v->data(), v->data() + v->size());
}

// Strings: checked against `limit` before copying.
Result<std::string> toString(const FieldPath& path, const fb::String* s, std::size_t limit) {
  if (s == nullptr) return std::string();
  if (s->size() > limit) {
    return tooLarge(path,
                    "is " + std::to_string(s->size()) + " bytes, limit " + std::to_string(limit));
  }
  return s->str();
}

// Alignment FlatBuffers' accessors assume for a vector's elements: the
// scalar's own, a struct's declared one, 4 for offsets.
template <typename T>
struct WireElementAlignment {
  static constexpr std::size_t value = alignof(T);
};
template <typename S>
struct WireElementAlignment<const S*> {
  static constexpr std::size_t value = alignof(S);
};
template <typename S>
struct WireElementAlignment<fb::Offset<S>> {
  static constexpr std::size_t value = alignof(fb::uoffset_t);
};

// Every vector passes here before its elements are read. Besides the count,
// the elements' alignment: the Verifier (FlatBuffers 2.0.8) only checks the
// 4-byte length prefix, so a [ulong] or [AccuracySample] vector 4 bytes off
// passed it and was then read with misaligned 8-byte loads (undefined
// behaviour; found by protocol/fuzz/fuzz_decode.cpp, regression seed
// fuzz/corpus/protocol/crash-misaligned-ulong-vector.bin). Writers align
// vectors to their elements, so only a hand-made message is rejected.
// decode() gives the Verifier an 8-aligned buffer, so absolute addresses do.
template <typename T>
Status checkVectorCount(const FieldPath& path, const fb::Vector<T>* v, std::size_t limit) {
  if (v != nullptr && v->size() > limit) {
    return tooLarge(
        path, "has " + std::to_string(v->size()) + " elements, limit " + std::to_string(limit));
  }
  constexpr std::size_t kAlign = WireElementAlignment<T>::value;
  if (v != nullptr && reinterpret_cast<std::uintptr_t>(v->Data()) % kAlign != 0) {
    return invalidField(path, "elements are not aligned to " + std::to_string(kAlign) + " bytes");
  }
  return Status();
}

Status requirePresent(const FieldPath& path, const void* field) {
  if (field == nullptr) return invalidField(path, "is missing");
  return Status();
}

// Decodes an optional Error table into *out (OK when absent); the return
// value says whether the table itself was well formed.
Status fromWire(const FieldPath& path, const w::Error* e, Status* out) {
  *out = Status();
  if (e == nullptr) return Status();
  auto code = errorCodeFromWire(static_cast<std::uint8_t>(e->code()));
  if (!code.ok()) return invalidField(path.child("code"), code.status().message());
  if (*code == ErrorCode::kOk) return invalidField(path.child("code"), "is Ok inside an Error");
  auto message = toString(path.child("message"), e->message(), kMaxTextBytes);
  if (!message.ok()) return message.status();
  *out = Status(*code, std::move(*message));
  return Status();
}

Result<std::vector<std::uint64_t>> fromWire(const FieldPath& path,
                                            const fb::Vector<std::uint64_t>* v) {
  THINLOD_RETURN_IF_ERROR(checkVectorCount(path, v, kMaxObjectIdsPerRequest));
  if (v == nullptr) return std::vector<std::uint64_t>();
  return std::vector<std::uint64_t>(v->begin(), v->end());
}

// A present texture table into `out` (left kNone when absent).
Status fromWire(const FieldPath& path, const w::Texture* t, Texture* out) {
  if (t == nullptr) return Status();
  if (t->codec() == w::TextureCodec::None) {
    return invalidField(path.child("codec"), "is None in a present texture");
  }
  out->codec = static_cast<TextureCodec>(t->codec());
  out->width = t->width();
  out->height = t->height();
  out->data = toBytes(t->data());
  return Status();
}

Result<Representation> fromWire(const FieldPath& path, const w::Representation* r) {
  THINLOD_RETURN_IF_ERROR(requirePresent(path, r));
  Representation out;
  out.representationId = r->representation_id();
  out.generation = r->generation();
  out.kind = static_cast<RepresentationKind>(r->kind());
  out.mesh = toBytes(r->mesh());
  THINLOD_RETURN_IF_ERROR(fromWire(path.child("texture"), r->texture(), &out.texture));
  THINLOD_RETURN_IF_ERROR(requirePresent(path.child("transform"), r->transform()));
  out.transform = fromWire(*r->transform());
  THINLOD_RETURN_IF_ERROR(requirePresent(path.child("validity"), r->validity()));
  out.validity = fromWire(*r->validity());
  out.accuracy = r->accuracy();
  out.triangleCount = r->triangle_count();
  out.pointCount = r->point_count();
  out.textureId = r->texture_id();
  return out;
}

Result<Message> fromWire(const FieldPath& path, const w::Hello* m) {
  Hello out;
  out.minVersion = m->min_version();
  out.maxVersion = m->max_version();
  out.role = static_cast<Role>(m->role());
  auto name = toString(path.child("name"), m->name(), kMaxNameBytes);
  if (!name.ok()) return name.status();
  out.name = std::move(*name);
  out.instanceId = m->instance_id();
  THINLOD_RETURN_IF_ERROR(
      checkVectorCount(path.child("capabilities"), m->capabilities(), kMaxCapabilities));
  if (const auto* caps = m->capabilities()) {
    for (fb::uoffset_t i = 0; i < caps->size(); ++i) {
      auto cap = toString(path.element("capabilities", i), caps->Get(i), kMaxNameBytes);
      if (!cap.ok()) return cap.status();
      out.capabilities.push_back(std::move(*cap));
    }
  }
  out.capacity = m->capacity();
  out.sceneFingerprint = m->scene_fingerprint();
  auto sceneFile = toString(path.child("scene_file"), m->scene_file(), kMaxPathBytes);
  if (!sceneFile.ok()) return sceneFile.status();
  out.sceneFile = std::move(*sceneFile);
  if (const w::FrameCost* c = m->frame_cost()) {
    FrameCostConstants costs;  // the values are checked by validate.cpp's check(Hello)
    costs.initSeconds = c->init_seconds();
    costs.finalSeconds = c->final_seconds();
    costs.setupSeconds = c->setup_seconds();
    costs.triangleSeconds = c->triangle_seconds();
    costs.pixelSeconds = c->pixel_seconds();
    costs.additive = c->additive();
    out.frameCost = costs;
  }
  // Counted and each entry present here; values checked by validate.cpp's check(Hello).
  THINLOD_RETURN_IF_ERROR(checkVectorCount(path.child("held"), m->held(), kMaxHeldRepresentations));
  if (const auto* held = m->held()) {
    out.held.reserve(held->size());
    for (fb::uoffset_t i = 0; i < held->size(); ++i) {
      const w::HeldRepresentation* h = held->Get(i);
      THINLOD_RETURN_IF_ERROR(requirePresent(path.element("held", i), h));
      HeldRepresentation item;
      item.objectId = h->object_id();
      item.representationId = h->representation_id();
      item.kind = static_cast<RepresentationKind>(h->kind());
      item.triangleCount = h->triangle_count();
      item.pointCount = h->point_count();
      out.held.push_back(item);
    }
  }
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath& path, const w::HelloReply* m) {
  HelloReply out;
  out.accepted = m->accepted();
  out.version = m->version();
  out.role = static_cast<Role>(m->role());
  auto name = toString(path.child("name"), m->name(), kMaxNameBytes);
  if (!name.ok()) return name.status();
  out.name = std::move(*name);
  out.heartbeatIntervalMs = m->heartbeat_interval_ms();
  THINLOD_RETURN_IF_ERROR(fromWire(path.child("error"), m->error(), &out.status));
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath& path, const w::ViewerPose* m) {
  ViewerPose out;
  out.timestampNs = m->timestamp_ns();
  out.sequence = m->sequence();
  THINLOD_RETURN_IF_ERROR(requirePresent(path.child("position"), m->position()));
  THINLOD_RETURN_IF_ERROR(requirePresent(path.child("orientation"), m->orientation()));
  out.position = fromWire(*m->position());
  out.orientation = fromWire(*m->orientation());
  out.fovY = m->fov_y();
  out.viewportWidth = m->viewport_width();
  out.viewportHeight = m->viewport_height();
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath& path, const w::SceneUpdate* m) {
  SceneUpdate out;
  out.plan = m->plan();
  out.frame = m->frame();
  out.targetAccuracy = m->target_accuracy();
  out.unitsKappa = m->units_kappa();
  const auto* ops = m->operations();
  THINLOD_RETURN_IF_ERROR(checkVectorCount(path.child("operations"), ops, kMaxSceneOperations));
  if (ops != nullptr) {
    out.operations.reserve(ops->size());
    for (fb::uoffset_t i = 0; i < ops->size(); ++i) {
      const FieldPath opPath = path.element("operations", i);
      const w::SceneOp* op = ops->Get(i);
      SceneOperation converted;
      converted.type = static_cast<SceneOperation::Type>(op->type());
      converted.objectId = op->object_id();
      if (op->type() == w::SceneOpType::Remove) {
        if (op->representation() != nullptr) {
          return invalidField(opPath.child("representation"), "must be absent in a Remove");
        }
      } else {
        auto rep = fromWire(opPath.child("representation"), op->representation());
        if (!rep.ok()) return rep.status();
        converted.representation = std::move(*rep);
      }
      out.operations.push_back(std::move(converted));
    }
  }
  const auto* textures = m->textures();
  THINLOD_RETURN_IF_ERROR(checkVectorCount(path.child("textures"), textures, kMaxSharedTextures));
  if (textures != nullptr) {
    out.textures.reserve(textures->size());
    for (fb::uoffset_t i = 0; i < textures->size(); ++i) {
      const FieldPath texturePath = path.element("textures", i);
      const w::SharedTexture* t = textures->Get(i);
      SharedTexture converted;
      converted.textureId = t->texture_id();
      THINLOD_RETURN_IF_ERROR(requirePresent(texturePath.child("texture"), t->texture()));
      THINLOD_RETURN_IF_ERROR(
          fromWire(texturePath.child("texture"), t->texture(), &converted.texture));
      out.textures.push_back(std::move(converted));
    }
  }
  const auto* poses = m->bone_poses();
  THINLOD_RETURN_IF_ERROR(checkVectorCount(path.child("bone_poses"), poses, kMaxBonePoses));
  if (poses != nullptr) {
    out.bonePoses.reserve(poses->size());
    for (fb::uoffset_t i = 0; i < poses->size(); ++i) {
      const FieldPath posePath = path.element("bone_poses", i);
      const w::BonePose* pose = poses->Get(i);
      BonePose converted;
      converted.objectId = pose->object_id();
      const auto* matrices = pose->matrices();
      THINLOD_RETURN_IF_ERROR(
          checkVectorCount(posePath.child("matrices"), matrices, kMaxBonesPerPose));
      if (matrices != nullptr) {
        converted.matrices.reserve(matrices->size());
        for (fb::uoffset_t k = 0; k < matrices->size(); ++k) {
          glm::mat4 matrix(1.0f);
          for (int c = 0; c < 4; ++c) {
            for (int r = 0; r < 3; ++r) matrix[c][r] = matrices->Get(k)->m()->Get(c * 3 + r);
          }
          converted.matrices.push_back(matrix);
        }
      }
      out.bonePoses.push_back(std::move(converted));
    }
  }
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath& path, const w::SimplifyRequest* m) {
  SimplifyRequest out;
  out.requestId = m->request_id();
  out.objectId = m->object_id();
  auto sourcePath = toString(path.child("source_path"), m->source_path(), kMaxPathBytes);
  if (!sourcePath.ok()) return sourcePath.status();
  out.sourcePath = std::move(*sourcePath);
  out.sourceMesh = toBytes(m->source_mesh());
  out.target = static_cast<SimplifyRequest::Target>(m->target());
  out.targetTriangles = m->target_triangles();
  out.targetAccuracy = m->target_accuracy();
  out.curvePoints = m->curve_points();
  out.sceneFingerprint = m->scene_fingerprint();
  out.representation = static_cast<RepresentationKind>(m->representation());
  out.kappa = m->kappa();
  out.keepBoundary = m->keep_boundary();
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath& path, const w::SimplifyResult* m) {
  SimplifyResult out;
  out.requestId = m->request_id();
  out.objectId = m->object_id();
  THINLOD_RETURN_IF_ERROR(fromWire(path.child("error"), m->error(), &out.status));
  out.mesh = toBytes(m->mesh());
  out.triangleCount = m->triangle_count();
  out.accuracy = m->accuracy();
  out.kind = static_cast<RepresentationKind>(m->kind());
  out.pointCount = m->point_count();
  out.kappa = m->kappa();
  out.motionIncluded = m->motion_included();
  THINLOD_RETURN_IF_ERROR(checkVectorCount(path.child("curve"), m->curve(), kMaxCurveSamples));
  if (const auto* curve = m->curve()) {
    out.curve.reserve(curve->size());
    for (const w::AccuracySample* s : *curve) out.curve.push_back({s->accuracy(), s->resources()});
  }
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath& path, const w::ImpostorRequest* m) {
  ImpostorRequest out;
  out.requestId = m->request_id();
  auto ids = fromWire(path.child("object_ids"), m->object_ids());
  if (!ids.ok()) return ids.status();
  out.objectIds = std::move(*ids);
  THINLOD_RETURN_IF_ERROR(requirePresent(path.child("eye"), m->eye()));
  THINLOD_RETURN_IF_ERROR(requirePresent(path.child("orientation"), m->orientation()));
  out.eye = fromWire(*m->eye());
  out.orientation = fromWire(*m->orientation());
  out.fovY = m->fov_y();
  out.textureWidth = m->texture_width();
  out.textureHeight = m->texture_height();
  out.kind = static_cast<RepresentationKind>(m->kind());
  out.accuracyBound = m->accuracy_bound();
  out.textureCodec = static_cast<TextureCodec>(m->texture_codec());
  out.sceneFingerprint = m->scene_fingerprint();
  if (m->frame_center() != nullptr) out.frameCenter = fromWire(*m->frame_center());
  out.frameWidth = m->frame_width();
  out.frameHeight = m->frame_height();
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath& path, const w::ImpostorResult* m) {
  ImpostorResult out;
  out.requestId = m->request_id();
  auto ids = fromWire(path.child("object_ids"), m->object_ids());
  if (!ids.ok()) return ids.status();
  out.objectIds = std::move(*ids);
  THINLOD_RETURN_IF_ERROR(fromWire(path.child("error"), m->error(), &out.status));
  if (out.status.ok()) {
    auto rep = fromWire(path.child("representation"), m->representation());
    if (!rep.ok()) return rep.status();
    out.representation = std::move(*rep);
  } else if (m->representation() != nullptr) {
    return invalidField(path.child("representation"), "must be absent in an error result");
  }
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath& path, const w::FrameStats* m) {
  FrameStats out;
  out.frame = m->frame();
  out.plan = m->plan();
  out.timestampNs = m->timestamp_ns();
  out.polygons = m->polygons();
  out.linkBytes = m->link_bytes();
  out.hasSnr = m->has_snr();
  out.snrDb = m->snr_db();
  out.renderMs = m->render_ms();
  out.earlyPolygons = m->early_polygons();
  THINLOD_RETURN_IF_ERROR(
      checkVectorCount(path.child("rejected_plans"), m->rejected_plans(), kMaxRejectedPlans));
  if (const auto* rejected = m->rejected_plans())
    out.rejectedPlans.assign(rejected->begin(), rejected->end());
  return Message(std::move(out));
}

Result<Message> fromWire(const FieldPath&, const w::Heartbeat* m) {
  return Message(Heartbeat{m->timestamp_ns(), m->sequence()});
}

Result<Message> fromWire(const FieldPath& path, const w::Shutdown* m) {
  auto reason = toString(path.child("reason"), m->reason(), kMaxTextBytes);
  if (!reason.ok()) return reason.status();
  return Message(Shutdown{std::move(*reason)});
}

template <typename WireTable>
Result<Message> convertBody(const char* name, const w::Envelope* envelope) {
  const FieldPath root{nullptr, name};
  const auto* body = envelope->body_as<WireTable>();
  if (body == nullptr) return invalidField(root, "body is missing");
  Result<Message> message = fromWire(root, body);
  if (!message.ok()) return message;
  THINLOD_RETURN_IF_ERROR(detail::validateMessage(root, *message));
  return message;
}

Result<Message> decodeVerified(const std::uint8_t* data, std::size_t size) {
  if (size > kMaxMessageBytes) {
    return Status(
        ErrorCode::kResourceExhausted,
        "message is " + std::to_string(size) + " bytes, limit " + std::to_string(kMaxMessageBytes));
  }
  auto version = peekVersion(data, size);
  if (!version.ok()) return version.status();

  fb::Verifier verifier(data, size, kMaxTableDepth, kMaxTables);
  if (!verifier.VerifyBuffer<w::Envelope>(kIdentifier)) {
    return Status(ErrorCode::kInvalidArgument,
                  "message of " + std::to_string(size) + " bytes fails FlatBuffers verification");
  }
  const w::Envelope* envelope = fb::GetRoot<w::Envelope>(data);
  switch (envelope->body_type()) {
    case w::Body::NONE:
      return Status(ErrorCode::kInvalidArgument, "envelope has no body");
    case w::Body::Hello:
      return convertBody<w::Hello>("Hello", envelope);
    case w::Body::HelloReply:
      return convertBody<w::HelloReply>("HelloReply", envelope);
    case w::Body::ViewerPose:
      return convertBody<w::ViewerPose>("ViewerPose", envelope);
    case w::Body::SceneUpdate:
      return convertBody<w::SceneUpdate>("SceneUpdate", envelope);
    case w::Body::SimplifyRequest:
      return convertBody<w::SimplifyRequest>("SimplifyRequest", envelope);
    case w::Body::SimplifyResult:
      return convertBody<w::SimplifyResult>("SimplifyResult", envelope);
    case w::Body::ImpostorRequest:
      return convertBody<w::ImpostorRequest>("ImpostorRequest", envelope);
    case w::Body::ImpostorResult:
      return convertBody<w::ImpostorResult>("ImpostorResult", envelope);
    case w::Body::FrameStats:
      return convertBody<w::FrameStats>("FrameStats", envelope);
    case w::Body::Heartbeat:
      return convertBody<w::Heartbeat>("Heartbeat", envelope);
    case w::Body::Shutdown:
      return convertBody<w::Shutdown>("Shutdown", envelope);
  }
  return Status(
      ErrorCode::kUnsupported,
      "unknown message type " + std::to_string(static_cast<unsigned>(envelope->body_type())));
}

}  // namespace

std::uint8_t errorCodeToWire(ErrorCode code) { return static_cast<std::uint8_t>(code); }

Result<ErrorCode> errorCodeFromWire(std::uint8_t value) {
  if (value > static_cast<std::uint8_t>(ErrorCode::kInternal)) {
    return Status(ErrorCode::kInvalidArgument, "unknown error code " + std::to_string(value));
  }
  return static_cast<ErrorCode>(value);
}

Status validate(const Message& message) {
  return detail::validateMessage(FieldPath{nullptr, messageName(message)}, message);
}

Result<Bytes> encode(const Message& message) {
  fb::FlatBufferBuilder builder(1024);
  THINLOD_RETURN_IF_ERROR(buildEnvelope(builder, message));
  return Bytes(builder.GetBufferPointer(), builder.GetBufferPointer() + builder.GetSize());
}

struct Encoder::Impl {
  fb::FlatBufferBuilder builder{1024};
};

Encoder::Encoder() : impl_(std::make_unique<Impl>()) {}
Encoder::~Encoder() = default;

Result<Encoder::View> Encoder::encode(const Message& message) {
  THINLOD_RETURN_IF_ERROR(buildEnvelope(impl_->builder, message));
  return View{impl_->builder.GetBufferPointer(), impl_->builder.GetSize()};
}

Result<std::uint16_t> peekVersion(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size < kMinMessageBytes) {
    return Status(ErrorCode::kInvalidArgument,
                  "message is " + std::to_string(size) + " bytes, shorter than the 8-byte header");
  }
  if (!fb::BufferHasIdentifier(data, kIdentifier)) {
    return Status(ErrorCode::kInvalidArgument, "not a thinlod message (identifier is not TLOD)");
  }
  fb::Verifier verifier(data, size, kMaxTableDepth, kMaxTables);
  if (!verifier.VerifyBuffer<w::EnvelopeHeader>(kIdentifier)) {
    return Status(ErrorCode::kInvalidArgument, "envelope header fails FlatBuffers verification");
  }
  const std::uint16_t version = fb::GetRoot<w::EnvelopeHeader>(data)->version();
  if (version < kMinSupportedVersion || version > kProtocolVersion) {
    return Status(ErrorCode::kVersionMismatch, "message has protocol version " +
                                                   std::to_string(version) + ", this build reads " +
                                                   std::to_string(kMinSupportedVersion) + ".." +
                                                   std::to_string(kProtocolVersion));
  }
  return version;
}

Result<Message> decode(const std::uint8_t* data, std::size_t size) {
  // FlatBuffers reads scalars in place and its Verifier checks alignment
  // relative to the buffer start: give it a start aligned for the widest
  // scalar in the schema (8 bytes). ZeroMQ message data is 8-aligned, so the
  // copy below only happens for odd callers.
  constexpr std::uintptr_t kAlign = 8;
  if (data != nullptr && reinterpret_cast<std::uintptr_t>(data) % kAlign != 0 &&
      size <= kMaxMessageBytes) {
    std::vector<std::max_align_t> aligned((size + sizeof(std::max_align_t) - 1) /
                                          sizeof(std::max_align_t));
    std::memcpy(aligned.data(), data, size);
    return decodeVerified(reinterpret_cast<const std::uint8_t*>(aligned.data()), size);
  }
  return decodeVerified(data, size);
}

Result<std::uint16_t> negotiateVersion(const Hello& peer) {
  const std::uint16_t low = std::max(peer.minVersion, kMinSupportedVersion);
  const std::uint16_t high = std::min(peer.maxVersion, kProtocolVersion);
  if (peer.minVersion > peer.maxVersion || low > high) {
    return Status(ErrorCode::kVersionMismatch,
                  "peer speaks versions " + std::to_string(peer.minVersion) + ".." +
                      std::to_string(peer.maxVersion) + ", this build " +
                      std::to_string(kMinSupportedVersion) + ".." +
                      std::to_string(kProtocolVersion));
  }
  return high;
}

}  // namespace thinlod::protocol
