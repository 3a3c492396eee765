// RepresentationKind: what a representation on the link and at the frontend
// is. One enum for the protocol, the frontend and the simplifier; its values
// are the wire's (protocol/schema/thinlod_wire.fbs). The backbone's scheduling
// options have their own, finer OptionKind (original vs simplified mesh).
#pragma once

#include <cstdint>

namespace thinlod {

enum class RepresentationKind : std::uint8_t {
  kMesh = 0,
  kSimpleImpostor = 1,
  kMeshedImpostor = 2,
  // Triangles + disc points (Cohen-Aliaga-Zhang; docs/hybrid.md): the mesh
  // bytes are an encodeHybrid frame.
  kHybrid = 3,
};
// "Mesh", "SimpleImpostor", "MeshedImpostor", "Hybrid"; "invalid-kind" otherwise.
const char* representationKindName(RepresentationKind kind);

}  // namespace thinlod
