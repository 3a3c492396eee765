// Mesh link encoding with Draco (see encoding.h for the contract).
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

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
constexpr std::uint32_t kHasNormals = 1;
constexpr std::uint32_t kHasUvs = 2;
constexpr std::uint32_t kHasColors = 4;
constexpr std::uint32_t kHasSkin = 8;
constexpr int kMinPositionBits = 8;
constexpr int kMaxPositionBits = 20;

Status invalid(const std::string& message) {
  return Status(ErrorCode::kInvalidArgument, "encodeMesh: " + message);
}

// Triangles with a repeated corner index are dropped and unreferenced
// vertices removed, so the vertex and face counts Draco reports are the ones
// the decoder reproduces.
// A vertex's skin as the frame stores it: boneA, boneB, weightB * 65535.
using SkinValue = std::array<std::uint16_t, 3>;
constexpr float kWeightSteps = 65535.0f;

// `skin` (empty or one per vertex) is compacted alongside into `skinOut`.
IndexedMesh compactForEncoding(const IndexedMesh& mesh, const std::vector<SkinValue>& skin,
                               std::vector<SkinValue>& skinOut) {
  IndexedMesh out;
  std::vector<std::uint32_t> remap(mesh.vertexCount(), UINT32_MAX);
  auto mapVertex = [&](std::uint32_t v) {
    if (remap[v] == UINT32_MAX) {
      remap[v] = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(mesh.positions[v]);
      if (!skin.empty()) skinOut.push_back(skin[v]);
      if (!mesh.normals.empty()) out.normals.push_back(mesh.normals[v]);
      if (!mesh.uvs.empty()) out.uvs.push_back(mesh.uvs[v]);
      if (!mesh.colors.empty()) out.colors.push_back(mesh.colors[v]);
    }
    return remap[v];
  };
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    const std::uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
    if (a == b || b == c || c == a) continue;
    out.indices.push_back(mapVertex(a));
    out.indices.push_back(mapVertex(b));
    out.indices.push_back(mapVertex(c));
  }
  return out;
}

template <typename T>
int addAttribute(draco::Mesh& target, draco::GeometryAttribute::Type type, draco::DataType dataType,
                 int components, bool normalized, const std::vector<T>& values) {
  draco::GeometryAttribute attribute;
  attribute.Init(type, nullptr, static_cast<std::uint8_t>(components), dataType, normalized,
                 static_cast<std::int64_t>(sizeof(T)), 0);
  const int id = target.AddAttribute(attribute, true, static_cast<std::uint32_t>(values.size()));
  draco::PointAttribute* stored = target.attribute(id);
  for (std::size_t i = 0; i < values.size(); ++i) {
    stored->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)),
                              &values[i]);
  }
  return id;
}

Status decodeError(ErrorCode code, const std::string& message) {
  return Status(code, "decodeMesh: " + message);
}

// The skin attribute's values back as VertexSkin: a rigid vertex (one
// bone) must have weight 0.
Result<std::vector<anim::VertexSkin>> toSkin(const std::vector<SkinValue>& values) {
  std::vector<anim::VertexSkin> skin;
  skin.reserve(values.size());
  for (std::size_t v = 0; v < values.size(); ++v) {
    const SkinValue& value = values[v];
    if (value[0] == value[1] && value[2] != 0) {
      return decodeError(ErrorCode::kParseError,
                         "skin of vertex " + std::to_string(v) + " names one bone with a weight");
    }
    skin.push_back({value[0], value[1], float(value[2]) / kWeightSteps});
  }
  return skin;
}

