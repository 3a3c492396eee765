// RawGlBaseline: the frontend frame's work done with plain OpenGL calls and
// nothing of thinlod's renderer in between - the floor the frontend is judged
// against. One GLSL 3.30 program (world-space positions, uv, per-vertex array
// layer and colour; alpha-mask discard at 0.5), one VBO, one sampler2DArray,
// one glDrawArrays into a 640x480 RGBA8 + depth FBO, then glReadPixels RGBA.
//
// Contract:
// - GL symbols come from GLVND's libOpenGL, which dispatches to the context
//   current on the calling thread: only valid with the EGL back-end (OSMesa
//   exports its own gl* symbols). create() and every call need that context
//   current on this thread; destroy the object while it still is.
// - create() takes the merged mesh (MeshBatch output: positions, uvs, colours,
//   one layer per vertex) and the layer images (all width x height RGBA8);
//   a shader/FBO failure or inconsistent input is kInternal/kInvalidArgument.
// - renderFrame() draws with `viewProjection` and reads the frame into `rgba`
//   (width*height*4 bytes, bottom row first, as GL returns it).
// Bench-only code: not part of any module's API.
#pragma once
#include <cstdint>
#include <glm/mat4x4.hpp>
#include <memory>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"

namespace thinlod::bench {

class RawGlBaseline {
 public:
  static Result<std::unique_ptr<RawGlBaseline>> create(
      int width, int height, const IndexedMesh& mergedMesh,
      const std::vector<std::uint16_t>& vertexLayers,
      const std::vector<const RgbaImage*>& layerImages);
  ~RawGlBaseline();
  RawGlBaseline(const RawGlBaseline&) = delete;
  RawGlBaseline& operator=(const RawGlBaseline&) = delete;

  void renderFrame(const glm::mat4& viewProjection, std::vector<std::uint8_t>& rgba);
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  RawGlBaseline() = default;
  int width_ = 0;
  int height_ = 0;
  int vertexCount_ = 0;
  unsigned program_ = 0, vao_ = 0, vbo_ = 0, texture_ = 0;
  unsigned fbo_ = 0, colorBuffer_ = 0, depthBuffer_ = 0;
  int viewProjectionLocation_ = -1;
};

}  // namespace thinlod::bench
