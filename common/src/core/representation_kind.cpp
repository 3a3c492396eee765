#include "thinlod/common/core/representation_kind.h"

namespace thinlod {

const char* representationKindName(RepresentationKind kind) {
  switch (kind) {
    case RepresentationKind::kMesh:
      return "Mesh";
    case RepresentationKind::kSimpleImpostor:
      return "SimpleImpostor";
    case RepresentationKind::kMeshedImpostor:
      return "MeshedImpostor";
    case RepresentationKind::kHybrid:
      return "Hybrid";
  }
  return "invalid-kind";
}

}  // namespace thinlod
