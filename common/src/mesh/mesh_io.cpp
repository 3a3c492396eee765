// OpenMesh wants MeshIO.hh included before any mesh kernel header.
// clang-format off
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // see tri_mesh.h
#include <OpenMesh/Core/IO/MeshIO.hh>
#pragma GCC diagnostic pop
#include "thinlod/common/mesh/mesh_io.h"
// clang-format on

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <exception>
#include <filesystem>
#include <glm/geometric.hpp>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <new>
#include <sstream>

#include "mesh/mesh_precheck.h"
#include "thinlod/common/core/file_bytes.h"
#include "thinlod/common/mesh/tri_mesh.h"

namespace thinlod {
namespace {

using mesh_detail::MeshFormat;

// OpenMesh's readers are singletons and omerr() is one global stream: one
// load at a time.
std::mutex& openMeshMutex() {
  static std::mutex mutex;
  return mutex;
}

// Redirects OpenMesh's error stream into a string for the lifetime of the
// object (OpenMesh reports bad faces there and still returns "ok"), and
// silences its log stream. omerr() writes to std::cerr (its default
// target), and so do some readers directly ("Unsupported keyword"), so
// swapping std::cerr's buffer captures both; spdlog writes to the C stderr
// stream and is not affected. omerr()'s targets are never connected or
// disconnected here: OpenMesh's mostream::disconnect() drops a target
// without deleting it (16 bytes per load; found by LeakSanitizer under
// fuzz/mesh_file.cpp). Construct under openMeshMutex().
class ErrorStreamCapture {
 public:
  ErrorStreamCapture() {
    logWasEnabled_ = omlog().is_enabled();
    omlog().disable();
    outWasEnabled_ = omout().is_enabled();
    omout().disable();
    savedCerr_ = std::cerr.rdbuf(buffer_.rdbuf());
  }
  ~ErrorStreamCapture() {
    omerr().flush();
    std::cerr.rdbuf(savedCerr_);
    if (logWasEnabled_) omlog().enable();
    if (outWasEnabled_) omout().enable();
  }
  ErrorStreamCapture(const ErrorStreamCapture&) = delete;
  ErrorStreamCapture& operator=(const ErrorStreamCapture&) = delete;

  std::string text() {
    omerr().flush();
    return buffer_.str();
  }

 private:
  std::ostringstream buffer_;
  std::streambuf* savedCerr_ = nullptr;
  bool logWasEnabled_ = false;
  bool outWasEnabled_ = false;
};

std::string lowerExtension(const std::string& pathOrExtension) {
  std::string ext = pathOrExtension;
  const std::size_t dot = ext.rfind('.');
  const std::size_t slash = ext.find_last_of("/\\");
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) {
    ext = ext.substr(dot + 1);
  } else {
    ext.clear();  // no extension
  }
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

Result<MeshFormat> formatFromExtension(const std::string& ext, const std::string& name) {
  if (ext == "obj") return MeshFormat::kObj;
  if (ext == "ply") return MeshFormat::kPly;
  if (ext == "off") return MeshFormat::kOff;
  if (ext == "stl") return MeshFormat::kStl;
  return Status(ErrorCode::kUnsupported,
                name + ": unknown mesh file extension '" + ext + "' (expected obj, ply, off, stl)");
}

std::size_t countOccurrences(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (std::size_t pos = text.find(what); pos != std::string::npos;
       pos = text.find(what, pos + what.size())) {
    ++count;
  }
  return count;
}

// Lines of OpenMesh's error output that are not already accounted for.
std::vector<std::string> otherMessages(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line.find("equal vertices") != std::string::npos ||
        line.find("complex vertex") != std::string::npos ||
        line.find("complex edge") != std::string::npos ||
        line.find("patch re-linking failed") != std::string::npos) {
      continue;
    }
    lines.push_back(line);
  }
  return lines;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& l : lines) out += (out.empty() ? "" : "; ") + l;
  return out;
}

