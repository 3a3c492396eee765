#include "thinlod/common/render/mesh_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <limits>
#include <string>
#include <unordered_map>

#include "render/gl_functions.h"
#include "render/shaders.h"
#include "thinlod/common/core/finite.h"

namespace thinlod::render {
namespace {

// Interleaved vertex: one buffer, one VAO per mesh. 40 bytes.
struct GpuVertex {
  float position[3];
  float normal[3];
  float uv[2];
  std::uint8_t color[4];
  std::uint16_t layer;
  std::uint16_t padding;
};
static_assert(sizeof(GpuVertex) == 40, "GpuVertex layout");

struct MeshRecord {
  GLuint vertexArray = 0;
  GLuint vertexBuffer = 0;
  GLuint indexBuffer = 0;
  GLsizei indexCount = 0;
  bool hasLayers = false;
  GLuint skinBuffer = 0;          // skinned meshes: (bone A, bone B, weight) per vertex
  std::uint32_t bonesNeeded = 0;  // highest bone + 1; 0: not skinned
};

void deleteRecord(const GlFunctions& gl, const MeshRecord& record) {
  gl.glDeleteVertexArrays(1, &record.vertexArray);
  gl.glDeleteBuffers(1, &record.vertexBuffer);
  gl.glDeleteBuffers(1, &record.indexBuffer);
  if (record.skinBuffer != 0) gl.glDeleteBuffers(1, &record.skinBuffer);
}

struct TextureRecord {
  GLuint texture = 0;
  int width = 0;
  int height = 0;
  int layers = 0;
  TextureOptions options;
};

Status notCurrent(const char* what) {
  return Status(ErrorCode::kUnavailable,
                std::string(what) + ": the renderer's GL context is not current on this thread");
}

Status compileShader(const GlFunctions& gl, GLenum type, const std::string& defines,
                     const char* body, GLuint& shader) {
  shader = gl.glCreateShader(type);
  const char* parts[] = {"#version 330 core\n", defines.c_str(), body};
  gl.glShaderSource(shader, 3, parts, nullptr);
  gl.glCompileShader(shader);
  GLint ok = GL_FALSE;
  gl.glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok == GL_TRUE) return Status();
  char log[2048] = {0};
  gl.glGetShaderInfoLog(shader, sizeof(log) - 1, nullptr, log);
  return Status(ErrorCode::kInternal,
                std::string(type == GL_VERTEX_SHADER ? "vertex" : "fragment") +
                    " shader failed to compile: " + log);
}

// One compiled shader variant (see shaders.h) and its uniform locations.
struct Program {
  GLuint id = 0;
  struct {
    GLint model, viewProjection, normalMatrix, diffuse, specular, shininess, layer, alphaCutoff,
        texture, ambient, lightVector, lightColor, lightAttenuation, eyePosition, bones;
  } uniform{};
  bool frameUniformsSet = false;  // within the current draw()
};

// A variant's key packs what shaders.h's #defines fix. Lighting enters the
// key (count and type of each light) so the light loop is unrolled with
// constant types; a scene has one lighting set-up, so few variants are built.
using VariantKey = std::uint32_t;
constexpr VariantKey kLit = 1u << 0;
constexpr VariantKey kSpecular = 1u << 1;
constexpr VariantKey kTextured = 1u << 2;
constexpr VariantKey kVertexColors = 1u << 3;
constexpr VariantKey kVertexLayers = 1u << 4;
constexpr int kAlphaShift = 5;       // 2 bits
constexpr int kLightCountShift = 7;  // 3 bits
constexpr int kLightTypeShift = 10;  // one bit per light: 1 = point
constexpr VariantKey kSkinned = 1u << (kLightTypeShift + kMaxLights);

bool hasSpecular(const Material& m) { return m.specular != glm::vec3(0.0f); }

VariantKey variantOf(const Material& m, bool meshHasLayers, const Lighting& lighting,
                     bool skinned) {
  VariantKey key = static_cast<VariantKey>(m.alphaMode == AlphaMode::kOpaque ? 0
                                           : m.alphaMode == AlphaMode::kMask ? 1
                                                                             : 2)
                   << kAlphaShift;
  if (skinned) key |= kSkinned;
  if (m.useVertexColors) key |= kVertexColors;
  if (m.texture.valid()) {
    key |= kTextured;
    if (meshHasLayers) key |= kVertexLayers;
  }
  if (m.lit) {
    key |= kLit;
    if (hasSpecular(m)) key |= kSpecular;
    key |= static_cast<VariantKey>(lighting.lights.size()) << kLightCountShift;
    for (std::size_t i = 0; i < lighting.lights.size(); ++i) {
      if (lighting.lights[i].type != Light::Type::kDirectional) key |= 1u << (kLightTypeShift + i);
    }
  }
  return key;
}

std::string definesOf(VariantKey key) {
  auto flag = [&](const char* name, VariantKey bit) {
    return std::string("#define ") + name + ((key & bit) != 0 ? " 1\n" : " 0\n");
  };
  const unsigned lightCount = (key >> kLightCountShift) & 7u;
  std::string types = "int[" + std::to_string(kMaxLights) + "](";
  for (int i = 0; i < kMaxLights; ++i) {
    types += std::string(i > 0 ? "," : "") + (((key >> (kLightTypeShift + i)) & 1u) ? "1" : "0");
  }
  return flag("LIT", kLit) + flag("SPECULAR", kSpecular) + flag("TEXTURED", kTextured) +
         flag("VERTEX_COLORS", kVertexColors) + flag("VERTEX_LAYERS", kVertexLayers) +
         flag("SKINNED", kSkinned) + "#define ALPHA_MODE " +
         std::to_string((key >> kAlphaShift) & 3u) + "\n" + "#define LIGHT_COUNT " +
         std::to_string(lightCount) + "\n" + "#define LIGHT_TYPES " + types + ")\n";
}

Status buildProgram(const GlFunctions& gl, VariantKey key, Program& program) {
  const std::string defines = definesOf(key);
  GLuint vertexShader = 0;
  GLuint fragmentShader = 0;
  Status vertexStatus =
      compileShader(gl, GL_VERTEX_SHADER, defines, kMeshVertexShader, vertexShader);
  Status fragmentStatus =
      compileShader(gl, GL_FRAGMENT_SHADER, defines, kMeshFragmentShader, fragmentShader);
  const GLuint id = gl.glCreateProgram();
  gl.glAttachShader(id, vertexShader);
  gl.glAttachShader(id, fragmentShader);
  if (vertexStatus.ok() && fragmentStatus.ok()) gl.glLinkProgram(id);
  gl.glDeleteShader(vertexShader);  // flagged; freed with the program
  gl.glDeleteShader(fragmentShader);
  GLint linked = GL_FALSE;
  if (vertexStatus.ok() && fragmentStatus.ok()) gl.glGetProgramiv(id, GL_LINK_STATUS, &linked);
  if (linked != GL_TRUE) {
    char log[2048] = {0};
    gl.glGetProgramInfoLog(id, sizeof(log) - 1, nullptr, log);
    gl.glDeleteProgram(id);
    THINLOD_RETURN_IF_ERROR(vertexStatus);
    THINLOD_RETURN_IF_ERROR(fragmentStatus);
    return Status(ErrorCode::kInternal, std::string("mesh shader program failed to link: ") + log);
  }
  // Uniforms a variant does not declare get location -1, which GL ignores.
  auto location = [&](const char* name) { return gl.glGetUniformLocation(id, name); };
  auto& u = program.uniform;
  u.model = location("uModel");
  u.viewProjection = location("uViewProjection");
  u.normalMatrix = location("uNormalMatrix");
  u.diffuse = location("uDiffuse");
  u.specular = location("uSpecular");
  u.shininess = location("uShininess");
  u.layer = location("uLayer");
  u.alphaCutoff = location("uAlphaCutoff");
  u.texture = location("uTexture");
  u.ambient = location("uAmbient");
  u.lightVector = location("uLightVector");
  u.lightColor = location("uLightColor");
  u.lightAttenuation = location("uLightAttenuation");
  u.eyePosition = location("uEyePosition");
  u.bones = location("uBones");
  gl.glUseProgram(id);
  gl.glUniform1i(u.texture, 0);
  gl.glUniform1i(u.bones, static_cast<GLint>(kBoneTextureUnit));
  gl.glUseProgram(0);
  program.id = id;
  return checkGlErrors(gl, "building a mesh shader variant");
}

}  // namespace

