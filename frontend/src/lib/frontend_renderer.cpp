#include "thinlod/frontend/frontend_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include "renderer_checks.h"
#include "texture_fit.h"
#include "thinlod/common/core/finite.h"
#include "thinlod/common/render/mesh_batch.h"
#include "thinlod/common/render/render_target.h"

namespace thinlod::frontend {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::uint8_t toByte(float v) {
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
}

// Which merged draw a representation belongs to.
struct BatchKey {
  int page = 0;
  bool lit = false;
  bool operator<(const BatchKey& o) const { return page != o.page ? page < o.page : lit < o.lit; }
};

// GPU-side state of one uploaded representation.
struct GpuPart {
  BatchKey batch;
  int layer = -1;     // own texture layer in `batch.page`, or -1 (untextured: the white layer)
  IndexedMesh world;  // baked to world space, uvs mapped into the layer
  std::vector<std::uint16_t> layers;
  DiscPoints worldDiscs;  // kHybrid: world space, base colour x representation colour
  // A skinned mesh (Representation::skin): its own GPU mesh in the content
  // frame, drawn alone with its bone pose (not merged: the vertex shader
  // deforms it), and its material; `world` stays empty.
  render::MeshHandle skinnedMesh;
  render::Material skinnedMaterial;
  std::size_t skinnedVertices = 0;
};

bool sameLighting(const render::Lighting& a, const render::Lighting& b) {
  if (a.ambient != b.ambient || a.lights.size() != b.lights.size()) return false;
  for (std::size_t i = 0; i < a.lights.size(); ++i) {
    const render::Light& x = a.lights[i];
    const render::Light& y = b.lights[i];
    if (x.type != y.type || x.vector != y.vector || x.color != y.color ||
        x.attenuation != y.attenuation) {
      return false;
    }
  }
  return true;
}

struct Page {
  render::TextureHandle texture;
  std::vector<int> freeLayers;  // popped from the back
};

struct DrawBatch {
  render::MeshHandle mesh;
  bool dirty = true;
  std::size_t triangles = 0;
};

// Page 0, layer 0 is opaque white: untextured meshes sample it so they can
// share the draw call of textured ones.
constexpr int kWhiteLayer = 0;

}  // namespace

struct FrontendRenderer::Impl {
  render::OffscreenContext* context = nullptr;
  FrontendRendererOptions options;
  FrontendScene scene;
  std::unique_ptr<render::RenderTarget> target;
  std::unique_ptr<render::MeshRenderer> renderer;
  std::vector<Page> pages;
  std::unordered_map<RepresentationKey, GpuPart> parts;
  std::map<BatchKey, DrawBatch> batches;
  IndexedMesh mergeScratch;
  std::vector<std::uint16_t> layerScratch;
  std::vector<render::DrawItem> items;
  // Per skinned object drawn this frame: its pose extrapolated to the frame's
  // time (FrontendScene::bonePoseAt); sized before items point into it.
  std::vector<BoneMatrices> extrapolated;
  // Hybrid discs: one merged, pre-lit world-space set drawn in one call.
  std::unique_ptr<render::DiscRenderer> discs;
  render::DiscHandle discHandle;
  bool discsDirty = true;
  std::size_t discCount = 0;
  bool discsLit = false;
  render::Lighting discLighting;

  explicit Impl(const FrontendRendererOptions& o) : options(o), scene(o.limits) {}

  ~Impl() {
    // GL objects must go while the context is current; the renderer frees its
    // meshes and textures itself.
    if (context != nullptr && !context->isCurrent()) (void)context->makeCurrent();
    discs.reset();
    renderer.reset();
    target.reset();
  }