// OpenMesh's importer gives a face it cannot add manifoldly fresh copies of
// its vertices (flagged fixed_nonmanifold) and copies only their positions:
// the copies' normals, colours and texture coordinates are left as
// uninitialised memory (valgrind, loading suzanne.obj), which made two loads
// of one scene differ. Which file vertex was copied is not recorded, so each
// copy takes the attributes of the original at the same position; where
// several originals share it (a seam with split normals), the one whose
// normal is closest to the copy's face normals. A copy without an original
// gets a zero normal (so every normal is recomputed), white and (0, 0).
void copyAttributesToNonManifoldCopies(TriMesh& tm, const TriMeshAttributes& present) {
  if (!present.normals && !present.colors && !present.uvs) return;
  bool anyCopy = false;
  for (const auto vh : tm.vertices()) anyCopy = anyCopy || tm.status(vh).fixed_nonmanifold();
  if (!anyCopy) return;
  std::multimap<std::array<float, 3>, TriMesh::VertexHandle> originalsAt;
  for (const auto vh : tm.vertices()) {
    if (tm.status(vh).fixed_nonmanifold()) continue;
    const auto& p = tm.point(vh);
    originalsAt.emplace(std::array<float, 3>{p[0], p[1], p[2]}, vh);
  }
  for (const auto vh : tm.vertices()) {
    if (!tm.status(vh).fixed_nonmanifold()) continue;
    const auto& p = tm.point(vh);
    const auto [first, last] = originalsAt.equal_range(std::array<float, 3>{p[0], p[1], p[2]});
    if (first == last) {
      tm.set_normal(vh, TriMesh::Normal(0.0f, 0.0f, 0.0f));
      tm.set_color(vh, TriMesh::Color(255, 255, 255, 255));
      tm.set_texcoord2D(vh, TriMesh::TexCoord2D(0.0f, 0.0f));
      continue;
    }
    auto best = first;
    TriMesh::Normal faceNormal(0.0f, 0.0f, 0.0f);
    if (present.normals) {
      for (const auto fh : tm.vf_range(vh)) faceNormal += tm.calc_face_normal(fh);
    }
    float bestAlignment = -std::numeric_limits<float>::infinity();
    for (auto it = first; present.normals && it != last; ++it) {
      const float alignment = OpenMesh::dot(tm.normal(it->second), faceNormal);
      if (alignment > bestAlignment) {  // NaN never wins: the first stays
        bestAlignment = alignment;
        best = it;
      }
    }
    if (present.normals) tm.set_normal(vh, tm.normal(best->second));
    if (present.colors) tm.set_color(vh, tm.color(best->second));
    if (present.uvs) tm.set_texcoord2D(vh, tm.texcoord2D(best->second));
  }
}

Result<LoadedMesh> loadChecked(std::string_view bytes, MeshFormat format, const std::string& ext,
                               const std::string& name, const MeshLoadOptions& options) {
  if (bytes.size() > options.maxFileBytes) {
    return Status(ErrorCode::kResourceExhausted, name + ": " + std::to_string(bytes.size()) +
                                                     " bytes exceed the limit of " +
                                                     std::to_string(options.maxFileBytes));
  }
  if (bytes.empty()) return Status(ErrorCode::kInvalidArgument, name + ": empty file");
  Result<mesh_detail::PrecheckResult> pre = mesh_detail::precheckMesh(bytes, format, name, options);
  if (!pre.ok()) return pre.status();

  TriMesh tm;
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal |
                              OpenMesh::IO::Options::VertexColor |
                              OpenMesh::IO::Options::VertexTexCoord;
  if (pre->binary) opt += OpenMesh::IO::Options::Binary;
  std::string errors;
  bool readOk = false;
  {
    std::lock_guard<std::mutex> lock(openMeshMutex());
    ErrorStreamCapture capture;
    try {
      std::string text = pre->rewritten ? std::move(*pre->rewritten) : std::string(bytes);
      std::istringstream in{std::move(text), std::ios::in | std::ios::binary};
      readOk = OpenMesh::IO::read_mesh(tm, in, "." + ext, opt);
    } catch (const std::bad_alloc&) {
      return Status(ErrorCode::kResourceExhausted, name + ": out of memory while reading");
    } catch (const std::exception& e) {
      return Status(ErrorCode::kInvalidArgument, name + ": reader failed: " + e.what());
    }
    errors = capture.text();
  }
  if (!readOk) {
    return Status(ErrorCode::kInvalidArgument,
                  name + ": OpenMesh could not read the file" +
                      (errors.empty() ? std::string() : ": " + joined(otherMessages(errors))));
  }
  if (countOccurrences(errors, "invalid vertex index") > 0) {
    return Status(ErrorCode::kInvalidArgument,
                  name + ": a face references a vertex that does not exist");
  }

  LoadedMesh out;
  out.droppedDegenerateFaces = countOccurrences(errors, "equal vertices");
  for (const std::string& line : otherMessages(errors)) out.warnings.push_back(name + ": " + line);
  // The importer re-adds faces OpenMesh refuses on fresh vertices flagged
  // fixed_nonmanifold; count the triangles that use such vertices.
  for (const auto fh : tm.faces()) {
    for (const auto vh : tm.fv_range(fh)) {
      if (tm.status(vh).fixed_nonmanifold()) {
        ++out.nonManifoldTriangles;
        break;
      }
    }
  }
  if (out.nonManifoldTriangles > 0) {
    out.warnings.push_back(name + ": " + std::to_string(out.nonManifoldTriangles) +
                           " non-manifold triangles were added on duplicated vertices");
  }
  if (out.droppedDegenerateFaces > 0) {
    out.warnings.push_back(name + ": " + std::to_string(out.droppedDegenerateFaces) +
                           " faces with repeated vertices were dropped");
  }
  if (tm.n_faces() == 0) return Status(ErrorCode::kInvalidArgument, name + ": no faces");
  // Every declared face yields >= 1 triangle unless it was dropped.
  if (pre->declaredFaces > out.droppedDegenerateFaces &&
      tm.n_faces() < pre->declaredFaces - out.droppedDegenerateFaces) {
    return Status(ErrorCode::kInvalidArgument, name + ": only " + std::to_string(tm.n_faces()) +
                                                   " of " + std::to_string(pre->declaredFaces) +
                                                   " faces could be read");
  }

  TriMeshAttributes attributes;
  // STL has no per-vertex attributes, yet OpenMesh's STL reader reports
  // normals, colours and texcoords (left uninitialised).
  const bool perVertexAttributes = format != MeshFormat::kStl;
  attributes.normals = perVertexAttributes && opt.vertex_has_normal();
  attributes.colors = perVertexAttributes && opt.vertex_has_color();
  attributes.uvs = perVertexAttributes && opt.vertex_has_texcoord();
  copyAttributesToNonManifoldCopies(tm, attributes);
  out.mesh = toIndexedMesh(tm, attributes);
  THINLOD_RETURN_IF_ERROR(out.mesh.validate(name));
  // File normals are often unnormalised (VCG writes area-weighted ones);
  // zero ones cannot be fixed locally, so then all are recomputed. So are
  // ones whose float length overflows (components near FLT_MAX).
  bool zeroNormal = false;
  for (glm::vec3& n : out.mesh.normals) {
    const float len = glm::length(n);
    if (!(len > 1e-20f) || !std::isfinite(len)) {
      zeroNormal = true;
      break;
    }
    n /= len;
  }
  if (zeroNormal) {
    out.warnings.push_back(name + ": zero-length normals in the file; normals recomputed");
    out.mesh.computeNormals();
  }
  if (out.mesh.normals.empty() && options.computeMissingNormals) out.mesh.computeNormals();
  return out;
}

}  // namespace

