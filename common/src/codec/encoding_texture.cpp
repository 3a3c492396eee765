// Texture link encoding: raw RGBA8 + zstd, PNG or JPEG through OpenImageIO
// (see encoding.h for the frame and the codec policy).
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <new>
#include <string>
#include <vector>

#include "encoding_frame.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/file_bytes.h"

namespace thinlod::codec {
namespace {

// Longest side an encoder accepts (encoding.h).
constexpr int kMaxEncodedSide = 65500;

// A file name only selects OpenImageIO's format plugin; bytes go through
// an in-memory IOProxy.
const char* formatFileName(TextureCodec codec) {
  return codec == TextureCodec::kPng ? "link.png" : "link.jpg";
}

Status textureError(ErrorCode code, const std::string& message) {
  return Status(code, "texture: " + message);
}

Status checkTexture(const RgbaImage& texture) {
  const std::string size = std::to_string(texture.width) + "x" + std::to_string(texture.height);
  if (texture.width < 0 || texture.height < 0) {
    return textureError(ErrorCode::kInvalidArgument, "negative size " + size);
  }
  if (texture.width == 0 || texture.height == 0) {
    return textureError(ErrorCode::kInvalidArgument, "empty image (" + size + ")");
  }
  if (texture.width > kMaxEncodedSide || texture.height > kMaxEncodedSide) {
    return textureError(
        ErrorCode::kInvalidArgument,
        "size " + size + " has a side longer than " + std::to_string(kMaxEncodedSide) + " pixels");
  }
  // Both sides are in [1, 65500]: the product cannot overflow 64 bits.
  const std::uint64_t expected =
      static_cast<std::uint64_t>(texture.width) * static_cast<std::uint64_t>(texture.height) * 4;
  if (texture.pixels.size() != expected) {
    return textureError(ErrorCode::kInvalidArgument,
                        "pixel buffer has " + std::to_string(texture.pixels.size()) +
                            " bytes, expected " + std::to_string(expected));
  }
  return Status();
}

Result<std::vector<std::uint8_t>> zstdPayload(const RgbaImage& texture, int level) {
  std::vector<std::uint8_t> out(ZSTD_compressBound(texture.pixels.size()));
  const std::size_t written =
      ZSTD_compress(out.data(), out.size(), texture.pixels.data(), texture.pixels.size(), level);
  if (ZSTD_isError(written)) {
    return textureError(ErrorCode::kInternal, std::string("zstd: ") + ZSTD_getErrorName(written));
  }
  out.resize(written);
  return out;
}

Result<std::vector<std::uint8_t>> imagePayload(const RgbaImage& texture, TextureCodec codec,
                                               const TextureEncodeOptions& options) {
  const bool jpeg = codec == TextureCodec::kJpeg;
  const int channels = jpeg ? 3 : 4;
  std::vector<std::uint8_t> rgb;
  const std::uint8_t* pixels = texture.pixels.data();
  if (jpeg) {  // JPEG has no alpha channel: drop it (callers ensure it is 255)
    rgb.resize(texture.pixels.size() / 4 * 3);
    for (std::size_t p = 0, n = rgb.size() / 3; p < n; ++p) {
      for (int c = 0; c < 3; ++c) rgb[3 * p + c] = texture.pixels[4 * p + c];
    }
    pixels = rgb.data();
  }
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput proxy(bytes);
  OIIO::ImageSpec spec(texture.width, texture.height, channels, OIIO::TypeDesc::UINT8);
  if (jpeg) {
    spec.attribute("Compression", "jpeg:" + std::to_string(options.jpegQuality));
  } else {
    spec.attribute("png:compressionLevel", options.pngCompressionLevel);
    // libpng's default adaptive filter choice tries all five filters per
    // row; the fixed "sub" filter was 1.7x faster and 8% smaller on a
    // 256x256 impostor-like image (docs/results/error-validation.md).
    constexpr int kPngFilterSub = 0x10;  // PNG_FILTER_SUB
    spec.attribute("png:filter", kPngFilterSub);
    // Our pixels are stored as given: no premultiplication either way.
    spec.attribute("oiio:UnassociatedAlpha", 1);
  }
  std::unique_ptr<OIIO::ImageOutput> output =
      OIIO::ImageOutput::create(formatFileName(codec), &proxy);
  if (!output || !output->open(formatFileName(codec), spec) ||
      !output->write_image(OIIO::TypeDesc::UINT8, pixels) || !output->close()) {
    const std::string why = output ? output->geterror() : OIIO::geterror();
    return textureError(ErrorCode::kInternal, "OpenImageIO encode: " + why);
  }
  return std::vector<std::uint8_t>(bytes.begin(), bytes.end());
}

Result<std::vector<std::uint8_t>> payloadFor(const RgbaImage& texture, TextureCodec codec,
                                             const TextureEncodeOptions& options) {
  switch (codec) {
    case TextureCodec::kZstd:
      return zstdPayload(texture, options.zstdLevel);
    case TextureCodec::kPng:
    case TextureCodec::kJpeg:
      return imagePayload(texture, codec, options);
    case TextureCodec::kNone:
    case TextureCodec::kRawRgba8:
      break;
  }
  return textureError(ErrorCode::kInvalidArgument,
                      std::string("codec ") + textureCodecName(codec) + " has no frame");
}

Status decodeZstd(const std::uint8_t* payload, std::size_t size, RgbaImage& out) {
  const std::size_t expected = out.pixels.size();
  THINLOD_RETURN_IF_ERROR(detail::checkOneZstdFrame(payload, size, expected, "texture: "));
  const std::size_t written = ZSTD_decompress(out.pixels.data(), expected, payload, size);
  if (ZSTD_isError(written) || written != expected) {
    return textureError(ErrorCode::kParseError, "zstd payload is corrupt");
  }
  return Status();
}

// True when the bytes are a PNG signature followed by whole chunks ending
// exactly with IEND. OpenImageIO 2.4 leaks a string each time libpng hits
// the end of a short stream (PNGInput::PngReadCallback formats an error,
// then libpng longjmps past its destructor), so short PNGs never reach it.
bool pngChunksComplete(const std::uint8_t* data, std::size_t size) {
  static constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (size < 8 || !std::equal(kSignature, kSignature + 8, data)) return false;
  std::size_t at = 8;
  while (size - at >= 12) {
    const std::size_t length = (std::size_t{data[at]} << 24) | (std::size_t{data[at + 1]} << 16) |
                               (std::size_t{data[at + 2]} << 8) | data[at + 3];
    if (length > size - at - 12) return false;
    const bool end = std::equal(data + at + 4, data + at + 8, "IEND");
    at += 12 + length;
    if (end) return at == size;
  }
  return false;
}

// True when the bytes are SOI and whole marker segments up to SOS, each
// APP1 and APP13 segment holding a NUL. OpenImageIO 2.4's JpgInput::open
// compares those segments' data with strcmp ("Exif", the XMP namespace,
// "Photoshop 3.0"), reading past the segment when it has no NUL (a heap
// over-read found by fuzz/codec_texture_frame.cpp, seed
// fuzz/corpus/codec_texture/crash-jpeg-app1-without-nul.bin).
bool jpegHeaderSafe(const std::uint8_t* data, std::size_t size) {
  if (size < 4 || data[0] != 0xFF || data[1] != 0xD8) return false;
  std::size_t at = 2;
  while (at < size) {
    if (data[at] != 0xFF) return false;
    while (at < size && data[at] == 0xFF) ++at;  // fill bytes
    if (at >= size) return false;
    const std::uint8_t marker = data[at++];
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) continue;  // no length
    if (marker == 0xD9 || size - at < 2) return false;                   // EOI before SOS
    const std::size_t length = (std::size_t{data[at]} << 8) | data[at + 1];
    if (length < 2 || length > size - at) return false;
    if (marker == 0xDA) return true;  // SOS: entropy-coded data follows
    if ((marker == 0xE1 || marker == 0xED) &&
        std::find(data + at + 2, data + at + length, 0) == data + at + length) {
      return false;
    }
    at += length;
  }
  return false;
}

// PNG or JPEG bytes checked (whole chunks / segments, see above) and opened
// by OpenImageIO through `proxy`, which must outlive the returned input.
// `what` names the bytes in errors ("payload", "file").
// OpenImageIO reading the bytes behind `proxy` as the format `fileName` names.
Result<std::unique_ptr<OIIO::ImageInput>> openWithProxy(const char* fileName,
                                                        OIIO::Filesystem::IOMemReader& proxy) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  // OpenImageIO 2.4 only honours the proxy next to other configuration
  // hints when it arrives as the "oiio:ioproxy" hint itself.
  void* proxyPointer = &proxy;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxyPointer);
  // The reader of the extension's format only. ImageInput::open(name) (and
  // create with do_open) falls back, when that reader refuses the bytes, to
  // trying every reader OpenImageIO has (LibRaw, DICOM, FITS, ...): hostile
  // bytes we checked as PNG, JPEG or TGA would reach parsers we never
  // checked for. LibRaw alone allocated and zeroed megabytes per refused
  // file, most of the image file fuzzer's time.
  std::unique_ptr<OIIO::ImageInput> input =
      OIIO::ImageInput::create(fileName, /*do_open=*/false, &config, &proxy);
  if (!input) {
    return textureError(ErrorCode::kInternal, std::string("OpenImageIO has no reader for ") +
                                                  fileName + ": " + OIIO::geterror());
  }
  OIIO::ImageSpec opened;
  if (!input->open(fileName, opened, config)) {
    return textureError(ErrorCode::kParseError, "OpenImageIO decode: " + input->geterror());
  }
  return input;
}

