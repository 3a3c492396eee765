// ImpostorRenderer: renders simple and meshed impostors offscreen with the
// shared MeshRenderer (common/render) and derives their validity ranges.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>
#include <string>

#include "thinlod/simplifier/guarantee_check.h"
#include "thinlod/simplifier/impostor.h"
#include "thinlod/simplifier/progressive_mesh.h"

namespace thinlod::simplifier {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool finite(const glm::mat4& m) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(m[c][r])) return false;
    }
  }
  return true;
}

double coverageOf(const RgbaImage& image) {
  std::size_t covered = 0;
  for (std::size_t i = 3; i < image.pixels.size(); i += 4) covered += image.pixels[i] != 0;
  const std::size_t total = image.pixels.size() / 4;
  return total ? static_cast<double>(covered) / static_cast<double>(total) : 0.0;
}

}  // namespace

void bleedColorIntoTransparent(RgbaImage& image, int pixels) {
  if (image.empty() || !image.consistent() || pixels <= 0) return;
  const int w = image.width;
  const int h = image.height;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  // filled: texel has a colour to spread (covered, or filled in an earlier ring).
  std::vector<unsigned char> filled(n);
  for (std::size_t i = 0; i < n; ++i) filled[i] = image.pixels[i * 4 + 3] != 0;
  // A pass only visits its candidates (unfilled texels with a filled
  // 8-neighbour) instead of every texel: the first pass finds them with a
  // row-dilated mask, later ones are the unfilled neighbours of the last
  // ring (any other unfilled texel still has no filled neighbour). Same
  // result as scanning the image every pass, at a cost that follows the
  // silhouette's length (the full scans were about 0.26 ms per 256x256
  // capture, docs/results/core-benchmarks.md).
  std::vector<unsigned char> dilated(n);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      dilated[i] = filled[i] | (x > 0 ? filled[i - 1] : 0) | (x + 1 < w ? filled[i + 1] : 0);
    }
  }
  std::vector<std::size_t> candidates;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (filled[i]) continue;
      if (dilated[i] || (y > 0 && dilated[i - w]) || (y + 1 < h && dilated[i + w])) {
        candidates.push_back(i);
      }
    }
  }
  std::vector<int> queuedInPass(n, -1);
  std::vector<std::size_t> ring;
  for (int pass = 0; pass < pixels && !candidates.empty(); ++pass) {
    ring.clear();
    for (std::size_t i : candidates) {
      const int x = static_cast<int>(i % w);
      const int y = static_cast<int>(i / w);
      int sum[3] = {0, 0, 0};
      int count = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx;
          const int ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const std::size_t j = static_cast<std::size_t>(ny) * w + nx;
          if (!filled[j]) continue;
          for (int c = 0; c < 3; ++c) sum[c] += image.pixels[j * 4 + c];
          ++count;
        }
      }
      if (count == 0) continue;
      for (int c = 0; c < 3; ++c) {
        image.pixels[i * 4 + c] = static_cast<std::uint8_t>((sum[c] + count / 2) / count);
      }
      ring.push_back(i);
    }
    for (std::size_t i : ring) filled[i] = 1;  // after the pass: rings grow one pixel at a time
    candidates.clear();
    for (std::size_t i : ring) {
      const int x = static_cast<int>(i % w);
      const int y = static_cast<int>(i / w);
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx;
          const int ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          const std::size_t j = static_cast<std::size_t>(ny) * w + nx;
          if (filled[j] || queuedInPass[j] == pass) continue;
          queuedInPass[j] = pass;
          candidates.push_back(j);
        }
      }
    }
  }
}

ImpostorRenderer::ImpostorRenderer(render::OffscreenContext& context) : context_(&context) {}

ImpostorRenderer::~ImpostorRenderer() {
  // Handles die with the MeshRenderer; the target before the renderer (both need the context).
  target_.reset();
  renderer_.reset();
}

Result<std::unique_ptr<ImpostorRenderer>> ImpostorRenderer::create(
    render::OffscreenContext& context) {
  std::unique_ptr<ImpostorRenderer> impostors(new ImpostorRenderer(context));
  auto renderer = render::MeshRenderer::create(context);
  if (!renderer.ok()) return renderer.status();
  impostors->renderer_ = std::move(renderer).value();
  return impostors;
}

Status ImpostorRenderer::ensureTarget(int size) {
  if (target_ && target_->width() == size && target_->height() == size) return Status();
  target_.reset();
  auto target = render::RenderTarget::create(*context_, size, size);
  if (!target.ok()) return target.status();
  target_ = std::move(target).value();
  return Status();
}

