// DiscRenderer (disc_renderer.h): instanced screen-aligned quads.
#include "thinlod/common/render/disc_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <string>
#include <unordered_map>
#include <vector>

#include "gl_functions.h"
#include "thinlod/common/core/finite.h"
#include "thinlod/common/render/render_target.h"

namespace thinlod::render {
namespace {

constexpr const char* kDiscVertexShader = R"GLSL(#version 330 core
layout(location = 0) in vec2 aCorner;        // per vertex: the quad's corner in [-1, 1]^2
layout(location = 1) in vec4 aCentreRadius;  // per instance
layout(location = 2) in vec4 aColor;         // per instance, normalized RGBA8

uniform mat4 uModelView;
uniform mat4 uProjection;
uniform float uRadiusScale;
uniform float uPixelsPerClipW;  // viewport height * projection[1][1] / 2
uniform float uMinRadiusPixels;

out vec2 vCorner;
flat out vec4 vColor;

void main() {
  vec4 eye = uModelView * vec4(aCentreRadius.xyz, 1.0);
  // Eye-space size of one pixel at this depth: clip w / pixels per clip w.
  float w = (uProjection * eye).w;
  float pixel = abs(w) / uPixelsPerClipW;
  float radius = max(aCentreRadius.w * uRadiusScale, uMinRadiusPixels * pixel);
  eye.xy += aCorner * radius;
  gl_Position = uProjection * eye;
  vCorner = aCorner;
  vColor = aColor;
}
)GLSL";

// Point-sprite variant: one vertex per disc, gl_PointSize = the diameter in
// pixels (capped by the implementation's largest point size).
constexpr const char* kSpriteVertexShader = R"GLSL(#version 330 core
layout(location = 1) in vec4 aCentreRadius;
layout(location = 2) in vec4 aColor;

uniform mat4 uModelView;
uniform mat4 uProjection;
uniform float uRadiusScale;
uniform float uPixelsPerClipW;
uniform float uMinRadiusPixels;
uniform float uMaxPointSize;

flat out vec4 vColor;

void main() {
  vec4 eye = uModelView * vec4(aCentreRadius.xyz, 1.0);
  gl_Position = uProjection * eye;
  float radiusPixels = aCentreRadius.w * uRadiusScale * uPixelsPerClipW / abs(gl_Position.w);
  gl_PointSize = min(2.0 * max(radiusPixels, uMinRadiusPixels), uMaxPointSize);
  vColor = aColor;
}
)GLSL";

constexpr const char* kSpriteFragmentShader = R"GLSL(#version 330 core
flat in vec4 vColor;
out vec4 fragColor;
void main() {
  vec2 corner = 2.0 * gl_PointCoord - 1.0;
  if (dot(corner, corner) > 1.0) discard;
  fragColor = vec4(vColor.rgb, 1.0);
}
)GLSL";

constexpr const char* kDiscFragmentShader = R"GLSL(#version 330 core
in vec2 vCorner;
flat in vec4 vColor;
out vec4 fragColor;
void main() {
  if (dot(vCorner, vCorner) > 1.0) discard;
  fragColor = vec4(vColor.rgb, 1.0);
}
)GLSL";

struct GpuDisc {
  float centreRadius[4];
  std::uint8_t color[4];
};
static_assert(sizeof(GpuDisc) == 20, "tightly packed instance data");

struct DiscRecord {
  GLuint vertexArray = 0;
  GLuint instanceBuffer = 0;
  GLsizei count = 0;
};

Status notCurrent(const char* what) {
  return Status(ErrorCode::kInvalidArgument,
                std::string(what) + ": the renderer's context is not current");
}

Result<GLuint> compile(const GlFunctions& gl, GLenum type, const char* source) {
  const GLuint shader = gl.glCreateShader(type);
  gl.glShaderSource(shader, 1, &source, nullptr);
  gl.glCompileShader(shader);
  GLint ok = GL_FALSE;
  gl.glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[2048] = {0};
    gl.glGetShaderInfoLog(shader, sizeof(log) - 1, nullptr, log);
    gl.glDeleteShader(shader);
    return Status(ErrorCode::kInternal, std::string("disc shader failed to compile: ") + log);
  }
  return shader;
}

float largestAxisScale(const glm::mat4& m) {
  return std::max(
      {glm::length(glm::vec3(m[0])), glm::length(glm::vec3(m[1])), glm::length(glm::vec3(m[2]))});
}

void buildInstances(const DiscPoints& points, std::vector<GpuDisc>& out) {
  out.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::memcpy(out[i].centreRadius, &points.centres[i], 3 * sizeof(float));
    out[i].centreRadius[3] = points.radii[i];
    std::memcpy(out[i].color, points.colors[i].data(), 4);
  }
}

}  // namespace

