// Hybrid (triangles + disc points) link encoding: the triangles as a nested
// encodeMesh frame, the points as a Draco point cloud (see encoding.h).
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/point_cloud/point_cloud.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>

#include "encoding_draco.h"
#include "encoding_frame.h"
#include "thinlod/common/codec/encoding.h"

namespace thinlod::codec {
namespace {

constexpr std::uint8_t kCodecDraco = 1;
constexpr std::uint32_t kHasPointNormals = 1;
constexpr std::size_t kLengthPrefixBytes = 4;

Status encodeError(ErrorCode code, const std::string& message) {
  return Status(code, "encodeHybrid: " + message);
}
Status decodeError(ErrorCode code, const std::string& message) {
  return Status(code, "decodeHybrid: " + message);
}

std::uint32_t readU32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
         std::uint32_t{p[3]} << 24;
}

template <typename T>
void addAttribute(draco::PointCloud& target, draco::GeometryAttribute::Type type,
                  draco::DataType dataType, int components, bool normalized, const T* values,
                  std::size_t count) {
  draco::GeometryAttribute attribute;
  attribute.Init(type, nullptr, static_cast<std::uint8_t>(components), dataType, normalized,
                 static_cast<std::int64_t>(sizeof(T)), 0);
  const int id = target.AddAttribute(attribute, true, static_cast<std::uint32_t>(count));
  draco::PointAttribute* stored = target.attribute(id);
  for (std::size_t i = 0; i < count; ++i) {
    stored->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)),
                              &values[i]);
  }
}

Result<draco::EncoderBuffer> encodePoints(const DiscPoints& points,
                                          const MeshEncodeOptions& options) {
  draco::PointCloud cloud;
  cloud.set_num_points(static_cast<std::uint32_t>(points.size()));
  addAttribute(cloud, draco::GeometryAttribute::POSITION, draco::DT_FLOAT32, 3, false,
               points.centres.data(), points.size());
  if (!points.normals.empty()) {
    addAttribute(cloud, draco::GeometryAttribute::NORMAL, draco::DT_FLOAT32, 3, false,
                 points.normals.data(), points.size());
  }
  addAttribute(cloud, draco::GeometryAttribute::GENERIC, draco::DT_FLOAT32, 1, false,
               points.radii.data(), points.size());
  addAttribute(cloud, draco::GeometryAttribute::COLOR, draco::DT_UINT8, 4, true,
               points.colors.data(), points.size());
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, options.positionBits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, options.normalBits);
  encoder.SetSpeedOptions(options.encodeSpeed, options.decodeSpeed);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodePointCloudToBuffer(cloud, &buffer);
  if (!status.ok()) {
    return encodeError(ErrorCode::kInternal, std::string("Draco points: ") + status.error_msg());
  }
  return buffer;
}

Result<DiscPoints> decodePoints(const std::uint8_t* data, std::size_t size, std::uint32_t count,
                                bool hasNormals) {
  // Draco sizes its buffers from the point count in its own stream before
  // reading any attribute: a corrupted count made it allocate (and touch)
  // gigabytes (found by the corruption sweep in tests/codec). The header is
  // "DRACO", major, minor, geometry type, method, u16 flags (we never write
  // metadata), then the i32 point count of both point-cloud methods: it must
  // be the frame's count before Draco sees the stream.
  constexpr std::size_t kDracoCountOffset = 11;
  if (size < kDracoCountOffset + 4 || std::memcmp(data, "DRACO", 5) != 0) {
    return decodeError(ErrorCode::kParseError, "point part is not a Draco stream");
  }
  if ((data[9] | (data[10] << 8)) != 0) {
    return decodeError(ErrorCode::kParseError, "point part has Draco flags (metadata) set");
  }
  if (readU32(data + kDracoCountOffset) != count) {
    return decodeError(ErrorCode::kParseError,
                       "Draco point count " + std::to_string(readU32(data + kDracoCountOffset)) +
                           ", header says " + std::to_string(count));
  }
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data), size);
  draco::StatusOr<draco::EncodedGeometryType> type =
      draco::Decoder::GetEncodedGeometryType(&buffer);
  if (!type.ok() || type.value() != draco::POINT_CLOUD) {
    return decodeError(ErrorCode::kParseError, "point part is not a Draco point cloud");
  }
  draco::Decoder decoder;
  draco::StatusOr<std::unique_ptr<draco::PointCloud>> decoded =
      decoder.DecodePointCloudFromBuffer(&buffer);
  if (!decoded.ok()) {
    return decodeError(ErrorCode::kParseError,
                       std::string("Draco points: ") + decoded.status().error_msg());
  }
  const draco::PointCloud& cloud = *decoded.value();
  if (cloud.num_points() != count) {
    return decodeError(ErrorCode::kParseError, "decoded " + std::to_string(cloud.num_points()) +
                                                   " points, header says " + std::to_string(count));
  }
  DiscPoints points;
  THINLOD_RETURN_IF_ERROR(detail::readDracoAttribute<3>(cloud, draco::GeometryAttribute::POSITION,
                                                        "centres", draco::DT_FLOAT32,
                                                        "decodeHybrid", points.centres));
  if (hasNormals) {
    THINLOD_RETURN_IF_ERROR(detail::readDracoAttribute<3>(cloud, draco::GeometryAttribute::NORMAL,
                                                          "point normals", draco::DT_FLOAT32,
                                                          "decodeHybrid", points.normals));
  }
  std::vector<std::array<float, 1>> radii;
  THINLOD_RETURN_IF_ERROR(detail::readDracoAttribute<1>(
      cloud, draco::GeometryAttribute::GENERIC, "radii", draco::DT_FLOAT32, "decodeHybrid", radii));
  points.radii.reserve(radii.size());
  for (const auto& r : radii) points.radii.push_back(r[0]);
  THINLOD_RETURN_IF_ERROR(detail::readDracoAttribute<4>(cloud, draco::GeometryAttribute::COLOR,
                                                        "point colours", draco::DT_UINT8,
                                                        "decodeHybrid", points.colors));
  THINLOD_RETURN_IF_ERROR(points.validate("decodeHybrid: decoded points"));
  return points;
}

}  // namespace

