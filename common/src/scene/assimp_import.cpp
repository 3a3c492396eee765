// Assimp edge of the scene module (contract in scene_import.h). Assimp types
// stay in this file; everything it hands back is checked before use.
#include <assimp/DefaultIOSystem.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <exception>
#include <filesystem>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

#include "import_precheck.h"
#include "mesh/mesh_precheck.h"
#include "thinlod/common/core/file_bytes.h"
#include "thinlod/common/scene/scene_import.h"
#include "thinlod/common/scene/skinned_import.h"

namespace thinlod::scene {
namespace {

namespace fs = std::filesystem;

std::string lowerExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// Refuses, before a byte is read, any file above the per-file limit and any
// new file that would push the import's total above its limit. Assimp opens
// some files more than once (format probing), so a path counts once.
class BoundedIOSystem : public Assimp::DefaultIOSystem {
 public:
  explicit BoundedIOSystem(const ImportLimits& limits) : limits_(limits) {}

  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (file == nullptr || mode == nullptr) return nullptr;
    if (std::string(mode).find_first_of("wa+") != std::string::npos) return nullptr;  // read only
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(file, ec);
    if (ec) return nullptr;  // missing: Assimp reports it
    if (size > limits_.maxFileBytes) {
      refusal_ = std::string(file) + ": " + std::to_string(size) + " bytes exceed the limit of " +
                 std::to_string(limits_.maxFileBytes);
      return nullptr;
    }
    const std::string key = fs::path(file).lexically_normal().string();
    if (counted_.insert(key).second) {
      if (size > limits_.maxTotalBytes - std::min<std::uint64_t>(total_, limits_.maxTotalBytes)) {
        refusal_ = std::string(file) + ": the import's files would exceed " +
                   std::to_string(limits_.maxTotalBytes) + " bytes in total";
        return nullptr;
      }
      total_ += size;
    }
    return Assimp::DefaultIOSystem::Open(file, mode);
  }

  const std::string& refusal() const { return refusal_; }

 private:
  ImportLimits limits_;
  std::set<std::string> counted_;
  std::uint64_t total_ = 0;
  std::string refusal_;
};

bool finite3(const aiVector3D& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

glm::mat4 toGlm(const aiMatrix4x4& m) {
  // aiMatrix4x4 is row-major (a1..a4 is the first row); glm is column-major.
  glm::mat4 out;
  for (int row = 0; row < 4; ++row) {
    for (int col = 0; col < 4; ++col) out[col][row] = m[static_cast<unsigned>(row)][col];
  }
  return out;
}

bool isIdentity(const aiMatrix4x4& m) {
  for (unsigned row = 0; row < 4; ++row) {
    for (unsigned col = 0; col < 4; ++col) {
      if (m[row][col] != (row == col ? 1.0f : 0.0f)) return false;
    }
  }
  return true;
}

glm::vec3 clampColor(const aiColor4D& c) {
  return glm::clamp(glm::vec3(c.r, c.g, c.b), glm::vec3(0.0f), glm::vec3(1.0f));
}

bool finiteColor(const aiColor4D& c) {
  return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b) && std::isfinite(c.a);
}

// What the tree walk found before any mesh is copied.
struct TreeCensus {
  std::uint64_t triangleInstances = 0;
  std::size_t nodeInstances = 0;
  std::vector<bool> meshUsed;
};

// glTF pre-check, before Assimp sees the file. Assimp trusts a .glb header's
// declared length and allocates it (a 22-byte file declaring 4 GiB took 4 GB
// of memory), and it drops faces whose indices are out of range with only a
// log line. So: the .glb header and chunks must fit the file, and the
// triangles the JSON declares are counted here, to be compared with what
// Assimp returns.
constexpr int kMaxJsonDepth = 4096;

struct GltfDeclared {
  std::uint64_t triangles = 0;  // mode-4 primitives
  bool onlyTriangleLists = true;
};

std::uint32_t le32(const std::string& b, std::size_t at) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(b[at])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 1])) << 8 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 2])) << 16 |
         static_cast<std::uint32_t>(static_cast<unsigned char>(b[at + 3])) << 24;
}

// The longest media type a glTF data uri may name before ";base64,".
constexpr std::size_t kMaxDataUriMediaTypeLength = 64;