struct MeshRenderer::Impl {
  std::unordered_map<VariantKey, Program> programs;  // built on first use
  std::unordered_map<std::uint32_t, MeshRecord> meshes;
  std::unordered_map<std::uint32_t, TextureRecord> textures;
  std::uint32_t nextId = 1;
  RenderTarget* target = nullptr;
  GLint maxTextureSize = 0;
  GLint maxTextureLayers = 0;
  std::vector<GpuVertex> vertexScratch;
  std::vector<std::uint8_t> pixelScratch;
  // Skinned draws: one buffer texture refilled with each item's bones.
  GLuint boneBuffer = 0;
  GLuint boneTexture = 0;
  GLint maxTextureBufferTexels = 0;

  Status ensureProgram(const GlFunctions& gl, VariantKey key) {
    Program& program = programs[key];
    if (program.id != 0) return Status();
    Status status = buildProgram(gl, key, program);
    if (!status.ok()) programs.erase(key);
    return status;
  }

  std::uint32_t newId() {
    // Ids are never reused while the renderer lives, so a stale handle is kNotFound.
    return nextId++;
  }
};

MeshRenderer::MeshRenderer(OffscreenContext& context)
    : context_(&context), impl_(std::make_unique<Impl>()) {}

MeshRenderer::~MeshRenderer() {
  if (!context_->isCurrent()) return;  // deleting in another context would be worse than leaking
  const GlFunctions& gl = context_->gl();
  for (auto& entry : impl_->meshes) deleteRecord(gl, entry.second);
  if (impl_->boneBuffer != 0) gl.glDeleteBuffers(1, &impl_->boneBuffer);
  if (impl_->boneTexture != 0) gl.glDeleteTextures(1, &impl_->boneTexture);
  for (auto& entry : impl_->textures) gl.glDeleteTextures(1, &entry.second.texture);
  for (const auto& [key, program] : impl_->programs) {
    if (program.id != 0) gl.glDeleteProgram(program.id);
  }
}

