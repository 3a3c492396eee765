// Encoding and decoding of thinlod messages (pure: no I/O, no logging).
//
// Contract:
// - decode(bytes) never trusts its input: it checks the size limit, runs the
//   FlatBuffers Verifier (depth/table limits from messages.h) before reading
//   any field, then semantic checks (finite floats, unit quaternions,
//   consistent sizes, enums in range, every limit). It returns a Message or
//   a Status naming the field, e.g. "SceneUpdate.operations[3].representation
//   .texture: RawRgba8 data is 100 bytes, expected 262144".
// - Errors: kResourceExhausted (a size limit), kVersionMismatch (envelope
//   version outside [kMinSupportedVersion, kProtocolVersion]; the message
//   names the version), kUnsupported (unknown message type), kInvalidArgument
//   (anything else malformed).
// - encode(message) runs the same semantic checks, so what we send a peer
//   accepts. Output is deterministic for a given message.
// - The input may have any alignment (decode copies it when misaligned).
// - Thread-safety: free functions without shared state; Encoder is one per
//   thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "thinlod/common/core/status.h"
#include "thinlod/protocol/messages.h"

namespace thinlod::protocol {

Result<Bytes> encode(const Message& message);
Result<Message> decode(const std::uint8_t* data, std::size_t size);
inline Result<Message> decode(const Bytes& bytes) { return decode(bytes.data(), bytes.size()); }

// The semantic checks alone (what encode runs before building).
Status validate(const Message& message);

// Reads only the envelope version (after verifying the envelope header).
Result<std::uint16_t> peekVersion(const std::uint8_t* data, std::size_t size);

// Highest version both sides speak, or kVersionMismatch naming both ranges.
Result<std::uint16_t> negotiateVersion(const Hello& peer);

// Reusable encoder for hot paths: keeps its buffer between calls, so a steady
// stream of similar messages does not allocate. The returned view is valid
// until the next encode() or the Encoder's destruction.
class Encoder {
 public:
  Encoder();
  ~Encoder();
  Encoder(const Encoder&) = delete;
  Encoder& operator=(const Encoder&) = delete;

  struct View {
    const std::uint8_t* data = nullptr;
    std::size_t size = 0;
  };
  Result<View> encode(const Message& message);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ErrorCode <-> wire byte (identity today; kept explicit so the mapping is
// checked in one place). fromWire rejects bytes outside the enum.
std::uint8_t errorCodeToWire(ErrorCode code);
Result<ErrorCode> errorCodeFromWire(std::uint8_t value);

}  // namespace thinlod::protocol