Result<GltfDeclared> precheckGltf(const std::string& path, const std::string& bytes,
                                  const ImportLimits& limits) {
  std::string json;
  if (lowerExtension(path) == ".glb") {
    const std::string& b = bytes;
    if (b.size() < 20 || b.compare(0, 4, "glTF") != 0) {
      return Status(ErrorCode::kParseError, path + ": not a binary glTF (no 'glTF' header)");
    }
    if (le32(b, 4) != 2) {
      return Status(ErrorCode::kUnsupported,
                    path + ": binary glTF version " + std::to_string(le32(b, 4)) + " (only 2)");
    }
    if (le32(b, 8) != b.size()) {
      return Status(ErrorCode::kParseError, path + ": header declares " +
                                                std::to_string(le32(b, 8)) + " bytes, file has " +
                                                std::to_string(b.size()));
    }
    // Every chunk (8-byte header + data) must lie inside the file.
    for (std::size_t at = 12; at < b.size();) {
      if (b.size() - at < 8)
        return Status(ErrorCode::kParseError, path + ": truncated chunk header");
      const std::uint64_t length = le32(b, at);
      if (length > b.size() - at - 8) {
        return Status(ErrorCode::kParseError, path + ": chunk at byte " + std::to_string(at) +
                                                  " declares " + std::to_string(length) +
                                                  " bytes past the end of the file");
      }
      if (at == 12) {
        if (le32(b, at + 4) != 0x4E4F534Au) {
          return Status(ErrorCode::kParseError, path + ": first chunk is not JSON");
        }
        json = b.substr(at + 8, static_cast<std::size_t>(length));
      }
      at += 8 + static_cast<std::size_t>(length);
    }
  } else {
    json = bytes;
  }
  // A NUL byte ends the text for nlohmann's parser but not for Assimp's, so
  // the two read different documents ("{}\0..." passed, and Assimp leaked
  // on what followed: fuzz finding 36). JSON text has no raw NUL.
  if (json.find('\0') != std::string::npos) {
    return Status(ErrorCode::kParseError, path + ": a NUL byte in the glTF JSON");
  }
  // Nesting depth is bounded here (nlohmann's parser keeps its own stack;
  // the importer's JSON reader need not).
  bool tooDeep = false;
  const nlohmann::json::parser_callback_t depthCheck =
      [&tooDeep](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
        tooDeep = tooDeep || depth > kMaxJsonDepth;
        return !tooDeep;
      };
  const nlohmann::json doc = nlohmann::json::parse(json, depthCheck, /*allow_exceptions=*/false);
  if (tooDeep) {
    return Status(ErrorCode::kResourceExhausted,
                  path + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth));
  }
  if (doc.is_discarded() || !doc.is_object()) {
    return Status(ErrorCode::kParseError, path + ": not valid glTF JSON");
  }
  // Embedded data (buffers' and images' "data:...;base64," uris): Assimp's
  // base64 decoder leaked its output buffer when it met a character outside
  // the alphabet (fuzz finding 30), so the text must be plain base64: the
  // 64 characters, '=' only as the last one or two of a length divisible
  // by 4.
  for (const char* array : {"buffers", "images"}) {
    const auto items = doc.find(array);
    if (items == doc.end() || !items->is_array()) continue;
    for (const nlohmann::json& item : *items) {
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string& uri = item["uri"].get_ref<const std::string&>();
      if (uri.rfind("data:", 0) != 0) continue;
      const std::size_t marker = uri.find(";base64,");
      if (marker == std::string::npos) continue;  // not base64: Assimp refuses it itself
      // Assimp's data-uri reader leaked when "data:<media type>;base64," ran
      // to 128 characters (a 115-character media type: fuzz finding 37). Real
      // media types are short ("application/octet-stream" is 24).
      if (marker - 5 > kMaxDataUriMediaTypeLength) {
        return Status(ErrorCode::kParseError,
                      path + ": an embedded " + std::string(array) + " uri's media type has " +
                          std::to_string(marker - 5) + " characters (at most " +
                          std::to_string(kMaxDataUriMediaTypeLength) + ")");
      }
      if (!detail::isPlainBase64(std::string_view(uri).substr(marker + 8))) {
        return Status(ErrorCode::kParseError,
                      path + ": an embedded " + std::string(array) +
                          " uri is not plain base64 (characters outside the alphabet, "
                          "misplaced '=' or a length not divisible by 4)");
      }
    }
  }
  // The node graph: Assimp recurses over it without a depth limit (a chain
  // of 100 000 nodes overflowed the stack) and follows children indices as
  // given. Indices out of range are left to Assimp's own checks.
  const auto nodes = doc.find("nodes");
  if (nodes != doc.end() && nodes->is_array()) {
    std::vector<std::vector<std::uint32_t>> children(nodes->size());
    std::vector<bool> hasParent(nodes->size(), false);
    for (std::size_t n = 0; n < nodes->size(); ++n) {
      const nlohmann::json& node = (*nodes)[n];
      if (!node.is_object() || !node.contains("children") || !node["children"].is_array()) continue;
      for (const nlohmann::json& c : node["children"]) {
        if (!c.is_number_unsigned() || c.get<std::uint64_t>() >= nodes->size()) continue;
        children[n].push_back(static_cast<std::uint32_t>(c.get<std::uint64_t>()));
        hasParent[children[n].back()] = true;
      }
    }
    std::vector<std::uint32_t> roots;
    const auto scenes = doc.find("scenes");
    if (scenes != doc.end() && scenes->is_array()) {
      for (const nlohmann::json& scene : *scenes) {
        if (!scene.is_object() || !scene.contains("nodes") || !scene["nodes"].is_array()) continue;
        for (const nlohmann::json& r : scene["nodes"]) {
          if (r.is_number_unsigned() && r.get<std::uint64_t>() < nodes->size()) {
            roots.push_back(static_cast<std::uint32_t>(r.get<std::uint64_t>()));
          }
        }
      }
    }
    for (std::uint32_t n = 0; roots.empty() && n < nodes->size(); ++n) {
      if (!hasParent[n]) roots.push_back(n);  // no scene: every parentless node
    }
    THINLOD_RETURN_IF_ERROR(detail::checkNodeGraph(path, children, roots, limits));
  }
  GltfDeclared declared;
  const auto accessors = doc.find("accessors");
  auto accessorCount = [&](const nlohmann::json& index) -> std::optional<std::uint64_t> {
    if (!index.is_number_unsigned() || accessors == doc.end() || !accessors->is_array()) {
      return std::nullopt;
    }
    const std::uint64_t i = index.get<std::uint64_t>();
    if (i >= accessors->size()) return std::nullopt;
    const nlohmann::json& a = (*accessors)[static_cast<std::size_t>(i)];
    if (!a.is_object() || !a.contains("count") || !a["count"].is_number_unsigned()) {
      return std::nullopt;
    }
    return a["count"].get<std::uint64_t>();
  };
  const auto meshes = doc.find("meshes");
  if (meshes == doc.end() || !meshes->is_array()) return declared;  // Assimp judges the rest
  for (const nlohmann::json& mesh : *meshes) {
    if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) {
      continue;
    }
    for (const nlohmann::json& primitive : mesh["primitives"]) {
      if (!primitive.is_object()) continue;
      const nlohmann::json mode = primitive.value("mode", nlohmann::json(4));
      if (!mode.is_number_unsigned() || mode.get<std::uint64_t>() != 4) {
        declared.onlyTriangleLists = false;
        continue;
      }
      std::optional<std::uint64_t> count;
      if (primitive.contains("indices")) {
        count = accessorCount(primitive["indices"]);
      } else if (primitive.contains("attributes") && primitive["attributes"].is_object() &&
                 primitive["attributes"].contains("POSITION")) {
        count = accessorCount(primitive["attributes"]["POSITION"]);
      }
      if (!count) {
        declared.onlyTriangleLists = false;  // malformed: Assimp's checks decide
        continue;
      }
      declared.triangles += *count / 3;
      if (declared.triangles > limits.maxTriangles) {
        return Status(ErrorCode::kResourceExhausted, path + ": the meshes declare more than " +
                                                         std::to_string(limits.maxTriangles) +
                                                         " triangles");
      }
    }
  }
  return declared;
}

class Converter {
 public:
  Converter(const std::string& path, const aiScene& ai, const ImportLimits& limits,
            std::optional<GltfDeclared> declared)
      : path_(path), ai_(ai), limits_(limits), declared_(declared) {}