Result<IndexedMesh> toIndexedMesh(const draco::Mesh& decoded, std::uint32_t attributes) {
  IndexedMesh mesh;
  THINLOD_RETURN_IF_ERROR(detail::readDracoAttribute<3>(decoded, draco::GeometryAttribute::POSITION,
                                                        "positions", draco::DT_FLOAT32,
                                                        "decodeMesh", mesh.positions));
  if (attributes & kHasNormals) {
    THINLOD_RETURN_IF_ERROR(detail::readDracoAttribute<3>(decoded, draco::GeometryAttribute::NORMAL,
                                                          "normals", draco::DT_FLOAT32,
                                                          "decodeMesh", mesh.normals));
  }
  if (attributes & kHasUvs) {
    THINLOD_RETURN_IF_ERROR(
        detail::readDracoAttribute<2>(decoded, draco::GeometryAttribute::TEX_COORD, "uvs",
                                      draco::DT_FLOAT32, "decodeMesh", mesh.uvs));
  }
  if (attributes & kHasColors) {
    THINLOD_RETURN_IF_ERROR(detail::readDracoAttribute<4>(decoded, draco::GeometryAttribute::COLOR,
                                                          "colors", draco::DT_UINT8, "decodeMesh",
                                                          mesh.colors));
  }
  mesh.indices.reserve(static_cast<std::size_t>(decoded.num_faces()) * 3);
  for (draco::FaceIndex f(0); f < decoded.num_faces(); ++f) {
    for (const draco::PointIndex& corner : decoded.face(f)) mesh.indices.push_back(corner.value());
  }
  THINLOD_RETURN_IF_ERROR(mesh.validate("decodeMesh: decoded mesh"));
  return mesh;
}

}  // namespace

int positionBitsForAccuracy(double relativeAccuracy, double budgetFraction) {
  if (!(relativeAccuracy > 0.0) || !(budgetFraction > 0.0) || !std::isfinite(budgetFraction)) {
    return kMaxPositionBits;
  }
  if (!std::isfinite(relativeAccuracy)) return kMaxPositionBits;
  // diagonal / (2^b - 1) * sqrt(3) / 2 <= budgetFraction * diagonal / a
  const double levels = relativeAccuracy * std::sqrt(3.0) / (2.0 * budgetFraction) + 1.0;
  const int bits = static_cast<int>(std::ceil(std::log2(levels)));
  return std::clamp(bits, kMinPositionBits, kMaxPositionBits);
}

double positionErrorBound(const IndexedMesh& mesh, int bits) {
  const Bounds b = mesh.bounds();
  if (b.empty) return 0.0;
  const glm::vec3 extent = b.max - b.min;
  const double range = std::max({extent.x, extent.y, extent.z});
  const double step = range / (std::ldexp(1.0, bits) - 1.0);
  return 0.5 * step * std::sqrt(3.0);
}

