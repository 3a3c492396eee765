// SimplifierService: ImpostorRequest handling (service.h). Objects are drawn
// in world space from the coarsest level whose error stays under one texel
// (impostor_level.h), then the quad / depth mesh and the texture are encoded.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <optional>
#include <set>
#include <string>

#include "service_internal.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/scene_render/scene_render.h"
#include "thinlod/simplifier/impostor_level.h"

namespace thinlod::simplifier {

using namespace service_detail;

namespace {

// Levels kept per mesh for impostor rendering (each holds a GPU copy).
constexpr std::size_t kMaxRenderLevelsPerMesh = 4;
// Share of a texel that Draco may move a quad / depth-mesh vertex.
constexpr double kImpostorQuantizationTexels = 0.25;
// Parallax may add at least this share of the texture's own error to the
// credited error (else an impostor whose texture already costs the whole
// requested error would be valid at its capture point only).
constexpr double kMinParallaxShare = 0.5;

Status invalid(const std::string& message) {
  return Status(ErrorCode::kInvalidArgument, "impostor: " + message);
}

// Takes the image by value: the raw codec moves its pixels onto the wire.
Result<protocol::Texture> encodeTexture(RgbaImage image, protocol::TextureCodec requested) {
  protocol::Texture texture;
  texture.width = static_cast<std::uint32_t>(image.width);
  texture.height = static_cast<std::uint32_t>(image.height);
  if (requested == protocol::TextureCodec::kRawRgba8) {
    texture.codec = requested;
    texture.data = std::move(image.pixels);
    return texture;
  }
  // PNG unless zstd was asked for, or JPEG for an opaque image.
  texture.codec = protocol::TextureCodec::kPng;
  if (requested == protocol::TextureCodec::kZstd ||
      (requested == protocol::TextureCodec::kJpeg && image.opaque()))
    texture.codec = requested;
  Result<std::vector<std::uint8_t>> bytes = codec::encodeTextureWith(image, texture.codec);
  if (!bytes.ok()) return bytes.status();
  texture.data = std::move(bytes).value();
  return texture;
}

// thinlod::ConicRange (double) -> wire ConicRange (float), rounded outwards
// so that the capture viewpoint stays inside after the conversion.
protocol::ConicRange toWire(const ConicRange& range) {
  protocol::ConicRange wire;
  wire.center = glm::vec3(range.center());
  wire.distanceMin = std::max(0.0f, std::nextafter(static_cast<float>(range.minDistance()), 0.0f));
  wire.distanceMax = std::isfinite(range.maxDistance())
                         ? std::nextafter(static_cast<float>(range.maxDistance()), INFINITY)
                         : INFINITY;
  wire.direction = glm::vec3(glm::normalize(range.direction()));
  const float pi = 3.14159265358979f;
  wire.halfAngle = std::min(pi, std::nextafter(static_cast<float>(range.alpha()), pi));
  return wire;
}

}  // namespace

namespace service_detail {

const std::vector<glm::vec3>& LoadedScene::framingPointsOf(const scene::SceneObject& object) const {
  auto known = framingPoints.find(object.id);
  if (known != framingPoints.end()) return known->second;
  std::vector<glm::vec3>& points = framingPoints[object.id];
  std::vector<unsigned char> referenced(object.fullMesh->vertexCount(), 0);
  for (std::uint32_t index : object.fullMesh->indices) referenced[index] = 1;
  for (std::size_t v = 0; v < referenced.size(); ++v) {
    if (!referenced[v]) continue;
    points.push_back(
        glm::vec3(object.objectToWorld * glm::vec4(object.fullMesh->positions[v], 1.0f)));
  }
  return points;
}

}  // namespace service_detail

std::shared_ptr<const RgbaImage> SimplifierService::Impl::textureOf(
    const scene::SceneObject& object, const IndexedMesh& mesh) {
  if (object.shape == nullptr || mesh.uvs.empty()) return nullptr;
  const std::string& path = object.shape->appearance.texturePath;
  if (path.empty()) return nullptr;
  auto known = textureFiles.find(path);
  if (known != textureFiles.end()) return known->second;
  constexpr std::size_t kMaxTextureFiles = 256;
  if (textureFiles.size() >= kMaxTextureFiles) textureFiles.clear();
  std::shared_ptr<const RgbaImage> image;
  Result<RgbaImage> decoded = codec::readImageFile(path);
  if (decoded.ok()) {
    image = std::make_shared<const RgbaImage>(std::move(decoded).value());
  } else {
    progress("event=texture_failed error=\"" + decoded.status().message() +
             "\" action=impostor_untextured");
  }
  textureFiles.emplace(path, image);
  return image;
}

Status SimplifierService::Impl::ensureRendering() {
  if (impostors) return context->isCurrent() ? Status() : context->makeCurrent();
  Result<std::unique_ptr<render::OffscreenContext>> created =
      render::createOffscreenContext(options.backend, 16, 16);
  if (!created.ok()) {
    return Status(ErrorCode::kUnavailable,
                  "impostor rendering unavailable: " + created.status().message());
  }
  context = std::move(created).value();
  Result<std::unique_ptr<ImpostorRenderer>> renderer = ImpostorRenderer::create(*context);
  if (!renderer.ok()) {
    context.reset();
    return Status(ErrorCode::kUnavailable,
                  "impostor rendering unavailable: " + renderer.status().message());
  }
  impostors = std::move(renderer).value();
  return Status();
}

Result<protocol::Representation> SimplifierService::Impl::impostor(
    const protocol::ImpostorRequest& request) {
  // --- Request checks beyond the wire rules (validate() ran already). ---
  if (request.kind == protocol::RepresentationKind::kMesh) {
    return invalid("kind must be an impostor kind, not mesh");
  }
  if (request.textureCodec == protocol::TextureCodec::kNone) {
    return invalid("texture codec must not be none");
  }
  if (!(request.accuracyBound > 0.0) || !std::isfinite(request.accuracyBound)) {
    return invalid("accuracyBound (largest angular error, rad) must be positive and finite");
  }
  if (!std::isfinite(request.eye.x) || !std::isfinite(request.eye.y) ||
      !std::isfinite(request.eye.z)) {
    return invalid("eye is not finite");
  }
  std::uint32_t size = request.textureWidth;
  if (request.textureWidth == 0 && request.textureHeight == 0) size = options.defaultTextureSize;
  if (request.textureWidth != request.textureHeight) {
    return Status(ErrorCode::kUnsupported, "impostor: textures are square; asked for " +
                                               std::to_string(request.textureWidth) + "x" +
                                               std::to_string(request.textureHeight));
  }
  const std::uint32_t maxSize = std::min<std::uint32_t>(options.maxTextureSize, 4096);
  if (size < 8) return invalid("texture size " + std::to_string(size) + " below 8");
  if (size > maxSize) {
    return Status(ErrorCode::kResourceExhausted, "impostor: texture size " + std::to_string(size) +
                                                     " above the limit " + std::to_string(maxSize));
  }
  if (request.objectIds.empty()) return invalid("no object ids");
  std::set<std::uint64_t> unique(request.objectIds.begin(), request.objectIds.end());
  if (unique.size() != request.objectIds.size()) return invalid("object ids repeat");

  // --- Scene and objects. ---
  const LoadedScene* loaded = lastScene;
  if (!options.defaultScenePath.empty()) {
    Result<LoadedScene*> found = scene(options.defaultScenePath);
    if (!found.ok()) return found.status();
    loaded = *found;
  }
  if (request.sceneFingerprint != 0) {
    // Several backbones may share this worker: render from the scene the
    // requesting backbone loaded, whichever was loaded last.
    for (const auto& cached : scenes)
      if (cached->scene.fingerprint == request.sceneFingerprint) loaded = cached.get();
  }
  if (loaded == nullptr) {
    return Status(ErrorCode::kUnavailable,
                  "impostor: no scene loaded (configure a default scene or send a "
                  "SimplifyRequest with the scene path first)");
  }
  THINLOD_RETURN_IF_ERROR(protocol::checkSameScene("simplifier", loaded->scene.fingerprint,
                                                   loaded->path, "backbone",
                                                   request.sceneFingerprint, "its scene"));
  std::vector<const scene::SceneObject*> objects;
  for (std::uint64_t id : request.objectIds) {
    const scene::SceneObject* object = scene::findSceneObject(loaded->objects, id);
    if (object == nullptr || object->shape == nullptr || !object->fullMesh) {
      return Status(ErrorCode::kNotFound,
                    "impostor: object " + std::to_string(id) + " not in scene " + loaded->path);
    }
    objects.push_back(object);
  }
  THINLOD_RETURN_IF_ERROR(ensureRendering());

  // --- Texel size from a framing of the full meshes. ---
  ImpostorOptions base;
  base.textureSize = static_cast<int>(size);
  base.maxAngularError = request.accuracyBound;
  base.up = request.orientation * glm::vec3(0.0f, 1.0f, 0.0f);
  base.fixedCenter = request.frameCenter;
  base.fixedSize = glm::vec2(request.frameWidth, request.frameHeight);
  std::vector<glm::vec3> points;  // several objects: their points together
  std::vector<BoundingSphere> spheres;
  for (const scene::SceneObject* object : objects) {
    spheres.push_back(object->worldSphere);
    if (objects.size() > 1) {
      const std::vector<glm::vec3>& world = loaded->framingPointsOf(*object);
      points.insert(points.end(), world.begin(), world.end());
    }
  }
  Result<ImpostorFraming> framing = frameImpostor(
      objects.size() > 1 ? points : loaded->framingPointsOf(*objects.front()), request.eye, base);
  if (!framing.ok()) return framing.status();
  // The smallest texel footprint on the objects (impostor_level.h says why
  // one texel); 0 when levels are switched off: every object at full resolution.
  const double allowedError = options.impostorFromLevels ? impostorLevelTolerance(*framing) : 0.0;

  // --- The coarsest level of each object within one texel. ---
  ImpostorScene impostorScene;
  impostorScene.lighting = loaded->lighting;
  double levelError = 0.0;  // world metres, largest over the objects
  const int maxPrimitiveTriangles =
      std::clamp(options.maxPrimitiveTriangles, 12, kMaxPrimitiveTriangles);
  for (const scene::SceneObject* object : objects) {
    const double scale = scene::maxScale(object->objectToWorld);
    std::shared_ptr<const IndexedMesh> mesh;
    const scene::Geometry& geometry = object->shape->geometry;
    if (geometry.kind == scene::GeometryKind::kPrimitive) {
      const PrimitiveShape& shape = geometry.primitive;
      THINLOD_RETURN_IF_ERROR(validatePrimitive(shape));
      TessellationParams params = chooseTessellation(shape, maxPrimitiveTriangles);
      if (allowedError > 0.0 && scale > 0.0) {
        const double needed = primitiveDiameter(shape) * scale / allowedError;
        Result<TessellationParams> found =
            tessellationForAccuracy(shape, needed, maxPrimitiveTriangles);
        if (found.ok()) params = *found;
      }
      const PrimitiveLevelKey key{object->shape, params.segments, params.rings};
      auto cached = primitiveLevels.find(key);
      if (cached == primitiveLevels.end()) {
        cached = primitiveLevels
                     .emplace(key, std::make_shared<const IndexedMesh>(tessellate(shape, params)))
                     .first;
      }
      mesh = cached->second;
      levelError = std::max(levelError, tessellationError(shape, params) * scale);
    } else {
      // Cold start: without a known curve (memory or cache file) the full
      // mesh is rendered (error 0) rather than measuring the curve first.
      if (options.answerBeforeCurve && object->fullMesh) {
        // A region object's levels come from its border-keeping model.
        auto built = meshModels.find(ModelKey(object->fullMesh.get(), object->regionCount > 0));
        if (built == meshModels.end() || !curveWithoutMeasuring(*built->second)) {
          impostorScene.parts.push_back(ImpostorPart{object->fullMesh, object->objectToWorld,
                                                     scene::shapeMaterial(*object->shape)});
          continue;
        }
      }
      Result<MeshModel*> model = meshModelFor(*object, object->regionCount > 0);
      if (!model.ok()) return model.status();
      THINLOD_RETURN_IF_ERROR(ensureCurve(**model));
      MeshModel& m = **model;
      std::vector<double> credits(m.ladder.size());
      for (std::size_t i = 0; i < credits.size(); ++i) credits[i] = m.ladder[i].relativeError;
      const std::optional<std::size_t> level =
          chooseImpostorLevel(credits, m.diameter * scale, allowedError);
      const LevelCredit* chosen = level ? &m.ladder[*level] : nullptr;
      if (chosen == nullptr) {
        mesh = m.original;  // nothing coarser is fine enough: the full mesh (error 0)
      } else {
        auto cached = m.renderLevels.find(chosen->requestedTriangles);
        if (cached == m.renderLevels.end()) {
          if (m.renderLevels.size() >= kMaxRenderLevelsPerMesh) {
            m.renderLevels.erase(m.renderLevels.begin());
          }
          cached =
              m.renderLevels
                  .emplace(
                      chosen->requestedTriangles,
                      std::make_shared<const IndexedMesh>(m.pm.extract(chosen->requestedTriangles)))
                  .first;
          ++stats.impostorLevelsExtracted;
        }
        mesh = cached->second;
        levelError = std::max(levelError, chosen->relativeError * m.diameter * scale);
      }
    }
    impostorScene.parts.push_back(
        ImpostorPart{mesh, object->objectToWorld, scene::shapeMaterial(*object->shape)});
  }

  // Textured objects are captured with their texture (one part per object, in order).
  bool anyTexture = false;
  for (std::size_t i = 0; i < objects.size() && i < impostorScene.parts.size(); ++i) {
    impostorScene.textures.push_back(textureOf(*objects[i], *impostorScene.parts[i].mesh));
    anyTexture |= impostorScene.textures.back() != nullptr;
  }
  if (!anyTexture || impostorScene.textures.size() != impostorScene.parts.size())
    impostorScene.textures.clear();

  // --- Render. ---
  protocol::Representation representation;
  representation.kind = request.kind;
  RgbaImage image;
  IndexedMesh geometry;
  ImpostorFraming rendered;
  ImpostorErrorModel errorModel;
  double lossTexels = 0.0;  // meshed: the depth mesh's silhouette loss
  if (request.kind == protocol::RepresentationKind::kSimpleImpostor) {
    Result<SimpleImpostor> simple = impostors->renderSimple(impostorScene, request.eye, base);
    if (!simple.ok()) return simple.status();
    image = std::move(simple->texture);
    geometry = simple->quad.mesh();
    rendered = simple->framing;
    errorModel = simple->errorModel;
    representation.validity = toWire(simple->validity);
  } else {
    MeshedImpostorOptions meshed;
    static_cast<ImpostorOptions&>(meshed) = base;
    meshed.gridStep = std::clamp(static_cast<int>(size) / 32, 2, 16);
    meshed.targetTriangles = options.meshedImpostorTriangles;
    Result<MeshedImpostor> result = impostors->renderMeshed(impostorScene, request.eye, meshed);
    if (!result.ok()) return result.status();
    image = std::move(result->texture);
    geometry = std::move(result->mesh);
    rendered = result->framing;
    errorModel = result->errorModel;
    representation.validity = toWire(result->validity);
    if (options.impostorGuaranteeCredit) lossTexels = result->silhouetteLossTexels;
  }

  // --- Encode. ---
  const double texel =
      std::max(rendered.quad.width, rendered.quad.height) / static_cast<double>(size);
  codec::MeshEncodeOptions encode;
  const double meshDiagonal = geometry.diameter();
  encode.positionBits = codec::positionBitsForAccuracy(
      texel > 0.0 ? meshDiagonal / texel : kExactRelativeAccuracy, kImpostorQuantizationTexels);
  // uv steps of at most 1/16 texel.
  encode.texcoordBits =
      std::clamp(static_cast<int>(std::ceil(std::log2(static_cast<double>(size)))) + 4, 12, 20);
  Result<std::vector<std::uint8_t>> meshBytes = codec::encodeMesh(geometry, encode);
  if (!meshBytes.ok()) return meshBytes.status();
  representation.mesh = std::move(meshBytes).value();
  representation.triangleCount = frameTriangles(representation.mesh);
  Result<protocol::Texture> texture = encodeTexture(std::move(image), request.textureCodec);
  if (!texture.ok()) return texture.status();
  representation.texture = std::move(texture).value();
  representation.transform = glm::mat4(1.0f);
  // Error the texture carries (world metres): detail finer than two texels
  // is lost, plus the error of the level it was rendered from
  // (docs/simplifier.md), plus, for a meshed impostor, what its depth mesh
  // fails to show (the texture is only drawn where the mesh is: a hole or a
  // lost leg is that far from the nearest texel still shown).
  const BoundingSphere reference = enclosingSphere(spheres);
  const double length = referenceLength(reference);
  // A fixed frame that cuts part of the objects off (paper Figure 9, autosize
  // FALSE): a point outside the image is about that far from its edge.
  const double textureError =
      (2.0 + lossTexels) * texel + levelError + double(rendered.clippedExtent);
  if (!options.impostorGuaranteeCredit) {
    representation.accuracy = length / textureError;  // parallax not in the credit
    return representation;
  }
  // The credit must hold wherever the cone lets the impostor be seen: it is
  // the texture's error plus a parallax share, and the cone keeps the
  // parallax within that share's angle at every distance (impostorValidity
  // with a length). The share fills the request's error at the capture
  // (accuracyBound x the distance the backbone converts with), and is at
  // least kMinParallaxShare of the texture's (docs/results/guarantee.md).
  const double captureGap = std::max(
      0.1, glm::length(glm::dvec3(request.eye) - glm::dvec3(reference.center)) - reference.radius);
  const double requested = request.accuracyBound * captureGap;
  const double parallaxShare = std::max(requested - textureError, kMinParallaxShare * textureError);
  representation.validity =
      toWire(impostorValidity(rendered, errorModel, request.accuracyBound, parallaxShare));
  representation.accuracy = length / (textureError + parallaxShare);
  return representation;
}

}  // namespace thinlod::simplifier
