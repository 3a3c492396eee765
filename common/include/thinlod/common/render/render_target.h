// RenderTarget: an offscreen framebuffer (RGBA8 colour + 24-bit depth) inside
// an OffscreenContext, with readback in top-down row order.
//
// Contract:
// - create() needs the context current; size in [1, context.maxRenderTargetSize()],
//   else kInvalidArgument. GL failures (incomplete FBO, GL errors) are kInternal
//   or kResourceExhausted (out of memory) with the GL error named.
// - Rows: the framebuffer holds the picture upside down. Whatever draws into
//   a RenderTarget (MeshRenderer, DiscRenderer) applies kMirrorClipY after
//   its projection, so glReadPixels' bottom-up rows are the picture's
//   top-down rows and readback copies nothing (a CPU row flip cost 5% of a
//   640x480 frontend frame on llvmpipe). Front faces are then clockwise.
// - readColor(): RGBA8, non-premultiplied as rendered, row 0 = top of the image.
// - readDepth(): window-space depth in [0, 1] as float (1 = far plane / cleared
//   background), row 0 = top. Convert to world space with unprojectPixel
//   (camera.h) and the camera used to draw.
// - The caller-buffer overloads avoid allocation: dst must hold width*height*4
//   bytes (colour) or width*height floats (depth), else kInvalidArgument.
// - Thread rules: as OffscreenContext (context current on the calling thread
//   for every call and for destruction; destroy before the context).
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/mat4x4.hpp>
#include <memory>
#include <vector>

#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/render/offscreen_context.h"

namespace thinlod::render {

// Clip-space y mirror (see "Rows" above): clip = kMirrorClipY * projection * view * world.
inline const glm::mat4 kMirrorClipY{1.0f, 0.0f, 0.0f, 0.0f, 0.0f, -1.0f, 0.0f, 0.0f,
                                    0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f,  0.0f, 1.0f};

class RenderTarget {
 public:
  static Result<std::unique_ptr<RenderTarget>> create(OffscreenContext& context, int width,
                                                      int height);
  ~RenderTarget();
  RenderTarget(const RenderTarget&) = delete;
  RenderTarget& operator=(const RenderTarget&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  OffscreenContext& context() const { return *context_; }

  // Makes this the draw/read framebuffer and sets the viewport to its size.
  Status bind();
  // Clears colour to `rgba` (components in [0,1]) and depth to 1.
  Status clear(float r, float g, float b, float a);

  Status readColor(RgbaImage& out);
  Status readColor(std::uint8_t* dst, std::size_t dstBytes);
  Status readDepth(std::vector<float>& out);
  Status readDepth(float* dst, std::size_t dstCount);

 private:
  RenderTarget(OffscreenContext& context, int width, int height);
  Status readPixels(unsigned format, unsigned type, void* dst);

  OffscreenContext* context_;
  int width_;
  int height_;
  unsigned framebuffer_ = 0;
  unsigned colorBuffer_ = 0;
  unsigned depthBuffer_ = 0;
};

}  // namespace thinlod::render
