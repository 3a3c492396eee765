// Pre-checks of mesh files before OpenMesh reads them. OpenMesh trusts its
// input: a header count of 2e9 makes it allocate (bad_alloc), a "nan" in an
// OBJ is silently skipped, and a truncated OFF yields garbage faces. These
// scans reject such files with a message naming the line or byte count.
// Pure functions over bytes in memory.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "thinlod/common/core/status.h"
#include "thinlod/common/mesh/mesh_io.h"

namespace thinlod::mesh_detail {

enum class MeshFormat { kObj, kPly, kOff, kStl };

struct PrecheckResult {
  bool binary = false;              // PLY / STL: OpenMesh needs to be told for STL
  std::uint64_t declaredFaces = 0;  // from the header (0 when the format has none)
  // OBJ, OFF and PLY: the file as OpenMesh gets it, rewritten from the
  // tokens the pre-check validated (OBJ: v, vc, vn, vt and f lines only;
  // OFF: the magic, the three counts, the vertex and face lines; PLY: the
  // header's format, elements and properties, ASCII items line by line, a
  // binary body as walked up to the end of the faces; ASCII STL: every three
  // vertex lines one facet in the canonical layout; single spaces, LF line
  // ends, no comments), so OpenMesh cannot read anything the pre-check did
  // not see. Unset for binary STL (fixed 50-byte records, checked):
  // OpenMesh reads the original bytes.
  std::optional<std::string> rewritten;
};

// `name` prefixes every message.
Result<PrecheckResult> precheckMesh(std::string_view bytes, MeshFormat format,
                                    const std::string& name, const MeshLoadOptions& options);

// std::from_chars on a token (a leading '+' allowed); false when the token
// is not a number. `*value` may be non-finite ("nan", "inf", overflow).
bool parseNumberToken(std::string_view token, double* value);

}  // namespace thinlod::mesh_detail
