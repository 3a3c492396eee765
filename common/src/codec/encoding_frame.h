// Private to encoding*.cpp: the 32-byte frame header of encoding.h.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/status.h"

namespace thinlod::codec::detail {

struct FrameHeader {
  std::array<char, 4> magic{};
  std::uint16_t version = kFrameVersion;
  std::uint8_t codec = 0;
  std::uint8_t flags = 0;
  std::uint32_t countA = 0;  // mesh vertices / texture width / hybrid points
  std::uint32_t countB = 0;  // mesh triangles / texture height / hybrid triangles
  std::uint32_t payloadBytes = 0;
  std::uint32_t attributes = 0;
  std::uint64_t checksum = 0;
};

inline constexpr std::array<char, 4> kMeshMagic = {'T', 'L', 'M', 'E'};
inline constexpr std::array<char, 4> kTextureMagic = {'T', 'L', 'T', 'X'};
inline constexpr std::array<char, 4> kHybridMagic = {'T', 'L', 'H', 'Y'};

// Header + payload; fills payloadBytes and checksum. Precondition: the
// payload fits in 32 bits (callers check against their limits first).
std::vector<std::uint8_t> makeFrame(FrameHeader header, const std::uint8_t* payload,
                                    std::size_t payloadSize);

// Checks magic, version, flags, payload size (== size - header, within
// limits.maxPayloadBytes) and checksum. `what` names the stream in errors.
Result<FrameHeader> parseFrame(const std::uint8_t* data, std::size_t size,
                               const std::array<char, 4>& magic, const DecodeLimits& limits,
                               const char* what);

// Checks that `size` bytes are exactly one zstd frame stating a content
// size of `expected` bytes (before anything is decompressed). The error is
// kParseError, its message prefixed with `what` ("texture: ").
Status checkOneZstdFrame(const std::uint8_t* data, std::size_t size, std::size_t expected,
                         const char* what);

}  // namespace thinlod::codec::detail
