// libFuzzer entry point for the mesh loader: the first byte picks the
// format, the rest is the file. Build with -fsanitize=fuzzer to fuzz; the
// test suite replays tests/data/mesh through it (mesh_fuzz_replay_test.cpp).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "thinlod/common/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kFormats[] = {"obj", "ply", "off", "stl"};
  const char* format = kFormats[data[0] % 4];
  thinlod::MeshLoadOptions options;
  options.maxVertices = 100'000;  // keep single inputs cheap
  options.maxFaces = 100'000;
  thinlod::Result<thinlod::LoadedMesh> r = thinlod::loadMeshFromMemory(
      std::string_view(reinterpret_cast<const char*>(data + 1), size - 1), format, "fuzz", options);
  if (r.ok() && !r->mesh.validate("fuzz").ok()) __builtin_trap();  // contract broken
  return 0;
}
