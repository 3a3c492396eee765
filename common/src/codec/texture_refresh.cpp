// Incremental texture refreshes against the client's texture (texture_refresh.h).
#include "thinlod/common/codec/texture_refresh.h"

#include <zstd.h>

#include <algorithm>
#include <memory>
#include <new>
#include <string>

#include "encoding_frame.h"
#include "thinlod/common/core/hash.h"

namespace thinlod::codec {
namespace {

constexpr std::array<char, 4> kRefreshMagic = {'T', 'L', 'T', 'R'};
constexpr int kMaxSide = 65500;  // as encoding.h's encoders
constexpr std::size_t kFingerprintBytes = 8;

Status refreshError(ErrorCode code, const std::string& message) {
  return Status(code, "texture refresh: " + message);
}

bool validImage(const RgbaImage& image) {
  return image.width > 0 && image.height > 0 && image.width <= kMaxSide &&
         image.height <= kMaxSide && image.consistent();
}

// Interleaved RGBA -> 4 planes.
void toPlanes(const RgbaImage& image, std::vector<std::uint8_t>& planes) {
  const std::size_t n = image.pixels.size() / 4;
  planes.resize(image.pixels.size());
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t c = 0; c < 4; ++c) planes[c * n + i] = image.pixels[4 * i + c];
  }
}

// Nearest integer code of d / step (step odd): |d - code * step| <= (step - 1) / 2.
int quantize(int d, int step) {
  const int half = step / 2;
  return d >= 0 ? (d + half) / step : -((-d + half) / step);
}

struct CctxFree {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};
struct DctxFree {
  void operator()(ZSTD_DCtx* d) const { ZSTD_freeDCtx(d); }
};

// One zstd frame of `content` (pledged size known, so the frame states it),
// optionally with `prefix` as the reference prefix; appended to `out`.
Status compressInto(const std::vector<std::uint8_t>& content,
                    const std::vector<std::uint8_t>* prefix, int level,
                    std::vector<std::uint8_t>& out) {
  std::unique_ptr<ZSTD_CCtx, CctxFree> cctx(ZSTD_createCCtx());
  if (!cctx) return refreshError(ErrorCode::kResourceExhausted, "zstd context");
  std::size_t r = ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_compressionLevel, level);
  if (!ZSTD_isError(r)) r = ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_checksumFlag, 0);
  if (!ZSTD_isError(r) && prefix != nullptr) {
    // The window must reach back over the whole prefix.
    int windowLog = 10;
    while (windowLog < 27 && (std::size_t{1} << windowLog) < prefix->size() + content.size()) {
      ++windowLog;
    }
    r = ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_windowLog, windowLog);
    if (!ZSTD_isError(r)) r = ZSTD_CCtx_refPrefix(cctx.get(), prefix->data(), prefix->size());
  }
  if (ZSTD_isError(r)) {
    return refreshError(ErrorCode::kInternal, std::string("zstd: ") + ZSTD_getErrorName(r));
  }
  const std::size_t start = out.size();
  out.resize(start + ZSTD_compressBound(content.size()));
  const std::size_t written = ZSTD_compress2(cctx.get(), out.data() + start, out.size() - start,
                                             content.data(), content.size());
  if (ZSTD_isError(written)) {
    return refreshError(ErrorCode::kInternal, std::string("zstd: ") + ZSTD_getErrorName(written));
  }
  out.resize(start + written);
  return Status();
}

bool isResidual(TextureDeltaMode mode) {
  return mode == TextureDeltaMode::kResidual || mode == TextureDeltaMode::kResidualLeft;
}
bool isLeftPredicted(TextureDeltaMode mode) {
  return mode == TextureDeltaMode::kResidualLeft || mode == TextureDeltaMode::kIntraLeft;
}

// Each plane row replaced by its differences to the left neighbour (mod 256).
void leftDifferences(std::vector<std::uint8_t>& planes, std::size_t width) {
  for (std::size_t row = 0; row < planes.size() / width; ++row) {
    std::uint8_t* p = planes.data() + row * width;
    for (std::size_t x = width - 1; x > 0; --x) p[x] = static_cast<std::uint8_t>(p[x] - p[x - 1]);
  }
}
// The inverse: running sums along each row (mod 256).
void leftSums(std::vector<std::uint8_t>& planes, std::size_t width) {
  for (std::size_t row = 0; row < planes.size() / width; ++row) {
    std::uint8_t* p = planes.data() + row * width;
    for (std::size_t x = 1; x < width; ++x) p[x] = static_cast<std::uint8_t>(p[x] + p[x - 1]);
  }
}

