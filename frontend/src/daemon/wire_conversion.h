// Wire <-> frontend: turns a protocol::SceneUpdate (Draco meshes, codec-framed
// textures, docs/protocol.md) into a frontend::SceneBatch the renderer can
// submit, and a FrameRecord into the FrameStats sent back (the only place
// that does). Pure: no I/O, no logging, no globals; thread-safe.
//
// Contract:
// - The update is converted whole or not at all: the first bad operation
//   makes the result an error naming the update (plan, frame), the operation
//   index, the object id and the field; no partial batch is ever returned.
// - Skinned meshes: a kMesh frame with a skin (codec::decodeSkinnedMesh)
//   becomes Representation::skin; the update's bone poses go into the batch.
// - Meshes: Draco frames (codec::decodeMesh, bounded by `limits`); kMesh and
//   kMeshedImpostor need mesh bytes; a kSimpleImpostor with no mesh bytes gets
//   a null mesh (the unit quad placed by `transform`). triangleCount on the
//   wire must equal the decoded triangles (the wire contract says exact; an
//   empty simple-impostor mesh may say 0 or 2).
// - Textures: kRawRgba8 is taken as is (width*height*4 bytes); kPng, kJpeg,
//   kZstd are codec frames (codec::decodeTexture) whose own codec byte
//   and decoded size must match the wire's codec, width and height. kNone is
//   "no texture": an error for impostors (their lighting lives in it).
// - Shared textures (SceneUpdate::textures): see ConversionOptions; a mesh or
//   hybrid naming a texture id gets that image (and needs uvs); an unknown id
//   is an error naming it. Going past maxSharedTextures / maxSharedTextureBytes
//   refuses the update (kResourceExhausted) and adds none of its textures.
// - Colour: impostors are white (lighting baked in); meshes take the colour
//   the scene file gives their object (`meshColors`, by object id), white
//   when the id is not listed. Transform, generation and kind are copied.
// - What the frontend scene checks itself (ids unique, transforms invertible,
//   uvs on textured meshes) is checked again there on submit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/vec4.hpp>
#include <map>
#include <memory>
#include <vector>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/status.h"
#include "thinlod/frontend/frame_record.h"
#include "thinlod/frontend/frontend_scene.h"
#include "thinlod/protocol/messages.h"

namespace thinlod::frontend::daemon {

using MeshColors = std::map<std::uint64_t, glm::vec4>;  // object id -> RGBA in [0,1]

// Shared textures held for the session, by SharedTexture id (docs/protocol.md,
// "Shared textures"). Held representations keep their own reference, so a
// texture outlives the cache entry.
struct SharedTextureCache {
  std::map<std::uint64_t, std::shared_ptr<const RgbaImage>> textures;
  std::size_t decodedBytes = 0;  // RGBA bytes of `textures`
};

struct ConversionOptions {
  const MeshColors* meshColors = nullptr;  // may be null: every mesh is white
  codec::DecodeLimits limits;
  // Shared textures: an update's SharedTextures are decoded first (all or the
  // update is refused) and added here before its operations are converted, so
  // they stay held even when an operation is then refused; a later texture with
  // a held id replaces it. A representation's textureId must name one of this
  // update or one held here. Null: only the update's own textures resolve.
  SharedTextureCache* sharedTextures = nullptr;
  std::size_t maxSharedTextures = 4096;                  // held at once
  std::size_t maxSharedTextureBytes = std::size_t{1} << 30;  // decoded RGBA bytes held
};

// One representation; `what` prefixes error messages.
Result<Representation> convertRepresentation(const protocol::Representation& wire,
                                             std::uint64_t objectId,
                                             const ConversionOptions& options,
                                             const std::string& what);

// The whole update as one batch (plan copied), or the first error. Adds the
// update's shared textures to options.sharedTextures (see ConversionOptions).
Result<SceneBatch> convertUpdate(const protocol::SceneUpdate& update,
                                 const ConversionOptions& options);

// FrameStats of a frame: frame, plan, polygons (saturated to 32 bits),
// linkBytes and renderMs (0 when not finite) from the record; hasSnr only for
// a finite SNR (snrDb 0 otherwise: identical frames' +inf and a uniform
// frame's -inf are not sent); `timestampNs` = the pose's trace time;
// `rejectedPlans` at most protocol::kMaxRejectedPlans (the caller trims).
protocol::FrameStats toFrameStats(const FrameRecord& record, std::int64_t timestampNs,
                                  std::vector<std::uint64_t> rejectedPlans);

// What the scene holds (committed objects, ascending ids) as Hello.held says
// it: the backbone's representation id, kind, triangles (and a hybrid's
// points), each count saturated at the protocol's limit, at most
// protocol::kMaxHeldRepresentations entries (more objects than a scene
// update can carry never happen: the first ones are kept).
std::vector<protocol::HeldRepresentation> heldRepresentations(const FrontendScene& scene);
// Bytes of mesh and texture payload in an update (what decoding has to chew).
std::size_t payloadBytes(const protocol::SceneUpdate& update);

}  // namespace thinlod::frontend::daemon