Result<std::unique_ptr<MeshRenderer>> MeshRenderer::create(OffscreenContext& context) {
  if (!context.isCurrent()) return notCurrent("MeshRenderer::create");
  std::unique_ptr<MeshRenderer> renderer(new MeshRenderer(context));
  const GlFunctions& gl = context.gl();
  THINLOD_RETURN_IF_ERROR(checkGlErrors(gl, "before MeshRenderer::create"));
  Impl& impl = *renderer->impl_;
  // The default variant is built now so a broken GL fails here, not mid-frame.
  THINLOD_RETURN_IF_ERROR(impl.ensureProgram(gl, variantOf(Material(), false, Lighting(), false)));
  gl.glGetIntegerv(GL_MAX_TEXTURE_SIZE, &impl.maxTextureSize);
  gl.glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &impl.maxTextureBufferTexels);
  gl.glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &impl.maxTextureLayers);
  THINLOD_RETURN_IF_ERROR(checkGlErrors(gl, "MeshRenderer::create"));
  return renderer;
}

// ---------------------------------------------------------------- meshes

namespace {

Status validateUpload(const IndexedMesh& mesh, const std::vector<std::uint16_t>& layers) {
  THINLOD_RETURN_IF_ERROR(mesh.validate("uploaded mesh"));
  if (!layers.empty() && layers.size() != mesh.vertexCount()) {
    return Status(ErrorCode::kInvalidArgument,
                  "uploaded mesh: " + std::to_string(layers.size()) + " texture layers for " +
                      std::to_string(mesh.vertexCount()) + " vertices");
  }
  if (mesh.indices.size() > static_cast<std::size_t>(std::numeric_limits<GLsizei>::max())) {
    return Status(ErrorCode::kResourceExhausted, "uploaded mesh: too many indices for one draw");
  }
  return Status();
}

void buildVertices(const IndexedMesh& mesh, const std::vector<std::uint16_t>& layers,
                   std::vector<GpuVertex>& out) {
  IndexedMesh withNormals;
  const std::vector<glm::vec3>* normals = &mesh.normals;
  if (mesh.normals.empty()) {
    withNormals.positions = mesh.positions;
    withNormals.indices = mesh.indices;
    withNormals.computeNormals();
    normals = &withNormals.normals;
  }
  out.resize(mesh.vertexCount());
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
    GpuVertex& g = out[v];
    std::memcpy(g.position, &mesh.positions[v], sizeof(g.position));
    std::memcpy(g.normal, &(*normals)[v], sizeof(g.normal));
    const glm::vec2 uv = mesh.uvs.empty() ? glm::vec2(0.0f) : mesh.uvs[v];
    g.uv[0] = uv.x;
    g.uv[1] = uv.y;
    for (int c = 0; c < 4; ++c) g.color[c] = mesh.colors.empty() ? 255 : mesh.colors[v][c];
    g.layer = layers.empty() ? 0 : layers[v];
    g.padding = 0;
  }
}

