// Private to the scene module: checks of an imported file's bytes before
// Assimp parses them (scene_import.h's contract: validate before handing
// bytes to a third-party library). Assimp's Collada and glTF importers
// recurse over the node graph without a depth limit and follow
// instance_node references without cycle detection, so a cyclic or very
// deep node graph overflowed the stack (a crash, found by
// tests/scene/scene_hostile_test.cpp); instancing also multiplies nodes
// before any limit of ours could count them.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "thinlod/common/core/status.h"
#include "thinlod/common/scene/scene_import.h"

namespace thinlod::scene::detail {

// A node graph as the file declares it: children[n] are the nodes n holds
// (nested or instanced); roots are the nodes a scene shows. Refuses (the
// message starts with `path`) a cycle (kParseError), a path from a root
// deeper than limits.maxDepth nodes or more than limits.maxNodes node
// instances once every reference is expanded (kResourceExhausted).
// Iterative: any graph size is safe. Children indices must be < the count.
Status checkNodeGraph(const std::string& path,
                      const std::vector<std::vector<std::uint32_t>>& children,
                      const std::vector<std::uint32_t>& roots, const ImportLimits& limits);

// Collada: a light scan of the XML (tags, quotes, comments, CDATA; no DTD)
// before Assimp parses it. Refuses unterminated markup, a file whose
// elements are left open (truncated) or with a second document element
// (Assimp reads the first only), element nesting deeper than
// limits.maxDepth + 64, an accessor reading past the array it names
// (count * stride > the array's count), a transform without exactly its
// count of plain finite decimal numbers, an index list (p, vcount, v, h)
// with anything but unsigned integers below 2^31, an instance_geometry /
// _node / _controller / _visual_scene whose url is not "#id" of an element
// of the file (the shown scene's of a visual_scene), and node graphs
// (nesting plus instance_node) that checkNodeGraph refuses.
Status precheckCollada(const std::string& path, std::string_view xml, const ImportLimits& limits);

// Valve SMD (skinned imports): Assimp's reader loops without end when a
// section is cut off before its 'end' (a 16-byte file "version 1\nnodes\n"
// hung it, found by fuzz/imported_scene.cpp). Refuses anything but the
// format's line grammar: 'version 1', then sections nodes / skeleton /
// triangles / vertexanimation each closed by 'end'; nodes numbered 0, 1,
// ... with earlier parents; keys and vertices with the token counts of
// their lines, known bones and finite plain decimal numbers; triangles of a
// material line and three vertex lines.
Status precheckSmd(const std::string& path, std::string_view bytes);

// FBX (ASCII; a binary file, "Kaydara FBX Binary", passes untouched):
// Assimp's FBX parser leaked the elements of a scope when it threw inside
// it (fuzz finding 40: the 7 bytes "\x04\x0b:\x0b\x0b:\x0b" as .fbx).
// The tokenizer and the parser's grammar are replayed here as Assimp 5.2
// runs them (FBXTokenizer.cpp, FBXParser.cpp): every input Assimp's parser
// would throw on is refused, and so are a NUL byte (Assimp's tokenizer
// stops at it) and scopes nested deeper than limits.maxDepth + 64 (its
// parser recurses).
Status precheckFbx(const std::string& path, std::string_view bytes, const ImportLimits& limits);

// OBJ on the route to Assimp (after the mesh loader's OBJ pre-check): every
// line is blank, a comment or one of v vt vn f o g s mtllib usemtl, and
// there is no NUL byte. Assimp dispatches on a line's first characters, so
// a statement the mesh pre-check skips ("fox ...") was a face to it and its
// number parsing read past the buffer (fuzz finding 34). A v line holds
// 3, 4 or 6 values, vt 2 or 3, vn 3: Assimp silently skips a vertex of
// another count, and the faces after it named other vertices (finding 43).
Status checkObjStatementsForAssimp(const std::string& path, std::string_view text);

// RFC 4648 base64 with padding: A-Z a-z 0-9 + /, '=' only as the last one or
// two characters, a length divisible by 4. Assimp's decoder leaked its
// output on a character outside the alphabet (fuzz finding 30).
bool isPlainBase64(std::string_view text);

}  // namespace thinlod::scene::detail