  Result<Scene> run() {
    if (ai_.mRootNode == nullptr) return fail(ErrorCode::kInvalidArgument, "no root node");
    if (ai_.mNumMeshes > 0 && ai_.mMeshes == nullptr) {
      return fail(ErrorCode::kInternal, "mesh table missing");
    }
    if (declared_ && declared_->onlyTriangleLists) {
      std::uint64_t returned = 0;
      for (unsigned i = 0; i < ai_.mNumMeshes; ++i) {
        if (ai_.mMeshes[i] != nullptr &&
            (ai_.mMeshes[i]->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) {
          returned += ai_.mMeshes[i]->mNumFaces;
        }
      }
      if (returned < declared_->triangles) {
        return fail(ErrorCode::kInvalidArgument,
                    std::to_string(declared_->triangles - returned) + " of " +
                        std::to_string(declared_->triangles) +
                        " declared triangles were dropped (indices out of range or bad data)");
      }
    }
    TreeCensus census;
    census.meshUsed.assign(ai_.mNumMeshes, false);
    THINLOD_RETURN_IF_ERROR(countTree(*ai_.mRootNode, 1, census));
    if (census.triangleInstances == 0) {
      return fail(ErrorCode::kInvalidArgument, "contains no triangles");
    }
    if (census.triangleInstances > limits_.maxTriangles) {
      return fail(ErrorCode::kResourceExhausted,
                  std::to_string(census.triangleInstances) +
                      " triangles (over all mesh instances) exceed the limit of " +
                      std::to_string(limits_.maxTriangles));
    }
    std::uint64_t vertices = 0;
    for (unsigned i = 0; i < ai_.mNumMeshes; ++i) {
      if (census.meshUsed[i]) vertices += ai_.mMeshes[i]->mNumVertices;
    }
    if (vertices > limits_.maxVertices) {
      return fail(ErrorCode::kResourceExhausted, std::to_string(vertices) +
                                                     " vertices exceed the limit of " +
                                                     std::to_string(limits_.maxVertices));
    }

    scene_.sourceName = path_;
    Result<NodePtr> root = convertNode(*ai_.mRootNode);
    if (!root.ok()) return root.status();
    scene_.roots.push_back(std::move(*root));
    scene_.nodeCount = nextId_ - 1;
    if (ai_.mNumCameras > 0) warn(std::to_string(ai_.mNumCameras) + " camera(s) ignored");
    if (ai_.mNumLights > 0) warn(std::to_string(ai_.mNumLights) + " light(s) ignored");
    if (ai_.mNumAnimations > 0) warn(std::to_string(ai_.mNumAnimations) + " animation(s) ignored");
    return std::move(scene_);
  }

 private:
  Status fail(ErrorCode code, const std::string& problem) const {
    return Status(code, path_ + ": " + problem);
  }
  void warn(const std::string& what) { scene_.warnings.push_back(path_ + ": " + what); }

  // Walks the tree as it will be converted: bounds depth and node count and
  // sums triangles per mesh reference, touching no vertex data.
  Status countTree(const aiNode& node, int depth, TreeCensus& census) {
    if (depth > limits_.maxDepth) {
      return fail(ErrorCode::kResourceExhausted,
                  "node tree deeper than " + std::to_string(limits_.maxDepth));
    }
    if (++census.nodeInstances > limits_.maxNodes) {
      return fail(ErrorCode::kResourceExhausted,
                  "more than " + std::to_string(limits_.maxNodes) + " nodes");
    }
    if (node.mNumMeshes > 0 && node.mMeshes == nullptr) {
      return fail(ErrorCode::kInternal, "node mesh list missing");
    }
    for (unsigned i = 0; i < node.mNumMeshes; ++i) {
      const unsigned m = node.mMeshes[i];
      if (m >= ai_.mNumMeshes || ai_.mMeshes[m] == nullptr) {
        return fail(ErrorCode::kInvalidArgument, "node '" + std::string(node.mName.C_Str()) +
                                                     "' names mesh " + std::to_string(m) + " of " +
                                                     std::to_string(ai_.mNumMeshes));
      }
      const aiMesh& mesh = *ai_.mMeshes[m];
      if ((mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;  // dropped
      census.triangleInstances += mesh.mNumFaces;
      census.meshUsed[m] = true;
    }
    if (node.mNumChildren > 0 && node.mChildren == nullptr) {
      return fail(ErrorCode::kInternal, "node child list missing");
    }
    for (unsigned i = 0; i < node.mNumChildren; ++i) {
      if (node.mChildren[i] == nullptr) return fail(ErrorCode::kInternal, "null child node");
      THINLOD_RETURN_IF_ERROR(countTree(*node.mChildren[i], depth + 1, census));
    }
    return Status();
  }

  Result<NodePtr> transformFor(const aiNode& node) {
    const aiMatrix4x4& m = node.mTransformation;
    if (isIdentity(m)) return NodePtr(std::make_shared<GroupNode>());
    const glm::mat4 target = toGlm(m);
    float magnitude = 1.0f;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) {
        if (!std::isfinite(target[c][r])) {
          return fail(ErrorCode::kInvalidArgument,
                      "node '" + std::string(node.mName.C_Str()) + "' has a non-finite matrix");
        }
        magnitude = std::max(magnitude, std::fabs(target[c][r]));
      }
    }
    aiVector3D scaling, axis, position;
    ai_real angle = 0;
    m.Decompose(scaling, axis, angle, position);
    auto transform = std::make_shared<TransformNode>();
    transform->translation = glm::vec3(position.x, position.y, position.z);
    transform->scale = glm::vec3(scaling.x, scaling.y, scaling.z);
    const float axisLength = std::sqrt(axis.x * axis.x + axis.y * axis.y + axis.z * axis.z);
    if (std::isfinite(angle) && std::isfinite(axisLength) && axisLength > 1e-6f) {
      transform->rotation = glm::vec4(axis.x / axisLength, axis.y / axisLength, axis.z / axisLength,
                                      static_cast<float>(angle));
    }
    // The decomposition is exact only for T * R * S; a shear or projective
    // row does not survive it, and TransformNode cannot hold one.
    const glm::mat4 rebuilt = transform->localTransform();
    float error = 0.0f;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) error = std::max(error, std::fabs(rebuilt[c][r] - target[c][r]));
    }
    if (!(error <= 1e-4f * magnitude)) {
      return fail(ErrorCode::kUnsupported,
                  "node '" + std::string(node.mName.C_Str()) +
                      "' has a sheared, projective or singular matrix (only translation * "
                      "rotation * scale is supported)");
    }
    return NodePtr(std::move(transform));
  }

  Result<NodePtr> convertNode(const aiNode& node) {
    Result<NodePtr> made = transformFor(node);
    if (!made.ok()) return made.status();
    NodePtr out = std::move(*made);
    out->id = nextId_++;
    for (unsigned i = 0; i < node.mNumMeshes; ++i) {
      const unsigned m = node.mMeshes[i];
      if ((ai_.mMeshes[m]->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
      auto known = shapes_.find(m);
      if (known == shapes_.end()) {
        Result<NodePtr> shape = convertShape(m);
        if (!shape.ok()) return shape.status();
        known = shapes_.emplace(m, std::move(*shape)).first;
      }
      out->children.push_back(known->second);
    }
    for (unsigned i = 0; i < node.mNumChildren; ++i) {
      Result<NodePtr> child = convertNode(*node.mChildren[i]);
      if (!child.ok()) return child.status();
      out->children.push_back(std::move(*child));
    }
    return out;
  }

  Result<NodePtr> convertShape(unsigned meshIndex) {
    const aiMesh& src = *ai_.mMeshes[meshIndex];
    const std::string what =
        path_ + ": mesh " + std::to_string(meshIndex) +
        (src.mName.length > 0 ? " '" + std::string(src.mName.C_Str()) + "'" : std::string());
    if (src.mNumVertices > 0 && src.mVertices == nullptr) {
      return Status(ErrorCode::kInvalidArgument, what + ": no positions");
    }
    if (src.mNumFaces > 0 && src.mFaces == nullptr) {
      return Status(ErrorCode::kInvalidArgument, what + ": no faces");
    }
    auto mesh = std::make_shared<IndexedMesh>();
    mesh->positions.reserve(src.mNumVertices);
    for (unsigned v = 0; v < src.mNumVertices; ++v) {
      const aiVector3D& p = src.mVertices[v];
      mesh->positions.emplace_back(p.x, p.y, p.z);
    }
    if (src.HasNormals()) {
      bool usable = true;
      mesh->normals.reserve(src.mNumVertices);
      for (unsigned v = 0; v < src.mNumVertices && usable; ++v) {
        const aiVector3D& n = src.mNormals[v];
        const float length = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
        usable = finite3(n) && length > 1e-20f;
        mesh->normals.push_back(glm::vec3(n.x, n.y, n.z) / (usable ? length : 1.0f));
      }
      if (!usable) {
        mesh->normals.clear();
        warn("mesh " + std::to_string(meshIndex) +
             ": zero-length or non-finite normals; normals recomputed");
      }
    }
    if (src.HasTextureCoords(0)) {
      mesh->uvs.reserve(src.mNumVertices);
      for (unsigned v = 0; v < src.mNumVertices; ++v) {
        mesh->uvs.emplace_back(src.mTextureCoords[0][v].x, src.mTextureCoords[0][v].y);
      }
    }
    if (src.HasVertexColors(0)) {
      mesh->colors.reserve(src.mNumVertices);
      for (unsigned v = 0; v < src.mNumVertices; ++v) {
        const aiColor4D& c = src.mColors[0][v];
        if (!finiteColor(c)) {
          return Status(ErrorCode::kInvalidArgument,
                        what + ": vertex " + std::to_string(v) + " has a non-finite colour");
        }
        auto byte = [](float x) {
          return static_cast<std::uint8_t>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255.0f));
        };
        mesh->colors.push_back({byte(c.r), byte(c.g), byte(c.b), byte(c.a)});
      }
    }
    mesh->indices.reserve(std::size_t{src.mNumFaces} * 3);
    for (unsigned f = 0; f < src.mNumFaces; ++f) {
      const aiFace& face = src.mFaces[f];
      if (face.mNumIndices != 3) continue;  // a point or line left in a mixed mesh
      if (face.mIndices == nullptr) {
        return Status(ErrorCode::kInvalidArgument,
                      what + ": face " + std::to_string(f) + " has no indices");
      }
      for (unsigned k = 0; k < 3; ++k) mesh->indices.push_back(face.mIndices[k]);
    }
    // Indices in range, attribute sizes, finiteness: named on failure.
    THINLOD_RETURN_IF_ERROR(mesh->validate(what));
    if (mesh->normals.empty()) mesh->computeNormals();

    auto shape = std::make_shared<ShapeNode>();
    shape->id = nextId_++;
    shape->geometry.kind = GeometryKind::kMeshFile;
    shape->geometry.urls = {fs::path(path_).filename().string()};
    shape->geometry.resolvedPath = path_;
    shape->geometry.mesh = std::move(mesh);
    shape->appearance.hasMaterial = true;
    if (src.mMaterialIndex < ai_.mNumMaterials && ai_.mMaterials != nullptr &&
        ai_.mMaterials[src.mMaterialIndex] != nullptr) {
      THINLOD_RETURN_IF_ERROR(convertMaterial(*ai_.mMaterials[src.mMaterialIndex],
                                              src.mMaterialIndex, shape->appearance));
    }
    return NodePtr(std::move(shape));
  }

  Status convertMaterial(const aiMaterial& src, unsigned index, Appearance& out) {
    Material& m = out.material;
    aiColor4D color;
    if (src.Get(AI_MATKEY_BASE_COLOR, color) == AI_SUCCESS ||
        src.Get(AI_MATKEY_COLOR_DIFFUSE, color) == AI_SUCCESS) {
      if (!finiteColor(color)) return badMaterial(index, "base colour");
      m.diffuseColor = clampColor(color);
    }
    if (src.Get(AI_MATKEY_COLOR_EMISSIVE, color) == AI_SUCCESS) {
      if (!finiteColor(color)) return badMaterial(index, "emissive colour");
      m.emissiveColor = clampColor(color);
    }
    if (src.Get(AI_MATKEY_COLOR_SPECULAR, color) == AI_SUCCESS) {
      if (!finiteColor(color)) return badMaterial(index, "specular colour");
      m.specularColor = clampColor(color);
    }
    float value = 0.0f;
    if (src.Get(AI_MATKEY_SHININESS, value) == AI_SUCCESS) {
      if (!std::isfinite(value)) return badMaterial(index, "shininess");
      // Phong exponent -> VRML shininess (exponent = 128 * shininess).
      m.shininess = std::clamp(value / 128.0f, 0.0f, 1.0f);
    }
    if (src.Get(AI_MATKEY_OPACITY, value) == AI_SUCCESS) {
      if (!std::isfinite(value)) return badMaterial(index, "opacity");
      m.transparency = 1.0f - std::clamp(value, 0.0f, 1.0f);
    }
    for (aiTextureType type : {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE}) {
      aiString texture;
      if (src.GetTextureCount(type) > 0 && src.GetTexture(type, 0, &texture) == AI_SUCCESS &&
          texture.length > 0) {
        out.textureUrl = texture.C_Str();
        break;
      }
    }
    return Status();
  }

  Status badMaterial(unsigned index, const char* field) const {
    return fail(ErrorCode::kInvalidArgument,
                "material " + std::to_string(index) + " has a non-finite " + field);
  }

  std::string path_;
  const aiScene& ai_;
  ImportLimits limits_;
  std::optional<GltfDeclared> declared_;
  Scene scene_;
  std::uint32_t nextId_ = 1;
  std::map<unsigned, NodePtr> shapes_;  // by Assimp mesh index: one Shape per mesh
};

