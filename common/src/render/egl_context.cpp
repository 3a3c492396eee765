// EGL back-end: Mesa's surfaceless platform first (no X server, no GPU
// needed), then the default display so a real GPU driver works unchanged.
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <map>
#include <mutex>
#include <string>

#include "render/backends.h"
#include "render/gl_functions.h"

namespace thinlod::render {
namespace {

const char* eglErrorName(EGLint error) {
  switch (error) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE:
      return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP:
      return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW:
      return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE:
      return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST:
      return "EGL_CONTEXT_LOST";
    default:
      return "unknown EGL error";
  }
}

std::string eglFailure(const char* call) {
  return std::string(call) + " failed (" + eglErrorName(eglGetError()) + ")";
}

bool hasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t length = std::strlen(name);
  for (const char* p = std::strstr(list, name); p != nullptr; p = std::strstr(p + 1, name)) {
    const bool startOk = p == list || p[-1] == ' ';
    const bool endOk = p[length] == '\0' || p[length] == ' ';
    if (startOk && endOk) return true;
  }
  return false;
}

// eglInitialize/eglTerminate act on the whole display, which every context on
// it shares; count users so that destroying one context keeps the others alive.
std::mutex& displayMutex() {
  static std::mutex mutex;
  return mutex;
}
std::map<EGLDisplay, int>& displayUsers() {
  static std::map<EGLDisplay, int> users;
  return users;
}

bool acquireDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(displayMutex());
  int& users = displayUsers()[display];
  if (users == 0) {
    EGLint major = 0;
    EGLint minor = 0;
    if (!eglInitialize(display, &major, &minor)) {
      displayUsers().erase(display);
      return false;
    }
  }
  ++users;
  return true;
}

void releaseDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(displayMutex());
  auto it = displayUsers().find(display);
  if (it == displayUsers().end()) return;
  if (--it->second == 0) {
    eglTerminate(display);
    displayUsers().erase(it);
  }
}

OffscreenContext::GlProc loadEglProc(const char* name) {
  return reinterpret_cast<OffscreenContext::GlProc>(eglGetProcAddress(name));
}

class EglContext final : public OffscreenContext {
 public:
  EglContext(int width, int height) {
    width_ = width;
    height_ = height;
  }
  ~EglContext() override {
    if (display_ == EGL_NO_DISPLAY) return;
    releaseCurrent();
    if (surface_ != EGL_NO_SURFACE) eglDestroySurface(display_, surface_);
    if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
    releaseDisplay(display_);
  }

  // Builds display -> config -> context -> pbuffer and makes it current.
  Status open(EGLDisplay display, const char* displayName) {
    auto fail = [displayName](const std::string& what) {
      return Status(ErrorCode::kUnavailable, std::string(displayName) + ": " + what);
    };
    if (display == EGL_NO_DISPLAY) return fail("no display");
    if (!acquireDisplay(display)) return fail(eglFailure("eglInitialize"));
    display_ = display;
    if (!eglBindAPI(EGL_OPENGL_API)) return fail(eglFailure("eglBindAPI(EGL_OPENGL_API)"));
    // Surfaceless Mesa offers only pbuffer-capable configs (PLATFORM.md).
    const EGLint configAttributes[] = {EGL_SURFACE_TYPE,
                                       EGL_PBUFFER_BIT,
                                       EGL_RENDERABLE_TYPE,
                                       EGL_OPENGL_BIT,
                                       EGL_RED_SIZE,
                                       8,
                                       EGL_GREEN_SIZE,
                                       8,
                                       EGL_BLUE_SIZE,
                                       8,
                                       EGL_ALPHA_SIZE,
                                       8,
                                       EGL_DEPTH_SIZE,
                                       24,
                                       EGL_NONE};
    EGLConfig config = nullptr;
    EGLint configCount = 0;
    if (!eglChooseConfig(display_, configAttributes, &config, 1, &configCount)) {
      return fail(eglFailure("eglChooseConfig"));
    }
    if (configCount < 1) return fail("no RGBA8/depth24 pbuffer config for desktop OpenGL");
    const EGLint contextAttributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                        3,
                                        EGL_CONTEXT_MINOR_VERSION,
                                        3,
                                        EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                        EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                        EGL_NONE};
    context_ = eglCreateContext(display_, config, EGL_NO_CONTEXT, contextAttributes);
    if (context_ == EGL_NO_CONTEXT) return fail(eglFailure("eglCreateContext(3.3 core)"));
    const EGLint surfaceAttributes[] = {EGL_WIDTH, width_, EGL_HEIGHT, height_, EGL_NONE};
    surface_ = eglCreatePbufferSurface(display_, config, surfaceAttributes);
    if (surface_ == EGL_NO_SURFACE) return fail(eglFailure("eglCreatePbufferSurface"));
    Status current = makeCurrent();
    if (!current.ok()) return fail(current.message());
    Status gl = initializeGl(&loadEglProc);
    if (!gl.ok()) return Status(gl.code(), std::string(displayName) + ": " + gl.message());
    return Status();
  }

  Backend backend() const override { return Backend::kEgl; }

  Status makeCurrent() override {
    // The bound client API is per thread: bind it on every thread that uses us.
    if (!eglBindAPI(EGL_OPENGL_API)) {
      return Status(ErrorCode::kUnavailable, eglFailure("eglBindAPI(EGL_OPENGL_API)"));
    }
    if (!eglMakeCurrent(display_, surface_, surface_, context_)) {
      return Status(ErrorCode::kUnavailable, eglFailure("eglMakeCurrent"));
    }
    return Status();
  }

  void releaseCurrent() override {
    if (isCurrent()) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }

  bool isCurrent() const override {
    return context_ != EGL_NO_CONTEXT && eglGetCurrentContext() == context_;
  }

 private:
  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLContext context_ = EGL_NO_CONTEXT;
  EGLSurface surface_ = EGL_NO_SURFACE;
};

EGLDisplay surfacelessDisplay(std::string& why) {
  const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!hasExtension(clientExtensions, "EGL_EXT_platform_base") ||
      !hasExtension(clientExtensions, "EGL_MESA_platform_surfaceless")) {
    why = "surfaceless platform: EGL_MESA_platform_surfaceless not offered";
    return EGL_NO_DISPLAY;
  }
  auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (getPlatformDisplay == nullptr) {
    why = "surfaceless platform: eglGetPlatformDisplayEXT missing";
    return EGL_NO_DISPLAY;
  }
  EGLDisplay display =
      getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY)
    why = "surfaceless platform: " + eglFailure("eglGetPlatformDisplayEXT");
  return display;
}

}  // namespace

Result<std::unique_ptr<OffscreenContext>> createEglContext(int width, int height) {
  std::string surfacelessWhy;
  EGLDisplay surfaceless = surfacelessDisplay(surfacelessWhy);
  if (surfaceless != EGL_NO_DISPLAY) {
    auto context = std::make_unique<EglContext>(width, height);
    Status status = context->open(surfaceless, "surfaceless platform");
    if (status.ok()) return std::unique_ptr<OffscreenContext>(std::move(context));
    surfacelessWhy = status.message();
  }
  auto context = std::make_unique<EglContext>(width, height);
  Status status = context->open(eglGetDisplay(EGL_DEFAULT_DISPLAY), "default display");
  if (status.ok()) return std::unique_ptr<OffscreenContext>(std::move(context));
  return Status(status.code(), surfacelessWhy + "; " + status.message());
}

}  // namespace thinlod::render
