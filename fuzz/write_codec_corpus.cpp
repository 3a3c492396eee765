// Writes the seed corpora of the codec fuzzers: valid link frames
// (encoding.h) covering each Draco encoding method (speeds 0, 5, 10 select
// edgebreaker-valence, edgebreaker and sequential coding), each attribute
// combination, each texture codec and each texture refresh mode (inputs of
// fuzz/codec_texture_refresh.cpp: two size bytes, the reference, the frame).
// Run after a frame format change and
// commit the result as a reviewed change:
//   build/fuzz/thinlod_fuzz_write_codec_corpus fuzz/corpus
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/codec/texture_refresh.h"

namespace {

using thinlod::IndexedMesh;
using thinlod::RgbaImage;
namespace codec = thinlod::codec;

// An n x n grid of quads on a slightly bumped sheet, with the attributes asked for.
IndexedMesh grid(int n, bool normals, bool uvs, bool colors) {
  IndexedMesh mesh;
  for (int y = 0; y <= n; ++y) {
    for (int x = 0; x <= n; ++x) {
      const float u = static_cast<float>(x) / n, v = static_cast<float>(y) / n;
      mesh.positions.emplace_back(u, v, 0.1f * ((x * 7 + y * 3) % 5));
      if (uvs) mesh.uvs.emplace_back(u, v);
      if (colors) {
        mesh.colors.push_back(
            {static_cast<std::uint8_t>(x * 40), static_cast<std::uint8_t>(y * 40), 128, 255});
      }
    }
  }
  const auto at = [n](int x, int y) { return static_cast<std::uint32_t>(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      mesh.indices.insert(mesh.indices.end(), {at(x, y), at(x + 1, y), at(x + 1, y + 1)});
      mesh.indices.insert(mesh.indices.end(), {at(x, y), at(x + 1, y + 1), at(x, y + 1)});
    }
  }
  if (normals) mesh.computeNormals();
  return mesh;
}

RgbaImage image(int width, int height, bool opaque) {
  RgbaImage t(width, height);
  for (std::size_t i = 0; i < t.pixels.size(); ++i) {
    t.pixels[i] = static_cast<std::uint8_t>(i % 4 == 3 ? (opaque ? 255 : i * 5) : (i * 7) % 251);
  }
  return t;
}

bool write(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  std::printf("%s (%zu bytes)\n", path.c_str(), bytes.size());
  return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr,
                 "usage: %s CORPUS_DIR (writes CORPUS_DIR/codec_mesh, codec_texture, codec_hybrid, "
                 "codec_texture_refresh)\n",
                 argv[0]);
    return 2;
  }
  const std::filesystem::path root = argv[1];
  std::filesystem::create_directories(root / "codec_mesh");
  std::filesystem::create_directories(root / "codec_texture");
  std::filesystem::create_directories(root / "codec_hybrid");
  std::filesystem::create_directories(root / "codec_texture_refresh");
  bool ok = true;
  struct MeshSeed {
    const char* name;
    bool normals, uvs, colors;
    int speed, bits;
  };
  const MeshSeed meshes[] = {
      {"positions_speed0", false, false, false, 0, 11},
      {"positions_speed5", false, false, false, 5, 14},
      {"positions_speed10", false, false, false, 10, 20},
      {"normals_speed5", true, false, false, 5, 8},
      {"uvs_speed10", false, true, false, 10, 12},
      {"colors_speed0", false, false, true, 0, 14},
      {"all_speed5", true, true, true, 5, 14},
      {"all_speed10", true, true, true, 10, 14},
  };
  for (const MeshSeed& seed : meshes) {
    codec::MeshEncodeOptions options;
    options.encodeSpeed = options.decodeSpeed = seed.speed;
    options.positionBits = seed.bits;
    const auto frame = codec::encodeMesh(grid(4, seed.normals, seed.uvs, seed.colors), options);
    if (!frame.ok()) {
      std::fprintf(stderr, "%s: %s\n", seed.name, frame.status().toString().c_str());
      return 1;
    }
    ok &= write(root / "codec_mesh" / (std::string(seed.name) + ".bin"), *frame);
  }
  // Skinned frames (attribute bit 8, encodeSkinnedMesh): rigid and two-bone
  // vertices, with and without the other attributes, sequential and
  // edgebreaker coding.
  const MeshSeed skinnedMeshes[] = {
      {"skinned_positions_speed5", false, false, false, 5, 14},
      {"skinned_all_speed10", true, true, true, 10, 14},
  };
  for (const MeshSeed& seed : skinnedMeshes) {
    const IndexedMesh mesh = grid(4, seed.normals, seed.uvs, seed.colors);
    std::vector<thinlod::anim::VertexSkin> skin(mesh.vertexCount());
    for (std::size_t v = 0; v < skin.size(); ++v) {
      skin[v].boneA = static_cast<std::uint32_t>(v % 3);
      skin[v].boneB = static_cast<std::uint32_t>(v % 3 == 0 ? 0 : 3 + v % 2);
      skin[v].weightB = skin[v].boneA == skin[v].boneB ? 0.0f : 0.25f * float(1 + v % 3);
    }
    codec::MeshEncodeOptions options;
    options.encodeSpeed = options.decodeSpeed = seed.speed;
    options.positionBits = seed.bits;
    const auto frame = codec::encodeSkinnedMesh(mesh, skin, options);
    if (!frame.ok()) {
      std::fprintf(stderr, "%s: %s\n", seed.name, frame.status().toString().c_str());
      return 1;
    }
    ok &= write(root / "codec_mesh" / (std::string(seed.name) + ".bin"), *frame);
  }
  // Hybrid frames: points only, triangles and points, with and without
  // normals, at each Draco point-cloud method (speed 10: sequential; below:
  // kd-tree).
  struct HybridSeed {
    const char* name;
    bool triangles, normals;
    int speed, points;
  };
  const HybridSeed hybrids[] = {
      {"points_speed5", false, false, 5, 24},  {"points_normals_speed10", false, true, 10, 17},
      {"both_speed0", true, true, 0, 30},      {"both_speed10", true, false, 10, 9},
      {"one_point_speed5", false, true, 5, 1},
  };
  for (const HybridSeed& seed : hybrids) {
    thinlod::HybridGeometry g;
    if (seed.triangles) g.triangles = grid(3, false, false, false);
    for (int i = 0; i < seed.points; ++i) {
      g.points.centres.emplace_back(0.1f * i, 0.05f * (i % 7), 0.02f * (i % 3));
      if (seed.normals) g.points.normals.emplace_back(0.0f, 0.0f, 1.0f);
      g.points.radii.push_back(0.01f * (1 + i % 4));
      g.points.colors.push_back({static_cast<std::uint8_t>(i * 9), 100, 200, 255});
    }
    codec::MeshEncodeOptions options;
    options.encodeSpeed = options.decodeSpeed = seed.speed;
    const auto frame = codec::encodeHybrid(g, options);
    if (!frame.ok()) {
      std::fprintf(stderr, "%s: %s\n", seed.name, frame.status().toString().c_str());
      return 1;
    }
    ok &= write(root / "codec_hybrid" / (std::string(seed.name) + ".bin"), *frame);
  }
  struct TextureSeed {
    const char* name;
    codec::TextureCodec codec;
    int width, height;
    bool opaque;
  };
  const TextureSeed textures[] = {
      {"zstd_8x8", codec::TextureCodec::kZstd, 8, 8, false},
      {"zstd_17x3", codec::TextureCodec::kZstd, 17, 3, true},
      {"png_8x8", codec::TextureCodec::kPng, 8, 8, false},
      {"png_5x9_opaque", codec::TextureCodec::kPng, 5, 9, true},
      {"jpeg_8x8", codec::TextureCodec::kJpeg, 8, 8, true},
      {"jpeg_16x24", codec::TextureCodec::kJpeg, 16, 24, true},
  };
  for (const TextureSeed& seed : textures) {
    const auto frame =
        codec::encodeTextureWith(image(seed.width, seed.height, seed.opaque), seed.codec);
    if (!frame.ok()) {
      std::fprintf(stderr, "%s: %s\n", seed.name, frame.status().toString().c_str());
      return 1;
    }
    ok &= write(root / "codec_texture" / (std::string(seed.name) + ".bin"), *frame);
  }
  // Texture refreshes: the reference shifted by a texel and brightened.
  struct RefreshSeed {
    const char* name;
    codec::TextureDeltaMode mode;
    int width, height, tolerance;
  };
  const RefreshSeed refreshes[] = {
      {"residual_8x8", codec::TextureDeltaMode::kResidual, 8, 8, 0},
      {"residual_lossy_9x5", codec::TextureDeltaMode::kResidual, 9, 5, 2},
      {"prefix_8x8", codec::TextureDeltaMode::kReferencePrefix, 8, 8, 0},
      {"prefix_16x3", codec::TextureDeltaMode::kReferencePrefix, 16, 3, 0},
      {"residual_left_8x8", codec::TextureDeltaMode::kResidualLeft, 8, 8, 0},
      {"residual_left_lossy_7x9", codec::TextureDeltaMode::kResidualLeft, 7, 9, 3},
      {"intra_left_12x4", codec::TextureDeltaMode::kIntraLeft, 12, 4, 0},
  };
  for (const RefreshSeed& seed : refreshes) {
    const RgbaImage reference = image(seed.width, seed.height, false);
    RgbaImage next = reference;
    for (int y = 0; y < seed.height; ++y) {
      for (int x = seed.width - 1; x > 0; --x) {
        for (int c = 0; c < 4; ++c) {
          const int v = reference.at(x - 1, y)[c] + (c == 3 ? 0 : 3);
          next.at(x, y)[c] = static_cast<std::uint8_t>(v > 255 ? 255 : v);
        }
      }
    }
    codec::TextureDeltaOptions options;
    options.mode = seed.mode;
    options.colorTolerance = seed.tolerance;
    const auto delta = codec::encodeTextureDelta(reference, next, options);
    if (!delta.ok()) {
      std::fprintf(stderr, "%s: %s\n", seed.name, delta.status().toString().c_str());
      return 1;
    }
    std::vector<std::uint8_t> input = {static_cast<std::uint8_t>(seed.width - 1),
                                       static_cast<std::uint8_t>(seed.height - 1)};
    input.insert(input.end(), reference.pixels.begin(), reference.pixels.end());
    input.insert(input.end(), delta->bytes.begin(), delta->bytes.end());
    ok &= write(root / "codec_texture_refresh" / (std::string(seed.name) + ".bin"), input);
  }
  return ok ? 0 : 1;
}
