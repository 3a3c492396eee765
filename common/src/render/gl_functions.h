// Private: the table of GL entry points a context uses, loaded through the
// back-end's own getProcAddress. Never call gl* symbols directly in
// thinlod_render: libOSMesa and GLVND's libGL/libOpenGL both export them and
// the dynamic loader would bind a direct call to whichever it finds first.
#pragma once

#include <GL/glcorearb.h>

#include <string>

#include "thinlod/common/core/status.h"
#include "thinlod/common/render/offscreen_context.h"

// X(name, PFN type) for every GL function thinlod_render calls.
#define THINLOD_GL_FUNCTIONS(X)                                  \
  X(glGetString, PFNGLGETSTRINGPROC)                             \
  X(glGetIntegerv, PFNGLGETINTEGERVPROC)                         \
  X(glGetError, PFNGLGETERRORPROC)                               \
  X(glViewport, PFNGLVIEWPORTPROC)                               \
  X(glClearColor, PFNGLCLEARCOLORPROC)                           \
  X(glClearDepth, PFNGLCLEARDEPTHPROC)                           \
  X(glClear, PFNGLCLEARPROC)                                     \
  X(glEnable, PFNGLENABLEPROC)                                   \
  X(glDisable, PFNGLDISABLEPROC)                                 \
  X(glDepthFunc, PFNGLDEPTHFUNCPROC)                             \
  X(glDepthMask, PFNGLDEPTHMASKPROC)                             \
  X(glBlendFuncSeparate, PFNGLBLENDFUNCSEPARATEPROC)             \
  X(glCullFace, PFNGLCULLFACEPROC)                               \
  X(glFrontFace, PFNGLFRONTFACEPROC)                             \
  X(glPixelStorei, PFNGLPIXELSTOREIPROC)                         \
  X(glReadPixels, PFNGLREADPIXELSPROC)                           \
  X(glReadBuffer, PFNGLREADBUFFERPROC)                           \
  X(glDrawBuffers, PFNGLDRAWBUFFERSPROC)                         \
  X(glFinish, PFNGLFINISHPROC)                                   \
  X(glGenFramebuffers, PFNGLGENFRAMEBUFFERSPROC)                 \
  X(glDeleteFramebuffers, PFNGLDELETEFRAMEBUFFERSPROC)           \
  X(glBindFramebuffer, PFNGLBINDFRAMEBUFFERPROC)                 \
  X(glFramebufferRenderbuffer, PFNGLFRAMEBUFFERRENDERBUFFERPROC) \
  X(glCheckFramebufferStatus, PFNGLCHECKFRAMEBUFFERSTATUSPROC)   \
  X(glGenRenderbuffers, PFNGLGENRENDERBUFFERSPROC)               \
  X(glDeleteRenderbuffers, PFNGLDELETERENDERBUFFERSPROC)         \
  X(glBindRenderbuffer, PFNGLBINDRENDERBUFFERPROC)               \
  X(glRenderbufferStorage, PFNGLRENDERBUFFERSTORAGEPROC)         \
  X(glCreateShader, PFNGLCREATESHADERPROC)                       \
  X(glShaderSource, PFNGLSHADERSOURCEPROC)                       \
  X(glCompileShader, PFNGLCOMPILESHADERPROC)                     \
  X(glGetShaderiv, PFNGLGETSHADERIVPROC)                         \
  X(glGetShaderInfoLog, PFNGLGETSHADERINFOLOGPROC)               \
  X(glDeleteShader, PFNGLDELETESHADERPROC)                       \
  X(glCreateProgram, PFNGLCREATEPROGRAMPROC)                     \
  X(glAttachShader, PFNGLATTACHSHADERPROC)                       \
  X(glLinkProgram, PFNGLLINKPROGRAMPROC)                         \
  X(glGetProgramiv, PFNGLGETPROGRAMIVPROC)                       \
  X(glGetProgramInfoLog, PFNGLGETPROGRAMINFOLOGPROC)             \
  X(glDeleteProgram, PFNGLDELETEPROGRAMPROC)                     \
  X(glUseProgram, PFNGLUSEPROGRAMPROC)                           \
  X(glGetUniformLocation, PFNGLGETUNIFORMLOCATIONPROC)           \
  X(glUniform1i, PFNGLUNIFORM1IPROC)                             \
  X(glUniform1f, PFNGLUNIFORM1FPROC)                             \
  X(glUniform1iv, PFNGLUNIFORM1IVPROC)                           \
  X(glUniform1fv, PFNGLUNIFORM1FVPROC)                           \
  X(glUniform3fv, PFNGLUNIFORM3FVPROC)                           \
  X(glUniform4fv, PFNGLUNIFORM4FVPROC)                           \
  X(glUniformMatrix3fv, PFNGLUNIFORMMATRIX3FVPROC)               \
  X(glUniformMatrix4fv, PFNGLUNIFORMMATRIX4FVPROC)               \
  X(glGenBuffers, PFNGLGENBUFFERSPROC)                           \
  X(glDeleteBuffers, PFNGLDELETEBUFFERSPROC)                     \
  X(glBindBuffer, PFNGLBINDBUFFERPROC)                           \
  X(glBufferData, PFNGLBUFFERDATAPROC)                           \
  X(glGenVertexArrays, PFNGLGENVERTEXARRAYSPROC)                 \
  X(glDeleteVertexArrays, PFNGLDELETEVERTEXARRAYSPROC)           \
  X(glBindVertexArray, PFNGLBINDVERTEXARRAYPROC)                 \
  X(glVertexAttribPointer, PFNGLVERTEXATTRIBPOINTERPROC)         \
  X(glEnableVertexAttribArray, PFNGLENABLEVERTEXATTRIBARRAYPROC) \
  X(glDrawElements, PFNGLDRAWELEMENTSPROC)                       \
  X(glDrawArraysInstanced, PFNGLDRAWARRAYSINSTANCEDPROC)         \
  X(glVertexAttribDivisor, PFNGLVERTEXATTRIBDIVISORPROC)         \
  X(glGenTextures, PFNGLGENTEXTURESPROC)                         \
  X(glDeleteTextures, PFNGLDELETETEXTURESPROC)                   \
  X(glBindTexture, PFNGLBINDTEXTUREPROC)                         \
  X(glActiveTexture, PFNGLACTIVETEXTUREPROC)                     \
  X(glTexParameteri, PFNGLTEXPARAMETERIPROC)                     \
  X(glTexImage3D, PFNGLTEXIMAGE3DPROC)                           \
  X(glTexSubImage3D, PFNGLTEXSUBIMAGE3DPROC)                     \
  X(glGenerateMipmap, PFNGLGENERATEMIPMAPPROC)                   \
  X(glTexBuffer, PFNGLTEXBUFFERPROC)

namespace thinlod::render {

struct GlFunctions {
#define THINLOD_GL_MEMBER(name, type) type name = nullptr;
  THINLOD_GL_FUNCTIONS(THINLOD_GL_MEMBER)
#undef THINLOD_GL_MEMBER
};

// Fills `table` through `loader`; on failure returns false and lists the missing functions.
bool loadGlFunctions(OffscreenContext::GlProcLoader loader, GlFunctions& table,
                     std::string& missing);

// "GL_OUT_OF_MEMORY" etc.
const char* glErrorName(GLenum error);

// Drains glGetError(). Ok when there was no error; otherwise kResourceExhausted
// for GL_OUT_OF_MEMORY and kInternal for the rest, naming `what` and the errors.
Status checkGlErrors(const GlFunctions& gl, const char* what);

}  // namespace thinlod::render