bool isSupportedMeshExtension(const std::string& path) {
  return formatFromExtension(lowerExtension(path), path).ok();
}

Result<LoadedMesh> loadMeshFromMemory(std::string_view bytes, const std::string& extension,
                                      const std::string& name, const MeshLoadOptions& options) {
  const std::string ext =
      lowerExtension(extension.find('.') == std::string::npos ? "." + extension : extension);
  Result<MeshFormat> format = formatFromExtension(ext, name);
  if (!format.ok()) return format.status();
  return loadChecked(bytes, *format, ext, name, options);
}

Result<LoadedMesh> loadMeshFile(const std::string& path, const MeshLoadOptions& options) {
  const std::string ext = lowerExtension(path);
  Result<MeshFormat> format = formatFromExtension(ext, path);
  if (!format.ok()) return format.status();

  Result<std::string> bytes = readFileBounded(path, options.maxFileBytes);
  if (!bytes.ok()) return bytes.status();
  return loadChecked(*bytes, *format, ext, path, options);
}

Status saveMeshFile(const IndexedMesh& mesh, const std::string& path, bool binary) {
  THINLOD_RETURN_IF_ERROR(mesh.validate(path));
  const std::string ext = lowerExtension(path);
  Result<MeshFormat> format = formatFromExtension(ext, path);
  if (!format.ok()) return format.status();
  TriMeshConversion conv = fromIndexedMesh(mesh);
  OpenMesh::IO::Options opt;
  // STL stores no per-vertex attributes; OpenMesh's writer refuses them.
  if (*format != MeshFormat::kStl) {
    if (conv.attributes.normals) opt += OpenMesh::IO::Options::VertexNormal;
    if (conv.attributes.colors) opt += OpenMesh::IO::Options::VertexColor;
    if (conv.attributes.uvs) opt += OpenMesh::IO::Options::VertexTexCoord;
  }
  if (binary) opt += OpenMesh::IO::Options::Binary;
  std::lock_guard<std::mutex> lock(openMeshMutex());
  ErrorStreamCapture capture;
  bool ok = false;
  try {
    ok = OpenMesh::IO::write_mesh(conv.mesh, path, opt);
  } catch (const std::exception& e) {
    return Status(ErrorCode::kIoError, path + ": writer failed: " + e.what());
  }
  if (!ok) {
    return Status(ErrorCode::kIoError, path + ": OpenMesh could not write the file: " +
                                           joined(otherMessages(capture.text())));
  }
  return Status();
}

}  // namespace thinlod