double pointPositionErrorBound(const DiscPoints& points, int bits) {
  const Bounds b = points.bounds();
  if (b.empty) return 0.0;
  const glm::vec3 extent = b.max - b.min;
  const double range = std::max({extent.x, extent.y, extent.z});
  return 0.5 * range / (std::ldexp(1.0, bits) - 1.0) * std::sqrt(3.0);
}

Result<std::vector<std::uint8_t>> encodeHybrid(const HybridGeometry& geometry,
                                               const MeshEncodeOptions& options) {
  THINLOD_RETURN_IF_ERROR(geometry.triangles.validate("encodeHybrid: triangles"));
  THINLOD_RETURN_IF_ERROR(geometry.points.validate("encodeHybrid: points"));
  if (geometry.points.size() > UINT32_MAX) {
    return encodeError(ErrorCode::kInvalidArgument, "more than 2^32 points");
  }
  try {
    std::vector<std::uint8_t> meshFrame;
    std::uint32_t triangles = 0;
    if (geometry.triangles.triangleCount() > 0) {
      Result<std::vector<std::uint8_t>> encoded = encodeMesh(geometry.triangles, options);
      if (!encoded.ok()) {
        return encodeError(encoded.status().code(), "triangles: " + encoded.status().message());
      }
      meshFrame = std::move(encoded).value();
      triangles = readU32(meshFrame.data() + 12);  // what encodeMesh kept
    }
    if (triangles == 0 && geometry.points.empty()) {
      return encodeError(ErrorCode::kInvalidArgument, "no triangles and no points");
    }
    // encodeMesh validated the options; it is skipped when there are no triangles.
    if (options.positionBits < 8 || options.positionBits > 20 || options.normalBits < 4 ||
        options.normalBits > 20 || options.encodeSpeed < 0 || options.encodeSpeed > 10 ||
        options.decodeSpeed < 0 || options.decodeSpeed > 10) {
      return encodeError(ErrorCode::kInvalidArgument, "options out of range (see encodeMesh)");
    }
    draco::EncoderBuffer pointBuffer;
    if (!geometry.points.empty()) {
      Result<draco::EncoderBuffer> encoded = encodePoints(geometry.points, options);
      if (!encoded.ok()) return encoded.status();
      pointBuffer = std::move(encoded).value();
    }
    const std::size_t payloadSize = kLengthPrefixBytes + meshFrame.size() + pointBuffer.size();
    if (payloadSize > UINT32_MAX) {
      return encodeError(ErrorCode::kInvalidArgument, "encoding exceeds 4 GiB");
    }
    std::vector<std::uint8_t> payload(payloadSize);
    const std::uint32_t meshBytes = static_cast<std::uint32_t>(meshFrame.size());
    for (int i = 0; i < 4; ++i) payload[i] = static_cast<std::uint8_t>(meshBytes >> (8 * i));
    std::copy(meshFrame.begin(), meshFrame.end(), payload.begin() + kLengthPrefixBytes);
    if (pointBuffer.size() > 0) {
      const auto* bytes = reinterpret_cast<const std::uint8_t*>(pointBuffer.data());
      std::copy(bytes, bytes + pointBuffer.size(),
                payload.begin() + static_cast<std::ptrdiff_t>(kLengthPrefixBytes + meshBytes));
    }
    detail::FrameHeader header;
    header.magic = detail::kHybridMagic;
    header.codec = kCodecDraco;
    header.countA = static_cast<std::uint32_t>(geometry.points.size());
    header.countB = triangles;
    header.attributes = geometry.points.normals.empty() ? 0 : kHasPointNormals;
    return detail::makeFrame(header, payload.data(), payload.size());
  } catch (const std::bad_alloc&) {
    return encodeError(ErrorCode::kResourceExhausted, "out of memory");
  } catch (const std::exception& e) {
    return encodeError(ErrorCode::kInternal, e.what());
  }
}

