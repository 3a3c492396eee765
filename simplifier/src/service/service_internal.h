// Private parts of SimplifierService (service.h): caches and the level
// bookkeeping shared by service.cpp, service_levels.cpp and
// service_impostor.cpp.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/scene/scene.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/simplifier/animated_bound_cache.h"
#include "thinlod/simplifier/hybrid_curve_cache.h"
#include "thinlod/simplifier/hybrid_graph.h"
#include "thinlod/simplifier/impostor.h"
#include "thinlod/simplifier/mesh_curve.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier::service_detail {

// Tag of the progressive-mesh producer in curve cache keys: change it when
// BuildOptions or the simplifier's behaviour change.
inline constexpr const char* kCurveProducer = "qem-service v1 boundaries=1 flips=1";
// The producer of a textured object's curves (attribute quadrics on its uvs,
// ServiceOptions::texturedAttributeWeight) and of a mesh built with its open
// boundary kept (SimplifyRequest::keepBoundary, region objects): another
// progressive mesh each, so another cache key.
// skinSeams: built with the skins as weld keys (a skinned object's model).
std::string curveProducerFor(float attributeWeight, bool keepBoundary = false,
                             bool skinSeams = false);
// Share of a level's error budget that Draco quantization may add.
inline constexpr double kQuantizationBudget = 0.1;

// One rung of a measured ladder with the error we credit it with.
struct LevelCredit {
  std::size_t requestedTriangles = 0;  // what to pass to ProgressiveMesh::extract
  std::size_t triangles = 0;           // what extraction returns
  double relativeError = 0.0;          // max over this and every finer rung of max(d, floor)
};

// Worst relative displacement (fraction of the reference length L) of Draco
// quantization with `bits` position bits: half a step per axis, step =
// largest axis extent / (2^bits - 1) <= L / (2^bits - 1) (an enclosing
// sphere's diameter bounds every extent).
double quantizationError(int bits);
// Relative accuracy the client decodes: 1 / (geometric d + quantization),
// with the position bits positionBitsForAccuracy chooses for 1/d.
struct DeliveredLevel {
  int positionBits = 0;
  double accuracy = 0.0;
};
DeliveredLevel deliveredLevel(double relativeError);
// A shared quantization grid (codec::MeshEncodeOptions positionOrigin /
// positionRange) for every region object of one mesh: the whole mesh's box,
// kRegionGridBits bits, so a border vertex two regions keep decodes to the
// same floats in both (docs/regions.md). range 0: each level's own box.
struct PositionGrid {
  std::array<float, 3> origin{0.0f, 0.0f, 0.0f};
  float range = 0.0f;
};
inline constexpr int kRegionGridBits = 18;
// The grid of `whole` (a cube from its bounds' minimum, side its largest
// extent, widened by a few ulps so every vertex lies inside).
PositionGrid gridOf(const IndexedMesh& whole);
// deliveredLevel on a grid: kRegionGridBits bits over grid.range, whose
// quantization relative to a part of reference length `diameter` is
// (range / diameter) * quantizationError(kRegionGridBits). range 0: deliveredLevel.
DeliveredLevel deliveredOnGrid(double relativeError, const PositionGrid& grid, double diameter);
// Triangle count stored in an encodeMesh frame (header offset 12, u32 LE):
// what the client will hold; 0 for a frame shorter than its header.
std::uint32_t frameTriangles(const std::vector<std::uint8_t>& frame);
// A SimplifyResult carrying `mesh` encoded at `delivered`'s position bits and
// credited its accuracy (triangleCount from the encoded frame).
// A skinned object's level carries `skin` (one per vertex of `mesh`, the
// scene's palette indices; empty: a static mesh) in the frame.
Result<protocol::SimplifyResult> encodedMeshResult(const IndexedMesh& mesh,
                                                   const DeliveredLevel& delivered,
                                                   const std::vector<anim::VertexSkin>& skin = {},
                                                   const PositionGrid& grid = {});

// Credits from measured levels (increasing triangles): each rung gets the
// worst error measured at it or any finer rung, so credits never improve by
// coarsening and never exceed what was measured at or above the rung.
std::vector<LevelCredit> creditLevels(const std::vector<CurveLevel>& levels,
                                      double minRelativeError);
// Index of the rung that bounds a level of `triangles` triangles: the finest
// rung with at most that many (0 when none: rung 0 has the largest credit).
std::size_t creditFor(const std::vector<LevelCredit>& ladder, std::size_t triangles);

// (accuracy, triangles) points, strictly increasing in both, subsampled to at
// most `count` (first and last kept). count == 0: none.
std::vector<AccuracySample> curveSamples(std::vector<AccuracySample> points, std::size_t count);

// One rung of a hybrid object's measured ladder: the cut at `error` (graph
// units) and the relative error it is credited with.
struct HybridRung {
  double error = 0.0;  // cut threshold (HybridCut::adaptToError)
  double units = 0.0;  // triangles + points / kappa
  double relativeError = 0.0;
};

