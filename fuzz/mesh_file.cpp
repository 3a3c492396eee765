// libFuzzer entry point for mesh files (OBJ, PLY, OFF, STL: the pre-checks
// of mesh_precheck.cpp, then OpenMesh's readers). Built as the fuzzer
// thinlod_fuzz_mesh under -DTHINLOD_FUZZ=ON; replayed over fuzz/corpus/mesh
// (fuzz.FuzzReplay.mesh) and tests/data/mesh (mesh.MeshFuzzTarget.*) under
// any compiler.
//
// Input: the first byte picks the format (byte % 4: 0 obj, 1 ply, 2 off,
// 3 stl; the corpus uses the digits '0'..'3'), the rest is the file.
// Oracle: a loaded mesh passes IndexedMesh::validate and has triangles; an
// error names the file.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "thinlod/common/mesh/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kFormats[] = {"obj", "ply", "off", "stl"};
  const char* format = kFormats[data[0] % 4];
  thinlod::MeshLoadOptions options;
  options.maxVertices = 100'000;  // keep single inputs cheap
  options.maxFaces = 100'000;
  thinlod::Result<thinlod::LoadedMesh> r = thinlod::loadMeshFromMemory(
      std::string_view(reinterpret_cast<const char*>(data + 1), size - 1), format, "fuzz", options);
  if (r.ok()) {
    if (const thinlod::Status valid = r->mesh.validate("fuzz"); !valid.ok()) {
      std::fprintf(stderr, "mesh fuzz oracle: loaded mesh is invalid: %s\n",
                   valid.message().c_str());
      std::abort();
    }
    if (r->mesh.triangleCount() == 0) {  // mesh_io.h: zero faces is an error
      std::fprintf(stderr, "mesh fuzz oracle: loaded a mesh without triangles\n");
      std::abort();
    }
  } else if (r.status().message().rfind("fuzz", 0) != 0) {
    std::fprintf(stderr, "mesh fuzz oracle: error does not name the file: %s\n",
                 r.status().message().c_str());
    std::abort();
  }
  return 0;
}