namespace {

// encodeMesh, with the skin attribute when `skin` is not empty (one entry a vertex).
Result<std::vector<std::uint8_t>> encodeMeshFrame(const IndexedMesh& input,
                                                  const std::vector<SkinValue>& skin,
                                                  const MeshEncodeOptions& options) {
  THINLOD_RETURN_IF_ERROR(input.validate("encodeMesh: input"));
  if (options.positionBits < kMinPositionBits || options.positionBits > kMaxPositionBits) {
    return invalid("positionBits " + std::to_string(options.positionBits) + " outside [8, 20]");
  }
  if (options.normalBits < 4 || options.normalBits > 20 || options.texcoordBits < 4 ||
      options.texcoordBits > 20) {
    return invalid("normalBits and texcoordBits must be in [4, 20]");
  }
  if (options.encodeSpeed < 0 || options.encodeSpeed > 10 || options.decodeSpeed < 0 ||
      options.decodeSpeed > 10) {
    return invalid("Draco speeds must be in [0, 10]");
  }
  const bool grid = options.positionRange != 0.0f;
  if (grid) {
    const auto& o = options.positionOrigin;
    if (!(options.positionRange > 0.0f) || !std::isfinite(options.positionRange) ||
        !std::isfinite(o[0]) || !std::isfinite(o[1]) || !std::isfinite(o[2])) {
      return invalid("position grid: origin and range must be finite, range > 0");
    }
    for (const glm::vec3& p : input.positions) {
      for (int k = 0; k < 3; ++k) {
        if (p[k] < o[k] || p[k] > o[k] + options.positionRange) {
          return invalid("position grid: a vertex lies outside the grid's cube");
        }
      }
    }
  }
  std::vector<SkinValue> compactSkin;
  const IndexedMesh mesh = compactForEncoding(input, skin, compactSkin);
  if (mesh.triangleCount() == 0) return invalid("no non-degenerate triangles");

  try {
    draco::Mesh draco;
    draco.set_num_points(static_cast<std::uint32_t>(mesh.vertexCount()));
    addAttribute(draco, draco::GeometryAttribute::POSITION, draco::DT_FLOAT32, 3, false,
                 mesh.positions);
    std::uint32_t attributes = 0;
    if (!mesh.normals.empty()) {
      addAttribute(draco, draco::GeometryAttribute::NORMAL, draco::DT_FLOAT32, 3, false,
                   mesh.normals);
      attributes |= kHasNormals;
    }
    if (!mesh.uvs.empty()) {
      addAttribute(draco, draco::GeometryAttribute::TEX_COORD, draco::DT_FLOAT32, 2, false,
                   mesh.uvs);
      attributes |= kHasUvs;
    }
    if (!mesh.colors.empty()) {
      addAttribute(draco, draco::GeometryAttribute::COLOR, draco::DT_UINT8, 4, true, mesh.colors);
      attributes |= kHasColors;
    }
    if (!compactSkin.empty()) {
      // Integers: Draco predicts them from neighbours and entropy-codes
      // them (a skin is constant over most of a region), where float32
      // GENERIC values travel raw (12 bytes a vertex).
      addAttribute(draco, draco::GeometryAttribute::GENERIC, draco::DT_UINT16, 3, false,
                   compactSkin);
      attributes |= kHasSkin;
    }
    draco.SetNumFaces(mesh.triangleCount());
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
      draco::Mesh::Face face;
      for (int k = 0; k < 3; ++k) face[k] = draco::PointIndex(mesh.indices[3 * t + k]);
      draco.SetFace(draco::FaceIndex(t), face);
    }

    draco::Encoder encoder;
    if (grid) {
      encoder.SetAttributeExplicitQuantization(
          draco::GeometryAttribute::POSITION, options.positionBits, 3,
          options.positionOrigin.data(), options.positionRange);
    } else {
      encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, options.positionBits);
    }
    encoder.SetAttributeQuantization(draco::GeometryAttribute::NORMAL, options.normalBits);
    encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, options.texcoordBits);
    encoder.SetSpeedOptions(options.encodeSpeed, options.decodeSpeed);
    encoder.SetTrackEncodedProperties(true);
    draco::EncoderBuffer buffer;
    const draco::Status status = encoder.EncodeMeshToBuffer(draco, &buffer);
    if (!status.ok()) {
      return Status(ErrorCode::kInternal, std::string("encodeMesh: Draco: ") + status.error_msg());
    }
    if (buffer.size() > UINT32_MAX) return invalid("encoded mesh exceeds 4 GiB");

    detail::FrameHeader header;
    header.magic = detail::kMeshMagic;
    header.codec = kCodecDraco;
    header.countA = static_cast<std::uint32_t>(encoder.num_encoded_points());
    header.countB = static_cast<std::uint32_t>(encoder.num_encoded_faces());
    header.attributes = attributes;
    return detail::makeFrame(header, reinterpret_cast<const std::uint8_t*>(buffer.data()),
                             buffer.size());
  } catch (const std::bad_alloc&) {
    return Status(ErrorCode::kResourceExhausted, "encodeMesh: out of memory");
  } catch (const std::exception& e) {
    return Status(ErrorCode::kInternal, std::string("encodeMesh: ") + e.what());
  }
}

}  // namespace

Result<std::vector<std::uint8_t>> encodeMesh(const IndexedMesh& mesh,
                                             const MeshEncodeOptions& options) {
  return encodeMeshFrame(mesh, {}, options);
}

Result<std::vector<std::uint8_t>> encodeSkinnedMesh(const IndexedMesh& mesh,
                                                    const std::vector<anim::VertexSkin>& skin,
                                                    const MeshEncodeOptions& options) {
  if (skin.size() != mesh.vertexCount()) {
    return invalid("skin has " + std::to_string(skin.size()) + " entries for " +
                   std::to_string(mesh.vertexCount()) + " vertices");
  }
  THINLOD_RETURN_IF_ERROR(
      anim::validateSkin(skin, mesh.vertexCount(), kMaxSkinBones, "encodeSkinnedMesh: skin"));
  std::vector<SkinValue> values;
  values.reserve(skin.size());
  for (const anim::VertexSkin& s : skin) {
    // A rigid vertex (weight 0) names one bone: its unused second bone
    // would otherwise reach the renderer's palette.
    const bool rigid = s.rigid();
    const auto weight = static_cast<std::uint16_t>(std::lround(s.weightB * kWeightSteps));
    values.push_back({static_cast<std::uint16_t>(s.boneA),
                      static_cast<std::uint16_t>(rigid ? s.boneA : s.boneB),
                      static_cast<std::uint16_t>(rigid || s.boneA == s.boneB ? 0 : weight)});
  }
  return encodeMeshFrame(mesh, values, options);
}