// A TGA file's 18-byte header, checked before OpenImageIO sees the bytes:
// no colour map, true-colour or grey (raw 2/3, RLE 10/11), 8/16/24/32 bits,
// sides >= 1, and a raw image's pixels all inside the file.
bool tgaHeaderSafe(const std::uint8_t* data, std::size_t size) {
  constexpr std::size_t kHeader = 18;
  if (size < kHeader) return false;
  const unsigned idLength = data[0];
  const unsigned colorMapType = data[1];
  const unsigned imageType = data[2];
  const unsigned width = data[12] | (unsigned(data[13]) << 8);
  const unsigned height = data[14] | (unsigned(data[15]) << 8);
  const unsigned bits = data[16];
  if (colorMapType != 0) return false;
  if (imageType != 2 && imageType != 3 && imageType != 10 && imageType != 11) return false;
  if (bits != 8 && bits != 16 && bits != 24 && bits != 32) return false;
  if (width == 0 || height == 0) return false;
  if (size < kHeader + idLength) return false;
  if (imageType == 2 || imageType == 3) {
    const std::uint64_t pixels = std::uint64_t(width) * height * (bits / 8);
    if (size < kHeader + idLength + pixels) return false;
  }
  return true;
}

Result<std::unique_ptr<OIIO::ImageInput>> openImage(const std::uint8_t* data, std::size_t size,
                                                    TextureCodec codec, const char* what,
                                                    OIIO::Filesystem::IOMemReader& proxy) {
  if (codec == TextureCodec::kPng && !pngChunksComplete(data, size)) {
    return textureError(ErrorCode::kParseError,
                        std::string("PNG ") + what + " is truncated or malformed");
  }
  if (codec == TextureCodec::kJpeg && !jpegHeaderSafe(data, size)) {
    return textureError(ErrorCode::kParseError,
                        std::string("JPEG ") + what + " has a malformed header");
  }
  return openWithProxy(formatFileName(codec), proxy);
}

