// SimplifierService (service.h): request validation, the scene cache and the
// progressive-mesh cache, and SimplifyRequest handling. Impostors are in
// service_impostor.cpp, level bookkeeping in service_levels.cpp.
#include "thinlod/simplifier/service.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <filesystem>
#include <mutex>
#include <new>
#include <system_error>
#include <utility>

#include "service_internal.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/parallel_for.h"
#include "thinlod/common/mesh/mesh_regions.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/common/scene_render/scene_render.h"
#include "thinlod/protocol/codec.h"
#include "thinlod/simplifier/skinned_level.h"

namespace thinlod::simplifier {

using namespace service_detail;
namespace fs = std::filesystem;

namespace {

Status invalid(const std::string& message) { return Status(ErrorCode::kInvalidArgument, message); }

// True when `path` lies strictly inside `root` (both canonical).
bool isInside(const fs::path& path, const fs::path& root) {
  const fs::path relative = path.lexically_relative(root);
  if (relative.empty() || relative == ".") return false;
  return *relative.begin() != "..";
}

template <typename ResultT>
ResultT failure(std::uint64_t requestId, const Status& status) {
  ResultT result;
  result.requestId = requestId;
  result.status = status;
  return result;
}

}  // namespace

MeshCurveOptions ServiceOptions::defaultCurveOptions() {
  MeshCurveOptions curve;
  curve.levels = 12;
  // The service only needs the triangles curve; 30k samples per direction
  // keep a first measurement of a 6k-triangle mesh well under a second.
  curve.measureEncodedBytes = false;
  curve.error.samplesPerMesh = 30000;
  // All cores: a worker measures one curve at a time, and its levels are
  // independent (several workers on one host: --curve-threads 1).
  curve.threads = 0;
  return curve;
}

AnimatedErrorOptions ServiceOptions::defaultAnimatedErrorOptions() {
  AnimatedErrorOptions animated;
  // A quarter of the bench's surface samples and about half its poses:
  // Testwuson.X's 12 rungs took 8.7 s on this machine's 2 cores under load
  // (docs/animation.md, "Measured accuracy under motion"), once per clip.
  animated.maxPoses = 33;
  animated.surface.samplesPerMesh = 5000;
  return animated;
}

SimplifierService::Impl::Impl(ServiceOptions o) : options(std::move(o)) {
  if (!options.sceneRoot.empty()) {
    std::error_code ec;
    const fs::path root = fs::canonical(options.sceneRoot, ec);
    if (!ec && fs::is_directory(root, ec)) sceneRootCanonical = root.string();
  }
  if (!options.curveCacheDir.empty()) {
    curveCache = std::make_unique<MeshCurveCache>(options.curveCacheDir);
    hybridCurveCache = std::make_unique<HybridCurveCache>(options.curveCacheDir);
    animatedBoundCache = std::make_unique<AnimatedBoundCache>(options.curveCacheDir);
  }
}

SimplifierService::Impl::~Impl() {
  // GL objects die while the context is current on this thread.
  if (context) (void)context->makeCurrent();
  impostors.reset();
  context.reset();
}

Result<LoadedScene*> SimplifierService::Impl::scene(const std::string& path) {
  if (path.empty()) return invalid("scene path is empty");
  if (sceneRootCanonical.empty()) {
    return invalid("scene " + path + ": no scene root configured (or it does not exist)");
  }
  std::error_code ec;
  const fs::path lexical = fs::weakly_canonical(fs::path(path), ec);
  if (ec) return invalid("scene " + path + ": cannot resolve the path: " + ec.message());
  if (!isInside(lexical, fs::path(sceneRootCanonical))) {
    return invalid("scene " + path + ": outside the allowed scene root " + sceneRootCanonical);
  }
  const fs::path canonical = fs::canonical(lexical, ec);
  if (ec || !fs::is_regular_file(canonical, ec)) {
    return Status(ErrorCode::kNotFound, "scene " + path + ": no such file");
  }
  // Symlinks inside the root may point outside it: check the real path too.
  if (!isInside(canonical, fs::path(sceneRootCanonical))) {
    return invalid("scene " + path + ": resolves outside the allowed scene root " +
                   sceneRootCanonical);
  }
  const std::string key = canonical.string();
  for (auto& loaded : scenes) {
    if (loaded->path == key) {
      loaded->lastUse = ++useClock;
      lastScene = loaded.get();
      return loaded.get();
    }
  }

  scene::SceneLoadOptions loadOptions;
  loadOptions.meshSearchPaths = options.modelSearchPaths;
  Result<scene::Scene> parsed = scene::loadSceneFile(key, loadOptions);
  if (!parsed.ok()) return parsed.status();
  auto loaded = std::make_unique<LoadedScene>();
  loaded->path = key;
  loaded->scene = std::move(parsed).value();
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(loaded->scene);
  if (!objects.ok()) return objects.status();
  loaded->objects = std::move(objects).value();
  loaded->lighting = scene::sceneLighting(loaded->scene);
  loaded->lastUse = ++useClock;
  ++stats.sceneLoads;

  const std::size_t capacity = std::max<std::size_t>(1, options.maxCachedScenes);
  while (scenes.size() >= capacity) {
    auto oldest = std::min_element(scenes.begin(), scenes.end(), [](const auto& a, const auto& b) {
      return a->lastUse < b->lastUse;
    });
    if (lastScene == oldest->get()) lastScene = nullptr;
    scenes.erase(oldest);
    // Keys of primitive levels point at shapes of the dropped scene. (Their
    // GPU copies go at the next impostor render, when the renderer sees the
    // meshes expired.)
    primitiveLevels.clear();
    dropUnusedModels();
  }
  scenes.push_back(std::move(loaded));
  lastScene = scenes.back().get();
  return scenes.back().get();
}

void SimplifierService::Impl::dropUnusedModels() {
  for (auto it = meshModels.begin(); it != meshModels.end();) {
    // Only the model still holds the mesh: its scene is gone.
    if (it->second->original.use_count() == 1) {
      it = meshModels.erase(it);
    } else {
      ++it;
    }
  }
}

Result<MeshModel*> SimplifierService::Impl::buildModel(std::shared_ptr<const IndexedMesh> mesh,
                                                       float attributeWeight, bool keepBoundary,
                                                       const std::string& what,
                                                       std::vector<std::uint64_t> weldKeys) {
  auto model = std::make_unique<MeshModel>();
  // Builds of large meshes take a second or more: say so in the log.
  constexpr std::size_t kReportBuildsFrom = 20000;
  const bool report = mesh->triangleCount() >= kReportBuildsFrom;
  const auto started = std::chrono::steady_clock::now();
  if (report)
    progress("event=pm_build_started what=\"" + what +
             "\" triangles=" + std::to_string(mesh->triangleCount()));
  BuildOptions build;
  build.attributeWeight = attributeWeight;
  model->attributeWeight = attributeWeight;
  model->keepBoundary = keepBoundary;
  model->skinSeams = !weldKeys.empty();
  build.weldKeys = std::move(weldKeys);
  if (keepBoundary) {
    // A region object's borders (and the mesh's outer border) stay where
    // they are at every level: independent levels of neighbouring regions
    // then meet on the same vertices (docs/regions.md, "In the running system").
    const std::vector<bool> boundary = openBoundaryVertices(*mesh);
    build.vertexConstraints.assign(mesh->positions.size(), VertexConstraint::kFree);
    for (std::size_t v = 0; v < boundary.size(); ++v)
      if (boundary[v]) build.vertexConstraints[v] = VertexConstraint::kKeep;
  }
  Result<ProgressiveMesh> pm = ProgressiveMesh::build(*mesh, build);
  if (!pm.ok()) return Status(pm.status().code(), what + ": " + pm.status().message());
  ++stats.progressiveMeshBuilds;
  if (report)
    progress("event=pm_build_done what=\"" + what + "\" ms=" +
             std::to_string(std::llround(std::chrono::duration<double, std::milli>(
                                             std::chrono::steady_clock::now() - started)
                                             .count())));
  model->pm = std::move(pm).value();
  model->diameter = referenceLength(referenceSphere(*mesh));
  model->original = std::move(mesh);
  if (model->pm.maxTriangles() == 0 || !(model->diameter > 0.0)) {
    return invalid(what + ": no triangles or zero size after cleanup");
  }
  MeshModel* raw = model.get();
  meshModels.emplace(ModelKey(raw->original.get(), keepBoundary), std::move(model));
  return raw;
}

Result<MeshModel*> SimplifierService::Impl::meshModelFor(const scene::SceneObject& object,
                                                         bool keepBoundary) {
  if (!object.fullMesh) return invalid("object " + std::to_string(object.id) + " has no mesh");
  auto found = meshModels.find(ModelKey(object.fullMesh.get(), keepBoundary));
  if (found != meshModels.end()) return found->second.get();
  // A textured object's levels keep their uvs (extract always carries them);
  // attribute quadrics keep the texture from sliding across the surface.
  const bool textured = object.shape != nullptr && !object.shape->appearance.texturePath.empty() &&
                        !object.fullMesh->uvs.empty();
  const std::string what = "object " + std::to_string(object.id);
  // A skinned mesh's vertices at one place with different skins part when it
  // moves: never weld them (docs/animation.md, "Levels of a skinned mesh").
  const scene::SkinnedAnimation* animation =
      object.shape != nullptr ? object.shape->geometry.animation.get() : nullptr;
  Result<MeshModel*> built =
      buildModel(object.fullMesh, textured ? options.texturedAttributeWeight : 0.0f, keepBoundary,
                 what, animation != nullptr ? anim::skinWeldKeys(animation->skin)
                                            : std::vector<std::uint64_t>{});
  if (built.ok() && keepBoundary && object.regionCount > 0 && object.shape != nullptr &&
      object.shape->geometry.mesh) {
    // Every region of the mesh on one quantization grid: the border
    // vertices they keep decode to the same floats (docs/regions.md).
    (*built)->grid = gridOf(*object.shape->geometry.mesh);
  }
  if (!built.ok() || object.shape == nullptr || !object.shape->geometry.animation) return built;
  // A skinned object's levels carry their vertices' skins in the palette's
  // bone indices (the backbone's bone poses hold one matrix per palette bone).
  const anim::SkinPalette& palette = object.shape->geometry.animation->palette;
  MeshModel& model = **built;
  Result<std::vector<anim::VertexSkin>> skin =
      tomSkin(model.pm, *object.fullMesh, palette.skin, palette.bones.size());
  if (!skin.ok()) {
    meshModels.erase(ModelKey(object.fullMesh.get(), keepBoundary));
    return Status(skin.status().code(), what + ": " + skin.status().message());
  }
  model.tomSkin = std::move(skin).value();
  model.originalSkin = palette.skin;
  return built;
}

Result<MeshModel*> SimplifierService::Impl::meshModelForSource(const protocol::Bytes& bytes,
                                                               bool keepBoundary) {
  const std::pair<std::uint64_t, bool> key(
      codec::frameChecksum(bytes.data(), bytes.size()) ^ (bytes.size() * 0x9e37u), keepBoundary);
  auto found = sourceMeshModels.find(key);
  if (found != sourceMeshModels.end()) return found->second.get();
  Result<IndexedMesh> decoded = codec::decodeMesh(bytes.data(), bytes.size());
  if (!decoded.ok()) {
    return Status(decoded.status().code(), "sourceMesh: " + decoded.status().message());
  }
  auto mesh = std::make_shared<const IndexedMesh>(std::move(decoded).value());
  Result<MeshModel*> built = buildModel(mesh, 0.0f, keepBoundary, "sourceMesh");
  if (!built.ok()) return built.status();
  // Move it from the scene-mesh map into the source map (bounded).
  auto node = meshModels.extract(ModelKey(mesh.get(), keepBoundary));
  constexpr std::size_t kMaxSourceMeshes = 16;
  if (sourceMeshModels.size() >= kMaxSourceMeshes) sourceMeshModels.erase(sourceMeshModels.begin());
  MeshModel* raw = node.mapped().get();
  sourceMeshModels.emplace(key, std::move(node.mapped()));
  return raw;
}

bool SimplifierService::Impl::curveWithoutMeasuring(MeshModel& model) {
  if (model.curveReady) return true;
  if (!curveCache || model.cacheLookedUp) return false;
  model.cacheLookedUp = true;
  Result<MeshCurves> curves =
      curveCache->find(*model.original, model.producer(),
                       model.pm, options.curve);
  if (!curves.ok() || curves->levels.empty()) return false;
  ++stats.curvesFromDisk;
  model.ladder = creditLevels(curves->levels, options.curve.minRelativeError);
  model.curveReady = true;
  return true;
}

Status SimplifierService::Impl::ensureCurve(MeshModel& model) {
  if (model.curveReady) return Status();
  Result<MeshCurves> curves = Status(ErrorCode::kInternal, "not measured");
  // A measurement takes seconds for a large mesh: one progress line per level.
  const std::size_t minTriangles = std::max<std::size_t>(1, model.pm.minTriangles());
  const auto started = std::chrono::steady_clock::now();
  const ExtractTriangles extract = [&](std::size_t n) { return model.pm.extract(n); };
  // Levels are measured on options.curve.threads threads; one line as each is done.
  MeshCurveOptions curveOptions = options.curve;
  curveOptions.levelMeasured = [&](const CurveLevel& measured, std::size_t done,
                                   std::size_t total) {
    progress("event=curve_progress mesh_triangles=" + std::to_string(model.pm.maxTriangles()) +
             " level=" + std::to_string(done) + "/" + std::to_string(total) +
             " triangles=" + std::to_string(measured.triangles) + " ms=" +
             std::to_string(std::llround(std::chrono::duration<double, std::milli>(
                                             std::chrono::steady_clock::now() - started)
                                             .count())));
  };
  if (curveCache) {
    const int hitsBefore = curveCache->stats().hits;
    curves = curveCache->getOrMeasure(*model.original,
                                      model.producer(),
                                      minTriangles, model.pm.maxTriangles(), extract, curveOptions);
    if (curves.ok()) {
      if (curveCache->stats().hits > hitsBefore) {
        ++stats.curvesFromDisk;
      } else {
        ++stats.curvesMeasured;
      }
    }
  } else {
    curves = measureMeshCurves(*model.original, minTriangles, model.pm.maxTriangles(), extract,
                               curveOptions);
    if (curves.ok()) ++stats.curvesMeasured;
  }
  if (!curves.ok()) return curves.status();
  if (curves->levels.empty()) return Status(ErrorCode::kInternal, "measured curve has no levels");
  model.ladder = creditLevels(curves->levels, options.curve.minRelativeError);
  model.curveReady = true;
  return Status();
}

Result<const std::vector<double>*> SimplifierService::Impl::animatedAccuracies(
    MeshModel& model, const scene::SkinnedAnimation& animation, bool measureIfMissing) {
  auto found = model.animatedAccuracies.find(&animation);
  if (found != model.animatedAccuracies.end()) return &found->second;
  if (!measureIfMissing && !curveWithoutMeasuring(model)) return nullptr;
  THINLOD_RETURN_IF_ERROR(ensureCurve(model));
  // Skeleton-bone skins (deformedLevelBound poses the skeleton, not the palette).
  Result<std::vector<anim::VertexSkin>> levelSkins = tomSkin(
      model.pm, *model.original, animation.skin, animation.skeleton.bones.size());
  if (!levelSkins.ok()) return levelSkins.status();
  AnimatedErrorOptions bound = options.animatedError;
  bound.t0 = 0.0;
  bound.t1 = animation.clip.duration;
  bound.wrap = anim::ClipWrap::kClamp;  // the window is the whole clip, as motionBound's
  auto measure = [&]() -> Result<std::vector<double>> {
    const auto started = std::chrono::steady_clock::now();
    std::vector<Result<AnimatedLevelError>> bounds(model.ladder.size(),
                                                   Status(ErrorCode::kInternal, "not measured"));
    std::atomic<std::size_t> done{0};
    std::mutex progressMutex;
    parallelFor(model.ladder.size(), options.curve.threads, [&](std::size_t i) {
      const IndexedMesh level = model.pm.extract(model.ladder[i].requestedTriangles);
      const std::vector<anim::VertexSkin> skin(
          levelSkins->begin(),
          levelSkins->begin() + static_cast<std::ptrdiff_t>(
                                    std::min(level.vertexCount(), levelSkins->size())));
      bounds[i] = deformedLevelBound(*model.original, animation.skin, animation.skeleton,
                                     animation.clip, level, skin, bound);
      const std::size_t finished = ++done;
      std::lock_guard<std::mutex> lock(progressMutex);
      progress("event=animated_curve_progress mesh_triangles=" +
               std::to_string(model.pm.maxTriangles()) + " level=" + std::to_string(finished) +
               "/" + std::to_string(model.ladder.size()) +
               " triangles=" + std::to_string(level.triangleCount()) + " ms=" +
               std::to_string(std::llround(std::chrono::duration<double, std::milli>(
                                               std::chrono::steady_clock::now() - started)
                                               .count())));
    });
    std::vector<double> errors;
    errors.reserve(bounds.size());
    for (const Result<AnimatedLevelError>& b : bounds) {
      if (!b.ok()) return b.status();
      errors.push_back(b->bound);
    }
    ++stats.animatedLaddersMeasured;
    return errors;
  };
  Result<std::vector<double>> errors = Status(ErrorCode::kNotFound, "not measured");
  if (animatedBoundCache) {
    AnimatedLadderInputs inputs{*model.original, animation.skin, animation.skeleton,
                                animation.clip, model.producer(),
                                {}, bound};
    for (const LevelCredit& rung : model.ladder) {
      inputs.rungTriangles.push_back(rung.requestedTriangles);
    }
    errors = animatedBoundCache->find(inputs);
    if (errors.ok()) {
      ++stats.animatedLaddersFromDisk;
    } else if (measureIfMissing) {
      errors = animatedBoundCache->getOrMeasure(inputs, measure);
    }
  } else if (measureIfMissing) {
    errors = measure();
  }
  if (!errors.ok() && !measureIfMissing) return nullptr;
  if (!errors.ok()) return errors.status();
  const double scale = anim::sampledMaxSkinningScale(animation.skeleton, animation.clip,
                                                     animation.palette, 128);
  std::vector<double> accuracies = animatedLadderAccuracies(
      model, *errors, animation.motionBound, scale, options.curve.minRelativeError);
  return &model.animatedAccuracies.emplace(&animation, std::move(accuracies)).first->second;
}

Result<protocol::SimplifyResult> SimplifierService::Impl::simplifyMesh(
    const protocol::SimplifyRequest& request, MeshModel& model,
    const scene::SkinnedAnimation* animation) {
  // An answer that must not wait for a whole ladder's measurement.
  const bool coldAnswer = options.answerBeforeCurve &&
                          request.target == protocol::SimplifyRequest::Target::kTriangles &&
                          request.curvePoints == 0;
  if (coldAnswer && !curveWithoutMeasuring(model)) {
    // Cold start: measure the one level asked for, not the whole ladder.
    const IndexedMesh mesh =
        model.pm.extract(std::min<std::size_t>(request.targetTriangles, model.pm.maxTriangles()));
    Result<SurfaceError> error = measureSurfaceError(*model.original, mesh, options.curve.error);
    if (!error.ok()) return error.status();
    ++stats.levelsMeasuredAlone;
    const double d =
        std::max(relativeError(error->max(), model.diameter), options.curve.minRelativeError);
    return encodedMeshResult(mesh, model.delivered(d), model.skinOf(mesh), model.grid);
  }
  THINLOD_RETURN_IF_ERROR(ensureCurve(model));
  // A skinned object's rungs are credited what they keep under its clip
  // (a cold answer only when that is known; else the bind-pose credit, which
  // the backbone converts by the motion bound).
  const std::vector<double>* moving = nullptr;
  if (animation != nullptr && options.measureAnimatedAccuracy) {
    Result<const std::vector<double>*> measured =
        animatedAccuracies(model, *animation, !coldAnswer);
    if (!measured.ok()) return measured.status();
    moving = *measured;
  }
  auto rungAccuracy = [&](std::size_t i) {
    return moving != nullptr ? (*moving)[i]
                             : model.delivered(model.ladder[i].relativeError).accuracy;
  };
  const ProgressiveMesh& pm = model.pm;
  std::size_t target = pm.maxTriangles();
  if (request.target == protocol::SimplifyRequest::Target::kTriangles) {
    target = std::min<std::size_t>(request.targetTriangles, pm.maxTriangles());
  } else {
    for (std::size_t i = 0; i < model.ladder.size(); ++i) {
      if (rungAccuracy(i) >= request.targetAccuracy) {
        target = model.ladder[i].requestedTriangles;
        break;
      }
    }
  }
  // A textured object's full resolution is its own mesh, uv seams intact:
  // the progressive mesh welds the seam's split vertices (one uv each), which
  // a texture shows. Only when cleanup dropped no triangle (same count).
  const bool original = model.attributeWeight > 0.0f && target >= pm.maxTriangles() &&
                        model.original->triangleCount() == pm.maxTriangles();
  const IndexedMesh mesh = original ? *model.original : pm.extract(target);
  const std::size_t rung = creditFor(model.ladder, mesh.triangleCount());
  Result<protocol::SimplifyResult> encoded =
      encodedMeshResult(mesh, model.delivered(model.ladder[rung].relativeError),
                        original ? model.originalSkin : model.skinOf(mesh), model.grid);
  if (!encoded.ok()) return encoded.status();
  protocol::SimplifyResult result = std::move(encoded).value();
  if (moving != nullptr) {
    result.accuracy = rungAccuracy(rung);
    result.motionIncluded = true;
  }
  if (request.curvePoints > 0) {
    std::vector<AccuracySample> points;
    for (std::size_t i = 0; i < model.ladder.size(); ++i) {
      points.push_back(
          AccuracySample{rungAccuracy(i), static_cast<double>(model.ladder[i].triangles)});
    }
    result.curve = curveSamples(std::move(points), request.curvePoints);
  }
  return result;
}

Result<protocol::SimplifyResult> SimplifierService::Impl::simplifyPrimitive(
    const protocol::SimplifyRequest& request, const PrimitiveShape& shape) {
  THINLOD_RETURN_IF_ERROR(validatePrimitive(shape));
  const int maxTriangles = std::clamp(options.maxPrimitiveTriangles, 12, kMaxPrimitiveTriangles);
  auto delivered = [&](const TessellationParams& p) {
    return deliveredLevel(relativeError(tessellationError(shape, p), primitiveDiameter(shape)));
  };
  TessellationParams params = chooseTessellation(shape, maxTriangles);
  if (request.target == protocol::SimplifyRequest::Target::kTriangles) {
    params = chooseTessellation(
        shape, static_cast<int>(std::min<std::uint32_t>(request.targetTriangles,
                                                        static_cast<std::uint32_t>(maxTriangles))));
  } else {
    // Ask the tessellation for a little more than the target so that the
    // quantization the encoder adds still leaves the target reached.
    double wanted = request.targetAccuracy;
    for (int attempt = 0; attempt < 8; ++attempt) {
      Result<TessellationParams> found = tessellationForAccuracy(shape, wanted, maxTriangles);
      if (!found.ok()) break;  // not reachable within the budget: the finest allowed
      params = *found;
      if (delivered(params).accuracy >= request.targetAccuracy) break;
      wanted *= 1.0 + kQuantizationBudget;
    }
  }
  const IndexedMesh mesh = tessellate(shape, params);
  Result<protocol::SimplifyResult> encoded = encodedMeshResult(mesh, delivered(params));
  if (!encoded.ok()) return encoded.status();
  protocol::SimplifyResult result = std::move(encoded).value();
  if (request.curvePoints > 0) {
    const int coarsest = tessellationTriangles(shape, chooseTessellation(shape, 0));
    const int finest = std::min(maxTriangles, 16384);
    std::vector<AccuracySample> points;
    const int rungs = std::max(16, static_cast<int>(request.curvePoints));
    for (std::size_t count : geometricLadder(static_cast<std::size_t>(coarsest),
                                             static_cast<std::size_t>(std::max(coarsest, finest)),
                                             std::min(rungs, 64))) {
      const TessellationParams p = chooseTessellation(shape, static_cast<int>(count));
      points.push_back(AccuracySample{delivered(p).accuracy,
                                      static_cast<double>(tessellationTriangles(shape, p))});
    }
    result.curve = curveSamples(std::move(points), request.curvePoints);
  }
  return result;
}

SimplifierService::SimplifierService(ServiceOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

SimplifierService::~SimplifierService() = default;

const ServiceStats& SimplifierService::stats() const { return impl_->stats; }
const ServiceOptions& SimplifierService::options() const { return impl_->options; }

Result<std::size_t> SimplifierService::loadScene(const std::string& path) {
  try {
    Result<LoadedScene*> loaded = impl_->scene(path);
    if (!loaded.ok()) return loaded.status();
    return (*loaded)->objects.size();
  } catch (const std::bad_alloc&) {
    return Status(ErrorCode::kResourceExhausted, "scene " + path + ": out of memory");
  } catch (const std::exception& e) {
    return Status(ErrorCode::kInternal, "scene " + path + ": " + e.what());
  }
}

Status SimplifierService::initializeRendering() {
  try {
    return impl_->ensureRendering();
  } catch (const std::exception& e) {
    return Status(ErrorCode::kInternal, std::string("rendering: ") + e.what());
  }
}

std::string SimplifierService::rendererDescription() const {
  if (!impl_->context || !impl_->impostors) return std::string();
  return std::string(render::backendName(impl_->context->backend())) + ": " +
         impl_->context->rendererName();
}

protocol::SimplifyResult SimplifierService::simplify(const protocol::SimplifyRequest& request) {
  ++impl_->stats.simplifyRequests;
  Result<protocol::SimplifyResult> result = Status(ErrorCode::kInternal, "not handled");
  try {
    const Status valid = protocol::validate(protocol::Message(request));
    if (!valid.ok()) {
      result = valid;
    } else if (!request.sourceMesh.empty()) {
      Result<MeshModel*> model =
          impl_->meshModelForSource(request.sourceMesh, request.keepBoundary);
      result = !model.ok() ? Result<protocol::SimplifyResult>(model.status())
               : request.representation == protocol::RepresentationKind::kHybrid
                   ? impl_->simplifyHybrid(request, **model)
                   : impl_->simplifyMesh(request, **model);
    } else {
      Result<LoadedScene*> loaded = impl_->scene(request.sourcePath);
      Status same = loaded.ok() ? protocol::checkSameScene(
                                      "simplifier", (*loaded)->scene.fingerprint, (*loaded)->path,
                                      "backbone", request.sceneFingerprint, request.sourcePath)
                                : Status();
      if (!loaded.ok()) {
        result = loaded.status();
      } else if (!same.ok()) {
        result = same;
      } else if (const scene::SceneObject* object =
                     scene::findSceneObject((*loaded)->objects, request.objectId)) {
        if (object->shape != nullptr &&
            object->shape->geometry.kind == scene::GeometryKind::kPrimitive) {
          result = request.representation == protocol::RepresentationKind::kHybrid
                       ? Result<protocol::SimplifyResult>(
                             Status(ErrorCode::kUnsupported,
                                    "object " + std::to_string(request.objectId) +
                                        ": analytic primitives have no hybrid representation"))
                       : impl_->simplifyPrimitive(request, object->shape->geometry.primitive);
        } else {
          Result<MeshModel*> model = impl_->meshModelFor(*object, request.keepBoundary);
          const scene::SkinnedAnimation* animation =
              object->shape != nullptr ? object->shape->geometry.animation.get() : nullptr;
          result = !model.ok() ? Result<protocol::SimplifyResult>(model.status())
                   : request.representation == protocol::RepresentationKind::kHybrid
                       ? impl_->simplifyHybrid(request, **model)
                       : impl_->simplifyMesh(request, **model, animation);
        }
      } else {
        result = Status(ErrorCode::kNotFound, "object " + std::to_string(request.objectId) +
                                                  " not in scene " + (*loaded)->path + " (" +
                                                  std::to_string((*loaded)->objects.size()) +
                                                  " objects)");
      }
    }
  } catch (const std::bad_alloc&) {
    result = Status(ErrorCode::kResourceExhausted, "simplify: out of memory");
  } catch (const std::exception& e) {
    result = Status(ErrorCode::kInternal, std::string("simplify: ") + e.what());
  }
  if (result.ok()) {
    result->requestId = request.requestId;
    result->objectId = request.objectId;
    // What we answer must pass the peer's decoder.
    const Status sendable = protocol::validate(protocol::Message(*result));
    if (!sendable.ok()) result = sendable;
  }
  if (!result.ok()) {
    ++impl_->stats.failedRequests;
    protocol::SimplifyResult failed =
        failure<protocol::SimplifyResult>(request.requestId, result.status());
    failed.objectId = request.objectId;
    return failed;
  }
  return std::move(result).value();
}

protocol::ImpostorResult SimplifierService::renderImpostor(
    const protocol::ImpostorRequest& request) {
  ++impl_->stats.impostorRequests;
  Result<protocol::Representation> representation = Status(ErrorCode::kInternal, "not handled");
  try {
    const Status valid = protocol::validate(protocol::Message(request));
    representation =
        valid.ok() ? impl_->impostor(request) : Result<protocol::Representation>(valid);
  } catch (const std::bad_alloc&) {
    representation = Status(ErrorCode::kResourceExhausted, "impostor: out of memory");
  } catch (const std::exception& e) {
    representation = Status(ErrorCode::kInternal, std::string("impostor: ") + e.what());
  }
  protocol::ImpostorResult result;
  result.requestId = request.requestId;
  result.objectIds = request.objectIds;
  if (representation.ok()) {
    result.representation = std::move(representation).value();
    const Status sendable = protocol::validate(protocol::Message(result));
    if (!sendable.ok()) {
      result.representation = protocol::Representation();
      result.status = sendable;
    }
  } else {
    result.status = representation.status();
  }
  if (!result.status.ok()) ++impl_->stats.failedRequests;
  return result;
}

}  // namespace thinlod::simplifier