  Status addPage() {
    render::TextureOptions textureOptions;
    textureOptions.linearFilter = options.linearFilter;
    textureOptions.mipmaps = false;
    // Repeat: a mesh's base-colour texture tiles (uvs may leave [0, 1]) and
    // fills its whole layer (fitRepeatingTextureToLayer); impostor textures
    // keep their uvs inside their own texels and transparent borders, so the
    // wrap changes nothing for them, and one sampler keeps one draw call.
    textureOptions.clampToEdge = false;
    auto texture = renderer->createTextureArray(options.layerSize, options.layerSize,
                                                options.layersPerPage, textureOptions);
    if (!texture.ok()) return texture.status();
    Page page;
    page.texture = *texture;
    const bool first = pages.empty();
    for (int layer = options.layersPerPage - 1; layer >= (first ? 1 : 0); --layer) {
      page.freeLayers.push_back(layer);
    }
    if (first) {
      RgbaImage white(options.layerSize, options.layerSize);
      std::fill(white.pixels.begin(), white.pixels.end(), std::uint8_t{255});
      Status status = renderer->setTextureLayer(page.texture, kWhiteLayer, white);
      if (!status.ok()) {
        renderer->deleteTexture(page.texture);
        return status;
      }
    }
    pages.push_back(std::move(page));
    return Status();
  }

  // A free (page, layer); makes a new page when all are taken.
  Status acquireLayer(int& pageIndex, int& layer) {
    for (std::size_t p = 0; p < pages.size(); ++p) {
      if (!pages[p].freeLayers.empty()) {
        pageIndex = static_cast<int>(p);
        layer = pages[p].freeLayers.back();
        pages[p].freeLayers.pop_back();
        return Status();
      }
    }
    THINLOD_RETURN_IF_ERROR(addPage());
    pageIndex = static_cast<int>(pages.size() - 1);
    layer = pages.back().freeLayers.back();
    pages.back().freeLayers.pop_back();
    return Status();
  }

  void releasePart(RepresentationKey key) {
    auto it = parts.find(key);
    if (it == parts.end()) return;
    if (it->second.skinnedMesh.valid()) renderer->deleteMesh(it->second.skinnedMesh);
    if (it->second.layer >= 0) pages[it->second.batch.page].freeLayers.push_back(it->second.layer);
    parts.erase(it);
  }

  Status uploadOne(const SceneObject& object) {
    const Representation& rep = object.representation;
    GpuPart part;
    part.batch.lit =
        rep.kind == RepresentationKind::kMesh || rep.kind == RepresentationKind::kHybrid;
    if (rep.points != nullptr && !rep.points->empty()) {
      render::appendWorldDiscs(part.worldDiscs, *rep.points, rep.transform);
      for (auto& c : part.worldDiscs.colors) {
        for (int k = 0; k < 4; ++k) c[k] = toByte(rep.color[k] * static_cast<float>(c[k]) / 255.0f);
      }
    }
    render::MeshBatch::Part batchPart;
    batchPart.model = rep.transform;
    batchPart.color = {toByte(rep.color.r), toByte(rep.color.g), toByte(rep.color.b),
                       toByte(rep.color.a)};
    if (rep.texture != nullptr) {
      int page = 0;
      int layer = 0;
      // A mesh's base-colour texture tiles (uvs may leave [0, 1]); an
      // impostor's is clamped.
      const bool repeat = part.batch.lit;
      THINLOD_RETURN_IF_ERROR(acquireLayer(page, layer));
      part.batch.page = page;
      part.layer = layer;
      const detail::FittedTexture fitted =
          repeat ? detail::fitRepeatingTextureToLayer(*rep.texture, options.layerSize)
                 : detail::fitTextureToLayer(*rep.texture, options.layerSize);
      Status status = renderer->setTextureLayer(pages[page].texture, layer,
                                                fitted.useSource ? *rep.texture : fitted.image);
      if (!status.ok()) {
        pages[page].freeLayers.push_back(layer);
        return status;
      }
      batchPart.textureLayer = layer;
      batchPart.uvScale = fitted.uvScale;
    } else {
      part.batch.page = 0;
      batchPart.textureLayer = kWhiteLayer;
    }
    if (rep.skin != nullptr) return uploadSkinned(object, batchPart, std::move(part));
    render::MeshBatch baked;
    Status status =
        rep.mesh->indices.empty()
            ? Status()  // a hybrid made of points only
            : baked.append(*rep.mesh, batchPart, "object " + std::to_string(object.id) + " mesh");
    if (!status.ok()) {
      if (part.layer >= 0) pages[part.batch.page].freeLayers.push_back(part.layer);
      return status;
    }
    part.world = baked.mesh();
    part.layers = baked.textureLayers();
    parts[object.key] = std::move(part);
    return Status();
  }