// The pixels of an opened `input` as RGBA8, row-major into `dest` (width *
// height * 4 bytes; the caller checked the dimensions against its limits):
// 1 channel is grey, 2 grey + alpha, 3 RGB (alpha 255), 4 or more RGBA (the
// rest dropped). Read in the file's own type, a band of rows at a time, and
// converted here: ImageInput::read_image asked for a conversion (a 16-bit
// PNG to UINT8, or a channel subset) allocates a buffer of about 64 MB
// whatever the image's size (OpenImageIO 2.4's chunk is 2^26 bytes of rows,
// not clamped to the height), which made every such file, even 1x1, cost a
// 64 MB allocation.
Status readAsRgba8(OIIO::ImageInput& input, std::uint8_t* dest) {
  const OIIO::ImageSpec& spec = input.spec();
  if (!spec.channelformats.empty()) {
    return textureError(ErrorCode::kUnsupported, "per-channel pixel formats");
  }
  const int fileChannels = spec.nchannels;
  const std::size_t rowValues = std::size_t(spec.width) * std::size_t(fileChannels);
  const std::size_t rowBytes = rowValues * spec.format.size();
  constexpr std::size_t kBandBytes = std::size_t{1} << 20;
  const int bandRows =
      static_cast<int>(std::clamp<std::size_t>(kBandBytes / std::max<std::size_t>(rowBytes, 1),
                                               1, std::size_t(spec.height)));
  const bool convert = spec.format != OIIO::TypeDesc::UINT8;
  std::vector<std::uint8_t> band(rowBytes * std::size_t(bandRows));
  std::vector<std::uint8_t> converted(convert ? rowValues * std::size_t(bandRows) : 0);
  for (int y0 = 0; y0 < spec.height; y0 += bandRows) {
    const int rows = std::min(bandRows, spec.height - y0);
    // All channels in the file's type: OpenImageIO's direct path, into `band`.
    if (!input.read_scanlines(0, 0, spec.y + y0, spec.y + y0 + rows, 0, 0, fileChannels,
                              OIIO::TypeDesc::UNKNOWN, band.data())) {
      return textureError(ErrorCode::kParseError, "OpenImageIO: " + input.geterror());
    }
    const std::size_t values = rowValues * std::size_t(rows);
    const std::uint8_t* bytes = band.data();
    if (convert) {
      if (!OIIO::convert_pixel_values(spec.format, band.data(), OIIO::TypeDesc::UINT8,
                                      converted.data(), static_cast<int>(values))) {
        return textureError(ErrorCode::kUnsupported,
                            std::string("pixel type ") + spec.format.c_str());
      }
      bytes = converted.data();
    }
    const std::size_t pixels = std::size_t(spec.width) * std::size_t(rows);
    for (std::size_t p = 0; p < pixels; ++p, dest += 4) {
      const std::uint8_t* src = bytes + p * std::size_t(fileChannels);
      if (fileChannels <= 2) {
        dest[0] = dest[1] = dest[2] = src[0];
        dest[3] = fileChannels == 2 ? src[1] : 255;
      } else {
        dest[0] = src[0];
        dest[1] = src[1];
        dest[2] = src[2];
        dest[3] = fileChannels >= 4 ? src[3] : 255;
      }
    }
  }
  return Status();
}