Status ImpostorRenderer::prepare(const ImpostorScene& scene, const ImpostorOptions& options,
                                 const glm::vec3& viewpoint, ImpostorFraming& framing,
                                 std::vector<render::DrawItem>& items) {
  if (!context_->isCurrent()) {
    return Status(ErrorCode::kUnavailable,
                  "impostor: the GL context is not current on this thread");
  }
  if (options.bleedPixels < 0 || options.bleedPixels > 64) {
    return Status(ErrorCode::kInvalidArgument, "impostor: bleedPixels outside 0..64");
  }
  if (!(options.maxAngularError > 0.0) || !std::isfinite(options.maxAngularError)) {
    return Status(ErrorCode::kInvalidArgument,
                  "impostor: maxAngularError must be positive and finite");
  }
  if (scene.parts.empty()) return Status(ErrorCode::kInvalidArgument, "impostor: no parts");
  if (!scene.textures.empty() && scene.textures.size() != scene.parts.size()) {
    return Status(ErrorCode::kInvalidArgument,
                  "impostor: " + std::to_string(scene.textures.size()) + " textures for " +
                      std::to_string(scene.parts.size()) + " parts");
  }
  pointScratch_.clear();
  std::size_t triangles = 0;
  for (std::size_t i = 0; i < scene.parts.size(); ++i) {
    const ImpostorPart& part = scene.parts[i];
    const std::string name = "impostor part " + std::to_string(i);
    if (!part.mesh) return Status(ErrorCode::kInvalidArgument, name + ": no mesh");
    if (!finite(part.model) || glm::determinant(glm::mat3(part.model)) == 0.0f) {
      return Status(ErrorCode::kInvalidArgument, name + ": model matrix singular or not finite");
    }
    THINLOD_RETURN_IF_ERROR(part.mesh->validate(name));
    const RgbaImage* texture = i < scene.textures.size() ? scene.textures[i].get() : nullptr;
    if (texture != nullptr) {
      if (part.material.texture.valid())
        return Status(ErrorCode::kInvalidArgument,
                      name + ": both a texture and a material texture handle");
      if (!texture->consistent() || texture->empty())
        return Status(ErrorCode::kInvalidArgument, name + ": texture is empty or inconsistent");
      if (part.mesh->uvs.empty())
        return Status(ErrorCode::kInvalidArgument, name + ": textured mesh has no uvs");
    }
    triangles += part.mesh->triangleCount();
    // Only referenced vertices frame the texture: stray points would waste texels.
    referencedScratch_.assign(part.mesh->vertexCount(), 0);
    for (std::uint32_t index : part.mesh->indices) referencedScratch_[index] = 1;
    for (std::size_t v = 0; v < part.mesh->vertexCount(); ++v) {
      if (referencedScratch_[v] == 0) continue;
      pointScratch_.push_back(glm::vec3(part.model * glm::vec4(part.mesh->positions[v], 1.0f)));
    }
  }
  if (triangles == 0) return Status(ErrorCode::kInvalidArgument, "impostor: no triangles");
  auto framed = frameImpostor(pointScratch_, viewpoint, options);
  if (!framed.ok()) return framed.status();
  framing = std::move(framed).value();
  THINLOD_RETURN_IF_ERROR(ensureTarget(options.textureSize));

  // Upload cache: a mesh stays on the GPU while its shared_ptr lives.
  const auto uploadStart = Clock::now();
  for (auto it = meshCache_.begin(); it != meshCache_.end();) {
    if (it->second.source.expired()) {
      renderer_->deleteMesh(it->second.handle);
      it = meshCache_.erase(it);
    } else {
      ++it;
    }
  }
  for (auto it = textureCache_.begin(); it != textureCache_.end();) {
    if (it->second.source.expired()) {
      renderer_->deleteTexture(it->second.handle);
      it = textureCache_.erase(it);
    } else {
      ++it;
    }
  }
  items.clear();
  for (std::size_t i = 0; i < scene.parts.size(); ++i) {
    const ImpostorPart& part = scene.parts[i];
    const std::shared_ptr<const RgbaImage> partTexture =
        i < scene.textures.size() ? scene.textures[i] : nullptr;
    auto cached = meshCache_.find(part.mesh.get());
    if (cached == meshCache_.end() || cached->second.source.lock() != part.mesh) {
      auto handle = renderer_->uploadMesh(*part.mesh);
      if (!handle.ok()) return handle.status();
      meshCache_[part.mesh.get()] = CachedMesh{part.mesh, *handle};
      cached = meshCache_.find(part.mesh.get());
    }
    render::Material material = part.material;
    if (partTexture != nullptr) {
      auto texture = textureCache_.find(partTexture.get());
      if (texture == textureCache_.end() || texture->second.source.lock() != partTexture) {
        render::TextureOptions textureOptions;
        textureOptions.linearFilter = true;
        textureOptions.clampToEdge = false;  // base-colour textures tile, as the frontend draws them
        auto handle = renderer_->uploadTexture(*partTexture, textureOptions);
        if (!handle.ok()) return handle.status();
        textureCache_[partTexture.get()] = CachedTexture{partTexture, *handle};
        texture = textureCache_.find(partTexture.get());
      }
      material.texture = texture->second.handle;
    }
    items.push_back(render::DrawItem{cached->second.handle, part.model, material});
  }
  timings_.uploadMs = millisecondsSince(uploadStart);
  return Status();
}

