// DiscRenderer: draws DiscPoints (the points of hybrid triangle + point
// representations, docs/hybrid.md) as screen-aligned, depth-tested, opaque
// discs: one instanced quad per point (GL 3.3 core: glDrawArraysInstanced
// with a per-instance centre, radius and colour), the fragments outside the
// disc discarded. Instanced quads rather than GL point sprites: a sprite's
// size is capped by GL_POINT_SIZE_RANGE (implementation-defined) and
// clipped by its centre; quads behave the same on llvmpipe and a GPU.
//
// Contract:
// - Needs the context of `create` current on the calling thread (as
//   MeshRenderer); destroy the renderer before the context.
// - draw() renders into the framebuffer and viewport that are bound (call it
//   after MeshRenderer::beginFrame / draw of the same frame, so discs and
//   triangles share the depth buffer). A disc of world radius r around c is
//   the view-facing square of half-side r at c's eye-space depth, clipped to
//   its inscribed circle; radii are scaled by the model matrix's largest
//   axis scale and never drawn below kMinDiscRadiusPixels (so a far disc
//   still covers its pixel: no holes).
// - Colours are drawn as they are: pre-light them (preLightDiscs) with the
//   lighting the triangles get.
// - Errors: invalid points (DiscPoints::validate) and non-finite matrices are
//   kInvalidArgument, unknown handles kNotFound, GL errors kInternal /
//   kResourceExhausted.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>
#include <memory>

#include "thinlod/common/core/disc_points.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/offscreen_context.h"

namespace thinlod::render {

inline constexpr float kMinDiscRadiusPixels = 0.75f;

struct DiscHandle {
  std::uint32_t id = 0;
  bool valid() const { return id != 0; }
};

struct DiscDrawItem {
  DiscHandle discs;
  glm::mat4 model{1.0f};  // object -> world
};

struct DiscStats {
  std::size_t drawCalls = 0;
  std::size_t discs = 0;
};

// kInstancedQuads: 4 vertices per disc, any size. kPointSprites: 1 vertex
// per disc (GL_POINTS, gl_PointSize); a disc is capped at the implementation's
// largest point size and vanishes when its centre leaves the view volume.
enum class DiscStyle : std::uint8_t { kInstancedQuads, kPointSprites };

class DiscRenderer {
 public:
  static Result<std::unique_ptr<DiscRenderer>> create(OffscreenContext& context,
                                                      DiscStyle style = DiscStyle::kInstancedQuads);
  ~DiscRenderer();
  DiscRenderer(const DiscRenderer&) = delete;
  DiscRenderer& operator=(const DiscRenderer&) = delete;

  Result<DiscHandle> upload(const DiscPoints& points);
  Status update(DiscHandle handle, const DiscPoints& points);  // replaces the contents
  void remove(DiscHandle handle);

  Status draw(const DiscDrawItem* items, std::size_t count, const Camera& camera);
  // Adds to stats() (reset with resetStats, e.g. at the frame start).
  const DiscStats& stats() const { return stats_; }
  void resetStats() { stats_ = DiscStats(); }

 private:
  struct Impl;
  explicit DiscRenderer(OffscreenContext& context);
  OffscreenContext* context_;
  std::unique_ptr<Impl> impl_;
  DiscStats stats_;
};

// CPU copy of MeshRenderer's Lambert lighting (no specular): each colour
// becomes diffuse * colour * (ambient + sum of lights . max(n . l, 0)) with
// n the point's normal through `model` (world space), evaluated at the
// point's world centre; alpha = diffuse.a * colour.a. Points without normals
// get ambient + the lights' full colour. Precondition: points.validate() ok.
DiscPoints preLightDiscs(const DiscPoints& points, const glm::mat4& model, const glm::vec4& diffuse,
                         const Lighting& lighting);

// Appends `points` to `out` in world space (centres through `model`, radii
// times its largest axis scale; normals through the inverse transpose when
// both have normals, else `out` keeps none). For drawing many objects' discs
// in one call, as MeshBatch does for triangles.
void appendWorldDiscs(DiscPoints& out, const DiscPoints& points, const glm::mat4& model);

}  // namespace thinlod::render
