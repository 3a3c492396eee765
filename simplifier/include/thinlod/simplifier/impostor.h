// Impostors (Pasman & Jansen 2002, sections 3.5-3.6): an object rendered
// offscreen from a capture viewpoint into an RGBA texture with a transparent
// background, shown either on one quad facing that viewpoint (simple
// impostor) or on a depth mesh built from the z-buffer (meshed impostor).
//
// Contract:
// - Object space is the frame of the parts' `model` matrices; the viewpoint,
//   lights, quad, depth mesh and validity range are all in that frame (metres).
// - Framing is automatic (the paper's autosize/autocenter): the off-axis
//   frustum hugs the projected vertices, so the object fills the texture up to
//   `paddingPixels` on each side; the quad lies in the plane through the
//   bounding-sphere centre perpendicular to the capture direction, and seen
//   from the viewpoint it covers exactly what the texture shows. The texture
//   is square; texels may be non-square when the quad is not.
// - Texture rows are top-down (RgbaImage), non-premultiplied, alpha 0 where
//   there is no object; quad/depth-mesh uvs use OpenGL's convention, v = 0 at
//   the image bottom, as MeshRenderer expects.
// - Validity: the cone of viewer positions around the capture direction in
//   which the angular error bound stays <= maxAngularError (radians); see
//   impostor_validity.cpp for the derivation. The capture viewpoint is inside.
// - Errors: no parts or no triangles, invalid meshes or matrices (kInvalidArgument
//   naming the part), viewpoint inside or too close to the object
//   (kInvalidArgument), GL failures (as MeshRenderer).
// - Threads: an ImpostorRenderer uses a context that must be current on the
//   calling thread (see offscreen_context.h); the pure functions (framing,
//   depth mesh, validity) are thread-safe.
#pragma once

#include <cstddef>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <unordered_map>
#include <optional>
#include <vector>

#include "thinlod/common/core/conic_range.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/common/render/render_target.h"

