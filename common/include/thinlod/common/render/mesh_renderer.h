// MeshRenderer: draws lit/unlit, coloured/textured triangle meshes into a
// RenderTarget with GL 3.3 core shaders. GPU-resident resources: upload once,
// get a handle, draw many handles per frame, delete handles.
//
// Contract:
// - create()/every method needs the renderer's context current on the calling
//   thread (see offscreen_context.h); destroy the renderer before the context.
// - Meshes are IndexedMesh (validated on upload: kInvalidArgument names the
//   bad element). Missing normals are computed; missing uvs are (0,0);
//   missing colours are white. Optional per-vertex texture layers select the
//   layer of an array texture (for batching, see mesh_batch.h).
// - Textures are always 2D array textures; uploadTexture() makes a 1-layer
//   one. uv (0,0) is the image's BOTTOM-left as in OpenGL/OBJ: RgbaImage rows
//   are top-down, so the upload flips them (v = 1 is the image's top row).
// - Batching: one draw call per DrawItem. To draw many textured objects in one
//   call, put their textures in layers of one array texture and merge their
//   triangles with MeshBatch (world space, per-vertex layer) into one mesh.
// - Handles are plain ids; a deleted or unknown handle is kNotFound at draw
//   time. Handle 0 means "none" (e.g. an untextured material). deleteMesh /
//   deleteTexture do nothing unless the context is current.
// - Shaders: one program per variant (lit, specular, textured, vertex colours,
//   per-vertex layers, alpha mode, and the count and types of the lights), so
//   no pixel pays for a feature it does not use. A variant is compiled the
//   first time a draw needs it; prepare() compiles it ahead (e.g. before a
//   frame with a deadline).
// - Skinned meshes (uploadSkinnedMesh; docs/animation.md): each vertex
//   depends on one or two bones (anim::VertexSkin) and the vertex shader
//   deforms it, P = (1 - s) T_A P + s T_B P (anim::deform's formula), with
//   the DrawItem's `bones` (at least one matrix per bone the skin names,
//   finite) before `model`. Normals blend the bones' linear parts. Such a
//   mesh cannot be updateMesh'd; a DrawItem with `bones` needs a skinned mesh.
// - Errors: invalid input is kInvalidArgument; GL errors are kInternal, GL
//   out-of-memory is kResourceExhausted; the message names the GL call.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/vec4.hpp>
#include <memory>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/common/render/render_target.h"

namespace thinlod::render {

struct MeshHandle {
  std::uint32_t id = 0;
  bool valid() const { return id != 0; }
};
struct TextureHandle {
  std::uint32_t id = 0;
  bool valid() const { return id != 0; }
};

enum class AlphaMode { kOpaque, kMask, kBlend };  // kMask discards alpha < alphaCutoff

struct Material {
  glm::vec4 diffuse{0.8f, 0.8f, 0.8f, 1.0f};  // multiplies texture and vertex colours
  glm::vec3 specular{0.0f};                   // Blinn-Phong, 0 = none
  float shininess = 32.0f;
  bool lit = true;               // false: colour = diffuse * texture * vertex colour
  bool useVertexColors = false;  // multiply by the mesh's per-vertex colours
  TextureHandle texture;         // none: untextured
  int textureLayer = 0;          // used when the mesh has no per-vertex layers
  AlphaMode alphaMode = AlphaMode::kOpaque;
  float alphaCutoff = 0.5f;
  bool doubleSided = true;  // false: back faces are culled
};

struct DrawItem {
  MeshHandle mesh;
  glm::mat4 model{1.0f};  // object -> world
  Material material;
  // A skinned mesh's bone matrices (mesh space -> object space; entry i for
  // the skin's bone i); null for any other mesh. Read during draw() only.
  const std::vector<glm::mat4>* bones = nullptr;
};

struct TextureOptions {
  bool linearFilter = true;  // false: nearest (pixel-exact tests)
  bool mipmaps = false;
  bool clampToEdge = true;  // false: repeat
};

struct RenderStats {
  std::size_t drawCalls = 0;
  std::size_t triangles = 0;
  std::size_t textureBinds = 0;
};

class MeshRenderer {
 public:
  static Result<std::unique_ptr<MeshRenderer>> create(OffscreenContext& context);
  ~MeshRenderer();
  MeshRenderer(const MeshRenderer&) = delete;
  MeshRenderer& operator=(const MeshRenderer&) = delete;

  // textureLayers: empty, or one layer index per vertex.
  Result<MeshHandle> uploadMesh(const IndexedMesh& mesh,
                                const std::vector<std::uint16_t>& textureLayers = {});
  // Replaces the contents of an existing mesh (e.g. a batch rebuilt each frame).
  Status updateMesh(MeshHandle handle, const IndexedMesh& mesh,
                    const std::vector<std::uint16_t>& textureLayers = {});
  // A mesh the vertex shader skins (see the contract); `skin` one entry per
  // vertex, bones below 65536, weights in [0, 1] (anim::validateSkin).
  Result<MeshHandle> uploadSkinnedMesh(const IndexedMesh& mesh,
                                       const std::vector<anim::VertexSkin>& skin);
  // Matrices a DrawItem of this skinned mesh needs (highest bone + 1); 0 for
  // an unskinned or unknown mesh.
  std::uint32_t bonesNeeded(MeshHandle handle) const;
  void deleteMesh(MeshHandle handle);

  Result<TextureHandle> uploadTexture(const RgbaImage& image, const TextureOptions& options = {});
  // An array texture of `layers` layers of width x height, initially transparent black.
  Result<TextureHandle> createTextureArray(int width, int height, int layers,
                                           const TextureOptions& options = {});
  // Writes `image` into `layer` at the layer's bottom-left-in-uv corner: the
  // image may be smaller than the layer; it then covers uv [0, w/W] x [0, h/H].
  Status setTextureLayer(TextureHandle texture, int layer, const RgbaImage& image);
  void deleteTexture(TextureHandle handle);

  // Binds the target, sets the viewport and clears colour (RGBA in [0,1]) and depth.
  Status beginFrame(RenderTarget& target, const glm::vec4& clearColor);
  // Draws opaque and masked items in order, then blended items in order
  // (no sorting: pass blended items back to front). Needs a prior beginFrame.
  Status draw(const DrawItem* items, std::size_t count, const Camera& camera,
              const Lighting& lighting);
  Status draw(const std::vector<DrawItem>& items, const Camera& camera, const Lighting& lighting) {
    return draw(items.data(), items.size(), camera, lighting);
  }
  // Compiles the shader variant that drawing `material` on a mesh with (or
  // without) per-vertex layers under `lighting` needs; cheap once it exists.
  Status prepare(const Material& material, bool meshHasLayers, const Lighting& lighting,
                 bool skinned = false);
  // Waits for the GPU (for timing); readback already synchronises.
  Status finish();

  const RenderStats& stats() const { return stats_; }  // since the last beginFrame
  OffscreenContext& context() const { return *context_; }

 private:
  struct Impl;
  explicit MeshRenderer(OffscreenContext& context);
  OffscreenContext* context_;
  std::unique_ptr<Impl> impl_;
  RenderStats stats_;
};

}  // namespace thinlod::render
