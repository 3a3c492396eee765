// OSMesa back-end: Mesa's software renderer into a client memory buffer.
// Deliberately does not include gl_functions.h: osmesa.h pulls in GL/gl.h,
// which clashes with glcorearb.h; the base class loads the GL table.
#include <GL/osmesa.h>

#include <string>
#include <vector>

#include "render/backends.h"

namespace thinlod::render {
namespace {

OffscreenContext::GlProc loadOsMesaProc(const char* name) {
  return reinterpret_cast<OffscreenContext::GlProc>(OSMesaGetProcAddress(name));
}

class OsMesaContext final : public OffscreenContext {
 public:
  OsMesaContext(int width, int height) {
    width_ = width;
    height_ = height;
  }
  ~OsMesaContext() override {
    releaseCurrent();
    if (context_ != nullptr) OSMesaDestroyContext(context_);
  }

  Status open() {
    const int attributes[] = {OSMESA_FORMAT,
                              OSMESA_RGBA,
                              OSMESA_DEPTH_BITS,
                              24,
                              OSMESA_STENCIL_BITS,
                              0,
                              OSMESA_ACCUM_BITS,
                              0,
                              OSMESA_PROFILE,
                              OSMESA_CORE_PROFILE,
                              OSMESA_CONTEXT_MAJOR_VERSION,
                              3,
                              OSMESA_CONTEXT_MINOR_VERSION,
                              3,
                              0};
    context_ = OSMesaCreateContextAttribs(attributes, nullptr);
    if (context_ == nullptr) {
      return Status(ErrorCode::kUnavailable,
                    "OSMesaCreateContextAttribs(RGBA, depth 24, 3.3 core) returned null");
    }
    buffer_.assign(static_cast<std::size_t>(width_) * height_ * 4, 0);
    THINLOD_RETURN_IF_ERROR(makeCurrent());
    return initializeGl(&loadOsMesaProc);
  }

  Backend backend() const override { return Backend::kOsMesa; }

  Status makeCurrent() override {
    if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_)) {
      return Status(ErrorCode::kUnavailable, "OSMesaMakeCurrent failed");
    }
    return Status();
  }

  void releaseCurrent() override {
    // Mesa's OSMesaMakeCurrent(NULL, NULL, ...) unbinds the thread's context.
    if (isCurrent()) OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
  }

  bool isCurrent() const override {
    return context_ != nullptr && OSMesaGetCurrentContext() == context_;
  }

 private:
  OSMesaContext context_ = nullptr;
  std::vector<unsigned char> buffer_;
};

}  // namespace

Result<std::unique_ptr<OffscreenContext>> createOsMesaContext(int width, int height) {
  auto context = std::make_unique<OsMesaContext>(width, height);
  THINLOD_RETURN_IF_ERROR(context->open());
  return std::unique_ptr<OffscreenContext>(std::move(context));
}

}  // namespace thinlod::render
