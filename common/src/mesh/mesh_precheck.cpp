#include "mesh/mesh_precheck.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <set>
#include <vector>

namespace thinlod::mesh_detail {
namespace {

// Splits `bytes` into lines (\n, \r\n or \r) and lines into tokens.
class LineScanner {
 public:
  explicit LineScanner(std::string_view bytes) : bytes_(bytes) {}

  // Next line; false at the end. lineNumber() is 1-based.
  bool next(std::string_view* line) {
    if (pos_ >= bytes_.size()) return false;
    std::size_t end = pos_;
    while (end < bytes_.size() && bytes_[end] != '\n' && bytes_[end] != '\r') ++end;
    *line = bytes_.substr(pos_, end - pos_);
    if (end < bytes_.size() && bytes_[end] == '\r' && end + 1 < bytes_.size() &&
        bytes_[end + 1] == '\n') {
      ++end;
    }
    pos_ = end + 1;
    ++line_;
    return true;
  }
  int lineNumber() const { return line_; }
  std::size_t offset() const { return pos_ > bytes_.size() ? bytes_.size() : pos_; }

 private:
  std::string_view bytes_;
  std::size_t pos_ = 0;
  int line_ = 0;
};

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

std::vector<std::string_view> tokenize(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isSpace(line[i])) ++i;
    std::size_t start = i;
    while (i < line.size() && !isSpace(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

// Appends a checked line to a rewritten file (PrecheckResult::rewritten):
// its tokens up to a comment, single spaces, an LF.
void appendCheckedLine(const std::vector<std::string_view>& tokens, std::string* rewritten) {
  for (std::size_t i = 0; i < tokens.size() && tokens[i][0] != '#'; ++i) {
    if (i > 0) *rewritten += ' ';
    rewritten->append(tokens[i].data(), tokens[i].size());
  }
  *rewritten += '\n';
}

std::string quoted(std::string_view token) {
  const std::size_t kMax = 32;
  std::string s(token.substr(0, kMax));
  if (token.size() > kMax) s += "...";
  return "'" + s + "'";
}

Status lineError(const std::string& name, int line, const std::string& problem) {
  return Status(ErrorCode::kInvalidArgument, name + ":" + std::to_string(line) + ": " + problem);
}

// OpenMesh's readers parse floats with operator>>, which fails on a value
// beyond the float range and leaves the element out, so face references
// checked against our count went past its vertices (an out-of-bounds normal
// write; fuzz campaign of session 10, seed
// fuzz/corpus/mesh/crash-obj-vertex-beyond-float.obj). The mesh stores
// floats anyway. The limit is where float rounding stops giving FLT_MAX
// (FLT_MAX + half an ulp): "3.40282347e+38", FLT_MAX as %.9g prints it,
// still loads.
constexpr double kFloatRoundsToInfinity = 0x1.ffffffp+127;

// One token: a finite number within the float range.
Status checkFiniteNumber(std::string_view token, const std::string& name, int line,
                         const char* what) {
  double v = 0.0;
  if (!parseNumberToken(token, &v)) {
    return lineError(name, line, std::string(what) + " has a bad number " + quoted(token));
  }
  if (!std::isfinite(v)) {
    return lineError(name, line, std::string(what) + " has a non-finite coordinate " + quoted(token));
  }
  if (!(std::fabs(v) < kFloatRoundsToInfinity)) {
    return lineError(name, line,
                     std::string(what) + " has a number beyond the float range " + quoted(token));
  }
  return Status();
}

// All tokens from `first` up to a comment must be finite numbers, at least
// `minCount` of them. A comment token does not count: "v 0 # 0 0" has one
// number, and OpenMesh skips such a vertex, so face indices checked against
// our count went past its vertices (an out-of-bounds texcoord write;
// found by fuzz/mesh_file.cpp, seed fuzz/corpus/mesh/crash-obj-comment-in-vertex.obj).
Status checkFiniteNumbers(const std::vector<std::string_view>& tokens, std::size_t first,
                          std::size_t minCount, const std::string& name, int line,
                          const char* what) {
  std::size_t end = first;
  while (end < tokens.size() && tokens[end][0] != '#') ++end;
  if (end < first + minCount) {
    return lineError(name, line,
                     std::string(what) + " needs " + std::to_string(minCount) + " numbers, found " +
                         std::to_string(end > first ? end - first : 0));
  }
  for (std::size_t i = first; i < end; ++i) {
    THINLOD_RETURN_IF_ERROR(checkFiniteNumber(tokens[i], name, line, what));
  }
  return Status();
}

bool parseUnsigned(std::string_view token, std::uint64_t* value) {
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  return ec == std::errc() && ptr == end;
}

bool parseSigned(std::string_view token, std::int64_t* value) {
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  return ec == std::errc() && ptr == end;
}

// A face's vertex index token: an unsigned integer below `vertexCount`.
Status checkFaceIndex(std::string_view token, std::uint64_t vertexCount, const std::string& name,
                      int line) {
  std::uint64_t index = 0;
  if (!parseUnsigned(token, &index)) {
    return lineError(name, line, "face has a bad vertex index " + quoted(token));
  }
  if (index >= vertexCount) {
    return lineError(name, line,
                     "face references vertex " + std::to_string(index) + " (only " +
                         std::to_string(vertexCount) + " vertices)");
  }
  return Status();
}

Status limitError(const std::string& name, const char* what, std::uint64_t count,
                  std::uint64_t limit) {
  return Status(ErrorCode::kResourceExhausted, name + ": " + std::to_string(count) + " " + what +
                                                   " exceed the limit of " + std::to_string(limit));
}

// ---------------------------------------------------------------- OBJ

// "v x y z r g b": OpenMesh reads the three numbers after z as a colour
// whenever all three are there, and converts each with 255 * value to an
// unsigned char; outside [0, 1] that conversion is undefined behaviour
// (OpenMesh color_cast.hh; found by fuzz/mesh_file.cpp, regression seed
// fuzz/corpus/mesh/crash-obj-vertex-colour-11.obj). Precondition: the
// tokens are finite numbers (checkFiniteNumbers). "vc r g b" lines (a
// colour of their own, from token 1; seed crash-obj-vc-line.obj) are read
// the same way.
Status checkColourRange(const std::vector<std::string_view>& tokens, std::size_t first,
                        const std::string& name, int line) {
  for (std::size_t i = first; i < first + 3; ++i) {
    double v = 0.0;
    parseNumberToken(tokens[i], &v);
    if (!(v >= 0.0 && v <= 1.0)) {
      return lineError(name, line,
                       "vertex colour component " + quoted(tokens[i]) + " is outside [0, 1]");
    }
  }
  return Status();
}

Status checkObjVertexColour(const std::vector<std::string_view>& tokens, const std::string& name,
                            int line) {
  std::size_t numbers = 0;
  while (1 + numbers < tokens.size() && tokens[1 + numbers][0] != '#') ++numbers;
  if (numbers < 6) return Status();
  return checkColourRange(tokens, 4, name, line);
}

// OpenMesh's OBJ reader ends lines at line feeds only, so a carriage return
// without one ("v 1 1 0\rv 0 1 0", old Mac line ends) hides the rest of its
// line from OpenMesh while our scanner saw two lines: face references
// checked against our vertex count then went past OpenMesh's vertices (an
// out-of-bounds texture-coordinate write, fuzz finding 19, seed
// fuzz/corpus/mesh/crash-obj-lone-carriage-return.obj). Refused, naming the line.
Status checkObjLineEnds(std::string_view bytes, const std::string& name) {
  int line = 1;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    if (bytes[i] == '\n') ++line;
    if (bytes[i] == '\r' && (i + 1 == bytes.size() || bytes[i + 1] != '\n')) {
      if (i + 1 == bytes.size()) break;  // a final CR ends the last line for both readers
      return lineError(name, line, "carriage return without a line feed (old Mac line end)");
    }
  }
  return Status();
}

Result<PrecheckResult> precheckObj(std::string_view bytes, const std::string& name,
                                   const MeshLoadOptions& options) {
  THINLOD_RETURN_IF_ERROR(checkObjLineEnds(bytes, name));
  LineScanner scanner(bytes);
  std::string_view line;
  std::uint64_t vertices = 0;
  std::uint64_t normals = 0;
  std::uint64_t texcoords = 0;
  std::uint64_t faces = 0;
  // Four of the mesh target's fuzz findings (6, 9, 19, 21) were lines
  // OpenMesh tokenised differently from this scan (comments, line ends, white
  // space). OpenMesh now reads only the lines rewritten here from the checked
  // tokens (PrecheckResult::rewritten), so a difference of that kind left
  // cannot reach it; numbers are still parsed by both (finding 20: checked).
  std::string rewritten;
  rewritten.reserve(bytes.size() + 1);  // never longer than the file and a final LF
  const auto keep = [&rewritten](const std::vector<std::string_view>& tokens) {
    appendCheckedLine(tokens, &rewritten);
  };
  while (scanner.next(&line)) {
    const std::vector<std::string_view> tokens = tokenize(line);
    if (tokens.empty() || tokens[0][0] == '#') continue;
    const std::string_view key = tokens[0];
    const int ln = scanner.lineNumber();
    // OpenMesh trims spaces and tabs only and then skips a line that starts
    // with any other white space, so "\vv 0 1 0" was a vertex to us and none
    // to it, and a face checked against our count wrote a texture
    // coordinate past its vertices (fuzz campaign of session 10, seed
    // fuzz/corpus/mesh/crash-obj-vertical-tab-before-vertex.obj). The rewrite
    // below now hides such lines from OpenMesh anyway; they stay refused with
    // a clear message (a file that needs them is read differently by other
    // OBJ readers too). White space alone stays a blank line.
    const std::size_t first = line.find_first_not_of(" \t");
    if (line[first] == '\v' || line[first] == '\f') {
      return lineError(name, ln, "line starts with a vertical tab or form feed");
    }
    if (key == "v") {
      THINLOD_RETURN_IF_ERROR(checkFiniteNumbers(tokens, 1, 3, name, ln, "vertex"));
      THINLOD_RETURN_IF_ERROR(checkObjVertexColour(tokens, name, ln));
      if (++vertices > options.maxVertices) {
        return limitError(name, "vertices", vertices, options.maxVertices);
      }
      keep(tokens);
    } else if (key == "vc") {
      THINLOD_RETURN_IF_ERROR(checkFiniteNumbers(tokens, 1, 3, name, ln, "vertex colour"));
      THINLOD_RETURN_IF_ERROR(checkColourRange(tokens, 1, name, ln));
      keep(tokens);
    } else if (key == "vn") {
      THINLOD_RETURN_IF_ERROR(checkFiniteNumbers(tokens, 1, 3, name, ln, "normal"));
      ++normals;
      keep(tokens);
    } else if (key == "vt") {
      THINLOD_RETURN_IF_ERROR(checkFiniteNumbers(tokens, 1, 2, name, ln, "texture coordinate"));
      ++texcoords;
      keep(tokens);
    } else if (key == "f") {
      std::size_t corners = 0;
      for (std::size_t i = 1; i < tokens.size(); ++i) {
        // OpenMesh's face parser knows no comments: "#4/4/1" is vertex
        // atoi("#4") - 1 = -1, and it then wrote that vertex's normal at
        // index -1 (found by fuzz/mesh_file.cpp, seed
        // fuzz/corpus/mesh/crash-obj-comment-in-face.obj).
        if (tokens[i].find('#') != std::string_view::npos) {
          return lineError(name, ln, "comment inside a face line " + quoted(tokens[i]));
        }
        // "v", "v/t", "v//n", "v/t/n": vertex, texture coordinate and
        // normal references, each 1-based or negative (counting back from
        // the last element read so far).
        const std::string_view token = tokens[i];
        const std::size_t slash1 = token.find('/');
        const std::string_view ref = token.substr(0, slash1);
        std::int64_t index = 0;
        if (!parseSigned(ref, &index)) {
          return lineError(name, ln, "face has a bad vertex index " + quoted(tokens[i]));
        }
        const std::int64_t n = static_cast<std::int64_t>(vertices);
        if (index == 0 || index > n || index < -n) {
          return lineError(name, ln,
                           "face references vertex " + std::to_string(index) + " (only " +
                               std::to_string(vertices) + " vertices so far)");
        }
        if (slash1 != std::string_view::npos) {
          const std::string_view rest = token.substr(slash1 + 1);
          const std::size_t slash2 = rest.find('/');
          const std::string_view texRef = rest.substr(0, slash2);
          const std::string_view normalRef =
              slash2 == std::string_view::npos ? std::string_view() : rest.substr(slash2 + 1);
          const auto checkRef = [&](std::string_view r, std::uint64_t count, const char* what) {
            if (r.empty()) return Status();
            std::int64_t k = 0;
            const std::int64_t c = static_cast<std::int64_t>(count);
            if (!parseSigned(r, &k) || k == 0 || k > c || k < -c) {
              return lineError(name, ln,
                               std::string("face references ") + what + " " + quoted(r) +
                                   " (only " + std::to_string(count) + " so far)");
            }
            return Status();
          };
          THINLOD_RETURN_IF_ERROR(checkRef(texRef, texcoords, "texture coordinate"));
          THINLOD_RETURN_IF_ERROR(checkRef(normalRef, normals, "normal"));
        }
        ++corners;
      }
      if (corners < 3) {
        return lineError(name, ln,
                         "face has " + std::to_string(corners) + " vertices (needs at least 3)");
      }
      if (++faces > options.maxFaces) return limitError(name, "faces", faces, options.maxFaces);
      keep(tokens);
    }
    // Other lines (o, g, s, usemtl, mtllib, ...) carry no geometry OpenMesh
    // reads from a stream: left out.
  }
  PrecheckResult result;
  result.declaredFaces = faces;
  result.rewritten = std::move(rewritten);
  return result;
}

// ---------------------------------------------------------------- OFF

Result<PrecheckResult> precheckOff(std::string_view bytes, const std::string& name,
                                   const MeshLoadOptions& options) {
  LineScanner scanner(bytes);
  std::string_view line;
  int commentLine = 0;  // set when nextContentLine stops at a comment
  // OpenMesh 9's OFF reader takes the first line as the header and then
  // reads counts and values with operator>>, skipping no comments: counts
  // on the header line were ignored (it read the first coordinates as
  // counts), and a '#' left a count unread and uninitialised, which it then
  // reserved (an 11 GB allocation from "OFF\v0 0"; found by
  // fuzz/mesh_file.cpp, seed fuzz/corpus/mesh/crash-off-counts-on-header.off).
  // So the header line holds the magic alone, and no comment may follow it.
  auto nextContentLine = [&](std::vector<std::string_view>* tokens) {
    while (scanner.next(&line)) {
      *tokens = tokenize(line);
      if (tokens->empty()) continue;
      for (const std::string_view token : *tokens) {
        if (token.find('#') != std::string_view::npos) {
          commentLine = scanner.lineNumber();
          return false;
        }
      }
      return true;
    }
    return false;
  };
  const auto stopped = [&](Status truncated) {
    if (commentLine == 0) return truncated;
    return lineError(name, commentLine,
                     "comments are not supported in OFF files (OpenMesh's reader does not skip "
                     "them)");
  };
  std::vector<std::string_view> tokens;
  if (!nextContentLine(&tokens)) {
    return stopped(Status(ErrorCode::kInvalidArgument, name + ": empty OFF file"));
  }
  if (scanner.lineNumber() != 1) {
    return lineError(name, scanner.lineNumber(), "the OFF header must be the first line");
  }
  const std::string_view magic = tokens[0];
  if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF") {
    return lineError(name, scanner.lineNumber(), "expected an OFF header, found " + quoted(magic));
  }
  if (magic.find('4') != std::string_view::npos || magic.find("n") == 0) {
    return Status(ErrorCode::kUnsupported,
                  name + ": OFF variant " + quoted(magic) + " (4D / nD) is not supported");
  }
  // The header grammar is [ST][C][N][4][n]OFF; 4 and n are refused above.
  // Anything else before OFF ("XOFF") is not a header OpenMesh knows.
  {
    std::string_view prefix = magic.substr(0, magic.size() - 3);
    for (const std::string_view part : {"ST", "C", "N"}) {
      if (prefix.substr(0, part.size()) == part) prefix.remove_prefix(part.size());
    }
    if (!prefix.empty()) {
      return lineError(name, 1,
                       "expected an OFF header ([ST][C][N]OFF), found " + quoted(magic));
    }
  }
  if (tokens.size() > 1 && tokens[1] == "BINARY") {
    return Status(ErrorCode::kUnsupported, name + ": binary OFF is not supported");
  }
  if (tokens.size() > 1) {
    return lineError(name, 1,
                     "the OFF header line holds only " + quoted(magic) +
                         "; counts go on the next line (OpenMesh ignores them here)");
  }
  if (!nextContentLine(&tokens)) {
    return stopped(
        Status(ErrorCode::kInvalidArgument, name + ": truncated: no vertex/face counts"));
  }
  const std::size_t countStart = 0;
  std::uint64_t nv = 0;
  std::uint64_t nf = 0;
  if (tokens.size() < countStart + 2 || !parseUnsigned(tokens[countStart], &nv) ||
      !parseUnsigned(tokens[countStart + 1], &nf)) {
    return lineError(name, scanner.lineNumber(), "expected vertex and face counts");
  }
  if (nv > options.maxVertices) return limitError(name, "vertices", nv, options.maxVertices);
  if (nf > options.maxFaces) return limitError(name, "faces", nf, options.maxFaces);
  // OpenMesh reads the file rewritten from the checked tokens (as an OBJ):
  // the magic alone, the three counts (OpenMesh always reads an edge count:
  // a file with two counts had its first coordinate taken for it), then
  // each checked line with single spaces and LF ends. Line ends (a lone \r
  // ended a line here and not in OpenMesh's header read: "OFF\r0 0" left
  // its counts unread and reserved 14 GB; fuzz finding 24, seed
  // fuzz/corpus/mesh/oom-off-cr-in-header.off), \v, \f and indentation
  // cannot then be read two ways.
  std::string rewritten;
  rewritten.reserve(bytes.size() + 16);
  // (No token holds a '#' here: nextContentLine stops at comments.)
  const auto keep = [&rewritten](const std::vector<std::string_view>& lineTokens) {
    appendCheckedLine(lineTokens, &rewritten);
  };
  rewritten.append(magic.data(), magic.size());
  rewritten += '\n';
  rewritten += std::to_string(nv) + ' ' + std::to_string(nf) + " 0\n";
  // "x y z\n" is at least 6 bytes, "3 a b c\n" at least 8.
  const std::uint64_t remaining = bytes.size() - scanner.offset();
  if (nv * 6 + nf * 8 > remaining) {
    return Status(ErrorCode::kInvalidArgument, name + ": truncated: header declares " +
                                                   std::to_string(nv) + " vertices and " +
                                                   std::to_string(nf) + " faces but only " +
                                                   std::to_string(remaining) + " bytes follow");
  }
  for (std::uint64_t v = 0; v < nv; ++v) {
    if (!nextContentLine(&tokens)) {
      return stopped(Status(ErrorCode::kInvalidArgument,
                            name + ": truncated: header declares " + std::to_string(nv) +
                                " vertices, found " + std::to_string(v)));
    }
    THINLOD_RETURN_IF_ERROR(checkFiniteNumbers(tokens, 0, 3, name, scanner.lineNumber(), "vertex"));
    keep(tokens);
  }
  for (std::uint64_t f = 0; f < nf; ++f) {
    if (!nextContentLine(&tokens)) {
      return stopped(Status(ErrorCode::kInvalidArgument, name + ": truncated: header declares " +
                                                             std::to_string(nf) + " faces, found " +
                                                             std::to_string(f)));
    }
    const int ln = scanner.lineNumber();
    std::uint64_t k = 0;
    if (!parseUnsigned(tokens[0], &k) || k < 3) {
      return lineError(name, ln, "face needs a vertex count >= 3, found " + quoted(tokens[0]));
    }
    if (tokens.size() < k + 1) {
      return lineError(name, ln,
                       "face declares " + std::to_string(k) + " vertices, found " +
                           std::to_string(tokens.size() - 1));
    }
    for (std::uint64_t i = 1; i <= k; ++i) {
      THINLOD_RETURN_IF_ERROR(checkFaceIndex(tokens[i], nv, name, ln));
    }
    // OpenMesh reads faces token by token and, without face colours asked
    // for, leaves values after the indices in the stream: one became the next
    // face's vertex count, and "3 0 1 2 999999999" reserved 3 GB (fuzz
    // finding 23, seed fuzz/corpus/mesh/oom-off-value-after-face-indices.off;
    // three colour values made the next face unreadable). Refused.
    if (tokens.size() != k + 1) {
      return lineError(name, ln,
                       "face has " + std::to_string(tokens.size() - k - 1) + " value(s) after its " +
                           std::to_string(k) + " vertex indices (face colours are not read)");
    }
    keep(tokens);
  }
  PrecheckResult result;
  result.declaredFaces = nf;
  result.rewritten = std::move(rewritten);
  return result;
}

// ---------------------------------------------------------------- PLY

// A PLY value type as the header names it: its size and how its ASCII
// tokens must look.
struct PlyType {
  int bytes = 0;  // 0: not a PLY type
  enum class Kind { kSigned, kUnsigned, kFloat, kDouble } kind = Kind::kSigned;
};

PlyType plyType(std::string_view type) {
  using K = PlyType::Kind;
  if (type == "char" || type == "int8") return {1, K::kSigned};
  if (type == "uchar" || type == "uint8") return {1, K::kUnsigned};
  if (type == "short" || type == "int16") return {2, K::kSigned};
  if (type == "ushort" || type == "uint16") return {2, K::kUnsigned};
  if (type == "int" || type == "int32") return {4, K::kSigned};
  if (type == "uint" || type == "uint32") return {4, K::kUnsigned};
  if (type == "float" || type == "float32") return {4, K::kFloat};
  if (type == "double" || type == "float64") return {8, K::kDouble};
  return {};
}

struct PlyProperty {
  std::string name;
  std::string_view valueTypeName;  // the header's own token (kept in the rewrite)
  std::string_view countTypeName;  // lists only
  PlyType value;                   // the value (or the list entries)
  PlyType count;                   // bytes == 0: not a list
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

bool isColourProperty(const std::string& name) {
  return name == "red" || name == "green" || name == "blue" || name == "alpha" ||
         name == "diffuse_red" || name == "diffuse_green" || name == "diffuse_blue";
}

// One ASCII token as a value of `type`. OpenMesh reads ASCII PLY values with
// operator>> into the declared type, so a token that is not exactly such a
// value ("1.5" for an int, "300" for a uchar) would be read in part and the
// rest left for the next value: everything after it shifts.
Status checkPlyAsciiValue(std::string_view token, const PlyType& type, const std::string& name,
                          int line, const char* what) {
  using K = PlyType::Kind;
  if (type.kind == K::kSigned || type.kind == K::kUnsigned) {
    std::int64_t v = 0;
    const int bits = 8 * type.bytes;
    const std::int64_t lo = type.kind == K::kSigned ? -(std::int64_t{1} << (bits - 1)) : 0;
    const std::int64_t hi = type.kind == K::kSigned ? (std::int64_t{1} << (bits - 1)) - 1
                                                     : (std::int64_t{1} << bits) - 1;
    if (!parseSigned(token, &v) || v < lo || v > hi) {
      return lineError(name, line,
                       std::string(what) + " " + quoted(token) + " is not " +
                           (type.kind == K::kSigned ? "a signed" : "an unsigned") + " " +
                           std::to_string(bits) + "-bit integer");
    }
    return Status();
  }
  // float and double alike: OpenMesh reads ASCII values into floats, and
  // operator>> fails beyond the float range (checkFiniteNumber's rule).
  return checkFiniteNumber(token, name, line, what);
}

// ASCII PLY: every item holds exactly its properties' values, each value
// fits its declared type, colours given as floats lie in [0, 1] (OpenMesh
// scales them by 255 into an integer: far outside, undefined behaviour in
// its reader), the face's vertex index list (the only list the header
// allows) has >= 3 indices of existing vertices. The checked tokens are
// appended to `rewritten`, one item per line.
Status checkPlyAsciiItem(const PlyElement& e, const std::vector<std::string_view>& tokens,
                         std::uint64_t vertexCount, const std::string& name, int line,
                         std::string* rewritten) {
  const bool isVertex = e.name == "vertex";
  const bool isFace = e.name == "face";
  std::size_t t = 0;
  for (std::size_t p = 0; p < e.properties.size(); ++p) {
    const PlyProperty& prop = e.properties[p];
    if (t >= tokens.size()) {
      return lineError(name, line,
                       e.name + " item ends before its property " + quoted(prop.name));
    }
    if (prop.count.bytes == 0) {
      THINLOD_RETURN_IF_ERROR(checkPlyAsciiValue(tokens[t], prop.value, name, line,
                                                 isVertex ? "vertex value" : "value"));
      if ((isVertex || isFace) && isColourProperty(prop.name) &&
          prop.value.kind == PlyType::Kind::kFloat) {
        double v = 0.0;
        parseNumberToken(tokens[t], &v);
        if (!(v >= 0.0 && v <= 1.0)) {
          return lineError(name, line,
                           e.name + " colour component " + quoted(tokens[t]) +
                               " is outside [0, 1]");
        }
      }
      ++t;
      continue;
    }
    THINLOD_RETURN_IF_ERROR(checkPlyAsciiValue(tokens[t], prop.count, name, line, "list count"));
    std::uint64_t k = 0;
    parseUnsigned(tokens[t], &k);  // a negative count (a signed count type) stays 0: refused
    ++t;
    if (k < 3) return lineError(name, line, "bad face line (fewer than 3 vertices)");
    if (k > tokens.size() - t) {
      return lineError(name, line,
                       "list " + quoted(prop.name) + " declares " + std::to_string(k) +
                           " values, the line has " + std::to_string(tokens.size() - t));
    }
    for (std::uint64_t j = 0; j < k; ++j, ++t) {
      THINLOD_RETURN_IF_ERROR(
          checkPlyAsciiValue(tokens[t], prop.value, name, line, "face vertex index"));
      THINLOD_RETURN_IF_ERROR(checkFaceIndex(tokens[t], vertexCount, name, line));
    }
  }
  if (t != tokens.size()) {
    return lineError(name, line,
                     e.name + " item has " + std::to_string(tokens.size() - t) +
                         " value(s) after its properties");
  }
  appendCheckedLine(tokens, rewritten);
  return Status();
}

// Binary PLY: walks every item as OpenMesh will read it, so the body is
// exactly as long as the header says and each value is one OpenMesh can
// take: face lists of >= 3 existing vertices (a negative count read as
// unsigned made it push ~4 billion indices), floats finite, doubles within
// the float range (it converts them to float, undefined beyond),
// colours given as floats in [0, 1] (it scales them by 255 into an int).
// `*walkedBytes` is where the last item ends.
Status walkPlyBinary(std::string_view body, bool bigEndian, const std::vector<PlyElement>& elements,
                     std::uint64_t vertexCount, const std::string& name,
                     std::size_t* walkedBytes) {
  using K = PlyType::Kind;
  std::size_t pos = 0;
  const auto truncated = [&](const PlyElement& e, std::uint64_t item) {
    return Status(ErrorCode::kInvalidArgument,
                  name + ": truncated: the data ends in " + e.name + " " + std::to_string(item) +
                      " (byte " + std::to_string(pos) + " of " + std::to_string(body.size()) +
                      " after the header)");
  };
  // Reads one value of `type` at pos; false when the body ends first.
  const auto read = [&](const PlyType& type, double* value) {
    if (body.size() - pos < static_cast<std::size_t>(type.bytes)) return false;
    unsigned char b[8];
    for (int i = 0; i < type.bytes; ++i) {
      b[i] = static_cast<unsigned char>(body[pos + (bigEndian ? type.bytes - 1 - i : i)]);
    }
    pos += static_cast<std::size_t>(type.bytes);
    std::uint64_t u = 0;
    for (int i = type.bytes - 1; i >= 0; --i) u = (u << 8) | b[i];
    switch (type.kind) {
      case K::kUnsigned: *value = static_cast<double>(u); break;
      case K::kSigned: {
        const int shift = 64 - 8 * type.bytes;
        *value = static_cast<double>(static_cast<std::int64_t>(u << shift) >> shift);
        break;
      }
      case K::kFloat: {
        float f;
        const std::uint32_t u32 = static_cast<std::uint32_t>(u);
        std::memcpy(&f, &u32, 4);
        *value = f;
        break;
      }
      case K::kDouble: std::memcpy(value, &u, 8); break;
    }
    return true;
  };
  for (const PlyElement& e : elements) {
    const bool isVertex = e.name == "vertex";
    if (e.properties.empty()) continue;  // nothing to read however many items
    for (std::uint64_t item = 0; item < e.count; ++item) {
      for (const PlyProperty& p : e.properties) {
        double v = 0.0;
        if (p.count.bytes == 0) {
          if (!read(p.value, &v)) return truncated(e, item);
          if (p.value.kind == K::kFloat || p.value.kind == K::kDouble) {
            if (!std::isfinite(v) || !(std::fabs(v) < kFloatRoundsToInfinity)) {
              return Status(ErrorCode::kInvalidArgument,
                            name + ": " + e.name + " " + std::to_string(item) + ": property " +
                                quoted(p.name) + " is not a finite float");
            }
            if ((isVertex || e.name == "face") && isColourProperty(p.name) &&
                !(v >= 0.0 && v <= 1.0)) {
              return Status(ErrorCode::kInvalidArgument,
                            name + ": " + e.name + " " + std::to_string(item) +
                                ": colour component " + quoted(p.name) + " is outside [0, 1]");
            }
          }
          continue;
        }
        // The face's vertex index list (the only list the header allows).
        if (!read(p.count, &v)) return truncated(e, item);
        if (!(v >= 3.0)) {
          return Status(ErrorCode::kInvalidArgument,
                        name + ": face " + std::to_string(item) + " has " +
                            std::to_string(static_cast<long long>(v)) +
                            " vertices (at least 3)");
        }
        const std::uint64_t k = static_cast<std::uint64_t>(v);
        for (std::uint64_t j = 0; j < k; ++j) {
          if (!read(p.value, &v)) return truncated(e, item);
          if (!(v >= 0.0) || v >= static_cast<double>(vertexCount)) {
            return Status(ErrorCode::kInvalidArgument,
                          name + ": face " + std::to_string(item) + " references vertex " +
                              std::to_string(static_cast<long long>(v)) + " (only " +
                              std::to_string(vertexCount) + " vertices)");
          }
        }
      }
    }
    if (e.name == "face") break;  // OpenMesh reads nothing after the faces
  }
  *walkedBytes = pos;
  return Status();
}

Result<PrecheckResult> precheckPly(std::string_view bytes, const std::string& name,
                                   const MeshLoadOptions& options) {
  LineScanner scanner(bytes);
  std::string_view line;
  if (!scanner.next(&line) || line != "ply") {
    return Status(ErrorCode::kInvalidArgument, name + ": missing 'ply' magic line");
  }
  std::string format;
  std::vector<PlyElement> elements;
  std::set<std::string> elementNames;
  bool afterFace = false;  // an element after the faces: OpenMesh never reads it
  bool ended = false;
  while (!ended && scanner.next(&line)) {
    const std::vector<std::string_view> tokens = tokenize(line);
    const int ln = scanner.lineNumber();
    if (tokens.empty()) continue;
    const std::string_view key = tokens[0];
    // OpenMesh reads the header as a stream of words, not lines: a word
    // more or less on a line shifts everything after it (the words of a
    // short property line ran into 'end_header', which it then never saw
    // and looped at the end of the file). So every line has exactly its
    // words. (OpenMesh now reads the header as rewritten below; the rule
    // stays, since such a line is malformed.)
    if (key == "format") {
      if (tokens.size() != 3 || tokens[2] != "1.0") {
        return Status(ErrorCode::kVersionMismatch,
                      name + ":" + std::to_string(ln) + ": unsupported PLY format line");
      }
      format = std::string(tokens[1]);
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
        return lineError(name, ln, "unknown PLY format " + quoted(tokens[1]));
      }
    } else if (key == "element") {
      PlyElement e;
      if (tokens.size() != 3 || !parseUnsigned(tokens[2], &e.count)) {
        return lineError(name, ln, "element line needs a name and a count, nothing else");
      }
      e.name = std::string(tokens[1]);
      // OpenMesh reads counts as 32-bit unsigned; a larger one failed its
      // stream and left it reading the header forever. Every element is
      // held to the face limit (vertex and face to their own, below).
      if (e.count > options.maxFaces && e.name != "vertex" && e.name != "face") {
        return limitError(name, ("'" + e.name + "' items").c_str(), e.count, options.maxFaces);
      }
      if (!elementNames.insert(e.name).second) {
        return lineError(name, ln, "element " + quoted(e.name) + " declared twice");
      }
      if (e.name == "face" && elementNames.count("vertex") == 0) {
        return lineError(name, ln, "the face element comes before the vertex element");
      }
      afterFace = !elements.empty() && (afterFace || elements.back().name == "face");
      elements.push_back(e);
    } else if (key == "property") {
      if (elements.empty()) return lineError(name, ln, "property before any element");
      PlyProperty p;
      if (tokens.size() == 5 && tokens[1] == "list") {
        p.countTypeName = tokens[2];
        p.valueTypeName = tokens[3];
        p.count = plyType(tokens[2]);
        p.value = plyType(tokens[3]);
        p.name = std::string(tokens[4]);
      } else if (tokens.size() == 3 && tokens[1] != "list") {
        p.valueTypeName = tokens[1];
        p.value = plyType(tokens[1]);
        p.name = std::string(tokens[2]);
      }
      if (p.value.bytes == 0 || (tokens[1] == "list" && p.count.bytes == 0)) {
        return lineError(name, ln,
                         "bad property line (property TYPE NAME or property list TYPE TYPE NAME)");
      }
      if (p.count.bytes != 0 && !afterFace) {
        // OpenMesh reads one list only, a face's vertex indices; any other
        // list it skips as one value, and everything after it shifts (an
        // element after the faces it never reads).
        if (elements.back().name != "face" ||
            (p.name != "vertex_indices" && p.name != "vertex_index")) {
          return lineError(name, ln,
                           "list property " + quoted(p.name) + " of element " +
                               quoted(elements.back().name) +
                               " is not supported (only a face's vertex_indices list is read)");
        }
        // The count types OpenMesh's header reader accepts; the indices must
        // be integers (it reads a float index as 0 and without its bytes).
        if (p.countTypeName != "uchar" && p.countTypeName != "uint8" &&
            p.countTypeName != "uint16" && p.countTypeName != "int") {
          return lineError(name, ln,
                           "list count type " + quoted(p.countTypeName) +
                               " is not supported (uchar, uint8, uint16 or int)");
        }
        if (p.value.kind != PlyType::Kind::kSigned && p.value.kind != PlyType::Kind::kUnsigned) {
          return lineError(name, ln, "face vertex indices must have an integer type");
        }
      }
      // OpenMesh reads a colour as a float (times 255) only when it is
      // declared float; a double colour it reads as an integer, without its
      // bytes when binary: everything after it shifts.
      if (p.count.bytes == 0 && isColourProperty(p.name) && p.value.kind == PlyType::Kind::kDouble) {
        return lineError(name, ln, "colour property " + quoted(p.name) +
                                       " of type double is not supported (float or an integer type)");
      }

      elements.back().properties.push_back(p);
    } else if (key == "end_header") {
      if (tokens.size() != 1) return lineError(name, ln, "end_header line holds only 'end_header'");
      ended = true;
    } else if (key != "comment" && key != "obj_info") {
      return lineError(name, ln, "unknown PLY header keyword " + quoted(key));
    }
  }
  if (!ended) return Status(ErrorCode::kInvalidArgument, name + ": truncated: no end_header");
  if (format.empty()) return Status(ErrorCode::kInvalidArgument, name + ": no format line");
  // A binary vertex coordinate, normal or texture coordinate OpenMesh reads
  // only as float or double: of an integer type it reads 0 and consumes no
  // bytes, so everything after it shifts. (ASCII reads any number into a
  // float.)
  for (const PlyElement& e : elements) {
    if (format == "ascii" || e.name != "vertex") continue;
    for (const PlyProperty& p : e.properties) {
      const bool read = p.name == "x" || p.name == "y" || p.name == "z" || p.name == "nx" ||
                        p.name == "ny" || p.name == "nz" || p.name == "u" || p.name == "v" ||
                        p.name == "s" || p.name == "t";
      if (read && p.count.bytes == 0 && p.value.kind != PlyType::Kind::kFloat &&
          p.value.kind != PlyType::Kind::kDouble) {
        return Status(ErrorCode::kInvalidArgument,
                      name + ": binary vertex property " + quoted(p.name) + " of type " +
                          quoted(p.valueTypeName) + " is not supported (float or double)");
      }
    }
  }
  // Our scanner ends a line at a lone carriage return, OpenMesh's header
  // reader at line feeds only: it skipped "comment ...\rend_header" as one
  // comment, never saw end_header and looped at the end of the file (fuzz
  // finding 25, seed fuzz/corpus/mesh/timeout-ply-cr-in-comment.ply). The
  // rewrite below would hide that, but the bytes after such a header are
  // then not where the writer meant them (binary bodies): refused. CRLF
  // stays allowed.
  {
    const std::string_view header = bytes.substr(0, scanner.offset());
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == '\r' && (i + 1 >= header.size() || header[i + 1] != '\n')) {
        return Status(ErrorCode::kInvalidArgument,
                      name + ": a carriage return without a line feed in the PLY header "
                             "(header lines end with LF or CRLF)");
      }
    }
  }

