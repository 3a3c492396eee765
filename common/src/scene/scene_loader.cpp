// File edge of the scene module: reads the scene file, then the mesh files
// its Inline urls name.
#include <filesystem>
#include <map>

#include "thinlod/common/core/file_bytes.h"
#include "thinlod/common/core/hash.h"
#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::scene {
namespace {

namespace fs = std::filesystem;

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
      if (!isSupportedMeshExtension(url) && !flatten) {
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
