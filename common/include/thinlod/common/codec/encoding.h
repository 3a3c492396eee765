// Link encoding: meshes (Draco) and RGBA8 textures (zstd / PNG / JPEG) in a
// small versioned frame. The encoded byte size is the link cost of a
// representation (resources of a bytes accuracy curve).
//
// Frame (all integers little-endian, 32-byte header then payload):
//   0 magic "TLME" (mesh) / "TLTX" (texture)   4 u16 version (kFrameVersion)
//   6 u8 codec   7 u8 flags (0)   8 u32 mesh: vertices / texture: width
//  12 u32 mesh: triangles / texture: height   16 u32 payload bytes
//  20 u32 mesh: attribute bits (1 normals, 2 uvs, 4 colors, 8 skin) / texture: 0
//  24 u64 FNV-1a 64 of the payload            32 payload
// Contract:
// - Mesh positions are quantized by Draco: each vertex moves by at most
//   positionErrorBound() (half a step per axis, step = largest bbox extent /
//   (2^bits - 1)); normals and uvs are quantized too; colors are exact.
//   Triangles whose corners repeat an index are dropped before encoding;
//   Draco may reorder or split vertices, so compare meshes geometrically.
// - positionBitsForAccuracy(a): the fewest bits (clamped to [8, 20]) whose
//   worst displacement, step * sqrt(3) / 2 with step <= diagonal/(2^bits-1),
//   is at most budgetFraction of the error budget diagonal / a. Coarse levels
//   get fewer bits.
// - Decoders take untrusted bytes: header fields, payload size and checksum
//   are verified and counts checked against DecodeLimits before anything is
//   allocated or a third-party decoder runs; the decoded result is validated
//   again. Any failure returns an error (kParseError, kVersionMismatch,
//   kResourceExhausted, kUnsupported); decoders never crash or throw.
// - Pure functions, no globals; safe to call concurrently.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "thinlod/common/core/disc_points.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/core/texture_codec.h"

namespace thinlod::codec {

// 2: texture frames carry the one TextureCodec's values (zstd = 4, was 1).
inline constexpr std::uint16_t kFrameVersion = 2;
inline constexpr std::size_t kFrameHeaderBytes = 32;

struct DecodeLimits {
  std::size_t maxPayloadBytes = 64u << 20;
  std::size_t maxVertices = 1u << 24;
  std::size_t maxTriangles = 1u << 24;
  std::uint32_t maxTextureDimension = 8192;  // per side
  std::size_t maxPoints = 1u << 24;          // hybrid frames' disc points

