// Not a ctest test: encode/decode time and size of the link encodings for
// shared models (Draco at the bits chosen for several accuracies) and a
// 256x256 RGBA impostor-like texture (each codec). Prints CSV; times are
// thread CPU milliseconds (insensitive to other load), median of 9 runs.
// Usage: encoding_measure [model.obj ...]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <functional>
#include <string>
#include <vector>

#include "test_meshes.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/cpu_time.h"

namespace {

using namespace thinlod;
using namespace thinlod::codec;

double medianMillis(const std::function<void()>& work) {
  std::vector<double> times;
  for (int i = 0; i < 9; ++i) {
    const double start = thinlod::threadCpuSeconds();
    work();
    times.push_back((thinlod::threadCpuSeconds() - start) * 1e3);
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

RgbaImage impostorLike(int size) {
  // A shaded blob covering ~30% of the image on transparent black.
  RgbaImage t(size, size);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size - 0.5, v = (y + 0.5) / size - 0.55;
      if (u * u / 0.09 + v * v / 0.12 >= 1.0) continue;
      std::uint8_t* p = t.at(x, y);
      const double shade = 0.35 + 0.6 * std::max(0.0, 0.6 - u + 0.4 * v);
      p[0] = static_cast<std::uint8_t>(std::min(255.0, 230 * shade + ((x * 7 + y * 13) % 5)));
      p[1] = static_cast<std::uint8_t>(std::min(255.0, 190 * shade));
      p[2] = static_cast<std::uint8_t>(std::min(255.0, 150 * shade));
      p[3] = 255;
    }
  }
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> models = {"cow.obj", "stanford-bunny.obj"};
  if (argc > 1) models.assign(argv + 1, argv + argc);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  std::printf("kind,name,setting,triangles,bytes,encode_ms,decode_ms\n");
  for (const std::string& name : models) {
    Result<IndexedMesh> mesh = testing::readObjPositions(testing::sharedModelPath(name));
    if (!mesh.ok()) {
      std::fprintf(stderr, "%s\n", mesh.status().toString().c_str());
      return 1;
    }
    for (int bits : {8, 11, 14, 20}) {
      MeshEncodeOptions options;
      options.positionBits = bits;
      Result<std::vector<std::uint8_t>> first = encodeMesh(*mesh, options);
      if (!first.ok()) {
        std::fprintf(stderr, "%s: %s\n", name.c_str(), first.status().toString().c_str());
        return 1;
      }
      std::vector<std::uint8_t> frame;
      const double enc = medianMillis([&] { frame = *encodeMesh(*mesh, options); });
      const double dec = medianMillis([&] {
        if (!decodeMesh(frame.data(), frame.size()).ok()) std::abort();
      });
      std::printf("mesh,%s,bits=%d,%zu,%zu,%.3f,%.3f\n", name.c_str(), bits, mesh->triangleCount(),
                  frame.size(), enc, dec);
    }
  }
  // Transparent background (alpha 0 outside the object), as rendered.
  const RgbaImage transparent = impostorLike(256);
  // The same on an opaque grey background, so JPEG applies.
  RgbaImage grey = transparent;
  for (std::size_t i = 0; i < grey.pixels.size(); i += 4) {
    if (grey.pixels[i + 3] == 0) grey.pixels[i] = grey.pixels[i + 1] = grey.pixels[i + 2] = 96;
    grey.pixels[i + 3] = 255;
  }
  struct Case {
    const char* name;
    const RgbaImage* texture;
    TextureCodec codec;
    int level;  // zstd level / PNG zlib level / JPEG quality
  };
  for (const Case& c : {Case{"rgba_alpha", &transparent, TextureCodec::kZstd, 1},
                        Case{"rgba_alpha", &transparent, TextureCodec::kZstd, 9},
                        Case{"rgba_alpha", &transparent, TextureCodec::kPng, 1},
                        Case{"rgba_alpha", &transparent, TextureCodec::kPng, 6},
                        Case{"rgb_opaque", &grey, TextureCodec::kZstd, 1},
                        Case{"rgb_opaque", &grey, TextureCodec::kPng, 1},
                        Case{"rgb_opaque", &grey, TextureCodec::kPng, 6},
                        Case{"rgb_opaque", &grey, TextureCodec::kJpeg, 85}}) {
    TextureEncodeOptions options;
    options.zstdLevel = options.pngCompressionLevel = options.jpegQuality = c.level;
    std::vector<std::uint8_t> frame;
    const double enc =
        medianMillis([&] { frame = *encodeTextureWith(*c.texture, c.codec, options); });
    const double dec = medianMillis([&] {
      if (!decodeTexture(frame.data(), frame.size()).ok()) std::abort();
    });
    const char* codec = c.codec == TextureCodec::kZstd  ? "zstd"
                        : c.codec == TextureCodec::kPng ? "png"
                                                        : "jpeg";
    std::printf("texture,%s,%s-%d,0,%zu,%.3f,%.3f\n", c.name, codec, c.level, frame.size(), enc,
                dec);
  }
  for (TexturePolicy policy :
       {TexturePolicy::kFastest, TexturePolicy::kSmallestLossless, TexturePolicy::kSmallest}) {
    TextureEncodeOptions options;
    options.policy = policy;
    EncodedTexture e;
    const double enc = medianMillis([&] { e = *encodeTexture(grey, options); });
    std::printf("texture_policy,rgb_opaque,policy=%d->codec=%d,0,%zu,%.3f,\n",
                static_cast<int>(policy), static_cast<int>(e.codec), e.bytes.size(), enc);
  }
  return 0;
}