void fillBuffers(const GlFunctions& gl, MeshRecord& record, const std::vector<GpuVertex>& vertices,
                 const std::vector<std::uint32_t>& indices) {
  gl.glBindVertexArray(record.vertexArray);
  gl.glBindBuffer(GL_ARRAY_BUFFER, record.vertexBuffer);
  gl.glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(GpuVertex)),
                  vertices.data(), GL_STATIC_DRAW);
  gl.glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, record.indexBuffer);
  gl.glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                  static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(),
                  GL_STATIC_DRAW);
  auto offset = [](std::size_t bytes) { return reinterpret_cast<const void*>(bytes); };
  const GLsizei stride = sizeof(GpuVertex);
  gl.glEnableVertexAttribArray(kAttributePosition);
  gl.glVertexAttribPointer(kAttributePosition, 3, GL_FLOAT, GL_FALSE, stride,
                           offset(offsetof(GpuVertex, position)));
  gl.glEnableVertexAttribArray(kAttributeNormal);
  gl.glVertexAttribPointer(kAttributeNormal, 3, GL_FLOAT, GL_FALSE, stride,
                           offset(offsetof(GpuVertex, normal)));
  gl.glEnableVertexAttribArray(kAttributeUv);
  gl.glVertexAttribPointer(kAttributeUv, 2, GL_FLOAT, GL_FALSE, stride,
                           offset(offsetof(GpuVertex, uv)));
  gl.glEnableVertexAttribArray(kAttributeColor);
  gl.glVertexAttribPointer(kAttributeColor, 4, GL_UNSIGNED_BYTE, GL_TRUE, stride,
                           offset(offsetof(GpuVertex, color)));
  gl.glEnableVertexAttribArray(kAttributeLayer);
  gl.glVertexAttribPointer(kAttributeLayer, 1, GL_UNSIGNED_SHORT, GL_FALSE, stride,
                           offset(offsetof(GpuVertex, layer)));
  gl.glBindVertexArray(0);
  record.indexCount = static_cast<GLsizei>(indices.size());
}

}  // namespace

Result<MeshHandle> MeshRenderer::uploadMesh(const IndexedMesh& mesh,
                                            const std::vector<std::uint16_t>& textureLayers) {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::uploadMesh");
  THINLOD_RETURN_IF_ERROR(validateUpload(mesh, textureLayers));
  const GlFunctions& gl = context_->gl();
  MeshRecord record;
  gl.glGenVertexArrays(1, &record.vertexArray);
  gl.glGenBuffers(1, &record.vertexBuffer);
  gl.glGenBuffers(1, &record.indexBuffer);
  buildVertices(mesh, textureLayers, impl_->vertexScratch);
  fillBuffers(gl, record, impl_->vertexScratch, mesh.indices);
  record.hasLayers = !textureLayers.empty();
  Status status = checkGlErrors(gl, "MeshRenderer::uploadMesh");
  if (!status.ok()) {
    gl.glDeleteVertexArrays(1, &record.vertexArray);
    gl.glDeleteBuffers(1, &record.vertexBuffer);
    gl.glDeleteBuffers(1, &record.indexBuffer);
    return status;
  }
  const std::uint32_t id = impl_->newId();
  impl_->meshes.emplace(id, record);
  return MeshHandle{id};
}

Result<MeshHandle> MeshRenderer::uploadSkinnedMesh(const IndexedMesh& mesh,
                                                   const std::vector<anim::VertexSkin>& skin) {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::uploadSkinnedMesh");
  THINLOD_RETURN_IF_ERROR(mesh.validate("uploaded skinned mesh"));
  THINLOD_RETURN_IF_ERROR(
      anim::validateSkin(skin, mesh.vertexCount(), 1u << 16, "uploaded skinned mesh"));
  // A rigid vertex fetches its one bone twice: an unused second bone (weight
  // 0) could name a matrix the draw does not have.
  std::vector<float> values;
  values.reserve(skin.size() * 3);
  std::uint32_t bonesNeeded = 0;
  for (const anim::VertexSkin& v : skin) {
    const std::uint32_t boneB = v.rigid() ? v.boneA : v.boneB;
    values.push_back(static_cast<float>(v.boneA));
    values.push_back(static_cast<float>(boneB));
    values.push_back(v.rigid() ? 0.0f : v.weightB);
    bonesNeeded = std::max({bonesNeeded, v.boneA + 1, boneB + 1});
  }
  Result<MeshHandle> handle = uploadMesh(mesh);
  if (!handle.ok()) return handle;
  MeshRecord& record = impl_->meshes.find(handle->id)->second;
  const GlFunctions& gl = context_->gl();
  gl.glGenBuffers(1, &record.skinBuffer);
  gl.glBindVertexArray(record.vertexArray);
  gl.glBindBuffer(GL_ARRAY_BUFFER, record.skinBuffer);
  gl.glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(values.size() * sizeof(float)),
                  values.data(), GL_STATIC_DRAW);
  gl.glEnableVertexAttribArray(kAttributeSkin);
  gl.glVertexAttribPointer(kAttributeSkin, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  gl.glBindVertexArray(0);
  record.bonesNeeded = bonesNeeded;
  Status status = checkGlErrors(gl, "MeshRenderer::uploadSkinnedMesh");
  if (!status.ok()) {
    deleteMesh(*handle);
    return status;
  }
  return handle;
}

std::uint32_t MeshRenderer::bonesNeeded(MeshHandle handle) const {
  auto it = impl_->meshes.find(handle.id);
  return it == impl_->meshes.end() ? 0 : it->second.bonesNeeded;
}