Result<EncodedTextureDelta> encodeMode(const RgbaImage& reference, const RgbaImage& texture,
                                       const std::vector<std::uint8_t>& referencePlanes,
                                       TextureDeltaMode mode, int step, int level) {
  const std::size_t n = texture.pixels.size() / 4;
  EncodedTextureDelta encoded;
  encoded.mode = mode;
  encoded.decoded = texture;
  std::vector<std::uint8_t> content;
  if (isResidual(mode)) {
    content.resize(texture.pixels.size());
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c = 0; c < 4; ++c) {
        const int ref = reference.pixels[4 * i + c];
        const int now = texture.pixels[4 * i + c];
        std::uint8_t code;
        if (c == 3 || step == 1) {
          code = static_cast<std::uint8_t>(now - ref);  // mod 256
        } else {
          const int q = quantize(now - ref, step);
          code = static_cast<std::uint8_t>(static_cast<std::int8_t>(q));
          encoded.decoded.pixels[4 * i + c] =
              static_cast<std::uint8_t>(std::clamp(ref + q * step, 0, 255));
        }
        content[c * n + i] = code;
      }
    }
  } else {
    toPlanes(texture, content);
  }
  if (isLeftPredicted(mode)) leftDifferences(content, static_cast<std::size_t>(texture.width));
  std::vector<std::uint8_t> payload(kFingerprintBytes);
  const std::uint64_t fingerprint = textureFingerprint(reference);
  for (std::size_t i = 0; i < kFingerprintBytes; ++i) {
    payload[i] = static_cast<std::uint8_t>(fingerprint >> (8 * i));
  }
  THINLOD_RETURN_IF_ERROR(
      compressInto(content, mode == TextureDeltaMode::kReferencePrefix ? &referencePlanes : nullptr,
                   level, payload));
  if (payload.size() > 0xFFFFFFFFu) {
    return refreshError(ErrorCode::kResourceExhausted, "payload over 4 GiB");
  }
  detail::FrameHeader header;
  header.magic = kRefreshMagic;
  header.codec = static_cast<std::uint8_t>(mode);
  header.countA = static_cast<std::uint32_t>(texture.width);
  header.countB = static_cast<std::uint32_t>(texture.height);
  header.attributes = static_cast<std::uint32_t>(step);
  encoded.bytes = detail::makeFrame(header, payload.data(), payload.size());
  return encoded;
}

}  // namespace

std::uint64_t textureFingerprint(const RgbaImage& image) {
  return fnv1a64(image.pixels.data(), image.pixels.size());
}

Result<EncodedTextureDelta> encodeTextureDelta(const RgbaImage& reference, const RgbaImage& texture,
                                               const TextureDeltaOptions& options) {
  if (!validImage(texture) || !validImage(reference)) {
    return refreshError(ErrorCode::kInvalidArgument,
                        "images must be consistent with sides in [1, 65500]");
  }
  if (reference.width != texture.width || reference.height != texture.height) {
    return refreshError(ErrorCode::kInvalidArgument,
                        "reference is " + std::to_string(reference.width) + "x" +
                            std::to_string(reference.height) + ", texture " +
                            std::to_string(texture.width) + "x" + std::to_string(texture.height) +
                            " (send a full texture)");
  }
  if (options.zstdLevel < 1 || options.zstdLevel > 19) {
    return refreshError(ErrorCode::kInvalidArgument, "zstd level outside 1..19");
  }
  if (options.colorTolerance < 0 || options.colorTolerance > 127) {
    return refreshError(ErrorCode::kInvalidArgument, "colour tolerance outside 0..127");
  }
  const int step = 2 * options.colorTolerance + 1;
  if (step > 1 && (options.mode == TextureDeltaMode::kReferencePrefix ||
                   options.mode == TextureDeltaMode::kIntraLeft)) {
    return refreshError(ErrorCode::kInvalidArgument, "a colour tolerance needs a residual mode");
  }
  if (static_cast<std::uint8_t>(options.mode) > 4) {
    return refreshError(ErrorCode::kInvalidArgument, "unknown mode");
  }
  try {
    std::vector<std::uint8_t> referencePlanes;
    std::vector<TextureDeltaMode> modes;
    if (options.mode != TextureDeltaMode::kAuto) {
      modes.push_back(options.mode);
    } else {
      modes = {TextureDeltaMode::kResidual, TextureDeltaMode::kResidualLeft};
      if (step == 1) {
        modes.push_back(TextureDeltaMode::kReferencePrefix);
        modes.push_back(TextureDeltaMode::kIntraLeft);
      }
    }
    if (std::find(modes.begin(), modes.end(), TextureDeltaMode::kReferencePrefix) != modes.end()) {
      toPlanes(reference, referencePlanes);
    }
    Result<EncodedTextureDelta> best = refreshError(ErrorCode::kInternal, "no mode");
    for (TextureDeltaMode mode : modes) {
      Result<EncodedTextureDelta> encoded =
          encodeMode(reference, texture, referencePlanes, mode, step, options.zstdLevel);
      if (!encoded.ok()) return encoded.status();
      if (!best.ok() || encoded->bytes.size() < best->bytes.size()) best = std::move(encoded);
    }
    return best;
  } catch (const std::bad_alloc&) {
    return refreshError(ErrorCode::kResourceExhausted, "out of memory");
  }
}

