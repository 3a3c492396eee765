#include "thinlod/common/render/render_target.h"

#include <algorithm>
#include <string>

#include "render/backends.h"
#include "render/gl_functions.h"

namespace thinlod::render {
namespace {

Status notCurrent(const char* what) {
  return Status(ErrorCode::kUnavailable,
                std::string(what) + ": the target's GL context is not current on this thread");
}

const char* framebufferStatusName(GLenum status) {
  switch (status) {
    case GL_FRAMEBUFFER_COMPLETE:
      return "complete";
    case GL_FRAMEBUFFER_UNDEFINED:
      return "GL_FRAMEBUFFER_UNDEFINED";
    case GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT:
      return "GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT";
    case GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT:
      return "GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT";
    case GL_FRAMEBUFFER_UNSUPPORTED:
      return "GL_FRAMEBUFFER_UNSUPPORTED";
    case GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE:
      return "GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE";
    default:
      return "incomplete (unknown reason)";
  }
}

}  // namespace

RenderTarget::RenderTarget(OffscreenContext& context, int width, int height)
    : context_(&context), width_(width), height_(height) {}

Result<std::unique_ptr<RenderTarget>> RenderTarget::create(OffscreenContext& context, int width,
                                                           int height) {
  if (!context.isCurrent()) return notCurrent("RenderTarget::create");
  const int maxEdge = context.maxRenderTargetSize();
  if (width < 1 || height < 1 || width > maxEdge || height > maxEdge ||
      static_cast<long long>(width) * height > kMaxSurfacePixels) {
    return Status(ErrorCode::kInvalidArgument,
                  "render target size " + std::to_string(width) + "x" + std::to_string(height) +
                      " out of range (each edge 1.." + std::to_string(maxEdge) + ", at most " +
                      std::to_string(kMaxSurfacePixels) + " pixels)");
  }
  std::unique_ptr<RenderTarget> target(new RenderTarget(context, width, height));
  const GlFunctions& gl = context.gl();
  THINLOD_RETURN_IF_ERROR(checkGlErrors(gl, "before RenderTarget::create"));
  gl.glGenFramebuffers(1, &target->framebuffer_);
  gl.glGenRenderbuffers(1, &target->colorBuffer_);
  gl.glGenRenderbuffers(1, &target->depthBuffer_);
  gl.glBindRenderbuffer(GL_RENDERBUFFER, target->colorBuffer_);
  gl.glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  gl.glBindRenderbuffer(GL_RENDERBUFFER, target->depthBuffer_);
  gl.glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  gl.glBindRenderbuffer(GL_RENDERBUFFER, 0);
  gl.glBindFramebuffer(GL_FRAMEBUFFER, target->framebuffer_);
  gl.glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                               target->colorBuffer_);
  gl.glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                               target->depthBuffer_);
  THINLOD_RETURN_IF_ERROR(checkGlErrors(gl, "allocating render target renderbuffers"));
  const GLenum status = gl.glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    return Status(ErrorCode::kInternal,
                  std::string("render target framebuffer is ") + framebufferStatusName(status));
  }
  THINLOD_RETURN_IF_ERROR(target->bind());
  return target;
}

RenderTarget::~RenderTarget() {
  // Deleting names in a context that is not current would hit another context.
  if (!context_->isCurrent()) return;
  const GlFunctions& gl = context_->gl();
  if (framebuffer_ != 0) gl.glDeleteFramebuffers(1, &framebuffer_);
  if (colorBuffer_ != 0) gl.glDeleteRenderbuffers(1, &colorBuffer_);
  if (depthBuffer_ != 0) gl.glDeleteRenderbuffers(1, &depthBuffer_);
}

Status RenderTarget::bind() {
  if (!context_->isCurrent()) return notCurrent("RenderTarget::bind");
  const GlFunctions& gl = context_->gl();
  gl.glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  const GLenum drawBuffer = GL_COLOR_ATTACHMENT0;
  gl.glDrawBuffers(1, &drawBuffer);
  gl.glReadBuffer(GL_COLOR_ATTACHMENT0);
  gl.glViewport(0, 0, width_, height_);
  return checkGlErrors(gl, "RenderTarget::bind");
}

Status RenderTarget::clear(float r, float g, float b, float a) {
  THINLOD_RETURN_IF_ERROR(bind());
  const GlFunctions& gl = context_->gl();
  gl.glClearColor(r, g, b, a);
  gl.glClearDepth(1.0);
  gl.glDepthMask(GL_TRUE);
  gl.glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  return checkGlErrors(gl, "RenderTarget::clear");
}

Status RenderTarget::readPixels(unsigned format, unsigned type, void* dst) {
  THINLOD_RETURN_IF_ERROR(bind());
  const GlFunctions& gl = context_->gl();
  gl.glPixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  // Bottom-up rows of an upside-down picture: top-down rows of the picture.
  gl.glReadPixels(0, 0, width_, height_, format, type, dst);
  return checkGlErrors(gl, "glReadPixels");
}

Status RenderTarget::readColor(RgbaImage& out) {
  out.width = width_;
  out.height = height_;
  out.pixels.resize(static_cast<std::size_t>(width_) * height_ * 4);
  return readColor(out.pixels.data(), out.pixels.size());
}

Status RenderTarget::readColor(std::uint8_t* dst, std::size_t dstBytes) {
  const std::size_t needed = static_cast<std::size_t>(width_) * height_ * 4;
  if (dst == nullptr || dstBytes < needed) {
    return Status(ErrorCode::kInvalidArgument, "readColor: buffer holds " +
                                                   std::to_string(dstBytes) + " bytes, need " +
                                                   std::to_string(needed));
  }
  return readPixels(GL_RGBA, GL_UNSIGNED_BYTE, dst);
}

Status RenderTarget::readDepth(std::vector<float>& out) {
  out.resize(static_cast<std::size_t>(width_) * height_);
  return readDepth(out.data(), out.size());
}

Status RenderTarget::readDepth(float* dst, std::size_t dstCount) {
  const std::size_t needed = static_cast<std::size_t>(width_) * height_;
  if (dst == nullptr || dstCount < needed) {
    return Status(ErrorCode::kInvalidArgument, "readDepth: buffer holds " +
                                                   std::to_string(dstCount) + " floats, need " +
                                                   std::to_string(needed));
  }
  return readPixels(GL_DEPTH_COMPONENT, GL_FLOAT, dst);
}

}  // namespace thinlod::render
