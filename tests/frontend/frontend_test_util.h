// Helpers for the frontend tests: simple meshes and images, an ortho camera,
// pixel checks with explicit tolerances, and a context fixture per back-end.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <string>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/frontend/frontend_scene.h"

namespace thinlod::frontend::testing {

// Axis-aligned quad in the plane z, counter-clockwise seen from +z, normal +z,
// uv (0,0) at (x0,y0) and (1,1) at (x1,y1).
inline std::shared_ptr<const IndexedMesh> quadMesh(float x0, float y0, float x1, float y1,
                                                   float z) {
  auto m = std::make_shared<IndexedMesh>();
  m->positions = {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}};
  m->normals.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
  m->uvs = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {0.0f, 1.0f}};
  m->indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// UV sphere of radius r at the origin with outward normals and uvs.
inline std::shared_ptr<const IndexedMesh> sphereMesh(float r, int slices, int stacks) {
  auto m = std::make_shared<IndexedMesh>();
  const float pi = 3.14159265358979f;
  for (int j = 0; j <= stacks; ++j) {
    const float v = static_cast<float>(j) / stacks;
    const float phi = v * pi;
    for (int i = 0; i <= slices; ++i) {
      const float u = static_cast<float>(i) / slices;
      const float theta = u * 2.0f * pi;
      const glm::vec3 n(std::sin(phi) * std::cos(theta), std::cos(phi),
                        std::sin(phi) * std::sin(theta));
      m->positions.push_back(n * r);
      m->normals.push_back(n);
      m->uvs.push_back(glm::vec2(u, 1.0f - v));
    }
  }
  const auto row = static_cast<std::uint32_t>(slices + 1);
  for (int j = 0; j < stacks; ++j) {
    for (int i = 0; i < slices; ++i) {
      const std::uint32_t a = j * row + i, b = a + 1, c = a + row, d = c + 1;
      if (j != 0) m->indices.insert(m->indices.end(), {a, b, c});
      if (j != stacks - 1) m->indices.insert(m->indices.end(), {b, d, c});
    }
  }
  return m;
}

inline std::shared_ptr<const RgbaImage> solidImage(int w, int h, std::uint8_t r, std::uint8_t g,
                                                   std::uint8_t b, std::uint8_t a = 255) {
  auto image = std::make_shared<RgbaImage>(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::uint8_t* p = image->at(x, y);
      p[0] = r;
      p[1] = g;
      p[2] = b;
      p[3] = a;
    }
  }
  return image;
}

// Looks down -z from z = 5 at the square [-1,1]^2; world x,y map linearly to pixels.
inline render::Camera orthoCamera() {
  render::Camera camera;
  camera.view = glm::lookAt(glm::vec3(0.0f, 0.0f, 5.0f), glm::vec3(0.0f), glm::vec3(0, 1, 0));
  camera.projection = glm::ortho(-1.0f, 1.0f, -1.0f, 1.0f, 1.0f, 9.0f);
  return camera;
}

// Lighting that leaves a lit surface at exactly its base colour.
inline render::Lighting flatLighting() {
  render::Lighting lighting;
  lighting.ambient = glm::vec3(1.0f);
  return lighting;
}

inline ::testing::AssertionResult pixelNear(const RgbaImage& image, int x, int y, int r, int g,
                                            int b, int tolerance) {
  const std::uint8_t* p = image.at(x, y);
  const int expected[3] = {r, g, b};
  for (int c = 0; c < 3; ++c) {
    if (std::abs(static_cast<int>(p[c]) - expected[c]) > tolerance) {
      return ::testing::AssertionFailure()
             << "pixel (" << x << "," << y << ") = (" << int(p[0]) << "," << int(p[1]) << ","
             << int(p[2]) << "), expected (" << r << "," << g << "," << b << ") +-" << tolerance;
    }
  }
  return ::testing::AssertionSuccess();
}

inline SceneOperation addOp(ObjectId id, RepresentationKind kind,
                            std::shared_ptr<const IndexedMesh> mesh,
                            std::shared_ptr<const RgbaImage> texture,
                            const glm::mat4& transform = glm::mat4(1.0f),
                            const glm::vec4& color = glm::vec4(1.0f)) {
  SceneOperation op;
  op.type = SceneOperation::Type::kAddOrReplace;
  op.id = id;
  op.representation.kind = kind;
  op.representation.mesh = std::move(mesh);
  op.representation.texture = std::move(texture);
  op.representation.transform = transform;
  op.representation.color = color;
  return op;
}

inline SceneOperation removeOp(ObjectId id) {
  SceneOperation op;
  op.type = SceneOperation::Type::kRemove;
  op.id = id;
  return op;
}

inline std::string backendParamName(const ::testing::TestParamInfo<render::Backend>& info) {
  return render::backendName(info.param);
}

}  // namespace thinlod::frontend::testing