Result<IndexedMesh> decodeMesh(const std::uint8_t* data, std::size_t size,
                               const DecodeLimits& limits) {
  Result<SkinnedMeshFrame> decoded = decodeSkinnedMesh(data, size, limits);
  if (!decoded.ok()) return decoded.status();
  return std::move(decoded->mesh);
}

Result<SkinnedMeshFrame> decodeSkinnedMesh(const std::uint8_t* data, std::size_t size,
                                           const DecodeLimits& limits) {
  Result<detail::FrameHeader> parsed =
      detail::parseFrame(data, size, detail::kMeshMagic, limits, "decodeMesh");
  if (!parsed.ok()) return parsed.status();
  const detail::FrameHeader& header = *parsed;
  if (header.codec != kCodecDraco) {
    return decodeError(ErrorCode::kUnsupported, "unknown codec " + std::to_string(header.codec));
  }
  if (header.attributes & ~(kHasNormals | kHasUvs | kHasColors | kHasSkin)) {
    return decodeError(ErrorCode::kUnsupported,
                       "unknown attribute bits " + std::to_string(header.attributes));
  }
  if (header.countA > limits.maxVertices || header.countB > limits.maxTriangles) {
    return decodeError(ErrorCode::kResourceExhausted,
                       std::to_string(header.countA) + " vertices / " +
                           std::to_string(header.countB) + " triangles exceed the limits");
  }
  if (header.countB == 0 || header.countA < 3) {
    return decodeError(ErrorCode::kParseError, "frame declares an empty mesh");
  }
  try {
    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char*>(data + kFrameHeaderBytes), header.payloadBytes);
    draco::StatusOr<draco::EncodedGeometryType> type =
        draco::Decoder::GetEncodedGeometryType(&buffer);
    if (!type.ok() || type.value() != draco::TRIANGULAR_MESH) {
      return decodeError(ErrorCode::kParseError, "payload is not a Draco triangle mesh");
    }
    draco::Decoder decoder;
    draco::StatusOr<std::unique_ptr<draco::Mesh>> decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok()) {
      return decodeError(ErrorCode::kParseError,
                         std::string("Draco: ") + decoded.status().error_msg());
    }
    const draco::Mesh& mesh = *decoded.value();
    if (mesh.num_points() != header.countA || mesh.num_faces() != header.countB) {
      return decodeError(ErrorCode::kParseError,
                         "decoded " + std::to_string(mesh.num_points()) + " vertices / " +
                             std::to_string(mesh.num_faces()) + " triangles, header says " +
                             std::to_string(header.countA) + " / " + std::to_string(header.countB));
    }
    SkinnedMeshFrame out;
    Result<IndexedMesh> converted = toIndexedMesh(mesh, header.attributes);
    if (!converted.ok()) return converted.status();
    out.mesh = std::move(converted).value();
    if (header.attributes & kHasSkin) {
      std::vector<SkinValue> values;
      THINLOD_RETURN_IF_ERROR(detail::readDracoAttribute<3>(
          mesh, draco::GeometryAttribute::GENERIC, "skin", draco::DT_UINT16, "decodeMesh", values));
      Result<std::vector<anim::VertexSkin>> skin = toSkin(values);
      if (!skin.ok()) return skin.status();
      out.skin = std::move(skin).value();
    }
    return out;
  } catch (const std::bad_alloc&) {
    return decodeError(ErrorCode::kResourceExhausted, "out of memory");
  } catch (const std::exception& e) {
    return decodeError(ErrorCode::kParseError, e.what());
  }
}

}  // namespace thinlod::codec