  // A skinned mesh goes up as it is (content frame, uvs into its layer) with
  // its skin; the material carries what the batch would bake per vertex.
  Status uploadSkinned(const SceneObject& object, const render::MeshBatch::Part& batchPart,
                       GpuPart part) {
    const Representation& rep = object.representation;
    IndexedMesh mesh = *rep.mesh;
    for (glm::vec2& uv : mesh.uvs) uv = uv * batchPart.uvScale + batchPart.uvOffset;
    auto handle = renderer->uploadSkinnedMesh(mesh, *rep.skin);
    if (!handle.ok()) {
      if (part.layer >= 0) pages[part.batch.page].freeLayers.push_back(part.layer);
      return handle.status();
    }
    part.skinnedMesh = *handle;
    part.skinnedVertices = mesh.vertexCount();
    render::Material& m = part.skinnedMaterial;
    m = materialFor(part.batch);
    m.diffuse = rep.color;
    m.textureLayer = batchPart.textureLayer;
    parts[object.key] = std::move(part);
    return Status();
  }

  void uploadPending(FrameReport& report) {
    const std::vector<PendingUpload> plan = scene.planUploads(options.uploadBytesPerFrame);
    for (const PendingUpload& upload : plan) {
      Status status = uploadOne(*upload.object);
      if (status.ok()) {
        report.uploadedBytes += upload.object->uploadBytes;
        ++report.uploadedObjects;
        (void)scene.markUploaded(upload.key);
        continue;
      }
      // The batch can never be shown whole: drop it and free what it uploaded.
      for (RepresentationKey key : scene.dropBatch(upload.batchSequence)) releasePart(key);
      ++report.droppedBatches;
      report.droppedPlans.push_back(upload.batchPlan);
      report.lastUploadError = status.toString();
      break;  // dropBatch may have invalidated the remaining plan entries
    }
  }

  void markDirty(RepresentationKey key) {
    auto it = parts.find(key);
    if (it != parts.end()) {
      batches[it->second.batch].dirty = true;
      if (!it->second.worldDiscs.empty()) discsDirty = true;
    }
  }

  // Merges the held hybrids' discs and pre-lights them (again when the
  // lighting changes): the discs get the Lambert term the lit batch's
  // triangles get (render::preLightDiscs; no specular).
  Status rebuildDiscs(const render::Lighting& lighting) {
    if (!discsDirty && discsLit && sameLighting(lighting, discLighting)) return Status();
    DiscPoints merged;
    for (const auto& [id, object] : scene.objects()) {
      auto part = parts.find(object.key);
      if (part == parts.end() || part->second.worldDiscs.empty()) continue;
      render::appendWorldDiscs(merged, part->second.worldDiscs, glm::mat4(1.0f));
    }
    discsDirty = false;
    discsLit = true;
    discLighting = lighting;
    discCount = merged.size();
    if (merged.empty()) return Status();
    const DiscPoints lit =
        render::preLightDiscs(merged, glm::mat4(1.0f), glm::vec4(1.0f), lighting);
    if (discHandle.valid()) return discs->update(discHandle, lit);
    auto handle = discs->upload(lit);
    if (!handle.ok()) return handle.status();
    discHandle = *handle;
    return Status();
  }

