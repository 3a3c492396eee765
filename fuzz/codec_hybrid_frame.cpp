// libFuzzer entry point for hybrid (triangles + disc points) link frames
// (decodeHybrid: frame header, the nested mesh frame, then a Draco point
// cloud). Built as thinlod_fuzz_codec_hybrid under -DTHINLOD_FUZZ=ON;
// replayed over fuzz/corpus/codec_hybrid (fuzz.CodecHybridFrameFuzzer...)
// under any compiler. The outer checksum is recomputed first so mutations
// reach Draco's point-cloud decoder (the nested mesh frame keeps its own
// checksum: codec_mesh_frame.cpp fuzzes that decoder).
//
// Oracle: decoded triangles and points are valid, with the header's counts,
// within the limits.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "codec_frame.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace thinlod;
  const std::vector<std::uint8_t> frame = fuzz::resealedFrame(data, size);
  codec::DecodeLimits limits = fuzz::fuzzDecodeLimits();
  limits.maxPoints = 1u << 16;
  Result<HybridGeometry> decoded = codec::decodeHybrid(frame.data(), frame.size(), limits);
  if (!decoded.ok()) return 0;
  const std::uint32_t points = std::uint32_t{frame[8]} | std::uint32_t{frame[9]} << 8 |
                               std::uint32_t{frame[10]} << 16 | std::uint32_t{frame[11]} << 24;
  const std::uint32_t triangles = std::uint32_t{frame[12]} | std::uint32_t{frame[13]} << 8 |
                                  std::uint32_t{frame[14]} << 16 | std::uint32_t{frame[15]} << 24;
  if (!decoded->triangles.validate("fuzz").ok() || !decoded->points.validate("fuzz").ok() ||
      decoded->points.size() != points || decoded->triangles.triangleCount() != triangles ||
      points > limits.maxPoints || triangles > limits.maxTriangles) {
    std::fprintf(stderr,
                 "codec hybrid fuzz oracle: decoded %zu points / %zu triangles, header %u / %u\n",
                 decoded->points.size(), decoded->triangles.triangleCount(), points, triangles);
    std::abort();
  }
  return 0;
}