Status decodeImage(const std::uint8_t* payload, std::size_t size, TextureCodec codec,
                   RgbaImage& out) {
  OIIO::Filesystem::IOMemReader proxy(payload, size);
  Result<std::unique_ptr<OIIO::ImageInput>> opened =
      openImage(payload, size, codec, "payload", proxy);
  if (!opened.ok()) return opened.status();
  OIIO::ImageInput& input = **opened;
  const OIIO::ImageSpec& spec = input.spec();
  const int wantChannels = codec == TextureCodec::kJpeg ? 3 : 4;
  // Checked against the frame header before any pixel is decoded.
  if (spec.width != out.width || spec.height != out.height || spec.depth != 1 ||
      spec.nchannels != wantChannels) {
    return textureError(ErrorCode::kParseError,
                        "image is " + std::to_string(spec.width) + "x" +
                            std::to_string(spec.height) + "x" + std::to_string(spec.nchannels) +
                            ", header says " + std::to_string(out.width) + "x" +
                            std::to_string(out.height) + "x" + std::to_string(wantChannels));
  }
  return readAsRgba8(input, out.pixels.data());
}

double psnrRgb(const RgbaImage& a, const RgbaImage& b) {
  double squared = 0.0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    if (i % 4 == 3) continue;
    const double d = static_cast<double>(a.pixels[i]) - b.pixels[i];
    squared += d * d;
  }
  const double mse = squared / (a.pixels.size() / 4 * 3);
  return mse > 0.0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : INFINITY;
}

}  // namespace