  Status rebuildDirtyBatches(FrameReport& report) {
    for (auto& [key, batch] : batches) {
      if (!batch.dirty) continue;
      IndexedMesh& merged = mergeScratch;
      merged.positions.clear();
      merged.normals.clear();
      merged.uvs.clear();
      merged.colors.clear();
      merged.indices.clear();
      layerScratch.clear();
      for (const auto& [id, object] : scene.objects()) {
        auto part = parts.find(object.key);
        if (part == parts.end() || part->second.batch.page != key.page ||
            part->second.batch.lit != key.lit) {
          continue;
        }
        const IndexedMesh& world = part->second.world;
        const auto base = static_cast<std::uint32_t>(merged.positions.size());
        merged.positions.insert(merged.positions.end(), world.positions.begin(),
                                world.positions.end());
        merged.normals.insert(merged.normals.end(), world.normals.begin(), world.normals.end());
        merged.uvs.insert(merged.uvs.end(), world.uvs.begin(), world.uvs.end());
        merged.colors.insert(merged.colors.end(), world.colors.begin(), world.colors.end());
        for (std::uint32_t index : world.indices) merged.indices.push_back(base + index);
        layerScratch.insert(layerScratch.end(), part->second.layers.begin(),
                            part->second.layers.end());
      }
      batch.triangles = merged.triangleCount();
      batch.dirty = false;
      if (merged.indices.empty()) continue;  // drawn as nothing; the handle keeps its old data
      report.geometryBytesRebuilt +=
          merged.vertexCount() * kGpuVertexBytes + merged.indices.size() * kGpuIndexBytes;
      if (batch.mesh.valid()) {
        THINLOD_RETURN_IF_ERROR(renderer->updateMesh(batch.mesh, merged, layerScratch));
      } else {
        auto handle = renderer->uploadMesh(merged, layerScratch);
        if (!handle.ok()) return handle.status();
        batch.mesh = *handle;
      }
    }
    return Status();
  }

  render::Material materialFor(const BatchKey& key) const {
    render::Material m;
    m.diffuse = glm::vec4(1.0f);
    m.useVertexColors = true;
    m.texture = pages[key.page].texture;
    m.doubleSided = true;
    if (key.lit) {
      m.lit = true;
      m.specular = options.meshSpecular;
      m.shininess = options.meshShininess;
      m.alphaMode = render::AlphaMode::kOpaque;
    } else {
      m.lit = false;
      m.alphaMode = options.impostorAlpha;
      m.alphaCutoff = options.alphaCutoff;
    }
    return m;
  }
};

FrontendRenderer::FrontendRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FrontendRenderer::~FrontendRenderer() = default;

Result<std::unique_ptr<FrontendRenderer>> FrontendRenderer::create(
    render::OffscreenContext& context, const FrontendRendererOptions& options) {
  THINLOD_RETURN_IF_ERROR(
      detail::checkFrameContext(context, options.width, options.height, "FrontendRenderer"));
  if (options.layerSize < 2 || options.layerSize > 4096 || options.layersPerPage < 2 ||
      options.layersPerPage > 2048) {
    return Status(ErrorCode::kInvalidArgument,
                  "FrontendRenderer: layerSize " + std::to_string(options.layerSize) +
                      " (2..4096) or layersPerPage " + std::to_string(options.layersPerPage) +
                      " (2..2048) out of range");
  }
  if (options.uploadBytesPerFrame == 0) {
    return Status(ErrorCode::kInvalidArgument, "FrontendRenderer: uploadBytesPerFrame is 0");
  }
  if (!std::isfinite(options.alphaCutoff) || !std::isfinite(options.meshShininess) ||
      !std::isfinite(options.meshSpecular.x) || !std::isfinite(options.meshSpecular.y) ||
      !std::isfinite(options.meshSpecular.z) || !std::isfinite(options.clearColor.r) ||
      !std::isfinite(options.clearColor.g) || !std::isfinite(options.clearColor.b) ||
      !std::isfinite(options.clearColor.a)) {
    return Status(ErrorCode::kInvalidArgument,
                  "FrontendRenderer: alpha cutoff, shininess, specular or clear colour not finite");
  }
  auto impl = std::make_unique<Impl>(options);
  impl->context = &context;
  auto target = render::RenderTarget::create(context, options.width, options.height);
  if (!target.ok()) return target.status();
  impl->target = std::move(target).value();
  auto renderer = render::MeshRenderer::create(context);
  if (!renderer.ok()) return renderer.status();
  impl->renderer = std::move(renderer).value();
  auto discs = render::DiscRenderer::create(context, options.discStyle);
  if (!discs.ok()) return discs.status();
  impl->discs = std::move(discs).value();
  THINLOD_RETURN_IF_ERROR(impl->addPage());
  return std::unique_ptr<FrontendRenderer>(new FrontendRenderer(std::move(impl)));
}

