// ReferenceRenderer: the full-quality frame the frontend's frame is compared
// with (Pasman & Jansen 2002, section 4.2: "f is the maximum quality image"):
// every object at full resolution, same camera, lights, size and background.
//
// Contract:
// - create()/render() need `context` current on the calling thread; the
//   renderer keeps a pointer to it (it must outlive the renderer).
// - Objects are (mesh, material, transform, optional texture). Meshes and
//   textures are uploaded on first use and cached by the identity of their
//   shared_ptr while the caller keeps it alive (a cache entry whose source has
//   expired is freed at the next render). Material::texture must be empty: the
//   texture, if any, comes from ReferenceObject::texture.
// - A skinned object (docs/animation.md) carries its mesh's skin and this
//   frame's bone matrices, both or neither; its mesh is uploaded skinned (the
//   same mesh object is always drawn with its skin) and deformed by the
//   vertex shader, as the frontend draws its levels.
// - Blended materials are drawn after opaque ones in the given order (pass
//   them back to front).
// - Errors: invalid mesh/material/transform is kInvalidArgument naming the
//   object index (nothing drawn); GL failures as MeshRenderer.
// - Not thread-safe.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
#include <memory>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/offscreen_context.h"

namespace thinlod::frontend {

struct ReferenceObject {
  std::shared_ptr<const IndexedMesh> mesh;
  render::Material material;
  glm::mat4 transform{1.0f};                 // object -> world
  std::shared_ptr<const RgbaImage> texture;  // optional
  std::shared_ptr<const std::vector<anim::VertexSkin>> skin;  // optional, one per vertex
  const std::vector<glm::mat4>* bones = nullptr;              // with `skin`: read in render()
};

struct ReferenceRendererOptions {
  int width = 640;
  int height = 480;
  glm::vec4 clearColor{0.0f, 0.0f, 0.0f, 1.0f};  // match FrontendRendererOptions
  bool linearFilter = true;
};

struct ReferenceReport {
  double renderMs = 0.0;  // uploads + draw + readback
  std::size_t drawCalls = 0;
  std::size_t triangles = 0;
  std::size_t cachedMeshes = 0;
};

class ReferenceRenderer {
 public:
  static Result<std::unique_ptr<ReferenceRenderer>> create(render::OffscreenContext& context,
                                                           const ReferenceRendererOptions& options);
  ~ReferenceRenderer();
  ReferenceRenderer(const ReferenceRenderer&) = delete;
  ReferenceRenderer& operator=(const ReferenceRenderer&) = delete;

  Result<ReferenceReport> render(const std::vector<ReferenceObject>& objects,
                                 const render::Camera& camera, const render::Lighting& lighting,
                                 RgbaImage& frame);

  int width() const;
  int height() const;

 private:
  struct Impl;
  explicit ReferenceRenderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace thinlod::frontend