// A mesh object's simplification state, shared by every object that uses
// the same full mesh.
struct MeshModel {
  std::shared_ptr<const IndexedMesh> original;
  double diameter = 0.0;  // L of `original` (referenceLength(referenceSphere(original)))
  ProgressiveMesh pm;
  float attributeWeight = 0.0f;  // BuildOptions::attributeWeight pm was built with
  // pm keeps every open-boundary vertex (kKeep): SimplifyRequest::keepBoundary.
  bool keepBoundary = false;
  // pm was built with the object's skins as weld keys (a skinned object).
  bool skinSeams = false;
  // The curve producer of pm's settings (curve and bound cache keys).
  std::string producer() const {
    return curveProducerFor(attributeWeight, keepBoundary, skinSeams);
  }
  // A region object's levels (keepBoundary, from a scene): its whole mesh's grid.
  PositionGrid grid;
  DeliveredLevel delivered(double relativeError) const {
    return deliveredOnGrid(relativeError, grid, diameter);
  }
  bool curveReady = false;
  bool cacheLookedUp = false;  // curveWithoutMeasuring found no file once: do not ask again
  std::vector<LevelCredit> ladder;
  // A skinned object (scene Geometry::animation): the palette skin of every
  // TOM vertex (tomSkin), so a level's skin is its first vertexCount()
  // entries, and of every vertex of `original`. Empty: a static mesh.
  std::vector<anim::VertexSkin> tomSkin;
  std::vector<anim::VertexSkin> originalSkin;
  // Per clip the model's object plays (objects sharing a mesh may play
  // different clips): one relative accuracy per `ladder` rung that holds at
  // every pose, against the reference sphere grown by the motion bound
  // (animatedLadderAccuracies).
  std::map<const scene::SkinnedAnimation*, std::vector<double>> animatedAccuracies;
  // The skin of `level` (a pm.extract: TOM vertices); empty when static.
  std::vector<anim::VertexSkin> skinOf(const IndexedMesh& level) const {
    if (tomSkin.empty()) return {};
    return std::vector<anim::VertexSkin>(
        tomSkin.begin(), tomSkin.begin() + static_cast<std::ptrdiff_t>(
                                               std::min(level.vertexCount(), tomSkin.size())));
  }
  // Levels kept for impostor rendering (their GPU copies live as long as these).
  std::map<std::size_t, std::shared_ptr<const IndexedMesh>> renderLevels;
  // Hybrid graphs by kappa, with their measured ladder (increasing units).
  struct Hybrid {
    HybridGraph graph;
    std::vector<HybridRung> rungs;
  };
  std::map<double, std::unique_ptr<Hybrid>> hybrids;
};

// The relative accuracy each rung of model.ladder keeps while its object
// plays a clip (docs/animation.md, "Measured accuracy under motion"):
// `bounds[i]` the rung's deformedLevelBound over the clip (mesh units),
// `motionBound` m (SkinnedAnimation::motionBound), `skinningScale` how far
// skinning stretches a bind-space quantization step
// (anim::sampledMaxSkinningScale). Rung i is credited (L + 2m) / (e_i +
// scale * q_i L), e_i the largest bound at it or any finer rung (floored at
// minRelativeError L, as the rest credit), q_i its relative quantization,
// or the bind-pose credit converted by anim::animatedRelativeAccuracy when
// that is higher (both bound the same error); then no rung above a finer one.
std::vector<double> animatedLadderAccuracies(const MeshModel& model,
                                             const std::vector<double>& bounds, double motionBound,
                                             double skinningScale, double minRelativeError);

// (accuracy, primitive units) of every rung of a hybrid ladder, the accuracy
// credited as deliveredLevel(rung.relativeError).
std::vector<AccuracySample> hybridCurvePoints(const std::vector<HybridRung>& rungs);
// A measured hybrid ladder (measureHybridLevels, increasing units) credited
// like a mesh ladder: each rung the worst measured error / L at it or any
// finer rung, floored (creditedRelativeErrors).
std::vector<HybridRung> creditHybridLevels(const std::vector<HybridMeasuredLevel>& levels,
                                           double referenceLength, double minRelativeError);

struct LoadedScene {
  std::string path;  // canonical
  scene::Scene scene;
  std::vector<scene::SceneObject> objects;
  render::Lighting lighting;
  std::uint64_t lastUse = 0;
  // Derived from `objects`, filled on first use by impostor requests: each
  // object's referenced vertices in world space, the input of the framing
  // that sets an impostor's texel size (gathering them again cost every
  // bunny impostor request 0.4-0.9 ms, bench_impostor's gather-full-points).
  mutable std::map<std::uint64_t, std::vector<glm::vec3>> framingPoints;
  const std::vector<glm::vec3>& framingPointsOf(const scene::SceneObject& object) const;
};

