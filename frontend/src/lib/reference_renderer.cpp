#include "thinlod/frontend/reference_renderer.h"

#include <chrono>
#include <cmath>
#include <string>
#include <unordered_map>
#include <utility>

#include "renderer_checks.h"
#include "thinlod/common/render/render_target.h"

namespace thinlod::frontend {
namespace {

template <typename Source, typename Handle>
struct CacheEntry {
  std::weak_ptr<const Source> source;
  Handle handle;
};

}  // namespace

struct ReferenceRenderer::Impl {
  render::OffscreenContext* context = nullptr;
  ReferenceRendererOptions options;
  std::unique_ptr<render::RenderTarget> target;
  std::unique_ptr<render::MeshRenderer> renderer;
  std::unordered_map<const IndexedMesh*, CacheEntry<IndexedMesh, render::MeshHandle>> meshes;
  std::unordered_map<const RgbaImage*, CacheEntry<RgbaImage, render::TextureHandle>> textures;
  std::vector<render::DrawItem> items;

  ~Impl() {
    if (context != nullptr && !context->isCurrent()) (void)context->makeCurrent();
    renderer.reset();
    target.reset();
  }

  // Frees entries whose source is gone (its address may be reused by a new object).
  void evictExpired() {
    for (auto it = meshes.begin(); it != meshes.end();) {
      if (it->second.source.expired()) {
        renderer->deleteMesh(it->second.handle);
        it = meshes.erase(it);
      } else {
        ++it;
      }
    }
    for (auto it = textures.begin(); it != textures.end();) {
      if (it->second.source.expired()) {
        renderer->deleteTexture(it->second.handle);
        it = textures.erase(it);
      } else {
        ++it;
      }
    }
  }

  Result<render::MeshHandle> meshFor(const ReferenceObject& object) {
    const std::shared_ptr<const IndexedMesh>& mesh = object.mesh;
    auto it = meshes.find(mesh.get());
    if (it != meshes.end()) return it->second.handle;
    auto handle = object.skin != nullptr ? renderer->uploadSkinnedMesh(*mesh, *object.skin)
                                         : renderer->uploadMesh(*mesh);
    if (!handle.ok()) return handle.status();
    meshes.emplace(mesh.get(), CacheEntry<IndexedMesh, render::MeshHandle>{mesh, *handle});
    return *handle;
  }

  Result<render::TextureHandle> textureFor(const std::shared_ptr<const RgbaImage>& image) {
    auto it = textures.find(image.get());
    if (it != textures.end()) return it->second.handle;
    render::TextureOptions textureOptions;
    textureOptions.linearFilter = options.linearFilter;
    textureOptions.clampToEdge = false;  // base-colour textures tile (glTF / VRML repeat)
    auto handle = renderer->uploadTexture(*image, textureOptions);
    if (!handle.ok()) return handle.status();
    textures.emplace(image.get(), CacheEntry<RgbaImage, render::TextureHandle>{image, *handle});
    return *handle;
  }
};

ReferenceRenderer::ReferenceRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ReferenceRenderer::~ReferenceRenderer() = default;

Result<std::unique_ptr<ReferenceRenderer>> ReferenceRenderer::create(
    render::OffscreenContext& context, const ReferenceRendererOptions& options) {
  THINLOD_RETURN_IF_ERROR(
      detail::checkFrameContext(context, options.width, options.height, "ReferenceRenderer"));
  auto impl = std::make_unique<Impl>();
  impl->context = &context;
  impl->options = options;
  auto target = render::RenderTarget::create(context, options.width, options.height);
  if (!target.ok()) return target.status();
  impl->target = std::move(target).value();
  auto renderer = render::MeshRenderer::create(context);
  if (!renderer.ok()) return renderer.status();
  impl->renderer = std::move(renderer).value();
  return std::unique_ptr<ReferenceRenderer>(new ReferenceRenderer(std::move(impl)));
}

Result<ReferenceReport> ReferenceRenderer::render(const std::vector<ReferenceObject>& objects,
                                                  const render::Camera& camera,
                                                  const render::Lighting& lighting,
                                                  RgbaImage& frame) {
  Impl& impl = *impl_;
  if (!impl.context->isCurrent()) {
    return Status(ErrorCode::kUnavailable,
                  "ReferenceRenderer::render: the GL context is not current on this thread");
  }
  const auto start = std::chrono::steady_clock::now();
  // Check everything before uploading anything, so a bad list draws nothing.
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const ReferenceObject& object = objects[i];
    const std::string what = "reference object " + std::to_string(i);
    if (object.mesh == nullptr) {
      return Status(ErrorCode::kInvalidArgument, what + ": no mesh");
    }
    if (object.material.texture.valid()) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": material carries a texture handle; pass ReferenceObject::texture");
    }
    if (object.texture != nullptr && (!object.texture->consistent() || object.texture->empty())) {
      return Status(ErrorCode::kInvalidArgument, what + ": texture is empty or inconsistent");
    }
    if ((object.skin == nullptr) != (object.bones == nullptr)) {
      return Status(ErrorCode::kInvalidArgument, what + ": a skin needs bones and bones a skin");
    }
    if (impl.meshes.find(object.mesh.get()) == impl.meshes.end() ||
        impl.meshes.find(object.mesh.get())->second.source.expired()) {
      THINLOD_RETURN_IF_ERROR(object.mesh->validate(what + " mesh"));
    }
  }
  impl.evictExpired();
  impl.items.clear();
  impl.items.reserve(objects.size());
  for (const ReferenceObject& object : objects) {
    auto mesh = impl.meshFor(object);
    if (!mesh.ok()) return mesh.status();
    render::DrawItem item;
    item.mesh = *mesh;
    item.model = object.transform;
    item.material = object.material;
    item.bones = object.bones;
    if (object.texture != nullptr) {
      auto texture = impl.textureFor(object.texture);
      if (!texture.ok()) return texture.status();
      item.material.texture = *texture;
    }
    impl.items.push_back(item);
  }
  THINLOD_RETURN_IF_ERROR(impl.renderer->beginFrame(*impl.target, impl.options.clearColor));
  THINLOD_RETURN_IF_ERROR(impl.renderer->draw(impl.items, camera, lighting));
  THINLOD_RETURN_IF_ERROR(impl.target->readColor(frame));
  ReferenceReport report;
  report.renderMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  report.drawCalls = impl.renderer->stats().drawCalls;
  report.triangles = impl.renderer->stats().triangles;
  report.cachedMeshes = impl.meshes.size();
  return report;
}

int ReferenceRenderer::width() const { return impl_->options.width; }
int ReferenceRenderer::height() const { return impl_->options.height; }

}  // namespace thinlod::frontend
