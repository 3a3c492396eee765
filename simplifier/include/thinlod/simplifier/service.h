// SimplifierService: answers the backbone's SimplifyRequest / ImpostorRequest
// with protocol results (the library behind `thinlod-simplifier serve`).
//
// Contract:
// - Scenes are loaded on demand from SimplifyRequest.sourcePath, which must
//   resolve (realpath) inside options.sceneRoot; objects are numbered by
//   scene::collectSceneObjects. ImpostorRequests carry no path: they use
//   options.defaultScenePath when set, else the scene loaded most recently.
// - Meshes: one ProgressiveMesh per object, built once and cached; every
//   resolution is extracted from it. Its measured curve (MeshCurveCache on
//   options.curveCacheDir, in memory only when empty) gives the accuracy:
//   a level is credited with the worst error measured at its ladder rung or
//   any finer one, plus the Draco quantization bound (docs/simplifier.md).
//   Primitives use the analytic tessellation error instead.
// - Cold start (options.answerBeforeCurve; the daemon's default): a
//   kTriangles SimplifyRequest without curvePoints for a mesh whose curve is
//   neither in memory nor in the curve cache does not wait for the whole
//   ladder: the extracted level's own error is measured (one
//   measureSurfaceError, about 1/12 of a curve) and credited (plus the
//   quantization bound); such credits are not monotone across levels.
//   Requests with curvePoints > 0 (the backbone's curve requests) and
//   kAccuracy targets measure the full curve. Impostors of such a mesh render
//   the full mesh (error 0) until its curve is known.
// - options.progress (optional) hears long work: progressive-mesh builds of
//   large meshes and each level of a curve measurement (one line each).
// - Mesh bytes are codec frames (encodeMesh: Draco inside); textures are
//   raw RGBA8 for kRawRgba8, else encodeTextureWith frames. JPEG needs an
//   opaque texture: impostors have alpha, so a JPEG request gets PNG (the
//   texture's codec says which).
// - Hybrid requests (SimplifyRequest.representation = kHybrid): one hybrid
//   graph per (mesh, kappa), cached in memory with its measured ladder
//   (measureHybridLevels with options.curve's levels and sampling, credited
//   like a mesh ladder; the ladder is also kept in options.curveCacheDir,
//   HybridCurveCache, so a new process only rebuilds the graph); the rung
//   at the requested accuracy (or the finest with at most targetTriangles
//   primitive units) is an encodeHybrid frame, its accuracy 1 / (credited
//   error + quantization), the curve its rungs in primitive units. Analytic
//   primitives have no hybrid form (kUnsupported).
// - Impostors: world-space geometry, identity transform, world validity;
//   representationId/generation stay 0 (the backbone numbers them).
// - Errors are returned in the result's status, never thrown: kInvalidArgument
//   (bad path, ids, sizes, kinds, NaN), kNotFound (file, object), kUnsupported
//   (non-square texture), kResourceExhausted (limits), kUnavailable (no GL,
//   no scene), kInternal. A failed request leaves the service usable.
// - Not thread-safe: call from one thread. The GL context is created lazily
//   by the first impostor request and must only be used from that thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "thinlod/common/core/status.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/protocol/messages.h"
#include "thinlod/simplifier/mesh_curve.h"
#include "thinlod/simplifier/skinned_level.h"