struct DiscRenderer::Impl {
  DiscStyle style = DiscStyle::kInstancedQuads;
  float maxPointSize = 1.0f;
  GLint maxPointSizeUniform = -1;
  GLuint program = 0;
  GLuint quadBuffer = 0;
  GLint modelView = -1, projection = -1, radiusScale = -1, pixelsPerClipW = -1, minRadius = -1;
  std::unordered_map<std::uint32_t, DiscRecord> records;
  std::uint32_t nextId = 1;
  std::vector<GpuDisc> scratch;

  void fill(const GlFunctions& gl, DiscRecord& record, const DiscPoints& points) {
    buildInstances(points, scratch);
    gl.glBindVertexArray(record.vertexArray);
    const GLuint perDisc = style == DiscStyle::kInstancedQuads ? 1 : 0;
    if (style == DiscStyle::kInstancedQuads) {
      gl.glBindBuffer(GL_ARRAY_BUFFER, quadBuffer);
      gl.glEnableVertexAttribArray(0);
      gl.glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
      gl.glVertexAttribDivisor(0, 0);
    }
    gl.glBindBuffer(GL_ARRAY_BUFFER, record.instanceBuffer);
    gl.glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(scratch.size() * sizeof(GpuDisc)),
                    scratch.empty() ? nullptr : scratch.data(), GL_STATIC_DRAW);
    gl.glEnableVertexAttribArray(1);
    gl.glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, sizeof(GpuDisc), nullptr);
    gl.glVertexAttribDivisor(1, perDisc);
    gl.glEnableVertexAttribArray(2);
    gl.glVertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(GpuDisc),
                             reinterpret_cast<const void*>(4 * sizeof(float)));
    gl.glVertexAttribDivisor(2, perDisc);
    gl.glBindVertexArray(0);
    gl.glBindBuffer(GL_ARRAY_BUFFER, 0);
    record.count = static_cast<GLsizei>(points.size());
  }
};

DiscRenderer::DiscRenderer(OffscreenContext& context)
    : context_(&context), impl_(std::make_unique<Impl>()) {}

DiscRenderer::~DiscRenderer() {
  if (!context_->isCurrent()) return;  // as MeshRenderer: leak rather than delete elsewhere
  const GlFunctions& gl = context_->gl();
  for (auto& [id, record] : impl_->records) {
    gl.glDeleteVertexArrays(1, &record.vertexArray);
    gl.glDeleteBuffers(1, &record.instanceBuffer);
  }
  if (impl_->quadBuffer != 0) gl.glDeleteBuffers(1, &impl_->quadBuffer);
  if (impl_->program != 0) gl.glDeleteProgram(impl_->program);
}

Result<std::unique_ptr<DiscRenderer>> DiscRenderer::create(OffscreenContext& context,
                                                           DiscStyle style) {
  if (!context.isCurrent()) return notCurrent("DiscRenderer::create");
  std::unique_ptr<DiscRenderer> renderer(new DiscRenderer(context));
  renderer->impl_->style = style;
  const GlFunctions& gl = context.gl();
  THINLOD_RETURN_IF_ERROR(checkGlErrors(gl, "before DiscRenderer::create"));
  const bool sprites = style == DiscStyle::kPointSprites;
  Result<GLuint> vs =
      compile(gl, GL_VERTEX_SHADER, sprites ? kSpriteVertexShader : kDiscVertexShader);
  if (!vs.ok()) return vs.status();
  Result<GLuint> fs =
      compile(gl, GL_FRAGMENT_SHADER, sprites ? kSpriteFragmentShader : kDiscFragmentShader);
  if (!fs.ok()) {
    gl.glDeleteShader(*vs);
    return fs.status();
  }
  Impl& impl = *renderer->impl_;
  impl.program = gl.glCreateProgram();
  gl.glAttachShader(impl.program, *vs);
  gl.glAttachShader(impl.program, *fs);
  gl.glLinkProgram(impl.program);
  gl.glDeleteShader(*vs);
  gl.glDeleteShader(*fs);
  GLint linked = GL_FALSE;
  gl.glGetProgramiv(impl.program, GL_LINK_STATUS, &linked);
  if (linked != GL_TRUE) {
    char log[2048] = {0};
    gl.glGetProgramInfoLog(impl.program, sizeof(log) - 1, nullptr, log);
    return Status(ErrorCode::kInternal, std::string("disc shader failed to link: ") + log);
  }
  impl.modelView = gl.glGetUniformLocation(impl.program, "uModelView");
  impl.projection = gl.glGetUniformLocation(impl.program, "uProjection");
  impl.radiusScale = gl.glGetUniformLocation(impl.program, "uRadiusScale");
  impl.pixelsPerClipW = gl.glGetUniformLocation(impl.program, "uPixelsPerClipW");
  impl.minRadius = gl.glGetUniformLocation(impl.program, "uMinRadiusPixels");
  impl.maxPointSizeUniform = gl.glGetUniformLocation(impl.program, "uMaxPointSize");
  if (sprites) {
    GLint range[2] = {1, 1};
    gl.glGetIntegerv(GL_POINT_SIZE_RANGE, range);
    impl.maxPointSize = static_cast<float>(std::max(range[1], 1));
  }
  const float quad[8] = {-1.0f, -1.0f, 1.0f, -1.0f, -1.0f, 1.0f, 1.0f, 1.0f};  // a strip
  gl.glGenBuffers(1, &impl.quadBuffer);
  gl.glBindBuffer(GL_ARRAY_BUFFER, impl.quadBuffer);
  gl.glBufferData(GL_ARRAY_BUFFER, sizeof(quad), quad, GL_STATIC_DRAW);
  gl.glBindBuffer(GL_ARRAY_BUFFER, 0);
  THINLOD_RETURN_IF_ERROR(checkGlErrors(gl, "DiscRenderer::create"));
  return renderer;
}

