// Shared by the codec fuzz entry points: lets mutated payloads reach the
// inner decoders (Draco, zstd, libpng, libjpeg) behind the frame checksum.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "thinlod/common/codec/encoding.h"

namespace thinlod::fuzz {

// The input as a frame whose header payload size (bytes 16..19) and FNV-1a
// checksum (bytes 24..31) match the payload after it; inputs shorter than
// the header are returned unchanged (the frame parser rejects them).
inline std::vector<std::uint8_t> resealedFrame(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> frame(data, data + size);
  if (size < codec::kFrameHeaderBytes) return frame;
  const std::size_t payload = size - codec::kFrameHeaderBytes;
  const std::uint32_t stored = static_cast<std::uint32_t>(payload);
  for (int i = 0; i < 4; ++i) frame[16 + i] = static_cast<std::uint8_t>(stored >> (8 * i));
  const std::uint64_t sum = codec::frameChecksum(frame.data() + codec::kFrameHeaderBytes, payload);
  for (int i = 0; i < 8; ++i) frame[24 + i] = static_cast<std::uint8_t>(sum >> (8 * i));
  return frame;
}

// Limits small enough that one input stays cheap, large enough for the seeds.
inline codec::DecodeLimits fuzzDecodeLimits() {
  codec::DecodeLimits limits;
  limits.maxPayloadBytes = 1u << 20;
  limits.maxVertices = 1u << 16;
  limits.maxTriangles = 1u << 16;
  limits.maxTextureDimension = 1024;
  return limits;
}

}  // namespace thinlod::fuzz