Status MeshRenderer::updateMesh(MeshHandle handle, const IndexedMesh& mesh,
                                const std::vector<std::uint16_t>& textureLayers) {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::updateMesh");
  auto it = impl_->meshes.find(handle.id);
  if (it == impl_->meshes.end()) {
    return Status(ErrorCode::kNotFound, "updateMesh: no mesh " + std::to_string(handle.id));
  }
  if (it->second.bonesNeeded != 0) {
    return Status(ErrorCode::kInvalidArgument,
                  "updateMesh: mesh " + std::to_string(handle.id) + " is skinned");
  }
  THINLOD_RETURN_IF_ERROR(validateUpload(mesh, textureLayers));
  const GlFunctions& gl = context_->gl();
  buildVertices(mesh, textureLayers, impl_->vertexScratch);
  fillBuffers(gl, it->second, impl_->vertexScratch, mesh.indices);
  it->second.hasLayers = !textureLayers.empty();
  return checkGlErrors(gl, "MeshRenderer::updateMesh");
}

void MeshRenderer::deleteMesh(MeshHandle handle) {
  auto it = impl_->meshes.find(handle.id);
  if (it == impl_->meshes.end() || !context_->isCurrent()) return;
  deleteRecord(context_->gl(), it->second);
  impl_->meshes.erase(it);
}

// ---------------------------------------------------------------- textures

Result<TextureHandle> MeshRenderer::createTextureArray(int width, int height, int layers,
                                                       const TextureOptions& options) {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::createTextureArray");
  if (width < 1 || height < 1 || layers < 1 || width > impl_->maxTextureSize ||
      height > impl_->maxTextureSize || layers > impl_->maxTextureLayers ||
      static_cast<long long>(width) * height * layers > (1LL << 28)) {
    return Status(ErrorCode::kInvalidArgument,
                  "texture array " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                      std::to_string(layers) + " out of range (edge 1.." +
                      std::to_string(impl_->maxTextureSize) + ", layers 1.." +
                      std::to_string(impl_->maxTextureLayers) + ", at most 2^28 texels)");
  }
  const GlFunctions& gl = context_->gl();
  TextureRecord record;
  record.width = width;
  record.height = height;
  record.layers = layers;
  record.options = options;
  gl.glGenTextures(1, &record.texture);
  gl.glActiveTexture(GL_TEXTURE0);
  gl.glBindTexture(GL_TEXTURE_2D_ARRAY, record.texture);
  gl.glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA8, width, height, layers, 0, GL_RGBA,
                  GL_UNSIGNED_BYTE, nullptr);
  // GL leaves new storage undefined; the contract promises transparent black.
  impl_->pixelScratch.assign(static_cast<std::size_t>(width) * height * 4, 0);
  gl.glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  for (int layer = 0; layer < layers; ++layer) {
    gl.glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, width, height, 1, GL_RGBA,
                       GL_UNSIGNED_BYTE, impl_->pixelScratch.data());
  }
  const GLint minFilter =
      options.mipmaps ? (options.linearFilter ? GL_LINEAR_MIPMAP_LINEAR : GL_NEAREST_MIPMAP_NEAREST)
                      : (options.linearFilter ? GL_LINEAR : GL_NEAREST);
  gl.glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, minFilter);
  gl.glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER,
                     options.linearFilter ? GL_LINEAR : GL_NEAREST);
  const GLint wrap = options.clampToEdge ? GL_CLAMP_TO_EDGE : GL_REPEAT;
  gl.glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, wrap);
  gl.glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, wrap);
  if (options.mipmaps) gl.glGenerateMipmap(GL_TEXTURE_2D_ARRAY);
  gl.glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
  Status status = checkGlErrors(gl, "MeshRenderer::createTextureArray");
  if (!status.ok()) {
    gl.glDeleteTextures(1, &record.texture);
    return status;
  }
  const std::uint32_t id = impl_->newId();
  impl_->textures.emplace(id, record);
  return TextureHandle{id};
}

Result<TextureHandle> MeshRenderer::uploadTexture(const RgbaImage& image,
                                                  const TextureOptions& options) {
  if (!image.consistent() || image.empty()) {
    return Status(ErrorCode::kInvalidArgument,
                  "uploadTexture: image " + std::to_string(image.width) + "x" +
                      std::to_string(image.height) + " with " +
                      std::to_string(image.pixels.size()) + " bytes is empty or inconsistent");
  }
  auto texture = createTextureArray(image.width, image.height, 1, options);
  if (!texture.ok()) return texture.status();
  Status status = setTextureLayer(*texture, 0, image);
  if (!status.ok()) {
    deleteTexture(*texture);
    return status;
  }
  return texture;
}

