// Shared helpers for GL tests: a context+target+renderer fixture per back-end,
// simple meshes, and pixel checks with explicit tolerances.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <string>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/common/render/render_target.h"

namespace thinlod::render::testing {

// Axis-aligned quad in the plane z, counter-clockwise seen from +z, normal +z,
// uv (0,0) at (x0,y0) and (1,1) at (x1,y1).
inline IndexedMesh makeQuad(float x0, float y0, float x1, float y1, float z) {
  IndexedMesh m;
  m.positions = {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}};
  m.normals.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
  m.uvs = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {0.0f, 1.0f}};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

// Looks down -z from z = 5 at the square [-1,1]^2; world x,y map linearly to pixels.
inline Camera orthoCamera() {
  Camera camera;
  camera.view = glm::lookAt(glm::vec3(0.0f, 0.0f, 5.0f), glm::vec3(0.0f), glm::vec3(0, 1, 0));
  camera.projection = glm::ortho(-1.0f, 1.0f, -1.0f, 1.0f, 1.0f, 9.0f);
  return camera;
}

inline Material unlitColor(float r, float g, float b, float a = 1.0f) {
  Material m;
  m.lit = false;
  m.diffuse = glm::vec4(r, g, b, a);
  return m;
}

// |pixel - expected| <= tolerance in every channel.
inline ::testing::AssertionResult pixelNear(const RgbaImage& image, int x, int y, int r, int g,
                                            int b, int a, int tolerance) {
  const std::uint8_t* p = image.at(x, y);
  const int expected[4] = {r, g, b, a};
  for (int c = 0; c < 4; ++c) {
    if (std::abs(static_cast<int>(p[c]) - expected[c]) > tolerance) {
      return ::testing::AssertionFailure()
             << "pixel (" << x << "," << y << ") = (" << int(p[0]) << "," << int(p[1]) << ","
             << int(p[2]) << "," << int(p[3]) << "), expected (" << r << "," << g << "," << b << ","
             << a << ") +-" << tolerance;
    }
  }
  return ::testing::AssertionSuccess();
}

struct GlRig {
  std::unique_ptr<OffscreenContext> context;
  std::unique_ptr<RenderTarget> target;
  std::unique_ptr<MeshRenderer> renderer;

  ~GlRig() {
    // GL objects go before their context, with the context current.
    if (context) (void)context->makeCurrent();
    renderer.reset();
    target.reset();
    context.reset();
  }
};

inline ::testing::AssertionResult makeRig(Backend backend, int width, int height, GlRig& rig) {
  auto context = createOffscreenContext(backend, width, height);
  if (!context.ok()) {
    return ::testing::AssertionFailure()
           << backendName(backend) << ": " << context.status().toString();
  }
  rig.context = std::move(context).value();
  auto target = RenderTarget::create(*rig.context, width, height);
  if (!target.ok()) return ::testing::AssertionFailure() << target.status().toString();
  rig.target = std::move(target).value();
  auto renderer = MeshRenderer::create(*rig.context);
  if (!renderer.ok()) return ::testing::AssertionFailure() << renderer.status().toString();
  rig.renderer = std::move(renderer).value();
  return ::testing::AssertionSuccess();
}

inline std::string backendParamName(const ::testing::TestParamInfo<Backend>& info) {
  return backendName(info.param);
}

}  // namespace thinlod::render::testing