Status FrontendRenderer::warmUp(const render::Lighting& lighting) {
  Impl& impl = *impl_;
  if (!impl.context->isCurrent()) {
    return Status(ErrorCode::kUnavailable,
                  "FrontendRenderer::warmUp: the GL context is not current on this thread");
  }
  // One triangle near the centre of an identity camera's view, white layer,
  // drawn as both kinds of batch (merged meshes carry per-vertex layers).
  IndexedMesh triangle;
  triangle.positions = {{-0.1f, -0.1f, 0.0f}, {0.1f, -0.1f, 0.0f}, {0.0f, 0.1f, 0.0f}};
  triangle.normals.assign(3, glm::vec3(0.0f, 0.0f, 1.0f));
  triangle.uvs.assign(3, glm::vec2(0.5f));
  triangle.colors.assign(3, {255, 255, 255, 255});
  triangle.indices = {0, 1, 2};
  auto mesh = impl.renderer->uploadMesh(triangle, std::vector<std::uint16_t>(3, kWhiteLayer));
  if (!mesh.ok()) return mesh.status();
  std::vector<render::DrawItem> items;
  for (const bool lit : {false, true}) {
    render::DrawItem item;
    item.mesh = *mesh;
    item.material = impl.materialFor({0, lit});
    items.push_back(item);
  }
  render::Camera identity;
  Status status = impl.renderer->beginFrame(*impl.target, impl.options.clearColor);
  if (status.ok()) status = impl.renderer->draw(items, identity, lighting);
  if (status.ok()) status = impl.renderer->finish();
  impl.renderer->deleteMesh(*mesh);
  return status;
}

Status FrontendRenderer::submit(SceneBatch batch) { return impl_->scene.enqueue(std::move(batch)); }