namespace thinlod::simplifier {

struct ServiceOptions {
  std::vector<std::string> modelSearchPaths;  // where scene Inline urls are looked up
  std::string sceneRoot;         // request paths must lie inside (empty: no path accepted)
  std::string defaultScenePath;  // optional; must lie inside sceneRoot too
  std::string curveCacheDir;     // measured-curve files; empty: keep curves in memory only
  render::Backend backend = render::Backend::kAuto;
  std::uint32_t defaultTextureSize = 256;    // impostor requests with width = height = 0
  std::uint32_t maxTextureSize = 2048;       // larger requests: kResourceExhausted
  std::size_t maxCachedScenes = 4;           // least recently used scenes are dropped
  int maxPrimitiveTriangles = 65536;         // finest primitive tessellation served
  std::size_t meshedImpostorTriangles = 64;  // depth-mesh target (QEM) of meshed impostors
  // BuildOptions::attributeWeight of textured objects' progressive meshes
  // (a Shape with a resolved texture and a mesh with uvs): a full-range uv
  // change costs like sqrt(w) of the bbox diagonal, 10% at 0.01. Untextured
  // objects keep 0 (geometry only).
  float texturedAttributeWeight = 0.01f;
  // Render impostors from the coarsest level within one texel
  // (impostor_level.h); false: always the full meshes (the reference capture).
  bool impostorFromLevels = true;
  // Impostor credits the guarantee check holds (docs/simplifier.md,
  // ImpostorRequest 7): a meshed impostor's error includes its depth mesh's
  // silhouette loss (holes, lost thin parts), and the validity cone keeps the
  // parallax within the share of the credited error left to it at every
  // viewer distance. false: the credit and cone before the guarantee check
  // (texture and level only; parallax within accuracyBound), kept for
  // docs/results/guarantee.md's comparison.
  bool impostorGuaranteeCredit = true;
  // Answer meshes without a known curve from one measured level (see above);
  // false: measure the curve first (every credit from the ladder).
  bool answerBeforeCurve = false;
  MeshCurveOptions curve = defaultCurveOptions();
  // How a skinned object's ladder is measured under its clip
  // (deformedLevelBound per rung, docs/animation.md "Measured accuracy under
  // motion"); the window is the whole clip (t0, t1 and wrap are set by the
  // service). Coarser than the bench's defaults: a first request for a
  // figure waits for every rung.
  AnimatedErrorOptions animatedError = defaultAnimatedErrorOptions();
  // false: a skinned object's levels carry their bind-pose accuracies and the
  // backbone converts them by the clip's motion bound (4-17x looser on
  // Testwuson.X); kept for comparison and for workers short of CPU.
  bool measureAnimatedAccuracy = true;
  // Called (on the service's thread) with one log line per step of long work.
  std::function<void(const std::string&)> progress;
  // Hybrid requests (RepresentationKind::kHybrid, docs/hybrid.md): kappa when
  // the request leaves it 0, and the transition factor tau.
  double hybridKappa = 3.0;
  double hybridTau = 1.0;

  static MeshCurveOptions defaultCurveOptions();
  static AnimatedErrorOptions defaultAnimatedErrorOptions();
};

// Counters for tests and logs (monotone over the service's life).
struct ServiceStats {
  std::uint64_t sceneLoads = 0;
  std::uint64_t progressiveMeshBuilds = 0;
  std::uint64_t curvesMeasured = 0;       // computed (disk cache miss or no cache)
  std::uint64_t curvesFromDisk = 0;       // read from the curve cache directory
  std::uint64_t levelsMeasuredAlone = 0;  // cold-start answers: one level measured, no curve
  std::uint64_t simplifyRequests = 0;
  std::uint64_t impostorRequests = 0;
  std::uint64_t impostorLevelsExtracted = 0;  // render levels extracted (kept for reuse)
  std::uint64_t failedRequests = 0;
  std::uint64_t hybridGraphBuilds = 0;     // one per (mesh, kappa)
  // measureHybridLevels ran (cache miss, refused file, or no cache directory).
  std::uint64_t hybridCurvesMeasured = 0;
  std::uint64_t hybridCurvesFromDisk = 0;  // the ladder read from the curve cache directory
  // A skinned object's ladder measured under its clip (one per mesh and
  // clip), or read from the curve cache directory.
  std::uint64_t animatedLaddersMeasured = 0;
  std::uint64_t animatedLaddersFromDisk = 0;
};

class SimplifierService {
 public:
  explicit SimplifierService(ServiceOptions options);
  ~SimplifierService();
  SimplifierService(const SimplifierService&) = delete;
  SimplifierService& operator=(const SimplifierService&) = delete;

  protocol::SimplifyResult simplify(const protocol::SimplifyRequest& request);
  protocol::ImpostorResult renderImpostor(const protocol::ImpostorRequest& request);

  // Loads (or finds cached) the scene at `path` and returns its object count.
  Result<std::size_t> loadScene(const std::string& path);
  // Creates the GL context now (on the calling thread) instead of on the
  // first impostor request; kUnavailable names why each back-end failed.
  Status initializeRendering();
  // "egl: llvmpipe (LLVM 15.0.6, 256 bits)" once rendering works, else "".
  std::string rendererDescription() const;

  const ServiceStats& stats() const;
  const ServiceOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace thinlod::simplifier