  std::uint64_t nv = 0;
  std::uint64_t nf = 0;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") nv = e.count;
    if (e.name == "face") nf = e.count;
  }
  if (nv > options.maxVertices) return limitError(name, "vertices", nv, options.maxVertices);
  if (nf > options.maxFaces) return limitError(name, "faces", nf, options.maxFaces);

  // OpenMesh reads the header as rewritten from what was checked: the
  // magic, the format, each element with its properties (types as the file
  // spelled them), end_header; single spaces, LF, no comments. Findings 18
  // and 25 were OpenMesh's header reading and ours differing; that class
  // cannot reach it any more (as for OBJ and OFF).
  std::string rewritten = "ply\nformat " + format + " 1.0\n";
  for (const PlyElement& e : elements) {
    rewritten += "element " + e.name + " " + std::to_string(e.count) + "\n";
    for (const PlyProperty& p : e.properties) {
      rewritten += "property ";
      if (p.count.bytes != 0) {
        rewritten += "list ";
        rewritten.append(p.countTypeName.data(), p.countTypeName.size());
        rewritten += ' ';
      }
      rewritten.append(p.valueTypeName.data(), p.valueTypeName.size());
      rewritten += ' ' + p.name + '\n';
    }
  }
  rewritten += "end_header\n";

  PrecheckResult result;
  result.declaredFaces = nf;
  result.binary = format != "ascii";
  const std::uint64_t body = bytes.size() - scanner.offset();
  if (result.binary) {
    std::size_t bodyEnd = 0;
    THINLOD_RETURN_IF_ERROR(walkPlyBinary(bytes.substr(scanner.offset()),
                                          format == "binary_big_endian", elements, nv, name,
                                          &bodyEnd));
    // What OpenMesh reads: the elements up to the face element (it stops
    // there), nothing after the walked items.
    rewritten.append(bytes.substr(scanner.offset(), bodyEnd));
    result.rewritten = std::move(rewritten);
    return result;
  }
  // ASCII: one line per element item, in header order, rewritten from its
  // checked tokens; anything after the last item is dropped.
  std::vector<std::string_view> tokens;
  for (const PlyElement& e : elements) {
    if (e.name != "vertex" && e.name != "face" && e.properties.empty()) continue;
    if (e.count * 2 > body) {
      return Status(ErrorCode::kInvalidArgument,
                    name + ": truncated: header declares " + std::to_string(e.count) + " " +
                        e.name + " items but only " + std::to_string(body) + " bytes follow");
    }
    for (std::uint64_t i = 0; i < e.count; ++i) {
      do {
        if (!scanner.next(&line)) {
          return Status(ErrorCode::kInvalidArgument, name + ": truncated: header declares " +
                                                         std::to_string(e.count) + " " + e.name +
                                                         " items, found " + std::to_string(i));
        }
        tokens = tokenize(line);
      } while (tokens.empty());
      THINLOD_RETURN_IF_ERROR(
          checkPlyAsciiItem(e, tokens, nv, name, scanner.lineNumber(), &rewritten));
    }
    if (e.name == "face") break;  // OpenMesh reads nothing after the faces
  }
  result.rewritten = std::move(rewritten);
  return result;
}

