// OffscreenContext: a GL 3.3 core context without a window, on EGL (Mesa
// surfaceless platform, or the default display when a real GPU is present) or
// on OSMesa. Both back-ends sit behind this one interface.
//
// Contract:
// - createOffscreenContext(kAuto, ...) tries EGL, then OSMesa; on failure the
//   error names why each back-end failed. kEgl / kOsMesa try only that one.
// - width/height size the context's own default surface (pbuffer / OSMesa
//   buffer); real drawing goes to RenderTarget FBOs of any size up to
//   maxRenderTargetSize(). Each edge in [1, 16384] and at most 2^26 pixels;
//   else kInvalidArgument naming the size. Unavailable back-ends: kUnavailable.
// - Every GL entry point is loaded through the back-end's own
//   getProcAddress into a table owned by the context, so EGL and OSMesa
//   contexts may coexist in one process (libOSMesa and libGL both export gl*).
// - Threads: a context is current on at most one thread at a time. Call
//   makeCurrent() on the thread that will use it (creation leaves it current
//   on the creating thread); releaseCurrent() before handing it to another
//   thread. Objects created from a context (RenderTarget, MeshRenderer) must be
//   used and destroyed while that context is current on the calling thread,
//   and must be destroyed before the context.
// - Destroying the context releases it and frees all its GL objects. Drawing
//   uses only the context's own table: never call gl* directly on it.
#pragma once

#include <memory>
#include <string>

#include "thinlod/common/core/status.h"

namespace thinlod::render {

enum class Backend { kAuto, kEgl, kOsMesa };
const char* backendName(Backend backend);  // "auto", "egl", "osmesa"

// Opaque table of GL entry points (defined in common/src/render/gl_functions.h).
struct GlFunctions;

class OffscreenContext {
 public:
  virtual ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  virtual Backend backend() const = 0;  // kEgl or kOsMesa, never kAuto
  // Binds the context to the calling thread. kUnavailable if the back-end refuses.
  virtual Status makeCurrent() = 0;
  virtual void releaseCurrent() = 0;
  virtual bool isCurrent() const = 0;

  int width() const { return width_; }
  int height() const { return height_; }
  // GL_RENDERER / GL_VERSION strings, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  const std::string& rendererName() const { return renderer_; }
  const std::string& versionString() const { return version_; }
  // Largest FBO edge this context supports (min of renderbuffer and viewport limits).
  int maxRenderTargetSize() const { return maxTargetSize_; }

  // Internal: the entry-point table of this context (only src/render uses it).
  const GlFunctions& gl() const { return *gl_; }

  using GlProc = void (*)();
  using GlProcLoader = GlProc (*)(const char* name);

 protected:
  OffscreenContext();
  // Back-ends call this once their context is current: loads the GL table
  // through `loader`, checks the GL version (>= 3.3) and queries strings/limits.
  Status initializeGl(GlProcLoader loader);
  int width_ = 0;
  int height_ = 0;
  std::string renderer_;
  std::string version_;
  int maxTargetSize_ = 0;
  std::unique_ptr<GlFunctions> gl_;
};

Result<std::unique_ptr<OffscreenContext>> createOffscreenContext(Backend backend, int width,
                                                                 int height);

}  // namespace thinlod::render
