// File edge of the scene module: reads the scene file, then the mesh files
// its Inline urls name.
#include <cmath>
#include <filesystem>
#include <map>

#include "thinlod/common/core/file_bytes.h"
#include "thinlod/common/core/hash.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/common/scene/skinned_import.h"

namespace thinlod::scene {
namespace {

namespace fs = std::filesystem;

// The clip `wanted` names in `model`: "#N" is the N-th clip (0-based), any
// other text a clip's name (the first with that name). kNotFound lists what
// the file has.
Result<std::size_t> findClip(const SkinnedModel& model, const std::string& wanted) {
  if (wanted.size() > 1 && wanted[0] == '#' &&
      wanted.find_first_not_of("0123456789", 1) == std::string::npos && wanted.size() <= 10) {
    const std::size_t index = std::stoul(wanted.substr(1));
    if (index < model.clips.size()) return index;
    return Status(ErrorCode::kNotFound, "animation '" + wanted + "': the file has " +
                                            std::to_string(model.clips.size()) + " clips");
  }
  for (std::size_t i = 0; i < model.clips.size(); ++i) {
    if (model.clips[i].name == wanted) return i;
  }
  std::string names;
  for (std::size_t i = 0; i < model.clips.size() && i < 16; ++i) {
    // The names come from the file: quoted and cut, never trusted as text.
    names += (names.empty() ? "" : ", ") +
             ("#" + std::to_string(i) + " '" + model.clips[i].name.substr(0, 64) + "'");
  }
  return Status(ErrorCode::kNotFound, "animation '" + wanted +
                                          "': no clip of that name (the file has " +
                                          std::to_string(model.clips.size()) + " clips" +
                                          (names.empty() ? std::string() : ": " + names) + ")");
}

// An animated Inline's file: the skinned mesh and the named clip.
Result<std::pair<IndexedMesh, SkinnedAnimation>> loadAnimatedMesh(const std::string& path,
                                                                  const std::string& clip,
                                                                  const ImportLimits& limits) {
  SkinnedImportLimits skinnedLimits;
  skinnedLimits.files = limits;
  Result<SkinnedModel> model = importSkinnedModel(path, skinnedLimits);
  if (!model.ok()) return model.status();
  Result<std::size_t> index = findClip(*model, clip);
  if (!index.ok()) return Status(index.status().code(), path + ": " + index.status().message());
  // The importer validated all of it; checked again here because the scene
  // hands these to the backbone's clock and the frontend's skinning.
  THINLOD_RETURN_IF_ERROR(model->mesh.validate(path));
  THINLOD_RETURN_IF_ERROR(model->skeleton.validate(path));
  THINLOD_RETURN_IF_ERROR(anim::validateSkin(model->skin, model->mesh.vertexCount(),
                                             model->skeleton.bones.size(), path));
  SkinnedAnimation animation;
  animation.clip = std::move(model->clips[*index]);
  THINLOD_RETURN_IF_ERROR(animation.clip.validate(model->skeleton, path));
  animation.skeleton = std::move(model->skeleton);
  animation.skin = std::move(model->skin);
  animation.palette = anim::compactSkin(animation.skin);
  animation.motionBound =
      anim::sampledMaxDeviationFromBind(animation.skeleton, animation.clip, model->mesh.positions,
                                        animation.skin, SkinnedAnimation::kMotionSamples);
  if (!std::isfinite(animation.motionBound)) {
    return Status(ErrorCode::kInvalidArgument,
                  path + ": animation '" + clip + "' moves a vertex to a non-finite position");
  }
  return std::make_pair(std::move(model->mesh), std::move(animation));
}

}  // namespace

// Urls name files below a search directory: no scheme, no absolute path,
// no "..".
Status checkUrl(const std::string& url, const std::string& where) {
  if (url.empty()) return Status(ErrorCode::kInvalidArgument, where + ": empty url");
  if (url.find("://") != std::string::npos) {
    return Status(ErrorCode::kUnsupported, where + ": url '" + url + "' has a scheme; only " +
                                               "relative file names are supported");
  }
  const fs::path p(url);
  if (p.is_absolute() || p.has_root_name()) {
    return Status(ErrorCode::kInvalidArgument,
                  where + ": url '" + url + "' is absolute; use a relative name and a search path");
  }
  for (const fs::path& part : p) {
    if (part == "..") {
      return Status(ErrorCode::kInvalidArgument, where + ": url '" + url + "' contains '..'");
    }
  }
  return Status();
}

namespace {

void forEachShape(const Node& node, std::map<const Node*, bool>& seen,
                  std::vector<ShapeNode*>& out) {
  if (!seen.emplace(&node, true).second) return;
  if (node.kind == NodeKind::kShape) out.push_back(const_cast<ShapeNode*>(node.as<ShapeNode>()));
  for (const NodePtr& c : node.children) forEachShape(*c, seen, out);
}

template <typename T>
std::uint64_t hashVector(const std::vector<T>& v, std::uint64_t seed) {
  const std::uint64_t count = v.size();
  seed = fnv1a64(&count, sizeof count, seed);
  return v.empty() ? seed : fnv1a64(v.data(), v.size() * sizeof(T), seed);
}

}  // namespace

std::uint64_t sceneFingerprint(const std::string& text, const Scene& scene) {
  std::uint64_t hash = fnv1a64(text.data(), text.size());
  std::map<const Node*, bool> seen;
  std::vector<ShapeNode*> shapes;
  for (const NodePtr& root : scene.roots) forEachShape(*root, seen, shapes);
  std::map<const IndexedMesh*, bool> hashed;
  for (const ShapeNode* shape : shapes) {
    const IndexedMesh* mesh =
        shape->geometry.kind == GeometryKind::kMeshFile ? shape->geometry.mesh.get() : nullptr;
    if (mesh == nullptr || !hashed.emplace(mesh, true).second) continue;
    // Positions and triangles only: the geometry both daemons must agree on
    // to address the same objects. (Two loads of the gallery once hashed
    // differently through the normals: OpenMesh left the normals of vertices
    // it copies for non-manifold faces uninitialised; mesh_io.cpp now
    // defines them, see copyAttributesToNonManifoldCopies.)
    hash = hashVector(mesh->positions, hash);
    hash = hashVector(mesh->indices, hash);
    // A skinned mesh's skin too: the frontend deforms the simplifier's levels with it.
    if (shape->geometry.animation) hash = hashVector(shape->geometry.animation->skin, hash);
  }
  return hash == 0 ? 1 : hash;  // 0 means "no scene"
}

void resolveTextures(Scene& scene, const std::string& sceneDirectory) {
  std::map<const Node*, bool> seen;
  std::vector<ShapeNode*> shapes;
  for (const NodePtr& root : scene.roots) forEachShape(*root, seen, shapes);
  for (ShapeNode* shape : shapes) {
    Appearance& appearance = shape->appearance;
    if (appearance.textureUrl.empty() || !appearance.texturePath.empty()) continue;
    // Relative to the file that names it: the imported mesh file, else the scene.
    const fs::path base = shape->geometry.resolvedPath.empty()
                              ? fs::path(sceneDirectory)
                              : fs::path(shape->geometry.resolvedPath).parent_path();
    // The url, then the alternatives an ImageTexture listed: the first file that exists wins.
    std::vector<std::string> urls{appearance.textureUrl};
    urls.insert(urls.end(), appearance.textureAlternatives.begin(),
                appearance.textureAlternatives.end());
    std::string missing;
    for (const std::string& textureUrl : urls) {
      const std::string where = "texture '" + textureUrl + "'";
      if (textureUrl[0] == '*') {
        scene.warnings.push_back(where + ": embedded textures are not read yet; drawn untextured");
        missing.clear();
        break;
      }
      const Status url = checkUrl(textureUrl, where);
      if (!url.ok()) {
        scene.warnings.push_back(url.message() + "; drawn untextured");
        missing.clear();
        break;
      }
      const fs::path candidate = (base.empty() ? fs::path(".") : base) / textureUrl;
      std::error_code ec;
      if (fs::is_regular_file(candidate, ec)) {
        appearance.texturePath = candidate.string();
        missing.clear();
        break;
      }
      missing += (missing.empty() ? "" : ", ") + candidate.string();
    }
    if (!missing.empty()) {
      scene.warnings.push_back("texture '" + appearance.textureUrl + "': no file " + missing +
                               "; drawn untextured");
    }
  }
}

Status resolveMeshes(Scene& scene, const std::string& sceneDirectory,
                     const SceneLoadOptions& options) {
  std::vector<std::string> directories = options.meshSearchPaths;
  directories.push_back(sceneDirectory.empty() ? std::string(".") : sceneDirectory);
  std::map<const Node*, bool> seen;
  std::vector<ShapeNode*> shapes;
  for (const NodePtr& root : scene.roots) forEachShape(*root, seen, shapes);

  std::map<std::string, std::shared_ptr<const IndexedMesh>> loaded;  // by resolved path
  std::map<std::string, std::vector<std::string>> warningsOf;
  std::map<std::string, std::pair<std::shared_ptr<const IndexedMesh>,
                                  std::shared_ptr<const SkinnedAnimation>>>
      animated;  // by resolved path and clip
  for (ShapeNode* shape : shapes) {
    Geometry& g = shape->geometry;
    if (g.kind != GeometryKind::kMeshFile || g.mesh) continue;
    const std::string where = scene.sourceName + ":" + std::to_string(shape->sourceLocation.line) +
                              ":" + std::to_string(shape->sourceLocation.column);
    std::vector<std::string> tried;
    for (const std::string& url : g.urls) {
      THINLOD_RETURN_IF_ERROR(checkUrl(url, where));
      // .obj stays with the mesh loader; .gltf .glb .dae .fbx are imported
      // and flattened (scene_import.h).
      const bool flatten = !isSupportedMeshExtension(url) && isImportedSceneExtension(url);
      // An animated Inline goes to Assimp whatever the extension (.x, .smd, ...).
      if (g.animationClip.empty() && !isSupportedMeshExtension(url) && !flatten) {
        return Status(ErrorCode::kUnsupported,
                      where + ": url '" + url +
                          "' is not a mesh file (obj, ply, off, stl, gltf, glb, dae, fbx)");
      }
      for (const std::string& dir : directories) {
        const std::string candidate = (fs::path(dir) / url).lexically_normal().string();
        std::error_code ec;
        if (!fs::is_regular_file(candidate, ec)) {
          tried.push_back(candidate);
          continue;
        }
        if (!g.animationClip.empty()) {
          // Skinned: its own mesh (mesh space, not flattened), cached per clip.
          const std::string key = candidate + "\n" + g.animationClip;
          auto cached = animated.find(key);
          if (cached == animated.end()) {
            auto loadedAnimation =
                loadAnimatedMesh(candidate, g.animationClip, options.importLimits);
            if (!loadedAnimation.ok()) {
              return Status(loadedAnimation.status().code(),
                            where + ": " + loadedAnimation.status().message());
            }
            cached = animated
                         .emplace(key, std::make_pair(std::make_shared<const IndexedMesh>(
                                                          std::move(loadedAnimation->first)),
                                                      std::make_shared<const SkinnedAnimation>(
                                                          std::move(loadedAnimation->second))))
                         .first;
          }
          g.mesh = cached->second.first;
          g.animation = cached->second.second;
          g.resolvedPath = candidate;
          break;
        }
        auto cached = loaded.find(candidate);
        if (cached == loaded.end()) {
          Result<LoadedMesh> mesh = flatten ? importSceneAsMesh(candidate, options.importLimits)
                                            : loadMeshFile(candidate, options.meshOptions);
          if (!mesh.ok()) {
            return Status(mesh.status().code(), where + ": " + mesh.status().message());
          }
          for (const std::string& w : mesh->warnings) scene.warnings.push_back(w);
          warningsOf[candidate] = mesh->warnings;
          cached =
              loaded.emplace(candidate, std::make_shared<const IndexedMesh>(std::move(mesh->mesh)))
                  .first;
        }
        g.mesh = cached->second;
        g.resolvedPath = candidate;
        g.loadWarnings = warningsOf[candidate];
        break;
      }
      if (g.mesh) break;
    }
    if (!g.mesh) {
      std::string list;
      for (const std::string& t : tried) list += (list.empty() ? "" : ", ") + t;
      return Status(ErrorCode::kNotFound, where + ": mesh not found (tried " + list + ")");
    }
  }
  return Status();
}

Result<Scene> loadSceneFile(const std::string& path, const SceneLoadOptions& options) {
  const bool imported = isImportedSceneExtension(path);
  const std::uint64_t maxBytes =
      imported ? options.importLimits.maxFileBytes : std::uint64_t{options.limits.maxBytes};
  Result<std::string> read = readFileBounded(path, maxBytes);
  if (!read.ok()) return read.status();
  const std::string& text = *read;
  Result<Scene> scene =
      imported ? importScene(path, options.importLimits) : parseScene(text, path, options.limits);
  if (!scene.ok()) return scene.status();
  const std::string directory = fs::path(path).parent_path().string();
  if (!imported) THINLOD_RETURN_IF_ERROR(resolveMeshes(*scene, directory, options));
  resolveTextures(*scene, directory);
  scene->fingerprint = sceneFingerprint(text, *scene);
  return scene;
}

}  // namespace thinlod::scene