namespace thinlod::simplifier {

struct ImpostorPart {
  std::shared_ptr<const IndexedMesh> mesh;  // cached on the GPU while this pointer lives
  glm::mat4 model{1.0f};                    // part -> object space
  render::Material material;  // textures: handles from ImpostorRenderer::meshRenderer()
};

struct ImpostorScene {
  std::vector<ImpostorPart> parts;
  // Empty, or one per part: that part's base-colour texture (null: none;
  // needs uvs on its mesh, and its material.texture must then be none).
  // Uploaded and kept on the GPU while the pointer lives, drawn by the
  // common renderer as the frontend's reference draws it.
  std::vector<std::shared_ptr<const RgbaImage>> textures;
  render::Lighting lighting;  // object space
};

struct ImpostorOptions {
  int textureSize = 256;           // square texture edge, pixels, in [8, 4096]
  float paddingPixels = 1.0f;      // empty border so filtering never clips the object
  glm::vec3 up{0.0f, 1.0f, 0.0f};  // preferred image up; replaced when parallel to the view
  double maxAngularError = 1e-3;   // radians; the bound the validity range guarantees
  // Transparent texels within this many pixels of the object take the colour
  // of their covered neighbours (alpha stays 0), so bilinear filtering at the
  // silhouette does not darken it towards the black background.
  int bleedPixels = 2;
  // An imposter node with autocenter / autosize FALSE (Pasman & Jansen 2002,
  // Figure 9): the quad's centre is `fixedCenter` (projected onto the quad
  // plane along the view ray) and / or its width x height is `fixedSize`
  // (metres in the quad plane; 0 0: from the points). The quad still faces
  // the viewpoint. Points outside the fixed quad are not in the image
  // ("If the imposter is too small, the image will hold only part of the
  // objects it replaces"); ImpostorFraming::clippedExtent says how much.
  std::optional<glm::vec3> fixedCenter;
  glm::vec2 fixedSize{0.0f};
};

struct MeshedImpostorOptions : ImpostorOptions {
  int gridStep = 4;                 // depth-mesh node every gridStep pixels (>= 1)
  float maxSlope = 4.0f;            // split an edge whose depth change exceeds maxSlope x its width
  bool snapToSilhouette = true;     // move background nodes onto the nearest covered pixel
  std::size_t targetTriangles = 0;  // > 0: simplify the depth mesh (QEM) to this many
};

// The textured quad of a simple impostor (object space).
struct ImpostorQuad {
  glm::vec3 center{0.0f};
  glm::vec3 right{1.0f, 0.0f, 0.0f};   // unit; texture u grows along it
  glm::vec3 up{0.0f, 1.0f, 0.0f};      // unit; texture v grows along it
  glm::vec3 normal{0.0f, 0.0f, 1.0f};  // unit; points at the capture viewpoint
  float width = 0.0f;
  float height = 0.0f;
  // Two counter-clockwise triangles facing the viewpoint, uv (0,0) bottom-left.
  IndexedMesh mesh() const;
};

// How a texture was captured: enough to unproject its pixels.
struct ImpostorFraming {
  glm::vec3 viewpoint{0.0f};
  glm::vec3 forward{0.0f, 0.0f, -1.0f};  // unit, viewpoint -> object centre
  glm::vec3 objectCenter{0.0f};          // bounding-sphere centre
  float objectRadius = 0.0f;             // bounding-sphere radius
  float planeDistance = 0.0f;            // viewpoint -> quad plane along `forward`
  float nearDepth = 0.0f;                // depth range of the vertices along `forward`
  float farDepth = 0.0f;
  int textureSize = 0;
  render::Camera camera;  // off-axis perspective camera that rendered the texture
  ImpostorQuad quad;
  // A fixed frame (ImpostorOptions::fixedCenter / fixedSize) that cuts points
  // off: the largest distance (metres in the quad plane) by which a point's
  // projection lies outside the quad; 0 when everything is inside.
  float clippedExtent = 0.0f;
};

// Frames `points` (object space) for a capture from `viewpoint`.
// kInvalidArgument: no points, non-finite input, or the viewpoint within
// 1.05 bounding radii of the centre (no frustum can hold the object).
Result<ImpostorFraming> frameImpostor(const std::vector<glm::vec3>& points,
                                      const glm::vec3& viewpoint, const ImpostorOptions& options);

// What an impostor gets wrong, for the validity computation:
// - depthDeviation: metres along the capture rays between any surface point
//   and the impostor point drawn in its place, including depth jumps where a
//   hidden surface can appear (simple: the object's depth extent; meshed:
//   depth-mesh error and the largest depth jump it splits);
// - silhouetteRadius: > 0 for meshed impostors, whose fixed rim misses the
//   surface that turns into view past a smooth silhouette (metres).
struct ImpostorErrorModel {
  double depthDeviation = 0.0;
  double silhouetteRadius = 0.0;
};
// Upper bound of the angular error (radians) for a viewer at `eye` (object
// space); pi when the eye is inside the object's bounding sphere.
double impostorErrorBound(const ImpostorFraming& framing, const ImpostorErrorModel& model,
                          const glm::vec3& eye);
// The cone around the capture direction (apex at the object centre) within
// which impostorErrorBound <= maxAngularError; it contains the viewpoint.
// When no cone is possible (maxAngularError <= 0), the ball of radius 0 at
// the viewpoint.
ConicRange impostorValidity(const ImpostorFraming& framing, const ImpostorErrorModel& model,
                            double maxAngularError);
// As above, and with maxErrorLength > 0 (metres) the bound also stays within
// maxErrorLength / d for a viewer d from the object centre: the angle a
// relative accuracy credits at that distance (relative_accuracy.h), so that
// the error a credit states holds at every viewer of the cone, not only at
// the capture distance (docs/results/guarantee.md).
ConicRange impostorValidity(const ImpostorFraming& framing, const ImpostorErrorModel& model,
                            double maxAngularError, double maxErrorLength);

struct SimpleImpostor {
  RgbaImage texture;  // textureSize^2, transparent background
  ImpostorQuad quad;
  ImpostorFraming framing;
  ConicRange validity;
  ImpostorErrorModel errorModel;
  double coverage = 0.0;  // fraction of texels with alpha > 0
};

struct DepthMeshStats {
  std::size_t gridNodes = 0;   // covered (or snapped) nodes that became vertices
  std::size_t splitEdges = 0;  // grid edges dropped at a depth jump
  double maxDepthJump = 0.0;   // metres along the view, largest dropped edge between covered nodes
};

// Gives transparent texels near covered ones the mean colour of their covered
// 8-neighbours, `pixels` rings deep; alpha is unchanged.
void bleedColorIntoTransparent(RgbaImage& image, int pixels);

// Builds the depth mesh from a top-down window-depth buffer (1 = background)
// rendered with `framing.camera`. Vertices in object space with uvs into the
// captured texture; triangles never join nodes across a depth jump.
Result<IndexedMesh> buildDepthMesh(const std::vector<float>& depth, const ImpostorFraming& framing,
                                   const MeshedImpostorOptions& options, DepthMeshStats* stats);

struct MeshedImpostor {
  RgbaImage texture;
  IndexedMesh mesh;  // object space, uvs into `texture`, normals facing the viewpoint side
  ImpostorFraming framing;
  ConicRange validity;
  DepthMeshStats depthMesh;
  double meshDepthError = 0.0;  // metres, largest |mesh depth - z-buffer depth| over covered pixels
  ImpostorErrorModel errorModel;   // depthDeviation = max(meshDepthError, depthMesh.maxDepthJump)
  double coverage = 0.0;           // fraction of texels with alpha > 0
  double uncoveredFraction = 0.0;  // covered texels the depth mesh misses (silhouette loss)
  // Largest distance (texels) from a captured covered texel to the nearest
  // texel the depth mesh still shows, seen from the capture viewpoint
  // (silhouetteDistance, guarantee_check.h): holes and lost thin parts. The
  // texture only shows where the mesh is, so this detail is lost to every
  // viewer; the service adds it to the error it credits.
  double silhouetteLossTexels = 0.0;
};

struct ImpostorTimings {
  double uploadMs = 0.0;  // meshes uploaded this call (cache misses)
  double renderMs = 0.0;  // draw + colour (and depth) readback
  double meshMs = 0.0;    // meshed only: depth mesh, simplification, error measurement
  // meshMs in parts (meshed only): the grid mesh from the z-buffer, its QEM
  // simplification, and the check (draw the final mesh, depth readback,
  // silhouette loss, per-pixel depth error).
  double gridMs = 0.0;
  double simplifyMs = 0.0;
  double checkMs = 0.0;
  // checkMs in parts: upload + draw of the depth mesh and its depth
  // readback; the coverage masks and their silhouette distance; the
  // per-pixel depth error (unprojection of both depths).
  double checkDrawMs = 0.0;
  double checkSilhouetteMs = 0.0;
  double checkDepthErrorMs = 0.0;
};

class ImpostorRenderer {
 public:
  // Uses `context` (not owned; must outlive the renderer and be current on this thread).
  static Result<std::unique_ptr<ImpostorRenderer>> create(render::OffscreenContext& context);
  ~ImpostorRenderer();