Result<RgbaImage> decodeTextureDelta(const RgbaImage& reference, const std::uint8_t* data,
                                     std::size_t size, const DecodeLimits& limits) {
  Result<detail::FrameHeader> parsed =
      detail::parseFrame(data, size, kRefreshMagic, limits, "texture refresh");
  if (!parsed.ok()) return parsed.status();
  const detail::FrameHeader& h = *parsed;
  const auto mode = static_cast<TextureDeltaMode>(h.codec);
  if (h.codec < 1 || h.codec > 4) {
    return refreshError(ErrorCode::kUnsupported, "unknown mode " + std::to_string(h.codec));
  }
  const std::uint32_t step = h.attributes;
  if (step == 0 || step > 255 || step % 2 == 0 || (!isResidual(mode) && step != 1)) {
    return refreshError(ErrorCode::kUnsupported, "colour step " + std::to_string(step));
  }
  const std::uint32_t maxSide = limits.maxDecodableSide();
  if (h.countA == 0 || h.countB == 0 || h.countA > maxSide || h.countB > maxSide) {
    return refreshError(ErrorCode::kResourceExhausted,
                        "dimensions " + std::to_string(h.countA) + "x" + std::to_string(h.countB) +
                            " outside [1, " + std::to_string(maxSide) + "]");
  }
  if (!reference.consistent() || static_cast<std::uint32_t>(reference.width) != h.countA ||
      static_cast<std::uint32_t>(reference.height) != h.countB) {
    return refreshError(ErrorCode::kParseError,
                        "frame is " + std::to_string(h.countA) + "x" + std::to_string(h.countB) +
                            ", the held reference " + std::to_string(reference.width) + "x" +
                            std::to_string(reference.height));
  }
  if (h.payloadBytes < kFingerprintBytes) {
    return refreshError(ErrorCode::kParseError, "payload shorter than the reference fingerprint");
  }
  const std::uint8_t* payload = data + kFrameHeaderBytes;
  std::uint64_t fingerprint = 0;
  for (int i = static_cast<int>(kFingerprintBytes) - 1; i >= 0; --i) {
    fingerprint = (fingerprint << 8) | payload[i];
  }
  if (fingerprint != textureFingerprint(reference)) {
    return refreshError(ErrorCode::kParseError,
                        "frame was encoded against another reference texture");
  }
  const std::uint8_t* z = payload + kFingerprintBytes;
  const std::size_t zSize = h.payloadBytes - kFingerprintBytes;
  const std::size_t expected = reference.pixels.size();
  THINLOD_RETURN_IF_ERROR(detail::checkOneZstdFrame(z, zSize, expected, "texture refresh: "));
  try {
    std::vector<std::uint8_t> planes(expected);
    std::vector<std::uint8_t> referencePlanes;
    std::unique_ptr<ZSTD_DCtx, DctxFree> dctx(ZSTD_createDCtx());
    if (!dctx) return refreshError(ErrorCode::kResourceExhausted, "zstd context");
    if (mode == TextureDeltaMode::kReferencePrefix) {
      toPlanes(reference, referencePlanes);
      const std::size_t r =
          ZSTD_DCtx_refPrefix(dctx.get(), referencePlanes.data(), referencePlanes.size());
      if (ZSTD_isError(r)) return refreshError(ErrorCode::kInternal, "zstd prefix");
    }
    const std::size_t written =
        ZSTD_decompressDCtx(dctx.get(), planes.data(), planes.size(), z, zSize);
    if (ZSTD_isError(written) || written != expected) {
      return refreshError(ErrorCode::kParseError, "zstd payload is corrupt");
    }
    if (isLeftPredicted(mode)) leftSums(planes, static_cast<std::size_t>(reference.width));
    RgbaImage out(reference.width, reference.height);
    const std::size_t n = expected / 4;
    const int s = static_cast<int>(step);
    // One branch-free loop per channel (the decode is on the client's frame path).
    for (std::size_t c = 0; c < 4; ++c) {
      const std::uint8_t* code = planes.data() + c * n;
      const std::uint8_t* ref = reference.pixels.data() + c;
      std::uint8_t* dst = out.pixels.data() + c;
      if (!isResidual(mode)) {
        for (std::size_t i = 0; i < n; ++i) dst[4 * i] = code[i];
      } else if (c == 3 || s == 1) {
        for (std::size_t i = 0; i < n; ++i) {
          dst[4 * i] = static_cast<std::uint8_t>(ref[4 * i] + code[i]);  // mod 256
        }
      } else {
        for (std::size_t i = 0; i < n; ++i) {
          const int q = static_cast<std::int8_t>(code[i]);
          dst[4 * i] = static_cast<std::uint8_t>(std::clamp(int{ref[4 * i]} + q * s, 0, 255));
        }
      }
    }
    return out;
  } catch (const std::bad_alloc&) {
    return refreshError(ErrorCode::kResourceExhausted, "out of memory");
  }
}

}  // namespace thinlod::codec