// ---------------------------------------------------------------- STL

bool startsWithSolid(std::string_view bytes) {
  std::size_t i = 0;
  while (i < bytes.size() && (isSpace(bytes[i]) || bytes[i] == '\n' || bytes[i] == '\r')) ++i;
  return bytes.substr(i, 5) == "solid";
}

std::uint32_t readLe32(const char* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  return v;
}

Result<PrecheckResult> precheckStl(std::string_view bytes, const std::string& name,
                                   const MeshLoadOptions& options) {
  PrecheckResult result;
  const std::size_t kHeader = 84;
  const std::size_t kTriangle = 50;
  std::uint64_t declared = bytes.size() >= kHeader ? readLe32(bytes.data() + 80) : 0;
  const bool exactBinary =
      bytes.size() >= kHeader && kHeader + declared * kTriangle == bytes.size();
  if (exactBinary) {
    result.binary = true;
    result.declaredFaces = declared;
    if (declared > options.maxFaces) return limitError(name, "faces", declared, options.maxFaces);
    for (std::uint64_t t = 0; t < declared; ++t) {
      const char* tri = bytes.data() + kHeader + t * kTriangle;
      for (int k = 3; k < 12; ++k) {  // skip the facet normal, check the corners
        float f = 0.0f;
        std::memcpy(&f, tri + 4 * k, 4);
        if (!std::isfinite(f)) {
          return Status(ErrorCode::kInvalidArgument,
                        name + ": triangle " + std::to_string(t) + " has a non-finite coordinate");
        }
      }
    }
    return result;
  }
  if (!startsWithSolid(bytes)) {
    if (bytes.size() < kHeader) {
      return Status(ErrorCode::kInvalidArgument, name + ": too short for a binary STL (" +
                                                     std::to_string(bytes.size()) +
                                                     " bytes) and not an ASCII STL");
    }
    return Status(ErrorCode::kInvalidArgument,
                  name + ": truncated: binary STL declares " + std::to_string(declared) +
                      " triangles (" + std::to_string(kHeader + declared * kTriangle) +
                      " bytes) but the file has " + std::to_string(bytes.size()) + " bytes");
  }
  LineScanner scanner(bytes);
  std::string_view line;
  std::uint64_t corners = 0;
  bool endSolid = false;
  // OpenMesh reads the file as rewritten from the checked corners: every
  // three 'vertex' lines one facet, in the canonical layout, so nothing
  // else of the file (facet and loop lines, names, what follows endsolid)
  // reaches its reader.
  std::string rewritten = "solid thinlod\n";
  while (scanner.next(&line)) {
    const std::vector<std::string_view> tokens = tokenize(line);
    if (tokens.empty()) continue;
    if (tokens[0] == "vertex") {
      THINLOD_RETURN_IF_ERROR(
          checkFiniteNumbers(tokens, 1, 3, name, scanner.lineNumber(), "vertex"));
      if (tokens.size() != 4) {
        return lineError(name, scanner.lineNumber(), "a vertex line holds three numbers");
      }
      if (corners % 3 == 0) rewritten += "facet normal 0 0 0\nouter loop\n";
      rewritten += "vertex ";
      for (std::size_t i = 1; i <= 3; ++i) {
        if (i > 1) rewritten += ' ';
        rewritten.append(tokens[i].data(), tokens[i].size());
      }
      rewritten += '\n';
      ++corners;
      if (corners % 3 == 0) rewritten += "endloop\nendfacet\n";
      if (corners / 3 > options.maxFaces) {
        return limitError(name, "faces", corners / 3, options.maxFaces);
      }
    } else if (tokens[0] == "endsolid") {
      endSolid = true;  // several solids in one file: all are read
    }
  }
  if (!endSolid || corners % 3 != 0) {
    return Status(ErrorCode::kInvalidArgument, name + ": truncated ASCII STL (no endsolid)");
  }
  rewritten += "endsolid thinlod\n";
  result.declaredFaces = corners / 3;
  result.rewritten = std::move(rewritten);
  return result;
}

}  // namespace