Result<SimpleImpostor> ImpostorRenderer::renderSimple(const ImpostorScene& scene,
                                                      const glm::vec3& viewpoint,
                                                      const ImpostorOptions& options) {
  timings_ = ImpostorTimings();
  SimpleImpostor impostor;
  std::vector<render::DrawItem> items;
  THINLOD_RETURN_IF_ERROR(prepare(scene, options, viewpoint, impostor.framing, items));
  const auto renderStart = Clock::now();
  THINLOD_RETURN_IF_ERROR(renderer_->beginFrame(*target_, glm::vec4(0.0f)));
  THINLOD_RETURN_IF_ERROR(renderer_->draw(items, impostor.framing.camera, scene.lighting));
  THINLOD_RETURN_IF_ERROR(target_->readColor(impostor.texture));
  bleedColorIntoTransparent(impostor.texture, options.bleedPixels);
  timings_.renderMs = millisecondsSince(renderStart);

  // Simple impostor: every point is drawn on the quad plane, so the depth
  // deviation along a ray is at most the depth extent stretched by the
  // steepest ray (1 / cos of its angle to the axis); it also bounds what a
  // nearer part can uncover behind it.
  const ImpostorFraming& f = impostor.framing;
  double secant = 1.0;
  for (const glm::vec3& p : pointScratch_) {
    const glm::vec3 ray = p - f.viewpoint;
    secant = std::max(secant, static_cast<double>(glm::length(ray) / glm::dot(ray, f.forward)));
  }
  impostor.errorModel.depthDeviation = (f.farDepth - f.nearDepth) * secant;
  impostor.quad = f.quad;
  impostor.validity = impostorValidity(f, impostor.errorModel, options.maxAngularError);
  impostor.coverage = coverageOf(impostor.texture);
  return impostor;
}