Result<std::vector<std::uint8_t>> encodeTextureWith(const RgbaImage& texture, TextureCodec codec,
                                                    const TextureEncodeOptions& options) {
  THINLOD_RETURN_IF_ERROR(checkTexture(texture));
  if (codec == TextureCodec::kJpeg && !texture.opaque()) {
    return textureError(ErrorCode::kInvalidArgument, "JPEG needs an opaque image (alpha 255)");
  }
  try {
    Result<std::vector<std::uint8_t>> payload = payloadFor(texture, codec, options);
    if (!payload.ok()) return payload.status();
    detail::FrameHeader header;
    header.magic = detail::kTextureMagic;
    header.codec = static_cast<std::uint8_t>(codec);
    // checkTexture: both sides are in [1, 65500].
    header.countA = static_cast<std::uint32_t>(texture.width);
    header.countB = static_cast<std::uint32_t>(texture.height);
    return detail::makeFrame(header, payload->data(), payload->size());
  } catch (const std::bad_alloc&) {
    return textureError(ErrorCode::kResourceExhausted, "out of memory");
  } catch (const std::exception& e) {
    return textureError(ErrorCode::kInternal, e.what());
  }
}

Result<EncodedTexture> encodeTexture(const RgbaImage& texture,
                                     const TextureEncodeOptions& options) {
  std::vector<TextureCodec> candidates = {TextureCodec::kZstd};
  if (options.policy != TexturePolicy::kFastest) candidates.push_back(TextureCodec::kPng);
  if (options.policy == TexturePolicy::kSmallest && checkTexture(texture).ok() &&
      texture.opaque()) {
    candidates.push_back(TextureCodec::kJpeg);
  }
  EncodedTexture best;
  bool haveBest = false;
  for (TextureCodec codec : candidates) {
    Result<std::vector<std::uint8_t>> frame = encodeTextureWith(texture, codec, options);
    if (!frame.ok()) return frame.status();
    if (haveBest && frame->size() >= best.bytes.size()) continue;
    if (codec == TextureCodec::kJpeg) {
      Result<RgbaImage> decoded = decodeTexture(frame->data(), frame->size());
      if (!decoded.ok() || psnrRgb(texture, *decoded) < options.jpegMinPsnr) continue;
    }
    best.codec = codec;
    best.bytes = std::move(*frame);
    haveBest = true;
  }
  return best;
}

Result<RgbaImage> decodeTexture(const std::uint8_t* data, std::size_t size,
                                const DecodeLimits& limits) {
  Result<detail::FrameHeader> parsed =
      detail::parseFrame(data, size, detail::kTextureMagic, limits, "decodeTexture");
  if (!parsed.ok()) return parsed.status();
  const detail::FrameHeader& header = *parsed;
  if (!isFramedTextureCodec(static_cast<TextureCodec>(header.codec))) {
    return textureError(ErrorCode::kUnsupported, "unknown codec " + std::to_string(header.codec));
  }
  if (header.attributes != 0) {
    return textureError(ErrorCode::kUnsupported, "unknown attribute bits");
  }
  const std::uint32_t maxSide = limits.maxDecodableSide();
  if (header.countA == 0 || header.countB == 0 || header.countA > maxSide ||
      header.countB > maxSide) {
    return textureError(ErrorCode::kResourceExhausted,
                        "dimensions " + std::to_string(header.countA) + "x" +
                            std::to_string(header.countB) + " outside [1, " +
                            std::to_string(maxSide) + "]");
  }
  try {
    RgbaImage texture;
    texture.width = static_cast<int>(header.countA);
    texture.height = static_cast<int>(header.countB);
    texture.pixels.resize(std::size_t{header.countA} * header.countB * 4);
    const std::uint8_t* payload = data + kFrameHeaderBytes;
    const TextureCodec codec = static_cast<TextureCodec>(header.codec);
    if (codec == TextureCodec::kZstd) {
      THINLOD_RETURN_IF_ERROR(decodeZstd(payload, header.payloadBytes, texture));
    } else {
      THINLOD_RETURN_IF_ERROR(decodeImage(payload, header.payloadBytes, codec, texture));
    }
    return texture;
  } catch (const std::bad_alloc&) {
    return textureError(ErrorCode::kResourceExhausted, "out of memory");
  } catch (const std::exception& e) {
    return textureError(ErrorCode::kParseError, e.what());
  }
}