const char* formatName(const std::string& ext) {
  if (ext == ".gltf" || ext == ".glb") return "glTF2";
  if (ext == ".dae") return "Collada";
  if (ext == ".fbx") return "FBX";
  if (ext == ".obj") return "OBJ";
  return "Assimp";  // skinned formats (.x, .smd, .md5mesh, ...): importSkinnedModel
}

// The one front door to Assimp (importScene and importSkinnedModel): the
// file's size against the limits, the glTF and Collada pre-checks, Assimp
// behind the bounded IO system with its logging off, its failures and
// exceptions as a Status naming the file; `convert(aiScene, declared)` turns
// what Assimp returned into T inside the same guard.
template <typename T, typename Convert>
Result<T> readThroughAssimp(const std::string& path, const ImportLimits& limits,
                            Convert convert) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    return Status(ErrorCode::kNotFound, path + ": no such file");
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return Status(ErrorCode::kIoError, path + ": cannot stat: " + ec.message());
  if (size == 0) return Status(ErrorCode::kInvalidArgument, path + ": empty file");
  if (size > limits.maxFileBytes) {
    return Status(ErrorCode::kResourceExhausted, path + ": " + std::to_string(size) +
                                                     " bytes exceed the limit of " +
                                                     std::to_string(limits.maxFileBytes));
  }
  try {
    std::optional<GltfDeclared> declared;
    const std::string ext = lowerExtension(path);
    // The formats with a pre-check of ours are read once here; the others
    // (.x, binary .fbx) reach Assimp through BoundedIOSystem's byte limits only.
    const bool prechecked = ext == ".gltf" || ext == ".glb" || ext == ".dae" || ext == ".obj" ||
                            ext == ".smd" || ext == ".fbx";
    std::string bytes;
    if (prechecked) {
      Result<std::string> read = readFileBounded(path, size);
      if (!read.ok()) return read.status();
      bytes = std::move(*read);
    }
    if (ext == ".gltf" || ext == ".glb") {
      Result<GltfDeclared> checked = precheckGltf(path, bytes, limits);
      if (!checked.ok()) return checked.status();
      declared = *checked;
    } else if (ext == ".dae") {
      // Assimp's Collada reader recurses over nodes and instance_node
      // references unchecked: a cycle or deep nesting crashed it.
      THINLOD_RETURN_IF_ERROR(detail::precheckCollada(path, bytes, limits));
    } else if (ext == ".obj") {
      // The OBJ (+ MTL) route to Assimp: the mesh loader's OBJ pre-check
      // first (numbers, face indices in range, line grammar). Assimp's OBJ
      // reader leaked what it had built on a face naming a uv past the
      // file's (fuzz finding 32).
      Result<mesh_detail::PrecheckResult> checked =
          mesh_detail::precheckMesh(bytes, mesh_detail::MeshFormat::kObj, path, MeshLoadOptions{});
      if (!checked.ok()) return checked.status();
      // Then the statements both readers understand the same way, and no NUL
      // (fuzz finding 34).
      THINLOD_RETURN_IF_ERROR(detail::checkObjStatementsForAssimp(path, bytes));
    } else if (ext == ".smd") {
      THINLOD_RETURN_IF_ERROR(detail::precheckSmd(path, bytes));
    } else if (ext == ".fbx") {
      THINLOD_RETURN_IF_ERROR(detail::precheckFbx(path, bytes, limits));
    }
    Assimp::Importer importer;  // Assimp's DefaultLogger stays the null logger
    auto* io = new BoundedIOSystem(limits);
    importer.SetIOHandler(io);  // the importer owns it
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                                aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    // No aiProcess_PreTransformVertices: the hierarchy is kept as nodes.
    const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                           aiProcess_SortByPType | aiProcess_ValidateDataStructure;
    const aiScene* ai = nullptr;
    if (ext == ".smd") {
      // Assimp's SMD reader steps four bytes past a section's "end" token
      // whatever follows it; at the very end of a file that is past the
      // buffer's terminating NUL and it read the heap beyond (fuzz finding
      // 42). Files end "end" without a newline in the wild (the package's
      // SMD/triangle.smd does), so the checked bytes go to Assimp from
      // memory with one newline appended rather than being refused.
      bytes.push_back('\n');
      ai = importer.ReadFileFromMemory(bytes.data(), bytes.size(), flags, "smd");
    } else {
      ai = importer.ReadFile(path, flags);
    }
    if (!io->refusal().empty()) {
      return Status(ErrorCode::kResourceExhausted, path + ": " + io->refusal());
    }
    if (ai == nullptr) {
      std::string why = importer.GetErrorString();
      // SortByPType removed every point and line mesh: say it in our terms.
      if (why.find("No meshes remaining") != std::string::npos) {
        return Status(ErrorCode::kInvalidArgument,
                      path + ": contains no triangles (point and line primitives are dropped)");
      }
      return Status(ErrorCode::kParseError,
                    path + ": " + formatName(ext) + " import failed: " +
                        (why.empty() ? std::string("unknown Assimp error") : why));
    }
    return convert(*ai, declared);
  } catch (const std::bad_alloc&) {
    return Status(ErrorCode::kResourceExhausted, path + ": out of memory while importing");
  } catch (const std::exception& e) {
    return Status(ErrorCode::kParseError, path + ": import failed: " + e.what());
  } catch (...) {
    return Status(ErrorCode::kInternal, path + ": import failed with an unknown exception");
  }
}

}  // namespace