Result<MeshedImpostor> ImpostorRenderer::renderMeshed(const ImpostorScene& scene,
                                                      const glm::vec3& viewpoint,
                                                      const MeshedImpostorOptions& options) {
  timings_ = ImpostorTimings();
  MeshedImpostor impostor;
  std::vector<render::DrawItem> items;
  THINLOD_RETURN_IF_ERROR(prepare(scene, options, viewpoint, impostor.framing, items));
  const ImpostorFraming& f = impostor.framing;
  const int n = f.textureSize;
  const auto renderStart = Clock::now();
  THINLOD_RETURN_IF_ERROR(renderer_->beginFrame(*target_, glm::vec4(0.0f)));
  THINLOD_RETURN_IF_ERROR(renderer_->draw(items, f.camera, scene.lighting));
  THINLOD_RETURN_IF_ERROR(target_->readColor(impostor.texture));
  THINLOD_RETURN_IF_ERROR(target_->readDepth(depthScratch_));
  bleedColorIntoTransparent(impostor.texture, options.bleedPixels);
  timings_.renderMs = millisecondsSince(renderStart);

  const auto meshStart = Clock::now();
  auto mesh = buildDepthMesh(depthScratch_, f, options, &impostor.depthMesh);
  if (!mesh.ok()) return mesh.status();
  impostor.mesh = std::move(mesh).value();
  timings_.gridMs = millisecondsSince(meshStart);
  const auto simplifyStart = Clock::now();
  if (options.targetTriangles > 0 && options.targetTriangles < impostor.mesh.triangleCount()) {
    BuildOptions simplify;
    simplify.stopAtTriangles = options.targetTriangles;
    auto progressive = ProgressiveMesh::build(impostor.mesh, simplify);
    if (!progressive.ok()) return progressive.status();
    impostor.mesh = progressive->extract(options.targetTriangles);
  }
  timings_.simplifyMs = millisecondsSince(simplifyStart);
  const auto checkStart = Clock::now();

  // Measure what the depth mesh gets wrong: draw it with the capture camera
  // and compare its depth with the object's, pixel by pixel, as distances
  // along the pixel's ray.
  double meshError = 0.0;
  std::size_t covered = 0;
  std::size_t missed = 0;
  if (impostor.mesh.triangleCount() > 0) {
    const auto drawStart = Clock::now();
    auto handle = renderer_->uploadMesh(impostor.mesh);
    if (!handle.ok()) return handle.status();
    render::Material plain;
    plain.lit = false;
    const render::DrawItem item{*handle, glm::mat4(1.0f), plain};
    Status drawn = renderer_->beginFrame(*target_, glm::vec4(0.0f));
    if (drawn.ok()) drawn = renderer_->draw(&item, 1, f.camera, render::Lighting());
    std::vector<float>& meshDepth = meshDepthScratch_;
    if (drawn.ok()) drawn = target_->readDepth(meshDepth);
    renderer_->deleteMesh(*handle);
    THINLOD_RETURN_IF_ERROR(drawn);
    timings_.checkDrawMs = millisecondsSince(drawStart);
    const auto silhouetteStart = Clock::now();
    const glm::mat4 inverse = glm::inverse(f.camera.projection * f.camera.view);
    // inverse * (nx, ny, nz, 1) as glm evaluates it, (m0 nx + m1 ny) + (m2 nz
    // + m3), with the pixel's part computed once for both depths and the ndc
    // coordinates once per column / row: the same floats as unprojecting
    // each depth whole, for half the multiplications.
    std::vector<float> ndcX(static_cast<std::size_t>(n));
    for (int x = 0; x < n; ++x) ndcX[x] = 2.0f * (x + 0.5f) / n - 1.0f;
    auto unprojectAt = [&](const glm::vec4& pixelPart, float d) {
      const glm::vec4 world = pixelPart + (inverse[2] * (2.0f * d - 1.0f) + inverse[3]);
      return glm::vec3(world) / world.w;
    };
    CoverageMask captured;
    CoverageMask shown;
    captured.width = shown.width = n;
    captured.height = shown.height = n;
    captured.covered.resize(depthScratch_.size());
    shown.covered.resize(depthScratch_.size());
    for (std::size_t i = 0; i < depthScratch_.size(); ++i) {
      captured.covered[i] = depthScratch_[i] < 1.0f;
      // The frontend shows a texel where the mesh is and the texture is covered.
      shown.covered[i] = captured.covered[i] && meshDepth[i] < 1.0f;
    }
    Result<SilhouetteDistance> loss = silhouetteDistance(captured, shown);
    if (!loss.ok()) return loss.status();
    impostor.silhouetteLossTexels = std::isfinite(loss->missingPixels)
                                        ? loss->missingPixels
                                        : std::sqrt(2.0) * n;  // nothing shown: all of it lost
    timings_.checkSilhouetteMs = millisecondsSince(silhouetteStart);
    const auto depthErrorStart = Clock::now();
    for (int y = 0; y < n; ++y) {
      const float ndcY = 1.0f - 2.0f * (y + 0.5f) / n;
      const glm::vec4 rowPart = inverse[1] * ndcY;
      for (int x = 0; x < n; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * n + x;
        if (!(depthScratch_[i] < 1.0f)) continue;
        ++covered;
        if (!(meshDepth[i] < 1.0f)) {
          ++missed;
          continue;
        }
        const glm::vec4 pixelPart = inverse[0] * ndcX[x] + rowPart;
        const double error = glm::length(unprojectAt(pixelPart, depthScratch_[i]) -
                                         unprojectAt(pixelPart, meshDepth[i]));
        meshError = std::max(meshError, error);
      }
    }
    timings_.checkDepthErrorMs = millisecondsSince(depthErrorStart);
  } else {
    for (float d : depthScratch_) covered += d < 1.0f;
    missed = covered;
    impostor.silhouetteLossTexels = covered ? std::sqrt(2.0) * n : 0.0;
  }
  impostor.meshDepthError = meshError;
  impostor.uncoveredFraction = covered ? static_cast<double>(missed) / covered : 0.0;
  impostor.errorModel.depthDeviation = std::max(meshError, impostor.depthMesh.maxDepthJump);
  impostor.errorModel.silhouetteRadius = f.objectRadius;
  impostor.validity = impostorValidity(f, impostor.errorModel, options.maxAngularError);
  impostor.coverage = coverageOf(impostor.texture);
  timings_.checkMs = millisecondsSince(checkStart);
  timings_.meshMs = millisecondsSince(meshStart);
  return impostor;
}

}  // namespace thinlod::simplifier
