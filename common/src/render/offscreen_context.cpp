#include "thinlod/common/render/offscreen_context.h"

#include <algorithm>
#include <string>

#include "render/backends.h"
#include "render/gl_functions.h"

namespace thinlod::render {

const char* backendName(Backend backend) {
  switch (backend) {
    case Backend::kAuto:
      return "auto";
    case Backend::kEgl:
      return "egl";
    case Backend::kOsMesa:
      return "osmesa";
  }
  return "unknown";
}

OffscreenContext::OffscreenContext() : gl_(std::make_unique<GlFunctions>()) {}
OffscreenContext::~OffscreenContext() = default;

Status OffscreenContext::initializeGl(GlProcLoader loader) {
  std::string missing;
  if (!loadGlFunctions(loader, *gl_, missing)) {
    return Status(ErrorCode::kUnavailable, "GL entry points not found: " + missing);
  }
  const GlFunctions& gl = *gl_;
  auto text = [&gl](GLenum name) {
    const GLubyte* value = gl.glGetString(name);
    return value ? std::string(reinterpret_cast<const char*>(value)) : std::string();
  };
  renderer_ = text(GL_RENDERER);
  version_ = text(GL_VERSION);
  GLint major = 0;
  GLint minor = 0;
  gl.glGetIntegerv(GL_MAJOR_VERSION, &major);
  gl.glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 33) {
    return Status(ErrorCode::kUnsupported,
                  "need OpenGL 3.3, context is '" + version_ + "' on '" + renderer_ + "'");
  }
  GLint renderbufferMax = 0;
  GLint viewportMax[2] = {0, 0};
  gl.glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &renderbufferMax);
  gl.glGetIntegerv(GL_MAX_VIEWPORT_DIMS, viewportMax);
  maxTargetSize_ = std::min({renderbufferMax, viewportMax[0], viewportMax[1], kMaxSurfaceEdge});
  return checkGlErrors(gl, "querying context limits");
}

namespace {

Status checkSurfaceSize(int width, int height) {
  if (width < 1 || height < 1 || width > kMaxSurfaceEdge || height > kMaxSurfaceEdge ||
      static_cast<long long>(width) * height > kMaxSurfacePixels) {
    return Status(ErrorCode::kInvalidArgument,
                  "offscreen context size " + std::to_string(width) + "x" + std::to_string(height) +
                      " out of range (each edge 1.." + std::to_string(kMaxSurfaceEdge) +
                      ", at most " + std::to_string(kMaxSurfacePixels) + " pixels)");
  }
  return Status();
}

}  // namespace

Result<std::unique_ptr<OffscreenContext>> createOffscreenContext(Backend backend, int width,
                                                                 int height) {
  THINLOD_RETURN_IF_ERROR(checkSurfaceSize(width, height));
  switch (backend) {
    case Backend::kEgl:
      return createEglContext(width, height);
    case Backend::kOsMesa:
      return createOsMesaContext(width, height);
    case Backend::kAuto:
      break;
  }
  auto egl = createEglContext(width, height);
  if (egl.ok()) return egl;
  auto osmesa = createOsMesaContext(width, height);
  if (osmesa.ok()) return osmesa;
  return Status(ErrorCode::kUnavailable, "no offscreen GL back-end: EGL failed (" +
                                             egl.status().toString() + "); OSMesa failed (" +
                                             osmesa.status().toString() + ")");
}

}  // namespace thinlod::render