// A primitive tessellation kept for impostor rendering.
struct PrimitiveLevelKey {
  const scene::ShapeNode* shape = nullptr;
  int segments = 0;
  int rings = 0;
  bool operator<(const PrimitiveLevelKey& o) const {
    if (shape != o.shape) return shape < o.shape;
    if (segments != o.segments) return segments < o.segments;
    return rings < o.rings;
  }
};

}  // namespace thinlod::simplifier::service_detail

namespace thinlod::simplifier {

struct SimplifierService::Impl {
  ServiceOptions options;
  ServiceStats stats;
  std::string sceneRootCanonical;  // empty: no root configured or it does not exist
  std::vector<std::unique_ptr<service_detail::LoadedScene>> scenes;
  std::uint64_t useClock = 0;
  const service_detail::LoadedScene* lastScene = nullptr;
  // By full mesh and keepBoundary (a region object's model keeps its borders).
  using ModelKey = std::pair<const IndexedMesh*, bool>;
  std::map<ModelKey, std::unique_ptr<service_detail::MeshModel>> meshModels;
  // By the source bytes' checksum and keepBoundary.
  std::map<std::pair<std::uint64_t, bool>, std::unique_ptr<service_detail::MeshModel>>
      sourceMeshModels;
  std::map<service_detail::PrimitiveLevelKey, std::shared_ptr<const IndexedMesh>> primitiveLevels;
  std::unique_ptr<MeshCurveCache> curveCache;
  // Measured hybrid ladders, same directory (null without curveCacheDir).
  std::unique_ptr<HybridCurveCache> hybridCurveCache;
  // Skinned ladders' bounds under their clips, same directory.
  std::unique_ptr<AnimatedBoundCache> animatedBoundCache;
  // Decoded scene textures by file (null: the file failed, logged once).
  std::map<std::string, std::shared_ptr<const RgbaImage>> textureFiles;
  // Rendering (created lazily on the calling thread; renderer before context).
  std::unique_ptr<render::OffscreenContext> context;
  std::unique_ptr<ImpostorRenderer> impostors;

  explicit Impl(ServiceOptions o);
  ~Impl();

  Result<service_detail::LoadedScene*> scene(const std::string& path);
  // keepBoundary: the progressive mesh keeps every vertex on an open boundary
  // of the mesh (VertexConstraint::kKeep), docs/regions.md.
  Result<service_detail::MeshModel*> meshModelFor(const scene::SceneObject& object,
                                                  bool keepBoundary = false);
  Result<service_detail::MeshModel*> meshModelForSource(const protocol::Bytes& bytes,
                                                        bool keepBoundary = false);
  // weldKeys: BuildOptions::weldKeys (a skinned object's skins; empty otherwise).
  Result<service_detail::MeshModel*> buildModel(std::shared_ptr<const IndexedMesh> mesh,
                                                float attributeWeight, bool keepBoundary,
                                                const std::string& what,
                                                std::vector<std::uint64_t> weldKeys = {});
  Status ensureCurve(service_detail::MeshModel& model);
  // The curve from memory or the cache file only (never measured): true when
  // model.ladder is ready afterwards.
  bool curveWithoutMeasuring(service_detail::MeshModel& model);
  void progress(const std::string& line) const {
    if (options.progress) options.progress(line);
  }
  Status ensureRendering();
  void dropUnusedModels();
  // The base-colour texture an impostor draws `object` with when its part is
  // `mesh`: the Shape's resolved texture file when the mesh has uvs, else null.
  std::shared_ptr<const RgbaImage> textureOf(const scene::SceneObject& object,
                                             const IndexedMesh& mesh);

  // `animation`: the object's clip when it is skinned (its rungs credited
  // under motion, SimplifyResult::motionIncluded), else null.
  Result<protocol::SimplifyResult> simplifyMesh(const protocol::SimplifyRequest& request,
                                                service_detail::MeshModel& model,
                                                const scene::SkinnedAnimation* animation = nullptr);
  // model.animatedAccuracies[&animation]: from memory, the cache directory,
  // or (measureIfMissing) measured, every rung's deformedLevelBound over the
  // whole clip on options.curve.threads. Null when not measuring and neither
  // the rest ladder nor the bounds are known without measuring.
  Result<const std::vector<double>*> animatedAccuracies(service_detail::MeshModel& model,
                                                        const scene::SkinnedAnimation& animation,
                                                        bool measureIfMissing);
  Result<protocol::SimplifyResult> simplifyHybrid(const protocol::SimplifyRequest& request,
                                                  service_detail::MeshModel& model);
  Result<protocol::SimplifyResult> simplifyPrimitive(const protocol::SimplifyRequest& request,
                                                     const PrimitiveShape& shape);
  Result<protocol::Representation> impostor(const protocol::ImpostorRequest& request);
};

}  // namespace thinlod::simplifier
