#include "wire_conversion.h"

#include <algorithm>
#include <cmath>
#include <glm/common.hpp>
#include <limits>
#include <memory>
#include <string>
#include <utility>

namespace thinlod::frontend::daemon {
namespace {

// Byte 6 of a codec frame is its codec (common/codec/encoding.h, frame layout).
constexpr std::size_t kFrameCodecOffset = 6;

Status invalid(const std::string& what, const std::string& problem) {
  return Status(ErrorCode::kInvalidArgument, what + ": " + problem);
}

bool knownKind(protocol::RepresentationKind kind) {
  return kind == protocol::RepresentationKind::kMesh ||
         kind == protocol::RepresentationKind::kSimpleImpostor ||
         kind == protocol::RepresentationKind::kMeshedImpostor ||
         kind == protocol::RepresentationKind::kHybrid;
}

// The codec byte a frame of this wire codec must carry, or 0 when the wire
// codec is not a framed one.
std::uint8_t frameCodecOf(protocol::TextureCodec codec) {
  return isFramedTextureCodec(codec) ? static_cast<std::uint8_t>(codec) : 0;
}

std::string sizeText(std::uint64_t width, std::uint64_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// kNone -> null; otherwise the decoded image or an error.
Result<std::shared_ptr<const RgbaImage>> convertTexture(const protocol::Texture& wire,
                                                        const ConversionOptions& options,
                                                        const std::string& what) {
  if (wire.codec == protocol::TextureCodec::kNone) {
    if (!wire.data.empty() || wire.width != 0 || wire.height != 0) {
      return invalid(what, "codec None but " + sizeText(wire.width, wire.height) + " with " +
                               std::to_string(wire.data.size()) + " bytes");
    }
    return std::shared_ptr<const RgbaImage>();
  }
  const std::uint32_t maxSide = options.limits.maxDecodableSide();
  if (wire.width == 0 || wire.height == 0 || wire.width > maxSide || wire.height > maxSide) {
    return invalid(what, "size " + sizeText(wire.width, wire.height) + " outside 1.." +
                             std::to_string(maxSide) + " per side");
  }
  const std::size_t expectedBytes = static_cast<std::size_t>(wire.width) * wire.height * 4;
  if (wire.codec == protocol::TextureCodec::kRawRgba8) {
    if (wire.data.size() != expectedBytes) {
      return invalid(what, "RawRgba8 data is " + std::to_string(wire.data.size()) +
                               " bytes, expected " + std::to_string(expectedBytes));
    }
    auto image = std::make_shared<RgbaImage>();
    image->width = static_cast<int>(wire.width);
    image->height = static_cast<int>(wire.height);
    image->pixels = wire.data;
    return std::shared_ptr<const RgbaImage>(std::move(image));
  }
  const std::uint8_t frameCodec = frameCodecOf(wire.codec);
  if (frameCodec == 0) {
    return invalid(what, "unknown texture codec " + std::to_string(static_cast<int>(wire.codec)));
  }
  Result<RgbaImage> decoded =
      codec::decodeTexture(wire.data.data(), wire.data.size(), options.limits);
  if (!decoded.ok()) {
    return Status(decoded.status().code(), what + ": " + decoded.status().message());
  }
  // decodeTexture verified the header, so the frame is at least that long.
  if (wire.data[kFrameCodecOffset] != frameCodec) {
    return invalid(what, "frame codec " + std::to_string(wire.data[kFrameCodecOffset]) +
                             " does not match the wire codec " +
                             std::to_string(static_cast<int>(wire.codec)));
  }
  if (static_cast<std::uint32_t>(decoded->width) != wire.width ||
      static_cast<std::uint32_t>(decoded->height) != wire.height) {
    return invalid(what, "decoded size " + sizeText(decoded->width, decoded->height) +
                             " does not match the announced " + sizeText(wire.width, wire.height));
  }
  if (decoded->pixels.size() != expectedBytes) {
    return invalid(what, "decoded " + std::to_string(decoded->pixels.size()) + " bytes, expected " +
                             std::to_string(expectedBytes));
  }
  return std::shared_ptr<const RgbaImage>(std::make_shared<RgbaImage>(std::move(decoded).value()));
}

using TextureMap = std::map<std::uint64_t, std::shared_ptr<const RgbaImage>>;

Result<Representation> convertOne(const protocol::Representation& wire, std::uint64_t objectId,
                                  const ConversionOptions& options, const TextureMap* updateTextures,
                                  const std::string& what);

}  // namespace

Result<Representation> convertRepresentation(const protocol::Representation& wire,
                                             std::uint64_t objectId,
                                             const ConversionOptions& options,
                                             const std::string& what) {
  return convertOne(wire, objectId, options, nullptr, what);
}

namespace {

Result<Representation> convertOne(const protocol::Representation& wire, std::uint64_t objectId,
                                  const ConversionOptions& options, const TextureMap* updateTextures,
                                  const std::string& what) {
  if (!knownKind(wire.kind)) {
    return invalid(what,
                   "unknown representation kind " + std::to_string(static_cast<int>(wire.kind)));
  }
  Representation rep;
  rep.kind = wire.kind;  // one enum on the wire and at the frontend
  rep.transform = wire.transform;
  rep.generation = wire.generation;
  rep.representationId = wire.representationId;
  const std::string kindName = representationKindName(rep.kind);

  if (rep.kind == RepresentationKind::kHybrid) {
    if (wire.mesh.empty()) return invalid(what, "Hybrid has no mesh bytes");
    Result<HybridGeometry> geometry =
        codec::decodeHybrid(wire.mesh.data(), wire.mesh.size(), options.limits);
    if (!geometry.ok()) {
      return Status(geometry.status().code(), what + ": hybrid: " + geometry.status().message());
    }
    if (geometry->triangles.triangleCount() != wire.triangleCount ||
        geometry->points.size() != wire.pointCount) {
      return invalid(what, "hybrid has " + std::to_string(geometry->triangles.triangleCount()) +
                               " triangles / " + std::to_string(geometry->points.size()) +
                               " points, the representation announces " +
                               std::to_string(wire.triangleCount) + " / " +
                               std::to_string(wire.pointCount));
    }
    if (wire.texture.codec != protocol::TextureCodec::kNone) {
      return invalid(what, "Hybrid carries a texture");
    }
    if (geometry->triangles.triangleCount() > 0) {
      rep.mesh = std::make_shared<const IndexedMesh>(std::move(geometry->triangles));
    }
    if (!geometry->points.empty()) {
      rep.points = std::make_shared<const DiscPoints>(std::move(geometry->points));
    }
  } else if (wire.mesh.empty()) {
    if (rep.kind != RepresentationKind::kSimpleImpostor) {
      return invalid(what, kindName + " has no mesh bytes");
    }
    if (wire.triangleCount != 0 && wire.triangleCount != 2) {
      return invalid(what, "SimpleImpostor without a mesh (unit quad) announces " +
                               std::to_string(wire.triangleCount) + " triangles");
    }
  } else {
    Result<codec::SkinnedMeshFrame> frame =
        codec::decodeSkinnedMesh(wire.mesh.data(), wire.mesh.size(), options.limits);
    if (!frame.ok()) {
      return Status(frame.status().code(), what + ": mesh: " + frame.status().message());
    }
    if (frame->mesh.triangleCount() != wire.triangleCount) {
      return invalid(what, "mesh has " + std::to_string(frame->mesh.triangleCount()) +
                               " triangles, the representation announces " +
                               std::to_string(wire.triangleCount));
    }
    // A skinned level (an animated object, docs/animation.md): kMesh only.
    if (!frame->skin.empty()) {
      if (rep.kind != RepresentationKind::kMesh) return invalid(what, kindName + " carries a skin");
      rep.skin = std::make_shared<const std::vector<anim::VertexSkin>>(std::move(frame->skin));
    }
    rep.mesh = std::make_shared<const IndexedMesh>(std::move(frame->mesh));
  }

  Result<std::shared_ptr<const RgbaImage>> texture =
      convertTexture(wire.texture, options, what + ": texture");
  if (!texture.ok()) return texture.status();
  rep.texture = std::move(texture).value();
  if (wire.textureId != 0) {
    if (rep.kind != RepresentationKind::kMesh && rep.kind != RepresentationKind::kHybrid) {
      return invalid(what, kindName + " names shared texture " + std::to_string(wire.textureId));
    }
    if (rep.texture != nullptr) {
      return invalid(what, "names shared texture " + std::to_string(wire.textureId) +
                               " and carries an inline texture");
    }
    std::shared_ptr<const RgbaImage> shared;
    if (updateTextures != nullptr) {
      auto found = updateTextures->find(wire.textureId);
      if (found != updateTextures->end()) shared = found->second;
    }
    if (shared == nullptr && options.sharedTextures != nullptr) {
      auto found = options.sharedTextures->textures.find(wire.textureId);
      if (found != options.sharedTextures->textures.end()) shared = found->second;
    }
    if (shared == nullptr) {
      return invalid(what, "names shared texture " + std::to_string(wire.textureId) +
                               ", which neither this update nor an earlier one carried");
    }
    rep.texture = std::move(shared);
  }
  if (rep.kind != RepresentationKind::kMesh && rep.kind != RepresentationKind::kHybrid &&
      rep.texture == nullptr) {
    return invalid(what, kindName + " has no texture (codec None)");
  }
  if (rep.texture != nullptr && rep.mesh != nullptr && rep.mesh->uvs.empty()) {
    return invalid(what, "textured " + kindName + " mesh has no uvs");
  }

  if ((rep.kind == RepresentationKind::kMesh || rep.kind == RepresentationKind::kHybrid) &&
      options.meshColors != nullptr) {
    auto colour = options.meshColors->find(objectId);
    if (colour != options.meshColors->end()) {
      rep.color = glm::clamp(colour->second, glm::vec4(0.0f), glm::vec4(1.0f));
    }
  }
  return rep;
}

}  // namespace

Result<SceneBatch> convertUpdate(const protocol::SceneUpdate& update,
                                 const ConversionOptions& options) {
  SceneBatch batch;
  batch.plan = update.plan;
  batch.operations.reserve(update.operations.size());
  const std::string updateName =
      "SceneUpdate plan " + std::to_string(update.plan) + " frame " + std::to_string(update.frame);
  // Shared textures first, all or none.
  TextureMap updateTextures;
  std::size_t addedBytes = 0;
  std::size_t replacedBytes = 0;
  std::size_t newIds = 0;
  for (std::size_t i = 0; i < update.textures.size(); ++i) {
    const protocol::SharedTexture& shared = update.textures[i];
    const std::string what = updateName + ", shared texture " + std::to_string(i) + " (id " +
                             std::to_string(shared.textureId) + ")";
    if (shared.textureId == 0) return invalid(what, "texture id 0");
    if (shared.texture.codec == protocol::TextureCodec::kNone) {
      return invalid(what, "codec None");
    }
    Result<std::shared_ptr<const RgbaImage>> image = convertTexture(shared.texture, options, what);
    if (!image.ok()) return image.status();
    if (!updateTextures.emplace(shared.textureId, *image).second) {
      return invalid(what, "id listed twice");
    }
    addedBytes += (*image)->pixels.size();
    if (options.sharedTextures != nullptr) {
      auto held = options.sharedTextures->textures.find(shared.textureId);
      if (held != options.sharedTextures->textures.end()) {
        replacedBytes += held->second->pixels.size();
      } else {
        ++newIds;
      }
    }
  }
  if (options.sharedTextures != nullptr && !updateTextures.empty()) {
    SharedTextureCache& cache = *options.sharedTextures;
    const std::size_t count = cache.textures.size() + newIds;
    const std::size_t bytes = cache.decodedBytes - replacedBytes + addedBytes;
    if (count > options.maxSharedTextures || bytes > options.maxSharedTextureBytes) {
      return Status(ErrorCode::kResourceExhausted,
                    updateName + ": shared textures would grow to " + std::to_string(count) +
                        " textures / " + std::to_string(bytes) + " bytes, limit " +
                        std::to_string(options.maxSharedTextures) + " / " +
                        std::to_string(options.maxSharedTextureBytes));
    }
    for (auto& [id, image] : updateTextures) cache.textures[id] = image;
    cache.decodedBytes = bytes;
  }
  for (std::size_t i = 0; i < update.operations.size(); ++i) {
    const protocol::SceneOperation& wireOp = update.operations[i];
    const std::string what = updateName + ", operation " + std::to_string(i) + " (object " +
                             std::to_string(wireOp.objectId) + ")";
    SceneOperation op;
    op.id = wireOp.objectId;
    if (wireOp.type == protocol::SceneOperation::Type::kRemove) {
      op.type = SceneOperation::Type::kRemove;
    } else if (wireOp.type == protocol::SceneOperation::Type::kAddOrReplace) {
      op.type = SceneOperation::Type::kAddOrReplace;
      Result<Representation> rep =
          convertOne(wireOp.representation, wireOp.objectId, options, &updateTextures, what);
      if (!rep.ok()) return rep.status();
      op.representation = std::move(rep).value();
    } else {
      return invalid(what,
                     "unknown operation type " + std::to_string(static_cast<int>(wireOp.type)));
    }
    batch.operations.push_back(std::move(op));
  }
  // Bone poses (validated on decode: finite, affine, ids unique) ride with
  // the batch and apply when it commits.
  batch.bonePoses.reserve(update.bonePoses.size());
  for (const protocol::BonePose& pose : update.bonePoses)
    batch.bonePoses.emplace_back(pose.objectId, pose.matrices);
  return batch;
}

std::size_t payloadBytes(const protocol::SceneUpdate& update) {
  std::size_t bytes = 0;
  for (const protocol::SceneOperation& op : update.operations) {
    bytes += op.representation.mesh.size() + op.representation.texture.data.size();
  }
  for (const protocol::SharedTexture& shared : update.textures) bytes += shared.texture.data.size();
  // Bone poses: three rows of four floats a matrix, as the wire carries them.
  for (const protocol::BonePose& pose : update.bonePoses) bytes += 48 * pose.matrices.size();
  return bytes;
}

protocol::FrameStats toFrameStats(const FrameRecord& record, std::int64_t timestampNs,
                                  std::vector<std::uint64_t> rejectedPlans) {
  protocol::FrameStats stats;
  stats.frame = record.frame;
  stats.plan = record.plan;
  stats.timestampNs = timestampNs;
  stats.polygons = static_cast<std::uint32_t>(
      std::min<std::size_t>(record.polygons, std::numeric_limits<std::uint32_t>::max()));
  stats.linkBytes = record.linkBytes;
  stats.hasSnr = std::isfinite(record.quality.snrDb);
  stats.snrDb = stats.hasSnr ? record.quality.snrDb : 0.0;
  stats.renderMs = std::isfinite(record.renderMs) ? static_cast<float>(record.renderMs) : 0.0f;
  stats.rejectedPlans = std::move(rejectedPlans);
  stats.earlyPolygons = static_cast<std::uint32_t>(
      std::min<std::size_t>(record.earlyPolygons, stats.polygons));
  return stats;
}

std::vector<protocol::HeldRepresentation> heldRepresentations(const FrontendScene& scene) {
  std::vector<protocol::HeldRepresentation> held;
  held.reserve(scene.objects().size());
  for (const auto& [id, object] : scene.objects()) {  // ascending ids
    if (held.size() == protocol::kMaxHeldRepresentations) break;
    protocol::HeldRepresentation h;
    h.objectId = id;
    h.representationId = object.representation.representationId;
    h.kind = object.representation.kind;
    h.triangleCount = static_cast<std::uint32_t>(
        std::min<std::size_t>(object.triangleCount, protocol::kMaxTriangleCount));
    h.pointCount =
        object.representation.kind == RepresentationKind::kHybrid
            ? static_cast<std::uint32_t>(std::min<std::size_t>(object.pointCount,
                                                               protocol::kMaxPointCount))
            : 0;
    held.push_back(h);
  }
  return held;
}

}  // namespace thinlod::frontend::daemon
