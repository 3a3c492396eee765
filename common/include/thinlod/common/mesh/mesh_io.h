// Mesh files: OBJ, PLY (ascii and binary), OFF (ascii) and STL (ascii and
// binary) read through OpenMesh's IO and returned as IndexedMesh.
//
// Contract:
// - Input is untrusted. Every failure is a Status whose message starts with
//   the file name and names the problem: missing/unreadable file (kNotFound /
//   kIoError), unknown extension (kUnsupported), truncated data, header
//   counts that do not fit the file, NaN/Inf coordinates, out-of-range
//   indices, zero faces (kInvalidArgument), limits exceeded
//   (kResourceExhausted). Nothing is printed: OpenMesh's error stream is
//   captured while reading and folded into the Status or the warnings.
// - The file is pre-checked (size, header counts, finite numbers) before
//   OpenMesh sees it, and the result passes IndexedMesh::validate.
// - Polygons are triangulated (fans). Faces OpenMesh cannot add manifoldly
//   are added on duplicated vertices and counted in nonManifoldTriangles;
//   faces with repeated vertices are dropped and counted; both also produce
//   a human-readable line in `warnings`.
// - Normals: unit length; taken from the file when present (normalised; all
//   recomputed if one is zero), else computed (area-weighted) unless options
//   say otherwise. Colours and uvs only when the file has them; uvs are per
//   vertex, so an OBJ corner uv that differs from another corner's at the
//   same vertex (a seam) is lost (OpenMesh keeps the last one).
// - Thread-safe: calls are serialised internally (OpenMesh's reader
//   singletons and error stream are process-global).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod {

struct MeshLoadOptions {
  std::uint64_t maxFileBytes = std::uint64_t{1} << 30;
  std::uint64_t maxVertices = 50'000'000;
  std::uint64_t maxFaces = 50'000'000;
  bool computeMissingNormals = true;
};

struct LoadedMesh {
  IndexedMesh mesh;
  std::vector<std::string> warnings;
  std::size_t nonManifoldTriangles = 0;
  std::size_t droppedDegenerateFaces = 0;
};

// "obj", "ply", "off", "stl" (case-insensitive); the extension picks the reader.
bool isSupportedMeshExtension(const std::string& path);

Result<LoadedMesh> loadMeshFile(const std::string& path, const MeshLoadOptions& options = {});

// Same checks on bytes already in memory; `extension` like "obj" or ".obj",
// `name` is used in messages.
Result<LoadedMesh> loadMeshFromMemory(std::string_view bytes, const std::string& extension,
                                      const std::string& name, const MeshLoadOptions& options = {});

// Writes through OpenMesh (format from the extension; PLY/STL binary when
// `binary`). For tools and round-trip tests. Validates the mesh first.
Status saveMeshFile(const IndexedMesh& mesh, const std::string& path, bool binary = false);

}  // namespace thinlod