Result<RgbaImage> decodeImageFile(const std::uint8_t* data, std::size_t size,
                                  const DecodeLimits& limits) {
  if (data == nullptr || size == 0) return textureError(ErrorCode::kParseError, "empty file");
  if (size > limits.maxPayloadBytes) {
    return textureError(ErrorCode::kResourceExhausted, "file of " + std::to_string(size) +
                                                           " bytes is over the limit of " +
                                                           std::to_string(limits.maxPayloadBytes));
  }
  static constexpr std::uint8_t kPngMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  TextureCodec codec = TextureCodec::kNone;  // kNone: TGA (no magic; header checked)
  if (size >= 8 && std::equal(kPngMagic, kPngMagic + 8, data)) {
    codec = TextureCodec::kPng;
  } else if (size >= 2 && data[0] == 0xFF && data[1] == 0xD8) {
    codec = TextureCodec::kJpeg;
  } else if (!tgaHeaderSafe(data, size)) {
    return textureError(ErrorCode::kUnsupported,
                        "not a PNG, JPEG or TGA file (only those are read)");
  }
  try {
    OIIO::Filesystem::IOMemReader proxy(data, size);
    Result<std::unique_ptr<OIIO::ImageInput>> opened =
        codec == TextureCodec::kNone ? openWithProxy("file.tga", proxy)
                                     : openImage(data, size, codec, "file", proxy);
    if (!opened.ok()) return opened.status();
    std::unique_ptr<OIIO::ImageInput> input = std::move(opened).value();
    const OIIO::ImageSpec& spec = input->spec();
    const std::string dims = std::to_string(spec.width) + "x" + std::to_string(spec.height);
    if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1 || spec.nchannels <= 0 ||
        spec.nchannels > 16) {
      return textureError(ErrorCode::kParseError,
                          "image is " + dims + "x" + std::to_string(spec.nchannels));
    }
    const std::uint64_t side = limits.maxDecodableSide();
    const std::uint64_t bytes = std::uint64_t(spec.width) * std::uint64_t(spec.height) * 4u;
    if (std::uint64_t(spec.width) > side || std::uint64_t(spec.height) > side ||
        bytes > std::uint64_t(limits.maxPayloadBytes) * 16u) {
      return textureError(ErrorCode::kResourceExhausted,
                          "image of " + dims + " is over the decode limits");
    }
    RgbaImage out;
    out.width = spec.width;
    out.height = spec.height;
    out.pixels.assign(static_cast<std::size_t>(bytes), 0);
    THINLOD_RETURN_IF_ERROR(readAsRgba8(*input, out.pixels.data()));
    return out;
  } catch (const std::bad_alloc&) {
    return textureError(ErrorCode::kResourceExhausted, "out of memory decoding the image");
  } catch (const std::exception& e) {
    return textureError(ErrorCode::kParseError, std::string("OpenImageIO threw: ") + e.what());
  }
}

Result<RgbaImage> readImageFile(const std::string& path, const DecodeLimits& limits) {
  Result<std::string> bytes = readFileBounded(path, limits.maxPayloadBytes);
  if (!bytes.ok()) return bytes.status();  // names the path already
  Result<RgbaImage> decoded = decodeImageFile(
      reinterpret_cast<const std::uint8_t*>(bytes->data()), bytes->size(), limits);
  if (!decoded.ok()) return Status(decoded.status().code(), path + ": " + decoded.status().message());
  return decoded;
}

}  // namespace thinlod::codec