  Result<SimpleImpostor> renderSimple(const ImpostorScene& scene, const glm::vec3& viewpoint,
                                      const ImpostorOptions& options = {});
  Result<MeshedImpostor> renderMeshed(const ImpostorScene& scene, const glm::vec3& viewpoint,
                                      const MeshedImpostorOptions& options = {});

  render::MeshRenderer& meshRenderer() { return *renderer_; }
  const ImpostorTimings& lastTimings() const { return timings_; }

 private:
  struct CachedMesh {
    std::weak_ptr<const IndexedMesh> source;
    render::MeshHandle handle;
  };
  struct CachedTexture {
    std::weak_ptr<const RgbaImage> source;
    render::TextureHandle handle;
  };
  explicit ImpostorRenderer(render::OffscreenContext& context);
  Status prepare(const ImpostorScene& scene, const ImpostorOptions& options,
                 const glm::vec3& viewpoint, ImpostorFraming& framing,
                 std::vector<render::DrawItem>& items);
  Status ensureTarget(int size);

  render::OffscreenContext* context_;
  std::unique_ptr<render::MeshRenderer> renderer_;
  std::unique_ptr<render::RenderTarget> target_;
  std::unordered_map<const IndexedMesh*, CachedMesh> meshCache_;
  std::unordered_map<const RgbaImage*, CachedTexture> textureCache_;
  ImpostorTimings timings_;
  std::vector<float> depthScratch_;
  std::vector<float> meshDepthScratch_;  // the depth mesh's own depth (meshed check)
  std::vector<glm::vec3> pointScratch_;
  std::vector<unsigned char> referencedScratch_;
};

}  // namespace thinlod::simplifier