bool isImportedSceneExtension(const std::string& path) {
  const std::string ext = lowerExtension(path);
  return ext == ".gltf" || ext == ".glb" || ext == ".dae" || ext == ".fbx" || ext == ".obj";
}

Result<Scene> importScene(const std::string& path, const ImportLimits& limits) {
  if (!isImportedSceneExtension(path)) {
    return Status(ErrorCode::kUnsupported,
                  path + ": not an imported scene format (.gltf .glb .dae .fbx .obj)");
  }
  return readThroughAssimp<Scene>(
      path, limits, [&](const aiScene& ai, const std::optional<GltfDeclared>& declared) {
        Result<Scene> scene = Converter(path, ai, limits, declared).run();
        if (scene.ok()) scene->header = std::string("import ") + formatName(lowerExtension(path));
        return scene;
      });
}

Result<LoadedMesh> importSceneAsMesh(const std::string& path, const ImportLimits& limits) {
  Result<Scene> scene = importScene(path, limits);
  if (!scene.ok()) return scene.status();
  std::vector<std::pair<const IndexedMesh*, glm::mat4>> parts;
  bool allUvs = true;
  bool allColors = true;
  bool anyMaterialOrTexture = false;
  for (const NodeInstance& instance : flattenInstances(*scene)) {
    const ShapeNode* shape = instance.node->as<ShapeNode>();
    if (shape == nullptr || !shape->geometry.mesh) continue;
    const IndexedMesh& mesh = *shape->geometry.mesh;
    parts.emplace_back(&mesh, instance.contentToWorld);
    allUvs &= !mesh.uvs.empty();
    allColors &= !mesh.colors.empty();
    anyMaterialOrTexture |= !shape->appearance.textureUrl.empty();
  }
  LoadedMesh out;
  out.warnings = scene->warnings;
  IndexedMesh& merged = out.mesh;
  for (const auto& [mesh, toRoot] : parts) {
    // The importer bounded the instance triangles (limits.maxTriangles) and
    // vertices per distinct mesh; instancing can repeat vertices, so check
    // the merged size against 32-bit indices before growing.
    if (merged.positions.size() + mesh->positions.size() > 0xFFFFFFFFull) {
      return Status(ErrorCode::kResourceExhausted, path + ": too many vertices to flatten");
    }
    const auto base = static_cast<std::uint32_t>(merged.positions.size());
    const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(toRoot)));
    const bool mirrored = glm::determinant(glm::mat3(toRoot)) < 0.0f;
    for (const glm::vec3& p : mesh->positions)
      merged.positions.emplace_back(toRoot * glm::vec4(p, 1.0f));
    for (const glm::vec3& n : mesh->normals) {
      const glm::vec3 mapped = normalMatrix * n;
      const float length = glm::length(mapped);
      merged.normals.push_back(length > 1e-20f ? mapped / length : n);
    }
    if (allUvs) merged.uvs.insert(merged.uvs.end(), mesh->uvs.begin(), mesh->uvs.end());
    if (allColors)
      merged.colors.insert(merged.colors.end(), mesh->colors.begin(), mesh->colors.end());
    for (std::size_t i = 0; i + 2 < mesh->indices.size(); i += 3) {
      merged.indices.push_back(base + mesh->indices[i]);
      merged.indices.push_back(base + mesh->indices[mirrored ? i + 2 : i + 1]);
      merged.indices.push_back(base + mesh->indices[mirrored ? i + 1 : i + 2]);
    }
  }
  if (merged.normals.size() != merged.positions.size()) merged.computeNormals();
  THINLOD_RETURN_IF_ERROR(merged.validate(path));
  out.warnings.push_back(path + ": inlined as one mesh; its materials" +
                         std::string(anyMaterialOrTexture ? " and textures" : "") +
                         " are replaced by the Shape's Appearance");
  return out;
}

}  // namespace thinlod::scene