Result<DiscHandle> DiscRenderer::upload(const DiscPoints& points) {
  if (!context_->isCurrent()) return notCurrent("DiscRenderer::upload");
  THINLOD_RETURN_IF_ERROR(points.validate("uploaded discs"));
  const GlFunctions& gl = context_->gl();
  DiscRecord record;
  gl.glGenVertexArrays(1, &record.vertexArray);
  gl.glGenBuffers(1, &record.instanceBuffer);
  impl_->fill(gl, record, points);
  const Status status = checkGlErrors(gl, "DiscRenderer::upload");
  if (!status.ok()) {
    gl.glDeleteVertexArrays(1, &record.vertexArray);
    gl.glDeleteBuffers(1, &record.instanceBuffer);
    return status;
  }
  const std::uint32_t id = impl_->nextId++;
  impl_->records.emplace(id, record);
  return DiscHandle{id};
}

Status DiscRenderer::update(DiscHandle handle, const DiscPoints& points) {
  if (!context_->isCurrent()) return notCurrent("DiscRenderer::update");
  auto found = impl_->records.find(handle.id);
  if (found == impl_->records.end()) {
    return Status(ErrorCode::kNotFound, "disc handle " + std::to_string(handle.id));
  }
  THINLOD_RETURN_IF_ERROR(points.validate("updated discs"));
  impl_->fill(context_->gl(), found->second, points);
  return checkGlErrors(context_->gl(), "DiscRenderer::update");
}

void DiscRenderer::remove(DiscHandle handle) {
  if (!context_->isCurrent()) return;
  auto found = impl_->records.find(handle.id);
  if (found == impl_->records.end()) return;
  const GlFunctions& gl = context_->gl();
  gl.glDeleteVertexArrays(1, &found->second.vertexArray);
  gl.glDeleteBuffers(1, &found->second.instanceBuffer);
  impl_->records.erase(found);
}