Result<FrameReport> FrontendRenderer::renderFrame(const render::Camera& camera,
                                                  const render::Lighting& lighting,
                                                  RgbaImage& frame, double poseTimeS) {
  Impl& impl = *impl_;
  if (!impl.context->isCurrent()) {
    return Status(ErrorCode::kUnavailable,
                  "FrontendRenderer::renderFrame: the GL context is not current on this thread");
  }
  if (!allFinite(camera.view) || !allFinite(camera.projection)) {
    return Status(ErrorCode::kInvalidArgument, "renderFrame: camera matrices are not finite");
  }
  THINLOD_RETURN_IF_ERROR(render::validateLighting(lighting, "renderFrame"));
  FrameReport report;
  const Clock::time_point frameStart = Clock::now();

  impl.uploadPending(report);
  report.timing.uploadMs = millisecondsSince(frameStart);

  const Clock::time_point commitStart = Clock::now();
  const CommitResult commit = impl.scene.commitReady();
  for (RepresentationKey key : commit.released) {
    impl.markDirty(key);
    impl.releasePart(key);
  }
  for (RepresentationKey key : commit.activated) impl.markDirty(key);
  report.committedBatches = commit.plans.size();
  THINLOD_RETURN_IF_ERROR(impl.rebuildDirtyBatches(report));
  THINLOD_RETURN_IF_ERROR(impl.rebuildDiscs(lighting));
  report.timing.commitMs = millisecondsSince(commitStart);

  // Both kinds of batch have their shader before any batch of that kind
  // exists, so the first mesh to arrive does not pay for a compile.
  for (const bool lit : {false, true}) {
    THINLOD_RETURN_IF_ERROR(impl.renderer->prepare(impl.materialFor({0, lit}), true, lighting));
  }
  const Clock::time_point drawStart = Clock::now();
  impl.items.clear();
  for (const auto& [key, batch] : impl.batches) {
    if (batch.triangles == 0 || !batch.mesh.valid()) continue;
    render::DrawItem item;
    item.mesh = batch.mesh;
    item.material = impl.materialFor(key);
    impl.items.push_back(item);
  }
  // Skinned objects, one draw each with their pose; one without a pose (or
  // whose pose has fewer bones than its skin names) is not drawn this frame.
  // The scratch poses are sized once, so the pointers items keep stay valid.
  if (impl.extrapolated.size() < impl.scene.objects().size())
    impl.extrapolated.resize(impl.scene.objects().size());
  std::size_t slot = 0;
  for (const auto& [id, object] : impl.scene.objects()) {
    auto part = impl.parts.find(object.key);
    if (part == impl.parts.end() || !part->second.skinnedMesh.valid()) continue;
    BoneMatrices& scratch = impl.extrapolated[slot++];
    const BoneMatrices* pose = impl.scene.bonePoseAt(id, poseTimeS, scratch);
    if (pose == nullptr || pose->size() < impl.renderer->bonesNeeded(part->second.skinnedMesh)) {
      ++report.skinnedWithoutPose;
      continue;
    }
    render::DrawItem item;
    item.mesh = part->second.skinnedMesh;
    item.model = object.representation.transform;
    item.material = part->second.skinnedMaterial;
    item.bones = pose;
    impl.items.push_back(item);
    ++report.skinnedObjects;
    if (pose == &scratch) ++report.extrapolatedPoses;
    report.deformedVertices += part->second.skinnedVertices;
  }
  THINLOD_RETURN_IF_ERROR(impl.renderer->beginFrame(*impl.target, impl.options.clearColor));
  THINLOD_RETURN_IF_ERROR(impl.renderer->draw(impl.items, camera, lighting));
  impl.discs->resetStats();
  if (impl.discCount > 0 && impl.discHandle.valid()) {
    const render::DiscDrawItem discs{impl.discHandle, glm::mat4(1.0f)};
    THINLOD_RETURN_IF_ERROR(impl.discs->draw(&discs, 1, camera));
  }
  THINLOD_RETURN_IF_ERROR(impl.target->readColor(frame));
  report.timing.drawMs = millisecondsSince(drawStart);
  report.timing.totalMs = millisecondsSince(frameStart);

  const render::RenderStats& stats = impl.renderer->stats();
  report.drawCalls = stats.drawCalls + impl.discs->stats().drawCalls;
  report.discs = impl.discs->stats().discs;
  report.textureBinds = stats.textureBinds;
  report.triangles = stats.triangles;
  report.pendingBatches = impl.scene.pendingBatches();
  report.texturePages = impl.pages.size();
  report.appliedPlan = impl.scene.lastAppliedPlan();
  report.earlyPolygons = impl.scene.earlyPolygons();
  return report;
}

const FrontendScene& FrontendRenderer::scene() const { return impl_->scene; }
const FrontendRendererOptions& FrontendRenderer::options() const { return impl_->options; }
int FrontendRenderer::width() const { return impl_->options.width; }
int FrontendRenderer::height() const { return impl_->options.height; }

}  // namespace thinlod::frontend
