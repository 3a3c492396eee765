// Private to encoding*.cpp: reading Draco attributes defensively (shared by
// the mesh and the hybrid decoders).
#pragma once

#include <draco/point_cloud/point_cloud.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>

#include "thinlod/common/core/status.h"

namespace thinlod::codec::detail {

// Reads a per-point attribute of N components of `Element` (what encodeMesh
// writes: float32, or uint8 for colours). The bytes are copied out of
// Draco's buffer after checking the type, stride and bounds ourselves,
// instead of through GeometryAttribute::ConvertValue: that template (inlined
// here) reads the attribute's `normalized_` bool, which libdraco fills from
// the bitstream without checking it is 0 or 1 (a load of bool 131 is
// undefined behaviour; found by fuzz/codec_mesh_frame.cpp, regression seed
// fuzz/corpus/codec_mesh/crash-draco-bool-131.bin).
template <int N, typename Store>
Status readDracoAttribute(const draco::PointCloud& mesh, draco::GeometryAttribute::Type type,
                          const char* name, draco::DataType dataType, const char* decoder,
                          Store& out) {
  const auto decodeError = [decoder](ErrorCode code, const std::string& message) {
    return Status(code, std::string(decoder) + ": " + message);
  };
  using Element = std::remove_reference_t<decltype(out[0][0])>;
  const draco::PointAttribute* attribute = mesh.GetNamedAttribute(type);
  if (attribute == nullptr) {
    return decodeError(ErrorCode::kParseError, std::string("missing attribute ") + name);
  }
  if (attribute->num_components() != N || attribute->data_type() != dataType) {
    return decodeError(ErrorCode::kParseError,
                       std::string(name) + " has " +
                           std::to_string(static_cast<int>(attribute->num_components())) +
                           " components of Draco type " +
                           std::to_string(static_cast<int>(attribute->data_type())) +
                           ", expected " + std::to_string(N) + " of type " +
                           std::to_string(static_cast<int>(dataType)));
  }
  constexpr std::int64_t kValueBytes = N * static_cast<std::int64_t>(sizeof(Element));
  const draco::DataBuffer* buffer = attribute->buffer();
  const std::int64_t stride = attribute->byte_stride();
  const std::int64_t offset = attribute->byte_offset();
  if (buffer == nullptr || stride < kValueBytes || offset < 0 ||
      static_cast<std::uint64_t>(buffer->data_size()) < static_cast<std::uint64_t>(offset)) {
    return decodeError(ErrorCode::kParseError, std::string(name) + " has an invalid layout");
  }
  // Values that fit in the buffer; every mapped index must be below both.
  const std::uint64_t valuesInBuffer =
      (static_cast<std::uint64_t>(buffer->data_size()) - static_cast<std::uint64_t>(offset)) /
      static_cast<std::uint64_t>(stride);
  // mapped_index() indexes the explicit map unchecked.
  if (!attribute->is_mapping_identity() && attribute->indices_map_size() < mesh.num_points()) {
    return decodeError(ErrorCode::kParseError, std::string(name) + " maps fewer points than exist");
  }
  out.resize(mesh.num_points());
  for (std::uint32_t i = 0; i < mesh.num_points(); ++i) {
    const draco::AttributeValueIndex value = attribute->mapped_index(draco::PointIndex(i));
    if (value.value() >= attribute->size() || value.value() >= valuesInBuffer) {
      return decodeError(ErrorCode::kParseError, std::string(name) + " index out of range");
    }
    std::memcpy(&out[i][0], buffer->data() + offset + stride * value.value(), kValueBytes);
  }
  return Status();
}

}  // namespace thinlod::codec::detail
