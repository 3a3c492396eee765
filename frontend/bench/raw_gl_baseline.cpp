#include "raw_gl_baseline.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <cstddef>
#include <glm/gtc/type_ptr.hpp>
#include <string>

namespace thinlod::bench {
namespace {

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec2 aUv;
layout(location = 2) in float aLayer;
layout(location = 3) in vec4 aColor;
uniform mat4 uViewProjection;
out vec3 vUvLayer;
out vec4 vColor;
void main() {
  vUvLayer = vec3(aUv, aLayer);
  vColor = aColor;
  gl_Position = uViewProjection * vec4(aPosition, 1.0);
})";

constexpr const char* kFragmentShader = R"(#version 330 core
uniform sampler2DArray uTexture;
in vec3 vUvLayer;
in vec4 vColor;
out vec4 fragColor;
void main() {
  vec4 c = texture(uTexture, vUvLayer) * vColor;
  if (c.a < 0.5) discard;
  fragColor = c;
})";

// Interleaved vertex: what the shader reads, nothing more.
struct Vertex {
  float position[3];
  float uv[2];
  float layer;
  std::uint8_t color[4];
};

Result<GLuint> compile(GLenum type, const char* source) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[1024] = {};
    glGetShaderInfoLog(shader, sizeof(log), nullptr, log);
    glDeleteShader(shader);
    return Status(ErrorCode::kInternal, std::string("raw GL shader: ") + log);
  }
  return shader;
}

}  // namespace

Result<std::unique_ptr<RawGlBaseline>> RawGlBaseline::create(
    int width, int height, const IndexedMesh& mesh, const std::vector<std::uint16_t>& vertexLayers,
    const std::vector<const RgbaImage*>& layerImages) {
  if (width <= 0 || height <= 0 || mesh.uvs.size() != mesh.positions.size() ||
      mesh.colors.size() != mesh.positions.size() || vertexLayers.size() != mesh.positions.size() ||
      layerImages.empty()) {
    return Status(ErrorCode::kInvalidArgument, "raw GL baseline: inconsistent merged mesh");
  }
  const int layerWidth = layerImages[0]->width, layerHeight = layerImages[0]->height;
  for (const RgbaImage* image : layerImages) {
    if (image->width != layerWidth || image->height != layerHeight) {
      return Status(ErrorCode::kInvalidArgument, "raw GL baseline: layer sizes differ");
    }
  }
  // De-index: glDrawArrays over the triangle list.
  std::vector<Vertex> vertices;
  vertices.reserve(mesh.indices.size());
  for (const std::uint32_t i : mesh.indices) {
    if (i >= mesh.positions.size()) {
      return Status(ErrorCode::kInvalidArgument, "raw GL baseline: index out of range");
    }
    Vertex v{};
    for (int c = 0; c < 3; ++c) v.position[c] = mesh.positions[i][c];
    v.uv[0] = mesh.uvs[i].x;
    v.uv[1] = mesh.uvs[i].y;
    v.layer = static_cast<float>(vertexLayers[i]);
    for (int c = 0; c < 4; ++c) v.color[c] = mesh.colors[i][c];
    vertices.push_back(v);
  }

  std::unique_ptr<RawGlBaseline> self(new RawGlBaseline());
  self->width_ = width;
  self->height_ = height;
  self->vertexCount_ = static_cast<int>(vertices.size());

  auto vs = compile(GL_VERTEX_SHADER, kVertexShader);
  if (!vs.ok()) return vs.status();
  auto fs = compile(GL_FRAGMENT_SHADER, kFragmentShader);
  if (!fs.ok()) {
    glDeleteShader(vs.value());
    return fs.status();
  }
  self->program_ = glCreateProgram();
  glAttachShader(self->program_, vs.value());
  glAttachShader(self->program_, fs.value());
  glLinkProgram(self->program_);
  glDeleteShader(vs.value());
  glDeleteShader(fs.value());
  GLint linked = GL_FALSE;
  glGetProgramiv(self->program_, GL_LINK_STATUS, &linked);
  if (linked != GL_TRUE) return Status(ErrorCode::kInternal, "raw GL baseline: link failed");
  self->viewProjectionLocation_ = glGetUniformLocation(self->program_, "uViewProjection");
  glUseProgram(self->program_);
  glUniform1i(glGetUniformLocation(self->program_, "uTexture"), 0);

  glGenVertexArrays(1, &self->vao_);
  glBindVertexArray(self->vao_);
  glGenBuffers(1, &self->vbo_);
  glBindBuffer(GL_ARRAY_BUFFER, self->vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)),
               vertices.data(), GL_STATIC_DRAW);
  const auto offset = [](std::size_t bytes) { return reinterpret_cast<const void*>(bytes); };
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                        offset(offsetof(Vertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex), offset(offsetof(Vertex, uv)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 1, GL_FLOAT, GL_FALSE, sizeof(Vertex), offset(offsetof(Vertex, layer)));
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(Vertex),
                        offset(offsetof(Vertex, color)));
  glBindVertexArray(0);

  glGenTextures(1, &self->texture_);
  glBindTexture(GL_TEXTURE_2D_ARRAY, self->texture_);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA8, layerWidth, layerHeight,
               static_cast<GLsizei>(layerImages.size()), 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (std::size_t layer = 0; layer < layerImages.size(); ++layer) {
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, static_cast<GLint>(layer), layerWidth,
                    layerHeight, 1, GL_RGBA, GL_UNSIGNED_BYTE, layerImages[layer]->pixels.data());
  }

  glGenRenderbuffers(1, &self->colorBuffer_);
  glBindRenderbuffer(GL_RENDERBUFFER, self->colorBuffer_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glGenRenderbuffers(1, &self->depthBuffer_);
  glBindRenderbuffer(GL_RENDERBUFFER, self->depthBuffer_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  glGenFramebuffers(1, &self->fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, self->fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                            self->colorBuffer_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                            self->depthBuffer_);
  const GLenum fboStatus = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (fboStatus != GL_FRAMEBUFFER_COMPLETE) {
    return Status(ErrorCode::kInternal, "raw GL baseline: framebuffer incomplete");
  }
  if (glGetError() != GL_NO_ERROR) {
    return Status(ErrorCode::kInternal, "raw GL baseline: GL error during setup");
  }
  return self;
}

RawGlBaseline::~RawGlBaseline() {
  glDeleteFramebuffers(1, &fbo_);
  glDeleteRenderbuffers(1, &colorBuffer_);
  glDeleteRenderbuffers(1, &depthBuffer_);
  glDeleteTextures(1, &texture_);
  glDeleteBuffers(1, &vbo_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
}

void RawGlBaseline::renderFrame(const glm::mat4& viewProjection, std::vector<std::uint8_t>& rgba) {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width_, height_);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glUseProgram(program_);
  glUniformMatrix4fv(viewProjectionLocation_, 1, GL_FALSE, glm::value_ptr(viewProjection));
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D_ARRAY, texture_);
  glBindVertexArray(vao_);
  glDrawArrays(GL_TRIANGLES, 0, vertexCount_);
  glBindVertexArray(0);
  rgba.resize(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

}  // namespace thinlod::bench
