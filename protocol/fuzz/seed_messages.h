// One or more valid instances of every protocol message, with deterministic
// content: the round-trip tests, the fuzz seed corpus and the benchmarks
// start from these. Every returned message passes validate().
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "thinlod/protocol/messages.h"

namespace thinlod::protocol::seeds {

struct NamedMessage {
  std::string name;  // file-name safe, e.g. "scene_update_mixed"
  Message message;
};

std::vector<NamedMessage> seedMessages();

// Deterministic filler bytes (a fixed LCG from `seed`).
Bytes patternBytes(std::size_t size, std::uint32_t seed);

// A representation of `kind` with mesh/texture payloads of about the given sizes.
Representation sampleRepresentation(RepresentationKind kind, std::size_t meshBytes,
                                    std::uint32_t textureSide);

// A SceneUpdate holding one mesh representation whose Draco payload has
// `meshBytes` bytes (the 256 KiB benchmark message).
SceneUpdate sceneUpdateOfSize(std::size_t meshBytes, std::uint64_t plan);

}  // namespace thinlod::protocol::seeds
