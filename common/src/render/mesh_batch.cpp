#include "thinlod/common/render/mesh_batch.h"

#include <cmath>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <limits>

namespace thinlod::render {

void MeshBatch::clear() {
  mesh_ = IndexedMesh();
  layers_.clear();
  parts_ = 0;
}

void MeshBatch::reserve(std::size_t vertices, std::size_t indices) {
  mesh_.positions.reserve(vertices);
  mesh_.normals.reserve(vertices);
  mesh_.uvs.reserve(vertices);
  mesh_.colors.reserve(vertices);
  layers_.reserve(vertices);
  mesh_.indices.reserve(indices);
}

Status MeshBatch::append(const IndexedMesh& mesh, const Part& part, const std::string& what) {
  THINLOD_RETURN_IF_ERROR(mesh.validate(what));
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (!std::isfinite(part.model[c][r])) {
        return Status(ErrorCode::kInvalidArgument, what + ": model matrix is not finite");
      }
    }
  }
  const glm::mat3 linear(part.model);
  const float det = glm::determinant(linear);
  if (!std::isfinite(det) || std::fabs(det) < 1e-20f) {
    return Status(ErrorCode::kInvalidArgument, what + ": model matrix is singular");
  }
  if (part.textureLayer < 0 || part.textureLayer > 65535) {
    return Status(
        ErrorCode::kInvalidArgument,
        what + ": texture layer " + std::to_string(part.textureLayer) + " outside 0..65535");
  }
  if (!std::isfinite(part.uvScale.x) || !std::isfinite(part.uvScale.y) ||
      !std::isfinite(part.uvOffset.x) || !std::isfinite(part.uvOffset.y)) {
    return Status(ErrorCode::kInvalidArgument, what + ": uv transform is not finite");
  }
  const std::size_t base = mesh_.positions.size();
  if (base + mesh.vertexCount() > std::numeric_limits<std::uint32_t>::max()) {
    return Status(ErrorCode::kResourceExhausted, what + ": batch exceeds 2^32 vertices");
  }

  const glm::mat3 normalMatrix = glm::transpose(glm::inverse(linear));
  const bool hasNormals = !mesh.normals.empty();
  IndexedMesh computed;
  if (!hasNormals) {  // flat-ish normals from the mesh itself, before transforming
    computed.positions = mesh.positions;
    computed.indices = mesh.indices;
    computed.computeNormals();
  }
  const std::vector<glm::vec3>& normals = hasNormals ? mesh.normals : computed.normals;
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
    mesh_.positions.push_back(glm::vec3(part.model * glm::vec4(mesh.positions[v], 1.0f)));
    glm::vec3 n = normalMatrix * normals[v];
    const float length = glm::length(n);
    mesh_.normals.push_back(length > 0.0f ? n / length : glm::vec3(0.0f, 0.0f, 1.0f));
    const glm::vec2 uv = mesh.uvs.empty() ? glm::vec2(0.0f) : mesh.uvs[v];
    mesh_.uvs.push_back(uv * part.uvScale + part.uvOffset);
    std::array<std::uint8_t, 4> color = part.color;
    if (!mesh.colors.empty()) {
      for (int c = 0; c < 4; ++c) {
        color[c] = static_cast<std::uint8_t>((mesh.colors[v][c] * part.color[c] + 127) / 255);
      }
    }
    mesh_.colors.push_back(color);
    layers_.push_back(static_cast<std::uint16_t>(part.textureLayer));
  }
  for (std::uint32_t index : mesh.indices) {
    mesh_.indices.push_back(static_cast<std::uint32_t>(base) + index);
  }
  ++parts_;
  return Status();
}

}  // namespace thinlod::render
