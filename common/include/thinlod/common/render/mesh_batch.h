// MeshBatch: merges many small meshes (e.g. the frontend's ~350 textured
// polygons of impostors and simplified objects) into one world-space mesh
// with a per-vertex texture layer, so MeshRenderer draws them in ONE call
// with one array-texture bind (each extra call + bind costs ~30 us on llvmpipe).
//
// Contract:
// - append() transforms positions by `model` and normals by its inverse
//   transpose, maps uvs as uv * uvScale + uvOffset (to address a smaller image
//   inside an array layer), multiplies per-vertex colours by `color`, and tags
//   every vertex with `textureLayer` (0..65535).
// - append() validates the mesh (kInvalidArgument naming it) and appends
//   nothing on error; a non-finite or singular model matrix is kInvalidArgument.
// - The merged mesh always has normals, uvs and colours. Pure CPU, no GL:
//   any thread, no shared state.
#pragma once

#include <array>
#include <cstdint>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <string>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod::render {

class MeshBatch {
 public:
  struct Part {
    glm::mat4 model{1.0f};
    std::array<std::uint8_t, 4> color{255, 255, 255, 255};
    int textureLayer = 0;
    glm::vec2 uvScale{1.0f};
    glm::vec2 uvOffset{0.0f};
  };

  void clear();
  void reserve(std::size_t vertices, std::size_t indices);
  // `what` names the part in errors ("impostor 12").
  Status append(const IndexedMesh& mesh, const Part& part, const std::string& what);

  const IndexedMesh& mesh() const { return mesh_; }
  const std::vector<std::uint16_t>& textureLayers() const { return layers_; }
  std::size_t partCount() const { return parts_; }

 private:
  IndexedMesh mesh_;
  std::vector<std::uint16_t> layers_;
  std::size_t parts_ = 0;
};

}  // namespace thinlod::render
