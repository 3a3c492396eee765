// FrontendRenderer: draws what a FrontendScene holds, every frame, into an
// offscreen RGBA frame (Pasman & Jansen 2002, section 4: ~350 textured polygons).
//
// Contract:
// - create()/every call needs `context` current on the calling thread; the
//   renderer keeps a pointer to it (it must outlive the renderer; destroy the
//   renderer with the context current). Nothing here is thread-safe.
// - submit() queues an update batch (validated by FrontendScene::enqueue).
//   renderFrame() then, in order: uploads queued representations within
//   `uploadBytesPerFrame` (textures into layers of shared array textures,
//   geometry baked to world space), applies every fully uploaded batch at
//   once (older representations stay drawn until then), draws, and reads the
//   frame back (RGBA8, rows top-down, `width` x `height`).
// - Batching: all textures live in layers of a few array textures ("pages");
//   geometry is merged per (page, lit/unlit), so a frame costs about two draw
//   calls per page used; a skinned mesh (Representation::skin) is drawn on
//   its own with its bone pose at the frame's pose time `poseTimeS`
//   (FrontendScene::bonePoseAt: the newest pose, extrapolated from the two
//   newest when the frame is later than it; NaN: the newest as is), the
//   vertex shader deforming only its level's vertices. Meshes are lit (with `lighting`); impostors
//   are unlit (their lighting is baked in) and alpha-tested (or blended, unsorted). Only changed
//   objects are re-uploaded; merged vertex buffers are rebuilt on frames where the set of drawn
//   objects changes.
// - Textures larger than `layerSize` are shrunk to fit (box filter); smaller
//   ones occupy a corner of a layer. uvs outside [0,1] clamp.
// - Errors: bad camera/lighting is kInvalidArgument (nothing drawn); a batch
//   whose upload fails is dropped whole (FrameReport::droppedBatches,
//   lastUploadError) and rendering continues; GL failures while drawing are
//   kInternal / kResourceExhausted.
// - warmUp(lighting) draws one small triangle with each kind of batch under
//   `lighting` (the frame is cleared by the next renderFrame), so shader
//   compilation, including the driver's first-draw compile, happens before
//   the first frame that must meet a deadline. Optional; renderFrame works
//   without it and prepares the programs itself.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <limits>
#include <memory>
#include <string>

#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/disc_renderer.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/frontend/frontend_scene.h"

namespace thinlod::frontend {

struct FrontendRendererOptions {
  int width = 640;
  int height = 480;
  // Two 256x256 impostors (2 x 262,328 bytes with their quads) per frame.
  std::size_t uploadBytesPerFrame = 600 * 1024;
  int layerSize = 256;      // edge of one texture layer, pixels
  int layersPerPage = 128;  // layers per array texture; more pages are made on demand
  glm::vec4 clearColor{0.0f, 0.0f, 0.0f, 1.0f};
  render::AlphaMode impostorAlpha = render::AlphaMode::kMask;  // kMask or kBlend
  float alphaCutoff = 0.5f;
  bool linearFilter = true;
  glm::vec3 meshSpecular{0.0f};  // one Blinn-Phong term for all meshes (they share a draw)
  float meshShininess = 32.0f;
  SceneLimits limits;
  // How hybrid points are drawn (docs/hybrid.md, "Measured kappa": sprites
  // are the faster on llvmpipe).
  render::DiscStyle discStyle = render::DiscStyle::kPointSprites;
};

struct FrameTiming {
  double uploadMs = 0.0;  // texture layers + world-space geometry of new representations
  double commitMs = 0.0;  // applying batches and rebuilding merged vertex buffers
  double drawMs = 0.0;    // draw calls up to and including the readback (llvmpipe is lazy)
  double totalMs = 0.0;
};

struct FrameReport {
  FrameTiming timing;
  std::size_t drawCalls = 0;
  std::size_t textureBinds = 0;
  std::size_t triangles = 0;      // drawn this frame
  std::size_t discs = 0;          // hybrid disc points drawn this frame
  std::size_t uploadedBytes = 0;  // representation bytes uploaded this frame
  std::size_t uploadedObjects = 0;
  std::size_t geometryBytesRebuilt = 0;  // merged vertex/index bytes re-sent this frame
  std::size_t committedBatches = 0;
  std::size_t pendingBatches = 0;           // still queued after this frame
  std::size_t droppedBatches = 0;           // dropped this frame because an upload failed
  std::vector<std::uint64_t> droppedPlans;  // their plans (told to the backbone)
  std::string lastUploadError;              // why, when droppedBatches > 0
  std::size_t texturePages = 0;
  std::uint64_t appliedPlan = 0;  // FrontendScene::lastAppliedPlan()
  std::size_t earlyPolygons = 0;  // FrontendScene::earlyPolygons()
  // Skinned objects drawn (deformed in the vertex shader with their pose),
  // the vertices of their held levels (the only ones deformed), and held
  // skinned objects not drawn for want of a (large enough) pose.
  std::size_t skinnedObjects = 0;
  std::size_t deformedVertices = 0;
  std::size_t skinnedWithoutPose = 0;
  // Of skinnedObjects, those drawn with a pose extrapolated to the frame's time.
  std::size_t extrapolatedPoses = 0;
};

class FrontendRenderer {
 public:
  static Result<std::unique_ptr<FrontendRenderer>> create(render::OffscreenContext& context,
                                                          const FrontendRendererOptions& options);
  ~FrontendRenderer();
  FrontendRenderer(const FrontendRenderer&) = delete;
  FrontendRenderer& operator=(const FrontendRenderer&) = delete;

  Status warmUp(const render::Lighting& lighting);
  Status submit(SceneBatch batch);
  // `frame` is resized to width x height (no reallocation when already so).
  // `poseTimeS`: the pose time the frame shows (seconds, as SceneBatch::poseTimeS).
  Result<FrameReport> renderFrame(const render::Camera& camera, const render::Lighting& lighting,
                                  RgbaImage& frame,
                                  double poseTimeS = std::numeric_limits<double>::quiet_NaN());

  const FrontendScene& scene() const;
  const FrontendRendererOptions& options() const;
  int width() const;
  int height() const;

 private:
  struct Impl;
  explicit FrontendRenderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace thinlod::frontend