Status MeshRenderer::setTextureLayer(TextureHandle handle, int layer, const RgbaImage& image) {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::setTextureLayer");
  auto it = impl_->textures.find(handle.id);
  if (it == impl_->textures.end()) {
    return Status(ErrorCode::kNotFound, "setTextureLayer: no texture " + std::to_string(handle.id));
  }
  const TextureRecord& record = it->second;
  if (layer < 0 || layer >= record.layers) {
    return Status(ErrorCode::kInvalidArgument, "setTextureLayer: layer " + std::to_string(layer) +
                                                   " outside 0.." +
                                                   std::to_string(record.layers - 1));
  }
  if (!image.consistent() || image.empty() || image.width > record.width ||
      image.height > record.height) {
    return Status(ErrorCode::kInvalidArgument,
                  "setTextureLayer: image " + std::to_string(image.width) + "x" +
                      std::to_string(image.height) + " is empty, inconsistent or larger than the " +
                      std::to_string(record.width) + "x" + std::to_string(record.height) +
                      " layer");
  }
  // GL texture row 0 is v = 0 (bottom); RgbaImage row 0 is the top: flip while copying.
  const std::size_t rowBytes = static_cast<std::size_t>(image.width) * 4;
  impl_->pixelScratch.resize(rowBytes * image.height);
  for (int y = 0; y < image.height; ++y) {
    std::memcpy(impl_->pixelScratch.data() + static_cast<std::size_t>(y) * rowBytes,
                image.pixels.data() + static_cast<std::size_t>(image.height - 1 - y) * rowBytes,
                rowBytes);
  }
  const GlFunctions& gl = context_->gl();
  gl.glActiveTexture(GL_TEXTURE0);
  gl.glBindTexture(GL_TEXTURE_2D_ARRAY, record.texture);
  gl.glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl.glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  gl.glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, image.width, image.height, 1, GL_RGBA,
                     GL_UNSIGNED_BYTE, impl_->pixelScratch.data());
  if (record.options.mipmaps) gl.glGenerateMipmap(GL_TEXTURE_2D_ARRAY);
  gl.glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
  return checkGlErrors(gl, "MeshRenderer::setTextureLayer");
}

void MeshRenderer::deleteTexture(TextureHandle handle) {
  auto it = impl_->textures.find(handle.id);
  if (it == impl_->textures.end() || !context_->isCurrent()) return;
  context_->gl().glDeleteTextures(1, &it->second.texture);
  impl_->textures.erase(it);
}

// ---------------------------------------------------------------- drawing

Status MeshRenderer::beginFrame(RenderTarget& target, const glm::vec4& clearColor) {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::beginFrame");
  if (&target.context() != context_) {
    return Status(ErrorCode::kInvalidArgument,
                  "beginFrame: the render target belongs to another context");
  }
  if (!allFinite(clearColor)) {
    return Status(ErrorCode::kInvalidArgument, "beginFrame: clear colour is not finite");
  }
  stats_ = RenderStats();
  impl_->target = &target;
  return target.clear(clearColor.r, clearColor.g, clearColor.b, clearColor.a);
}

