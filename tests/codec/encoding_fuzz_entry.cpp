// libFuzzer entry point for the link decoders (build this file with
// -fsanitize=fuzzer under clang to fuzz). Under ctest it is an ordinary
// function; decoder_safety_test.cpp replays a seed corpus through it.
#include <cstddef>
#include <cstdint>

#include "thinlod/common/codec/encoding.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace thinlod::codec;
  DecodeLimits limits;
  limits.maxPayloadBytes = 1u << 20;
  limits.maxVertices = 1u << 16;
  limits.maxTriangles = 1u << 16;
  limits.maxTextureDimension = 1024;
  thinlod::Result<thinlod::IndexedMesh> mesh = decodeMesh(data, size, limits);
  if (mesh.ok() && !mesh->validate("fuzz").ok()) __builtin_trap();
  thinlod::Result<thinlod::RgbaImage> texture = decodeTexture(data, size, limits);
  if (texture.ok() && (texture->empty() || !texture->consistent())) __builtin_trap();
  return 0;
}