Result<HybridGeometry> decodeHybrid(const std::uint8_t* data, std::size_t size,
                                    const DecodeLimits& limits) {
  Result<detail::FrameHeader> parsed =
      detail::parseFrame(data, size, detail::kHybridMagic, limits, "decodeHybrid");
  if (!parsed.ok()) return parsed.status();
  const detail::FrameHeader& header = *parsed;
  if (header.codec != kCodecDraco) {
    return decodeError(ErrorCode::kUnsupported, "unknown codec " + std::to_string(header.codec));
  }
  if (header.attributes & ~kHasPointNormals) {
    return decodeError(ErrorCode::kUnsupported,
                       "unknown attribute bits " + std::to_string(header.attributes));
  }
  if (header.countA > limits.maxPoints || header.countB > limits.maxTriangles) {
    return decodeError(ErrorCode::kResourceExhausted, std::to_string(header.countA) + " points / " +
                                                          std::to_string(header.countB) +
                                                          " triangles exceed the limits");
  }
  if (header.countA == 0 && header.countB == 0) {
    return decodeError(ErrorCode::kParseError, "frame declares no triangles and no points");
  }
  if (header.payloadBytes < kLengthPrefixBytes) {
    return decodeError(ErrorCode::kParseError, "payload shorter than its length prefix");
  }
  const std::uint8_t* payload = data + kFrameHeaderBytes;
  const std::uint32_t meshBytes = readU32(payload);
  const std::size_t afterPrefix = header.payloadBytes - kLengthPrefixBytes;
  if (meshBytes > afterPrefix) {
    return decodeError(ErrorCode::kParseError, "triangle part of " + std::to_string(meshBytes) +
                                                   " bytes, only " + std::to_string(afterPrefix) +
                                                   " left");
  }
  const std::size_t pointBytes = afterPrefix - meshBytes;
  if ((meshBytes == 0) != (header.countB == 0) || (pointBytes == 0) != (header.countA == 0)) {
    return decodeError(ErrorCode::kParseError, "part sizes " + std::to_string(meshBytes) + " / " +
                                                   std::to_string(pointBytes) +
                                                   " bytes disagree with " +
                                                   std::to_string(header.countB) + " triangles / " +
                                                   std::to_string(header.countA) + " points");
  }
  try {
    HybridGeometry geometry;
    if (meshBytes > 0) {
      Result<IndexedMesh> mesh = decodeMesh(payload + kLengthPrefixBytes, meshBytes, limits);
      if (!mesh.ok()) {
        return decodeError(mesh.status().code(), "triangles: " + mesh.status().message());
      }
      if (mesh->triangleCount() != header.countB) {
        return decodeError(ErrorCode::kParseError,
                           "decoded " + std::to_string(mesh->triangleCount()) +
                               " triangles, header says " + std::to_string(header.countB));
      }
      geometry.triangles = std::move(mesh).value();
    }
    if (pointBytes > 0) {
      Result<DiscPoints> points = decodePoints(payload + kLengthPrefixBytes + meshBytes, pointBytes,
                                               header.countA, header.attributes & kHasPointNormals);
      if (!points.ok()) return points.status();
      geometry.points = std::move(points).value();
    }
    return geometry;
  } catch (const std::bad_alloc&) {
    return decodeError(ErrorCode::kResourceExhausted, "out of memory");
  } catch (const std::exception& e) {
    return decodeError(ErrorCode::kParseError, e.what());
  }
}

}  // namespace thinlod::codec