// ---------------------------------------------------------------------------
// Skinned models (contract in skinned_import.h). Here, not in a file of its
// own, because it shares the bounded IO system and the glTF pre-check.
namespace thinlod::scene {
namespace {

// Keys of one Assimp channel component, seconds, repeated times keep the
// last, clamped into [0, duration].
template <typename AiKey, typename Key, typename Convert>
std::vector<Key> convertKeys(const AiKey* keys, unsigned count, double ticksPerSecond,
                             double duration, Convert convert) {
  std::vector<Key> out;
  out.reserve(count);
  for (unsigned k = 0; k < count; ++k) {
    Key key;
    key.time = std::clamp(keys[k].mTime / ticksPerSecond, 0.0, duration);
    key.value = convert(keys[k].mValue);
    if (!out.empty() && !(key.time > out.back().time)) {
      if (key.time == out.back().time) out.back() = key;  // repeated time: keep the last
      continue;                                           // out of order: dropped
    }
    out.push_back(key);
  }
  return out;
}

class SkinnedConverter {
 public:
  SkinnedConverter(const std::string& path, const aiScene& ai, const SkinnedImportLimits& limits)
      : path_(path), ai_(ai), limits_(limits) {}

  Result<SkinnedModel> run() {
    THINLOD_RETURN_IF_ERROR(buildSkeleton());
    THINLOD_RETURN_IF_ERROR(copyMeshes());
    THINLOD_RETURN_IF_ERROR(copyClips());
    THINLOD_RETURN_IF_ERROR(model_.skeleton.validate(path_));
    THINLOD_RETURN_IF_ERROR(model_.mesh.validate(path_));
    THINLOD_RETURN_IF_ERROR(anim::validateSkin(model_.skin, model_.mesh.vertexCount(),
                                               model_.skeleton.bones.size(), path_));
    for (const anim::AnimationClip& clip : model_.clips) {
      THINLOD_RETURN_IF_ERROR(clip.validate(model_.skeleton, path_));
    }
    return std::move(model_);
  }

 private:
  Status fail(ErrorCode code, const std::string& message) const {
    return Status(code, path_ + ": " + message);
  }