  // The largest texture side a decoder may accept: maxTextureDimension, but
  // never above INT_MAX (RgbaImage sides are int).
  std::uint32_t maxDecodableSide() const {
    return std::min<std::uint32_t>(maxTextureDimension,
                                   static_cast<std::uint32_t>(std::numeric_limits<int>::max()));
  }
};

// --- Meshes ---
struct MeshEncodeOptions {
  int positionBits = 14;  // [8, 20]; see positionBitsForAccuracy
  // positionRange > 0: quantize positions on this grid (origin, cube side
  // positionRange, positionBits) instead of the mesh's own bounding box, so
  // meshes encoded on one grid decode a shared position bit-identically
  // (the regions of one mesh, docs/regions.md). Every position must lie in
  // the cube; a non-finite origin or range is kInvalidArgument.
  std::array<float, 3> positionOrigin{0.0f, 0.0f, 0.0f};
  float positionRange = 0.0f;
  int normalBits = 10;
  int texcoordBits = 12;
  int encodeSpeed = 5;  // Draco 0 (smallest) .. 10 (fastest)
  int decodeSpeed = 5;
};

int positionBitsForAccuracy(double relativeAccuracy, double budgetFraction = 0.1);
// Largest displacement of any vertex of `mesh` encoded with `bits` (units).
double positionErrorBound(const IndexedMesh& mesh, int bits);

// Errors: invalid mesh or options (kInvalidArgument), no triangles left.
Result<std::vector<std::uint8_t>> encodeMesh(const IndexedMesh& mesh,
                                             const MeshEncodeOptions& options = {});
Result<IndexedMesh> decodeMesh(const std::uint8_t* data, std::size_t size,
                               const DecodeLimits& limits = {});

// --- Skinned meshes (docs/animation.md, "Served") ---
// encodeMesh plus each vertex's two-bone skin (anim::VertexSkin, validateSkin
// against kMaxSkinBones; a rigid vertex is sent as one bone, weight 0) as a
// Draco GENERIC attribute, uint16 x3 (boneA, boneB, round(weightB * 65535)):
// bones exact, a weight within 0.5 / 65535; attribute bit 8. Draco moves it
// with its vertex. decodeSkinnedMesh returns the mesh and, when the frame has
// one, the skin (a vertex naming one bone with a non-zero weight is
// kParseError); decodeMesh reads the same frames and drops the skin. Bones
// index the sender's palette: the receiver checks them against the poses it
// gets.
inline constexpr std::uint32_t kMaxSkinBones = 65536;
Result<std::vector<std::uint8_t>> encodeSkinnedMesh(const IndexedMesh& mesh,
                                                    const std::vector<anim::VertexSkin>& skin,
                                                    const MeshEncodeOptions& options = {});
struct SkinnedMeshFrame {
  IndexedMesh mesh;
  std::vector<anim::VertexSkin> skin;  // empty: the frame carries none
};
Result<SkinnedMeshFrame> decodeSkinnedMesh(const std::uint8_t* data, std::size_t size,
                                           const DecodeLimits& limits = {});

// --- Hybrid triangles + points (docs/hybrid.md, "Link encoding") ---
// Frame magic "TLHY", codec 1 (Draco): countA = points, countB = triangles,
// attributes bit 1 = point normals. Payload: u32 LE M, then M bytes of an
// encodeMesh frame of the triangles (M = 0: no triangles), then the rest: a
// Draco point cloud (empty: no points) with POSITION (float32 x3, quantized
// to options.positionBits over the points' own bbox: each centre moves by at
// most positionErrorBound of those points), NORMAL (optional, normalBits),
// GENERIC (the radius, float32, exact) and COLOR (uint8 x4, exact). Draco
// may reorder points (all attributes move together).
// Errors: invalid geometry or options (kInvalidArgument), nothing to encode.
Result<std::vector<std::uint8_t>> encodeHybrid(const HybridGeometry& geometry,
                                               const MeshEncodeOptions& options = {});
// The decoded triangles pass IndexedMesh::validate, the points
// DiscPoints::validate (finite, radii > 0), with exactly the header's counts
// (points <= limits.maxPoints; the triangles' frame obeys decodeMesh).
Result<HybridGeometry> decodeHybrid(const std::uint8_t* data, std::size_t size,
                                    const DecodeLimits& limits = {});
// Largest centre displacement of `points` encoded with `bits` (units).
double pointPositionErrorBound(const DiscPoints& points, int bits);

// --- Textures: thinlod::RgbaImage (rgba_image.h) ---
// Encoders reject (kInvalidArgument) a zero or negative side, a side longer
// than 65500 pixels, or pixels.size() != width * height * 4. A decoded image
// has 1..limits.maxTextureDimension pixels per side and is consistent().

// The frame's codec byte is the TextureCodec value (texture_codec.h); only
// the framed codecs (png, jpeg, zstd) are encoded here.
using ::thinlod::TextureCodec;

// Codec choice (256x256 impostor-like image, CPU ms encode / decode, bytes;
// docs/results/error-validation.md): zstd-1 0.09 / 0.04 / 7.9 KB, PNG-6
// 2.1 / 0.5 / 7.8 KB, JPEG q85 (opaque only) 0.19 / 0.18 / 3.6 KB:
// - kFastest: zstd only; for impostors refreshed every few frames.
// - kSmallestLossless: PNG and zstd both, the smaller wins (costs both).
// - kSmallest: as kSmallestLossless, plus JPEG when every alpha is 255 and
//   the JPEG's PSNR >= jpegMinPsnr; the smallest acceptable encoding wins.
enum class TexturePolicy : std::uint8_t { kFastest, kSmallestLossless, kSmallest };

struct TextureEncodeOptions {
  TexturePolicy policy = TexturePolicy::kSmallest;
  int zstdLevel = 1;
  int pngCompressionLevel = 6;  // zlib 0..9
  int jpegQuality = 85;
  double jpegMinPsnr = 32.0;  // dB over RGB
};

struct EncodedTexture {
  TextureCodec codec = TextureCodec::kZstd;
  std::vector<std::uint8_t> bytes;  // the whole frame
};

Result<EncodedTexture> encodeTexture(const RgbaImage& texture,
                                     const TextureEncodeOptions& options = {});
// One codec, no policy (JPEG drops alpha: kInvalidArgument unless opaque).
Result<std::vector<std::uint8_t>> encodeTextureWith(const RgbaImage& texture, TextureCodec codec,
                                                    const TextureEncodeOptions& options = {});
Result<RgbaImage> decodeTexture(const std::uint8_t* data, std::size_t size,
                                const DecodeLimits& limits = {});

// A texture file of a scene (PNG or JPEG, told by its first bytes, or TGA,
// whose 18-byte header is checked first: no colour map, true-colour or grey,
// raw pixels inside the file; no frame header): the image's own width and height are checked against `limits`
// (maxDecodableSide, and width * height * 4 <= maxPayloadBytes * 16) before
// any pixel is decoded; grey, grey + alpha and RGB become RGBA8 (alpha 255).
// Other formats are kUnsupported, malformed bytes kParseError, images over
// the limits kResourceExhausted. Rows top-down, as RgbaImage stores them.
Result<RgbaImage> decodeImageFile(const std::uint8_t* data, std::size_t size,
                                  const DecodeLimits& limits = {});
// The image file at `path` (a scene's texture): read with readFileBounded
// (limits.maxPayloadBytes) and decoded as decodeImageFile; errors start with
// the path. The one loader of texture files for the three daemons.
Result<RgbaImage> readImageFile(const std::string& path, const DecodeLimits& limits = {});

// FNV-1a 64 over bytes: the frame's payload checksum (catches corruption on
// the link, not forgery).
std::uint64_t frameChecksum(const std::uint8_t* data, std::size_t size);

}  // namespace thinlod::codec
