#include "render/gl_functions.h"

namespace thinlod::render {

bool loadGlFunctions(OffscreenContext::GlProcLoader loader, GlFunctions& table,
                     std::string& missing) {
  missing.clear();
#define THINLOD_GL_LOAD(name, type)                   \
  table.name = reinterpret_cast<type>(loader(#name)); \
  if (table.name == nullptr) missing += (missing.empty() ? "" : ", ") + std::string(#name);
  THINLOD_GL_FUNCTIONS(THINLOD_GL_LOAD)
#undef THINLOD_GL_LOAD
  return missing.empty();
}

const char* glErrorName(GLenum error) {
  switch (error) {
    case GL_NO_ERROR:
      return "GL_NO_ERROR";
    case GL_INVALID_ENUM:
      return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE:
      return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION:
      return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION:
      return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY:
      return "GL_OUT_OF_MEMORY";
    case GL_STACK_UNDERFLOW:
      return "GL_STACK_UNDERFLOW";
    case GL_STACK_OVERFLOW:
      return "GL_STACK_OVERFLOW";
    default:
      return "unknown GL error";
  }
}

Status checkGlErrors(const GlFunctions& gl, const char* what) {
  std::string names;
  bool outOfMemory = false;
  // glGetError returns one flag per call; a lost context could return errors forever.
  for (int i = 0; i < 16; ++i) {
    const GLenum error = gl.glGetError();
    if (error == GL_NO_ERROR) break;
    outOfMemory = outOfMemory || error == GL_OUT_OF_MEMORY;
    names += (names.empty() ? "" : ", ") + std::string(glErrorName(error));
  }
  if (names.empty()) return Status();
  return Status(outOfMemory ? ErrorCode::kResourceExhausted : ErrorCode::kInternal,
                std::string(what) + ": " + names);
}

}  // namespace thinlod::render