Status DiscRenderer::draw(const DiscDrawItem* items, std::size_t count, const Camera& camera) {
  if (!context_->isCurrent()) return notCurrent("DiscRenderer::draw");
  if (!allFinite(camera.view) || !allFinite(camera.projection)) {
    return Status(ErrorCode::kInvalidArgument, "DiscRenderer::draw: non-finite camera");
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (!allFinite(items[i].model)) {
      return Status(ErrorCode::kInvalidArgument,
                    "DiscRenderer::draw: item " + std::to_string(i) + " has a non-finite model");
    }
    if (impl_->records.find(items[i].discs.id) == impl_->records.end()) {
      return Status(ErrorCode::kNotFound,
                    "DiscRenderer::draw: disc handle " + std::to_string(items[i].discs.id));
    }
  }
  const GlFunctions& gl = context_->gl();
  GLint viewport[4] = {0, 0, 1, 1};
  gl.glGetIntegerv(GL_VIEWPORT, viewport);
  const float pixelsPerClipW = 0.5f * static_cast<float>(std::max(viewport[3], 1)) *
                               std::max(std::abs(camera.projection[1][1]), 1e-12f);
  gl.glUseProgram(impl_->program);
  gl.glEnable(GL_DEPTH_TEST);
  gl.glDepthFunc(GL_LESS);
  gl.glDepthMask(GL_TRUE);
  gl.glDisable(GL_BLEND);
  gl.glDisable(GL_CULL_FACE);
  // The framebuffer holds the picture upside down (render_target.h, "Rows").
  const glm::mat4 projection = kMirrorClipY * camera.projection;
  gl.glUniformMatrix4fv(impl_->projection, 1, GL_FALSE, glm::value_ptr(projection));
  gl.glUniform1f(impl_->pixelsPerClipW, pixelsPerClipW);
  gl.glUniform1f(impl_->minRadius, kMinDiscRadiusPixels);
  const bool sprites = impl_->style == DiscStyle::kPointSprites;
  if (sprites) {
    gl.glUniform1f(impl_->maxPointSizeUniform, impl_->maxPointSize);
    gl.glEnable(GL_PROGRAM_POINT_SIZE);
  }
  for (std::size_t i = 0; i < count; ++i) {
    const DiscRecord& record = impl_->records.at(items[i].discs.id);
    if (record.count == 0) continue;
    const glm::mat4 modelView = camera.view * items[i].model;
    gl.glUniformMatrix4fv(impl_->modelView, 1, GL_FALSE, glm::value_ptr(modelView));
    gl.glUniform1f(impl_->radiusScale, largestAxisScale(items[i].model));
    gl.glBindVertexArray(record.vertexArray);
    if (sprites) {
      gl.glDrawArraysInstanced(GL_POINTS, 0, record.count, 1);
    } else {
      gl.glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, record.count);
    }
    ++stats_.drawCalls;
    stats_.discs += static_cast<std::size_t>(record.count);
  }
  gl.glBindVertexArray(0);
  gl.glUseProgram(0);
  if (sprites) gl.glDisable(GL_PROGRAM_POINT_SIZE);
  return checkGlErrors(gl, "DiscRenderer::draw");
}

DiscPoints preLightDiscs(const DiscPoints& points, const glm::mat4& model, const glm::vec4& diffuse,
                         const Lighting& lighting) {
  DiscPoints out = points;
  const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(model)));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const glm::vec3 world = glm::vec3(model * glm::vec4(points.centres[i], 1.0f));
    glm::vec3 n(0.0f);
    if (!points.normals.empty()) {
      n = normalMatrix * points.normals[i];
      const float length = glm::length(n);
      n = length > 0.0f ? n / length : glm::vec3(0.0f);
    }
    glm::vec3 light = lighting.ambient;
    for (const Light& l : lighting.lights) {
      glm::vec3 toLight;
      float attenuation = 1.0f;
      if (l.type == Light::Type::kDirectional) {
        toLight = -glm::normalize(l.vector);
      } else {
        const glm::vec3 d = l.vector - world;
        const float distance2 = glm::dot(d, d);
        toLight = d / std::sqrt(std::max(distance2, 1e-12f));
        attenuation = 1.0f / (1.0f + l.attenuation * distance2);
      }
      const float lambert = points.normals.empty() ? 1.0f : std::max(glm::dot(n, toLight), 0.0f);
      light += l.color * attenuation * lambert;
    }
    const auto& c = points.colors[i];
    for (int k = 0; k < 3; ++k) {
      const float base = diffuse[k] * static_cast<float>(c[k]) / 255.0f;
      const float value = std::clamp(base * light[k], 0.0f, 1.0f);
      out.colors[i][k] = static_cast<std::uint8_t>(std::lround(value * 255.0f));
    }
    out.colors[i][3] = static_cast<std::uint8_t>(std::lround(
        std::clamp(diffuse.a * static_cast<float>(c[3]) / 255.0f, 0.0f, 1.0f) * 255.0f));
  }
  return out;
}

void appendWorldDiscs(DiscPoints& out, const DiscPoints& points, const glm::mat4& model) {
  const bool keepNormals = !points.normals.empty() && out.normals.size() == out.centres.size();
  if (!keepNormals) out.normals.clear();
  const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(model)));
  const float scale = largestAxisScale(model);
  for (std::size_t i = 0; i < points.size(); ++i) {
    out.centres.push_back(glm::vec3(model * glm::vec4(points.centres[i], 1.0f)));
    out.radii.push_back(points.radii[i] * scale);
    out.colors.push_back(points.colors[i]);
    if (keepNormals) {
      const glm::vec3 n = normalMatrix * points.normals[i];
      const float length = glm::length(n);
      out.normals.push_back(length > 0.0f ? n / length : points.normals[i]);
    }
  }
}

}  // namespace thinlod::render