  Status buildSkeleton() {
    if (ai_.mRootNode == nullptr) return fail(ErrorCode::kInvalidArgument, "no node tree");
    // Preorder with an explicit stack: parents get lower indices.
    std::vector<std::pair<const aiNode*, int>> stack{{ai_.mRootNode, -1}};
    std::vector<int> depth;
    while (!stack.empty()) {
      const auto [node, parent] = stack.back();
      stack.pop_back();
      if (model_.skeleton.bones.size() >= limits_.files.maxNodes) {
        return fail(ErrorCode::kResourceExhausted,
                    "more than " + std::to_string(limits_.files.maxNodes) + " nodes");
      }
      const int d = parent < 0 ? 0 : depth[static_cast<std::size_t>(parent)] + 1;
      if (d > limits_.files.maxDepth) {
        return fail(ErrorCode::kResourceExhausted,
                    "node tree deeper than " + std::to_string(limits_.files.maxDepth));
      }
      anim::Bone bone;
      bone.name = node->mName.C_Str();
      bone.parent = parent;
      bone.restLocal = toGlm(node->mTransformation);
      const int index = static_cast<int>(model_.skeleton.bones.size());
      model_.skeleton.bones.push_back(std::move(bone));
      depth.push_back(d);
      nodes_.push_back(node);  // bone index == position
      byName_.emplace(node->mName.C_Str(), index);  // first node of a name wins
      if (node->mNumChildren > 0 && node->mChildren == nullptr) {
        return fail(ErrorCode::kInvalidArgument, "node without its children");
      }
      for (unsigned c = node->mNumChildren; c-- > 0;) {
        if (node->mChildren[c] == nullptr) continue;
        stack.push_back({node->mChildren[c], index});
      }
    }
    return Status::okStatus();
  }

  Status copyMeshes() {
    std::vector<bool> skinnedCopied(ai_.mNumMeshes, false);
    // Mesh instances in node order (bone i is nodes_[i]).
    for (std::size_t index = 0; index < nodes_.size(); ++index) {
      const aiNode* node = nodes_[index];
      for (unsigned m = 0; m < node->mNumMeshes; ++m) {
        const unsigned meshIndex = node->mMeshes[m];
        if (meshIndex >= ai_.mNumMeshes || ai_.mMeshes[meshIndex] == nullptr) {
          return fail(ErrorCode::kInvalidArgument, "node refers to a missing mesh");
        }
        const aiMesh& mesh = *ai_.mMeshes[meshIndex];
        if (mesh.mNumBones > 0) {
          if (skinnedCopied[meshIndex]) continue;  // bones place it, not the node
          skinnedCopied[meshIndex] = true;
          ++model_.skinnedMeshes;
        }
        THINLOD_RETURN_IF_ERROR(copyMesh(mesh, static_cast<std::uint32_t>(index)));
      }
    }
    if (model_.mesh.triangleCount() == 0) {
      return fail(ErrorCode::kInvalidArgument, "contains no triangles");
    }
    if (!allNormals_) model_.mesh.normals.clear();
    if (!allUvs_) model_.mesh.uvs.clear();
    if (model_.mesh.normals.empty()) model_.mesh.computeNormals();
    return Status::okStatus();
  }