Status MeshRenderer::draw(const DrawItem* items, std::size_t count, const Camera& camera,
                          const Lighting& lighting) {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::draw");
  if (impl_->target == nullptr) {
    return Status(ErrorCode::kInvalidArgument, "draw: call beginFrame first");
  }
  if (count > 0 && items == nullptr) {
    return Status(ErrorCode::kInvalidArgument, "draw: null item array");
  }
  if (!allFinite(camera.view) || !allFinite(camera.projection)) {
    return Status(ErrorCode::kInvalidArgument, "draw: camera matrices are not finite");
  }
  THINLOD_RETURN_IF_ERROR(validateLighting(lighting, "draw"));
  // Validate every item before drawing any, so a bad list draws nothing.
  for (std::size_t i = 0; i < count; ++i) {
    const DrawItem& item = items[i];
    const std::string name = "draw: item " + std::to_string(i);
    auto mesh = impl_->meshes.find(item.mesh.id);
    if (mesh == impl_->meshes.end()) {
      return Status(ErrorCode::kNotFound, name + ": no mesh " + std::to_string(item.mesh.id));
    }
    const Material& m = item.material;
    if (!allFinite(item.model) || !allFinite(m.diffuse) || !allFinite(m.specular) ||
        !std::isfinite(m.shininess) || !std::isfinite(m.alphaCutoff)) {
      return Status(ErrorCode::kInvalidArgument, name + ": non-finite model matrix or material");
    }
    const std::uint32_t needed = mesh->second.bonesNeeded;
    if ((needed != 0) != (item.bones != nullptr)) {
      return Status(ErrorCode::kInvalidArgument,
                    name + (needed != 0 ? ": a skinned mesh needs bones"
                                        : ": bones given for a mesh that is not skinned"));
    }
    if (item.bones != nullptr) {
      if (item.bones->size() < needed ||
          item.bones->size() * 4 > static_cast<std::size_t>(impl_->maxTextureBufferTexels)) {
        return Status(ErrorCode::kInvalidArgument,
                      name + ": " + std::to_string(item.bones->size()) +
                          " bone matrices, the skin needs " + std::to_string(needed) +
                          " (at most " + std::to_string(impl_->maxTextureBufferTexels / 4) + ")");
      }
      for (const glm::mat4& bone : *item.bones) {
        if (!allFinite(bone))
          return Status(ErrorCode::kInvalidArgument, name + ": a bone matrix is not finite");
      }
    }
    if (m.texture.valid()) {
      auto texture = impl_->textures.find(m.texture.id);
      if (texture == impl_->textures.end()) {
        return Status(ErrorCode::kNotFound, name + ": no texture " + std::to_string(m.texture.id));
      }
      if (!mesh->second.hasLayers &&
          (m.textureLayer < 0 || m.textureLayer >= texture->second.layers)) {
        return Status(ErrorCode::kInvalidArgument,
                      name + ": texture layer " + std::to_string(m.textureLayer) + " outside 0.." +
                          std::to_string(texture->second.layers - 1));
      }
    }
  }

  const GlFunctions& gl = context_->gl();
  // Every variant the list needs exists before anything is drawn.
  bool anySkinned = false;
  for (std::size_t i = 0; i < count; ++i) {
    const bool hasLayers = impl_->meshes.find(items[i].mesh.id)->second.hasLayers;
    const bool skinned = items[i].bones != nullptr;
    anySkinned = anySkinned || skinned;
    THINLOD_RETURN_IF_ERROR(
        impl_->ensureProgram(gl, variantOf(items[i].material, hasLayers, lighting, skinned)));
  }
  if (anySkinned && impl_->boneTexture == 0) {
    gl.glGenBuffers(1, &impl_->boneBuffer);
    gl.glGenTextures(1, &impl_->boneTexture);
    gl.glActiveTexture(GL_TEXTURE0 + kBoneTextureUnit);
    gl.glBindBuffer(GL_TEXTURE_BUFFER, impl_->boneBuffer);
    gl.glBindTexture(GL_TEXTURE_BUFFER, impl_->boneTexture);
    gl.glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, impl_->boneBuffer);
    gl.glBindTexture(GL_TEXTURE_BUFFER, 0);
    gl.glBindBuffer(GL_TEXTURE_BUFFER, 0);
    gl.glActiveTexture(GL_TEXTURE0);
    THINLOD_RETURN_IF_ERROR(checkGlErrors(gl, "MeshRenderer::draw: bone buffer texture"));
  }
  THINLOD_RETURN_IF_ERROR(impl_->target->bind());
  const glm::mat4 viewProjection = kMirrorClipY * camera.projection * camera.view;
  const glm::vec3 eye = glm::vec3(glm::inverse(camera.view)[3]);
  float lightVectors[kMaxLights * 3] = {0};
  float lightColors[kMaxLights * 3] = {0};
  float lightAttenuations[kMaxLights] = {0};
  const int lightCount = static_cast<int>(lighting.lights.size());
  for (int i = 0; i < lightCount; ++i) {
    const Light& light = lighting.lights[i];
    for (int c = 0; c < 3; ++c) {
      lightVectors[i * 3 + c] = light.vector[c];
      lightColors[i * 3 + c] = light.color[c];
    }
    lightAttenuations[i] = light.attenuation;
  }
  for (auto& [key, program] : impl_->programs) program.frameUniformsSet = false;
  // Switches to the item's variant; camera and lights go to each variant once per draw().
  const Program* current = nullptr;
  auto useProgram = [&](const Material& m, bool hasLayers, bool skinned) -> const Program& {
    Program& program = impl_->programs.find(variantOf(m, hasLayers, lighting, skinned))->second;
    if (&program == current) return program;
    current = &program;
    gl.glUseProgram(program.id);
    if (program.frameUniformsSet) return program;
    program.frameUniformsSet = true;
    const auto& u = program.uniform;
    gl.glUniformMatrix4fv(u.viewProjection, 1, GL_FALSE, glm::value_ptr(viewProjection));
    if (!m.lit) return program;
    gl.glUniform3fv(u.eyePosition, 1, glm::value_ptr(eye));
    gl.glUniform3fv(u.ambient, 1, glm::value_ptr(lighting.ambient));
    gl.glUniform3fv(u.lightVector, kMaxLights, lightVectors);
    gl.glUniform3fv(u.lightColor, kMaxLights, lightColors);
    gl.glUniform1fv(u.lightAttenuation, kMaxLights, lightAttenuations);
    return program;
  };

  gl.glEnable(GL_DEPTH_TEST);
  gl.glDepthFunc(GL_LEQUAL);
  gl.glFrontFace(GL_CW);  // CCW triangles of the picture, mirrored by kMirrorClipY
  gl.glCullFace(GL_BACK);
  gl.glActiveTexture(GL_TEXTURE0);
  GLuint boundTexture = 0;
  gl.glBindTexture(GL_TEXTURE_2D_ARRAY, 0);

  // Pass 0: opaque and masked items, depth writes on. Pass 1: blended items,
  // depth test on but no depth writes so later blended items still show.
  for (int pass = 0; pass < 2; ++pass) {
    const bool blendPass = pass == 1;
    if (blendPass) {
      gl.glEnable(GL_BLEND);
      gl.glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
      gl.glDepthMask(GL_FALSE);
    } else {
      gl.glDisable(GL_BLEND);
      gl.glDepthMask(GL_TRUE);
    }
    for (std::size_t i = 0; i < count; ++i) {
      const DrawItem& item = items[i];
      const Material& m = item.material;
      if ((m.alphaMode == AlphaMode::kBlend) != blendPass) continue;
      const MeshRecord& mesh = impl_->meshes.find(item.mesh.id)->second;
      if (mesh.indexCount == 0) continue;
      if (m.doubleSided) {
        gl.glDisable(GL_CULL_FACE);
      } else {
        gl.glEnable(GL_CULL_FACE);
      }
      const auto& u = useProgram(m, mesh.hasLayers, item.bones != nullptr).uniform;
      if (item.bones != nullptr) {
        // The buffer is refilled per item; GL orders it after earlier draws' reads.
        gl.glBindBuffer(GL_TEXTURE_BUFFER, impl_->boneBuffer);
        gl.glBufferData(GL_TEXTURE_BUFFER,
                        static_cast<GLsizeiptr>(item.bones->size() * sizeof(glm::mat4)),
                        item.bones->data(), GL_STREAM_DRAW);
        gl.glBindBuffer(GL_TEXTURE_BUFFER, 0);
        gl.glActiveTexture(GL_TEXTURE0 + kBoneTextureUnit);
        gl.glBindTexture(GL_TEXTURE_BUFFER, impl_->boneTexture);
        gl.glActiveTexture(GL_TEXTURE0);
      }
      gl.glUniformMatrix4fv(u.model, 1, GL_FALSE, glm::value_ptr(item.model));
      gl.glUniform4fv(u.diffuse, 1, glm::value_ptr(m.diffuse));
      if (m.lit) {
        const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(item.model)));
        gl.glUniformMatrix3fv(u.normalMatrix, 1, GL_FALSE, glm::value_ptr(normalMatrix));
        if (hasSpecular(m)) {
          gl.glUniform3fv(u.specular, 1, glm::value_ptr(m.specular));
          gl.glUniform1f(u.shininess, m.shininess);
        }
      }
      if (m.alphaMode == AlphaMode::kMask) gl.glUniform1f(u.alphaCutoff, m.alphaCutoff);
      if (m.texture.valid()) {
        const GLuint texture = impl_->textures.find(m.texture.id)->second.texture;
        if (texture != boundTexture) {
          gl.glBindTexture(GL_TEXTURE_2D_ARRAY, texture);
          boundTexture = texture;
          ++stats_.textureBinds;
        }
        if (!mesh.hasLayers) gl.glUniform1f(u.layer, static_cast<float>(m.textureLayer));
      }
      gl.glBindVertexArray(mesh.vertexArray);
      gl.glDrawElements(GL_TRIANGLES, mesh.indexCount, GL_UNSIGNED_INT, nullptr);
      ++stats_.drawCalls;
      stats_.triangles += static_cast<std::size_t>(mesh.indexCount) / 3;
    }
  }
  gl.glBindVertexArray(0);
  if (anySkinned) {
    gl.glActiveTexture(GL_TEXTURE0 + kBoneTextureUnit);
    gl.glBindTexture(GL_TEXTURE_BUFFER, 0);
    gl.glActiveTexture(GL_TEXTURE0);
  }
  gl.glDisable(GL_BLEND);
  gl.glDepthMask(GL_TRUE);
  gl.glFrontFace(GL_CCW);  // GL's default, for any other code in this context
  gl.glUseProgram(0);
  return checkGlErrors(gl, "MeshRenderer::draw");
}

Status MeshRenderer::prepare(const Material& material, bool meshHasLayers, const Lighting& lighting,
                             bool skinned) {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::prepare");
  THINLOD_RETURN_IF_ERROR(validateLighting(lighting, "prepare"));
  return impl_->ensureProgram(context_->gl(),
                              variantOf(material, meshHasLayers, lighting, skinned));
}

Status MeshRenderer::finish() {
  if (!context_->isCurrent()) return notCurrent("MeshRenderer::finish");
  context_->gl().glFinish();
  return checkGlErrors(context_->gl(), "glFinish");
}

}  // namespace thinlod::render