bool parseNumberToken(std::string_view token, double* value) {
  // One sign at most: from_chars takes no '+', so it is dropped here, but
  // "+-.5" must not then read as -0.5 while OpenMesh's operator>> refuses it
  // and drops the vertex (fuzz finding 26: a face then wrote a uv past its
  // vertices; seed fuzz/corpus/mesh/crash-obj-plus-minus-sign.obj).
  if (!token.empty() && token[0] == '+') {
    token.remove_prefix(1);
    if (!token.empty() && (token[0] == '-' || token[0] == '+')) return false;
  }
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  if (ptr != end) return false;
  if (ec == std::errc::result_out_of_range) {
    // Overflow or underflow: strtod tells them apart (HUGE_VAL vs ~0).
    const std::string copy(token);
    *value = std::strtod(copy.c_str(), nullptr);
    return true;
  }
  return ec == std::errc();
}

Result<PrecheckResult> precheckMesh(std::string_view bytes, MeshFormat format,
                                    const std::string& name, const MeshLoadOptions& options) {
  switch (format) {
    case MeshFormat::kObj:
      return precheckObj(bytes, name, options);
    case MeshFormat::kOff:
      return precheckOff(bytes, name, options);
    case MeshFormat::kPly:
      return precheckPly(bytes, name, options);
    case MeshFormat::kStl:
      return precheckStl(bytes, name, options);
  }
  return Status(ErrorCode::kInternal, name + ": unknown format");
}

}  // namespace thinlod::mesh_detail
