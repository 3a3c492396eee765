// Helpers for the frontend daemon tests: small meshes and textures encoded
// the way the backbone sends them, and wire representations around them.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <glm/gtc/matrix_transform.hpp>
#include <vector>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/protocol/messages.h"

namespace thinlod::frontend::daemon::testing {

// UV sphere of radius r at the origin with normals and uvs.
inline IndexedMesh sphereMesh(float r, int slices, int stacks) {
  IndexedMesh m;
  const float pi = 3.14159265358979f;
  for (int j = 0; j <= stacks; ++j) {
    const float v = static_cast<float>(j) / stacks;
    for (int i = 0; i <= slices; ++i) {
      const float u = static_cast<float>(i) / slices;
      const glm::vec3 n(std::sin(v * pi) * std::cos(u * 2 * pi), std::cos(v * pi),
                        std::sin(v * pi) * std::sin(u * 2 * pi));
      m.positions.push_back(n * r);
      m.normals.push_back(n);
      m.uvs.push_back(glm::vec2(u, 1.0f - v));
    }
  }
  const auto row = static_cast<std::uint32_t>(slices + 1);
  for (int j = 0; j < stacks; ++j) {
    for (int i = 0; i < slices; ++i) {
      const std::uint32_t a = j * row + i, b = a + 1, c = a + row, d = c + 1;
      if (j != 0) m.indices.insert(m.indices.end(), {a, b, c});
      if (j != stacks - 1) m.indices.insert(m.indices.end(), {b, d, c});
    }
  }
  return m;
}

// A quad with uvs (what an impostor's geometry looks like).
inline IndexedMesh quadMesh() {
  IndexedMesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

inline std::vector<std::uint8_t> encodeOrDie(const IndexedMesh& mesh) {
  auto bytes = codec::encodeMesh(mesh);
  EXPECT_TRUE(bytes.ok()) << bytes.status().toString();
  return bytes.ok() ? std::move(bytes).value() : std::vector<std::uint8_t>{};
}

inline RgbaImage gradientTexture(int w, int h) {
  RgbaImage t(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::uint8_t* p = t.at(x, y);
      p[0] = static_cast<std::uint8_t>(x * 255 / (w > 1 ? w - 1 : 1));
      p[1] = static_cast<std::uint8_t>(y * 255 / (h > 1 ? h - 1 : 1));
      p[2] = 40;
      p[3] = 255;
    }
  }
  return t;
}

inline protocol::Texture wireTexture(const RgbaImage& texture, protocol::TextureCodec codec) {
  protocol::Texture wire;
  wire.codec = codec;
  wire.width = static_cast<std::uint32_t>(texture.width);
  wire.height = static_cast<std::uint32_t>(texture.height);
  if (codec == protocol::TextureCodec::kRawRgba8) {
    wire.data = texture.pixels;
    return wire;
  }
  auto bytes = codec::encodeTextureWith(texture, codec);
  EXPECT_TRUE(bytes.ok()) << bytes.status().toString();
  if (bytes.ok()) wire.data = std::move(bytes).value();
  return wire;
}

inline protocol::Representation meshRepresentation(const IndexedMesh& mesh,
                                                   const glm::mat4& transform = glm::mat4(1.0f)) {
  protocol::Representation rep;
  rep.kind = protocol::RepresentationKind::kMesh;
  rep.mesh = encodeOrDie(mesh);
  rep.triangleCount = static_cast<std::uint32_t>(mesh.triangleCount());
  rep.transform = transform;
  rep.accuracy = 10.0;
  return rep;
}

inline protocol::Representation impostorRepresentation(protocol::TextureCodec codec,
                                                       int size = 32) {
  protocol::Representation rep;
  rep.kind = protocol::RepresentationKind::kMeshedImpostor;
  const IndexedMesh quad = quadMesh();
  rep.mesh = encodeOrDie(quad);
  rep.triangleCount = 2;
  rep.texture = wireTexture(gradientTexture(size, size), codec);
  rep.generation = 3;
  return rep;
}

inline protocol::SceneOperation addOp(std::uint64_t id, protocol::Representation rep) {
  protocol::SceneOperation op;
  op.type = protocol::SceneOperation::Type::kAddOrReplace;
  op.objectId = id;
  op.representation = std::move(rep);
  return op;
}

}  // namespace thinlod::frontend::daemon::testing
