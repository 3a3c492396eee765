// Guarantee check (Pasman & Jansen 2002, section 3: every shown representation
// meets the target accuracy the plan reports): measures, for one viewer
// position, how far a representation's image is from the full-quality
// object's, in radians, and compares it with the angular error its credited
// relative accuracy allows (docs/results/guarantee.md).
//
// The measure (silhouette distance). Both are rendered from the eye into
// coverage masks with one camera aimed at the object: the full object, and
// the representation as the frontend draws it (triangles, impostor texels with
// alpha < 0.5 discarded). The measured error is the symmetric Hausdorff
// distance between the two covered pixel sets (for every pixel covered by one,
// the Euclidean distance to the nearest pixel covered by the other; the
// largest), times the camera's tangent per pixel (an upper bound of the angle
// between any two pixel directions that far apart: the gnomonic projection
// never shrinks angles). Any representation whose surface lies within e of
// the object's (symmetric Hausdorff) projects within e / (closest distance)
// of its silhouette, so a measured value above the stated bound (by more than
// the rasterization tolerance) is a certain violation; a value below it is
// necessary, not sufficient (texture sliding inside the silhouette is not
// seen).
//
// Stated bound: a representation credited with relative accuracy a, seen from
// distance D (eye to the reference sphere's surface, as the scheduler's
// conversionDistance for a region of radius 0), may err by L / (a D) radians
// (relative_accuracy.h).
//
// Pure functions (masks, distances, cameras, verdicts) are thread-safe and do
// no I/O; CoverageRenderer uses its context on the calling thread only (it
// makes it current when another context is).
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/common/render/render_target.h"

namespace thinlod::simplifier {

// Row-major, top-down; nonzero = covered.
struct CoverageMask {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> covered;
  std::size_t coveredCount() const;
};

struct SilhouetteDistance {
  // Largest distance (pixels) from a pixel covered in `reference` to the
  // nearest one covered in `shown`: what the representation loses.
  double missingPixels = 0.0;
  // The other way: what the representation adds.
  double extraPixels = 0.0;
  std::size_t missingCount = 0;  // pixels covered in reference only
  std::size_t extraCount = 0;    // pixels covered in shown only
  double pixels() const { return missingPixels > extraPixels ? missingPixels : extraPixels; }
};

// Exact Euclidean distances. First a search: the distance of each pixel to
// the nearest covered one in its own column (two integer passes), then, from
// each differing pixel only, outwards along its row until no nearer pixel can
// exist or the pixel can no longer raise the maximum; O(pixels + the
// differing pixels' distances), the common case (a depth mesh losing a band
// of its capture's silhouette, a few texels wide). When that row search
// would visit more than `searchVisitsPerPixel` x the mask's pixels (many
// differing pixels far from the other mask), the distances come from the
// exact transform instead (Felzenszwalb-Huttenlocher, O(pixels), about ten
// times the work of one visit per pixel). Both give the same values (integer
// squared distances); 0 always transforms, +infinity always searches (tests
// compare the two). Masks of different or zero size: kInvalidArgument. One
// mask empty and the other not: the distances towards the empty one are
// +infinity.
inline constexpr double kSilhouetteSearchVisitsPerPixel = 4.0;
Result<SilhouetteDistance> silhouetteDistance(
    const CoverageMask& reference, const CoverageMask& shown,
    double searchVisitsPerPixel = kSilhouetteSearchVisitsPerPixel);

// A square camera at `eye` aimed at `center` whose view holds the ball of
// radius `reach` around it (with 10 % margin), with the fewest pixels (in
// [minPixels, maxPixels]) whose tangent per pixel is at most `pixelTangent`.
struct CheckCamera {
  render::Camera camera;
  int pixels = 0;
  double tangentPerPixel = 0.0;  // 2 tan(fov / 2) / pixels: radians-per-pixel upper bound
};
// kInvalidArgument: non-finite input, reach <= 0, pixelTangent <= 0, or the
// eye within 1.01 reach of the centre (no perspective view holds the ball).
Result<CheckCamera> makeCheckCamera(const glm::vec3& eye, const glm::vec3& center, double reach,
                                    double pixelTangent, int minPixels = 256, int maxPixels = 1024);

struct GuaranteeVerdict {
  double distance = 0.0;          // D, metres (eye to the reference sphere, >= minimalDistance)
  double statedRadians = 0.0;     // L / (a D)
  double measuredRadians = 0.0;   // silhouette distance x tangent per pixel
  double toleranceRadians = 0.0;  // one pixel: both masks are rasterized
  bool exceeds = false;           // measured > stated + tolerance
  // What the measure certainly shows (measured - tolerance, >= 0) over the
  // stated error: > 1 exactly when `exceeds`.
  double ratio() const {
    const double certain =
        measuredRadians > toleranceRadians ? measuredRadians - toleranceRadians : 0.0;
    return statedRadians > 0.0 ? certain / statedRadians : 0.0;
  }
};
// `sphereCenter` / `referenceLength`: the object's world reference sphere
// (centre, diameter L). Accuracy <= 0 or not finite: stated = +infinity.
GuaranteeVerdict judgeGuarantee(const SilhouetteDistance& measured, const CheckCamera& camera,
                                const glm::vec3& eye, const glm::vec3& sphereCenter,
                                double referenceLength, double relativeAccuracy,
                                double minimalDistance = 0.1);

// One drawable part of a coverage rendering (world space via `model`). With
// a texture, texels of alpha < 0.5 are discarded (the frontend's alpha mask).
struct CoveragePart {
  const IndexedMesh* mesh = nullptr;
  glm::mat4 model{1.0f};
  const RgbaImage* alphaTexture = nullptr;
};

class CoverageRenderer {
 public:
  // `context` is not owned; it must outlive the renderer and be current.
  static Result<std::unique_ptr<CoverageRenderer>> create(render::OffscreenContext& context);
  ~CoverageRenderer();
  // Covered = depth written. Uploads the parts for this call only.
  Result<CoverageMask> render(const std::vector<CoveragePart>& parts, const CheckCamera& camera);

 private:
  explicit CoverageRenderer(render::OffscreenContext& context) : context_(&context) {}
  render::OffscreenContext* context_;
  std::unique_ptr<render::MeshRenderer> renderer_;
  std::unique_ptr<render::RenderTarget> target_;
  std::vector<float> depth_;
};

}  // namespace thinlod::simplifier
