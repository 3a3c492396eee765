#include "encoding_frame.h"

#include <zstd.h>

#include <algorithm>
#include <string>

#include "thinlod/common/core/hash.h"

namespace thinlod::codec {

std::uint64_t frameChecksum(const std::uint8_t* data, std::size_t size) {
  return fnv1a64(data, size);
}

namespace detail {
namespace {

void putU16(std::uint8_t* p, std::uint16_t v) {
  for (int i = 0; i < 2; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void putU32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void putU64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
std::uint64_t getLittleEndian(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

std::vector<std::uint8_t> makeFrame(FrameHeader header, const std::uint8_t* payload,
                                    std::size_t payloadSize) {
  std::vector<std::uint8_t> frame(kFrameHeaderBytes + payloadSize);
  std::uint8_t* p = frame.data();
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(header.magic[i]);
  putU16(p + 4, header.version);
  p[6] = header.codec;
  p[7] = header.flags;
  putU32(p + 8, header.countA);
  putU32(p + 12, header.countB);
  putU32(p + 16, static_cast<std::uint32_t>(payloadSize));
  putU32(p + 20, header.attributes);
  putU64(p + 24, frameChecksum(payload, payloadSize));
  if (payloadSize > 0) std::copy(payload, payload + payloadSize, p + kFrameHeaderBytes);
  return frame;
}

Result<FrameHeader> parseFrame(const std::uint8_t* data, std::size_t size,
                               const std::array<char, 4>& magic, const DecodeLimits& limits,
                               const char* what) {
  const std::string name(what);
  if (data == nullptr || size < kFrameHeaderBytes) {
    return Status(ErrorCode::kParseError, name + ": " + std::to_string(size) +
                                              " bytes, shorter than the 32-byte frame header");
  }
  FrameHeader h;
  for (int i = 0; i < 4; ++i) h.magic[i] = static_cast<char>(data[i]);
  if (h.magic != magic) {
    return Status(ErrorCode::kParseError,
                  name + ": bad magic (expected " + std::string(magic.begin(), magic.end()) + ")");
  }
  h.version = static_cast<std::uint16_t>(getLittleEndian(data + 4, 2));
  if (h.version != kFrameVersion) {
    return Status(ErrorCode::kVersionMismatch, name + ": frame version " +
                                                   std::to_string(h.version) + ", expected " +
                                                   std::to_string(kFrameVersion));
  }
  h.codec = data[6];
  h.flags = data[7];
  h.countA = static_cast<std::uint32_t>(getLittleEndian(data + 8, 4));
  h.countB = static_cast<std::uint32_t>(getLittleEndian(data + 12, 4));
  h.payloadBytes = static_cast<std::uint32_t>(getLittleEndian(data + 16, 4));
  h.attributes = static_cast<std::uint32_t>(getLittleEndian(data + 20, 4));
  h.checksum = getLittleEndian(data + 24, 8);
  if (h.flags != 0) {
    return Status(ErrorCode::kUnsupported, name + ": unknown flags " + std::to_string(h.flags));
  }
  if (h.payloadBytes > limits.maxPayloadBytes) {
    return Status(ErrorCode::kResourceExhausted,
                  name + ": payload of " + std::to_string(h.payloadBytes) +
                      " bytes exceeds the limit " + std::to_string(limits.maxPayloadBytes));
  }
  if (h.payloadBytes != size - kFrameHeaderBytes) {
    return Status(ErrorCode::kParseError, name + ": header says " + std::to_string(h.payloadBytes) +
                                              " payload bytes, frame has " +
                                              std::to_string(size - kFrameHeaderBytes));
  }
  if (frameChecksum(data + kFrameHeaderBytes, h.payloadBytes) != h.checksum) {
    return Status(ErrorCode::kParseError, name + ": payload checksum mismatch");
  }
  return h;
}

Status checkOneZstdFrame(const std::uint8_t* data, std::size_t size, std::size_t expected,
                         const char* what) {
  const unsigned long long content = ZSTD_getFrameContentSize(data, size);
  if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN ||
      content != expected) {
    return Status(ErrorCode::kParseError,
                  std::string(what) + "zstd frame size does not match the image");
  }
  if (ZSTD_findFrameCompressedSize(data, size) != size) {
    return Status(ErrorCode::kParseError,
                  std::string(what) + "zstd payload is not exactly one frame");
  }
  return Status();
}

}  // namespace detail
}  // namespace thinlod::codec
