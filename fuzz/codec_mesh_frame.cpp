// libFuzzer entry point for link mesh frames (decodeMesh: frame header, then
// Draco). Built as the fuzzer thinlod_fuzz_codec_mesh under -DTHINLOD_FUZZ=ON;
// replayed over fuzz/corpus/codec_mesh (fuzz.FuzzReplay.codec_mesh) under any
// compiler. The checksum and payload size are recomputed first (the
// checksum's own check is unit-tested in tests/codec), so the fuzzer's
// mutations reach Draco.
//
// Oracle: a decoded mesh passes IndexedMesh::validate, has the vertex and
// triangle counts the header declared, and stays within the limits. The
// same frame also goes through decodeSkinnedMesh (skinned levels, attribute
// bit 8): its mesh is the one decodeMesh gives, and a skin it returns has
// one valid two-bone entry per vertex.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "codec_frame.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace thinlod;
  const std::vector<std::uint8_t> frame = fuzz::resealedFrame(data, size);
  const codec::DecodeLimits limits = fuzz::fuzzDecodeLimits();
  Result<IndexedMesh> mesh = codec::decodeMesh(frame.data(), frame.size(), limits);
  if (!mesh.ok()) return 0;
  const std::uint32_t vertices = std::uint32_t{frame[8]} | std::uint32_t{frame[9]} << 8 |
                                 std::uint32_t{frame[10]} << 16 | std::uint32_t{frame[11]} << 24;
  const std::uint32_t triangles = std::uint32_t{frame[12]} | std::uint32_t{frame[13]} << 8 |
                                  std::uint32_t{frame[14]} << 16 | std::uint32_t{frame[15]} << 24;
  if (!mesh->validate("fuzz").ok() || mesh->vertexCount() != vertices ||
      mesh->triangleCount() != triangles || vertices > limits.maxVertices ||
      triangles > limits.maxTriangles) {
    std::fprintf(stderr,
                 "codec mesh fuzz oracle: decoded %zu vertices / %zu triangles, header %u / %u\n",
                 mesh->vertexCount(), mesh->triangleCount(), vertices, triangles);
    std::abort();
  }
  Result<codec::SkinnedMeshFrame> skinned =
      codec::decodeSkinnedMesh(frame.data(), frame.size(), limits);
  if (!skinned.ok()) return 0;
  if (skinned->mesh.positions != mesh->positions || skinned->mesh.indices != mesh->indices) {
    std::fprintf(stderr, "codec mesh fuzz oracle: decodeSkinnedMesh's mesh differs\n");
    std::abort();
  }
  if (!skinned->skin.empty() &&
      !anim::validateSkin(skinned->skin, mesh->vertexCount(), codec::kMaxSkinBones, "fuzz")
           .ok()) {
    std::fprintf(stderr, "codec mesh fuzz oracle: decoded skin of %zu entries is invalid\n",
                 skinned->skin.size());
    std::abort();
  }
  return 0;
}