  Status copyMesh(const aiMesh& mesh, std::uint32_t node) {
    IndexedMesh& out = model_.mesh;
    if (mesh.mVertices == nullptr && mesh.mNumVertices > 0) {
      return fail(ErrorCode::kInvalidArgument, "mesh without vertex positions");
    }
    if (out.vertexCount() + mesh.mNumVertices > limits_.files.maxVertices) {
      return fail(ErrorCode::kResourceExhausted,
                  "more than " + std::to_string(limits_.files.maxVertices) + " vertices");
    }
    if (out.triangleCount() + mesh.mNumFaces > limits_.files.maxTriangles) {
      return fail(ErrorCode::kResourceExhausted,
                  "more than " + std::to_string(limits_.files.maxTriangles) + " triangles");
    }
    const auto base = static_cast<std::uint32_t>(out.vertexCount());
    allNormals_ &= mesh.mNormals != nullptr;
    allUvs_ &= mesh.mTextureCoords[0] != nullptr;
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      if (!finite3(mesh.mVertices[v])) {
        return fail(ErrorCode::kInvalidArgument, "non-finite vertex position");
      }
      out.positions.emplace_back(mesh.mVertices[v].x, mesh.mVertices[v].y, mesh.mVertices[v].z);
      if (mesh.mNormals != nullptr) {
        const aiVector3D& n = mesh.mNormals[v];
        out.normals.emplace_back(finite3(n) ? glm::vec3(n.x, n.y, n.z) : glm::vec3(0, 0, 1));
      }
      if (mesh.mTextureCoords[0] != nullptr) {
        const aiVector3D& t = mesh.mTextureCoords[0][v];
        out.uvs.emplace_back(std::isfinite(t.x) ? t.x : 0.0f, std::isfinite(t.y) ? t.y : 0.0f);
      }
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines: dropped
      for (unsigned i = 0; i < 3; ++i) {
        if (face.mIndices[i] >= mesh.mNumVertices) {
          return fail(ErrorCode::kInvalidArgument, "face index out of range");
        }
        out.indices.push_back(base + face.mIndices[i]);
      }
    }
    // Weights: every (vertex, weight) of every bone, then the two largest.
    std::vector<std::vector<std::pair<float, std::uint32_t>>> influences(mesh.mNumVertices);
    for (unsigned b = 0; b < mesh.mNumBones; ++b) {
      const aiBone* bone = mesh.mBones[b];
      if (bone == nullptr) return fail(ErrorCode::kInvalidArgument, "missing bone");
      const auto found = byName_.find(bone->mName.C_Str());
      if (found == byName_.end()) {
        return fail(ErrorCode::kInvalidArgument,
                    std::string("bone '") + bone->mName.C_Str() + "' names no node");
      }
      const glm::mat4 offset = toGlm(bone->mOffsetMatrix);
      if (model_.skeleton.bones.size() >= limits_.files.maxNodes) {
        return fail(ErrorCode::kResourceExhausted, "too many bones");
      }
      anim::Bone binding;
      binding.name = std::string(bone->mName.C_Str()) + "#bind";
      binding.parent = found->second;
      binding.inverseBind = offset;
      const auto bindingIndex = static_cast<std::uint32_t>(model_.skeleton.bones.size());
      model_.skeleton.bones.push_back(std::move(binding));
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const aiVertexWeight& weight = bone->mWeights[w];
        if (weight.mVertexId >= mesh.mNumVertices) {
          return fail(ErrorCode::kInvalidArgument, "bone weight for a vertex out of range");
        }
        if (!std::isfinite(weight.mWeight) || weight.mWeight < 0.0f) {
          return fail(ErrorCode::kInvalidArgument, "non-finite or negative bone weight");
        }
        if (weight.mWeight > 0.0f) influences[weight.mVertexId].push_back({weight.mWeight, bindingIndex});
      }
    }
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      auto& list = influences[v];
      anim::VertexSkin skin;
      if (list.empty()) {
        skin.boneA = skin.boneB = node;  // rigid on the node holding the mesh
        if (mesh.mNumBones > 0) ++model_.unweightedVertices;
      } else {
        std::sort(list.begin(), list.end(), std::greater<>());
        if (list.size() > 2) {
          ++model_.verticesOverTwoBones;
          model_.largestDroppedWeight = std::max(model_.largestDroppedWeight, list[2].first);
        }
        skin.boneA = skin.boneB = list[0].second;
        if (list.size() > 1) {
          skin.boneB = list[1].second;
          skin.weightB = list[1].first / (list[0].first + list[1].first);
        }
      }
      model_.skin.push_back(skin);
    }
    return Status::okStatus();
  }

  Status copyClips() {
    std::size_t keys = 0;
    for (unsigned a = 0; a < ai_.mNumAnimations; ++a) {
      const aiAnimation* animation = ai_.mAnimations[a];
      if (animation == nullptr) continue;
      const double ticksPerSecond =
          animation->mTicksPerSecond > 0.0 && std::isfinite(animation->mTicksPerSecond)
              ? animation->mTicksPerSecond
              : 25.0;
      if (!std::isfinite(animation->mDuration) || animation->mDuration <= 0.0) continue;
      anim::AnimationClip clip;
      clip.name = animation->mName.C_Str();
      clip.duration = animation->mDuration / ticksPerSecond;
      std::set<std::uint32_t> driven;
      for (unsigned c = 0; c < animation->mNumChannels; ++c) {
        const aiNodeAnim* channel = animation->mChannels[c];
        if (channel == nullptr) continue;
        const auto found = byName_.find(channel->mNodeName.C_Str());
        if (found == byName_.end() ||
            !driven.insert(static_cast<std::uint32_t>(found->second)).second) {
          ++model_.unmatchedChannels;
          continue;
        }
        keys += std::size_t{channel->mNumPositionKeys} + channel->mNumRotationKeys +
                channel->mNumScalingKeys;
        if (keys > limits_.maxKeys) {
          return fail(ErrorCode::kResourceExhausted,
                      "more than " + std::to_string(limits_.maxKeys) + " animation keys");
        }
        anim::BoneChannel out;
        out.bone = static_cast<std::uint32_t>(found->second);
        const auto vec = [](const aiVector3D& v) { return glm::vec3(v.x, v.y, v.z); };
        out.positions = convertKeys<aiVectorKey, anim::VectorKey>(
            channel->mPositionKeys, channel->mNumPositionKeys, ticksPerSecond, clip.duration, vec);
        out.scales = convertKeys<aiVectorKey, anim::VectorKey>(
            channel->mScalingKeys, channel->mNumScalingKeys, ticksPerSecond, clip.duration, vec);
        out.rotations = convertKeys<aiQuatKey, anim::RotationKey>(
            channel->mRotationKeys, channel->mNumRotationKeys, ticksPerSecond, clip.duration,
            [](const aiQuaternion& q) {
              glm::quat r(q.w, q.x, q.y, q.z);
              const float n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
              // Files store slightly denormalised quaternions; a zero or
              // non-finite one stays as it is and fails validation.
              return n > 1e-6f && std::isfinite(n) ? r / n : r;
            });
        clip.channels.push_back(std::move(out));
      }
      model_.clips.push_back(std::move(clip));
    }
    return Status::okStatus();
  }

  const std::string& path_;
  const aiScene& ai_;
  SkinnedImportLimits limits_;
  SkinnedModel model_;
  std::vector<const aiNode*> nodes_;  // the first bones, in preorder
  std::map<std::string, int> byName_;
  bool allNormals_ = true;
  bool allUvs_ = true;
};

}  // namespace

bool isSkinnedModelExtension(const std::string& path) {
  const std::string ext = lowerExtension(path);
  return ext == ".gltf" || ext == ".glb" || ext == ".dae" || ext == ".fbx" || ext == ".x" ||
         ext == ".smd";
}

Result<SkinnedModel> importSkinnedModel(const std::string& path,
                                        const SkinnedImportLimits& limits) {
  // Only the formats we have read and tested: every other Assimp reader
  // (md5, bvh, ms3d, ...) would get untrusted bytes no check of ours saw.
  if (!isSkinnedModelExtension(path)) {
    return Status(ErrorCode::kUnsupported,
                  path + ": not a skinned model format (.gltf .glb .dae .fbx .x .smd)");
  }
  return readThroughAssimp<SkinnedModel>(
      path, limits.files, [&](const aiScene& ai, const std::optional<GltfDeclared>&) {
        return SkinnedConverter(path, ai, limits).run();
      });
}

}  // namespace thinlod::scene

// ---------------------------------------------------------------------------
// Assimp's own assertions. Debian's libassimp is built with them on, and its
// default handler aborts the process: fuzz finding 44 reached one
// (ColladaParser's primitive count) from a 127-byte .dae, so a scene file
// could kill a daemon. This definition, in the object file that every
// import links, takes the place of the library's exported one (the library
// calls it through its PLT, so the executable's definition is the one
// bound) and turns a violated assertion into an exception: Assimp's
// ReadFile catches it and returns no scene with the message, and
// readThroughAssimp reports that as a parse error naming the file. The
// known cases are refused by the pre-checks before Assimp runs; this is the
// net under the ones not known yet. Tested by
// scene.SceneImport.AssimpAssertionsThrowInsteadOfAborting.
namespace Assimp {
// Declared by <assimp/ai_assert.h> only in Assimp's debug builds.
void aiAssertViolation(const char* failedExpression, const char* file, int line);
void aiAssertViolation(const char* failedExpression, const char* file, int line) {
  throw std::runtime_error(std::string("Assimp assertion failed: ") +
                           (failedExpression != nullptr ? failedExpression : "?") + " (" +
                           (file != nullptr ? file : "?") + ":" + std::to_string(line) + ")");
}
}  // namespace Assimp
