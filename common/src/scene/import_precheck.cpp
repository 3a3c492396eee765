#include "import_precheck.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>
#include <set>
#include <utility>
#include <vector>

namespace thinlod::scene::detail {

Status checkNodeGraph(const std::string& path,
                      const std::vector<std::vector<std::uint32_t>>& children,
                      const std::vector<std::uint32_t>& roots, const ImportLimits& limits) {
  const std::size_t n = children.size();
  // Post-order DFS with an explicit stack: state 0 unvisited, 1 on the
  // current path, 2 done. instances[v]: nodes in v's expanded subtree
  // (saturated just above maxNodes); depth[v]: nodes on its longest path.
  const std::uint64_t cap = static_cast<std::uint64_t>(limits.maxNodes) + 1;
  std::vector<std::uint8_t> state(n, 0);
  std::vector<std::uint64_t> instances(n, 0);
  std::vector<std::uint32_t> depth(n, 0);
  std::vector<std::pair<std::uint32_t, std::size_t>> stack;  // node, next child
  for (std::uint32_t start = 0; start < n; ++start) {
    if (state[start] != 0) continue;
    stack.push_back({start, 0});
    state[start] = 1;
    while (!stack.empty()) {
      auto& [v, next] = stack.back();
      if (next < children[v].size()) {
        const std::uint32_t c = children[v][next++];
        if (state[c] == 1) {
          return Status(ErrorCode::kParseError,
                        path + ": the node graph has a cycle (node " + std::to_string(c) +
                            " contains itself through its children or instances)");
        }
        if (state[c] == 0) {
          state[c] = 1;
          stack.push_back({c, 0});
        }
        continue;
      }
      std::uint64_t count = 1;
      std::uint32_t longest = 0;
      for (std::uint32_t c : children[v]) {
        count = std::min(cap, count + instances[c]);
        longest = std::max(longest, depth[c]);
      }
      instances[v] = count;
      depth[v] = longest + 1;
      state[v] = 2;
      stack.pop_back();
    }
  }
  std::uint64_t total = 0;
  for (std::uint32_t r : roots) {
    if (depth[r] > static_cast<std::uint32_t>(std::max(limits.maxDepth, 0))) {
      return Status(ErrorCode::kResourceExhausted,
                    path + ": the node tree is " + std::to_string(depth[r]) +
                        " levels deep, more than the limit of " + std::to_string(limits.maxDepth));
    }
    total = std::min(cap, total + instances[r]);
  }
  if (total > limits.maxNodes) {
    return Status(ErrorCode::kResourceExhausted, path + ": the node graph expands to more than " +
                                                     std::to_string(limits.maxNodes) +
                                                     " node instances");
  }
  return Status();
}

namespace {

// XML's white space (S: space, tab, CR, LF). Not std::isspace: a form feed
// or vertical tab is no separator to Assimp's Collada number reader, which
// then read a transform differently from this scan (fuzz finding 41:
// "0 \f\f...\f0 0" counted as three numbers here).
bool isXmlSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }


// Value of attribute `name` in a start tag's text (after the element name),
// empty when absent.
std::string_view attribute(std::string_view tag, std::string_view name) {
  std::size_t at = 0;
  while (at < tag.size()) {
    const std::size_t eq = tag.find('=', at);
    if (eq == std::string_view::npos) return {};
    std::size_t keyEnd = eq;
    while (keyEnd > at && isXmlSpace(tag[keyEnd - 1])) --keyEnd;
    std::size_t keyStart = keyEnd;
    while (keyStart > at && !isXmlSpace(tag[keyStart - 1])) {
      --keyStart;
    }
    std::size_t q = eq + 1;
    while (q < tag.size() && isXmlSpace(tag[q])) ++q;
    if (q >= tag.size() || (tag[q] != '"' && tag[q] != '\'')) return {};
    const std::size_t close = tag.find(tag[q], q + 1);
    if (close == std::string_view::npos) return {};
    if (tag.substr(keyStart, keyEnd - keyStart) == name) return tag.substr(q + 1, close - q - 1);
    at = close + 1;
  }
  return {};
}

std::uint64_t number(std::string_view text, std::uint64_t fallback) {
  if (text.empty()) return fallback;
  std::uint64_t value = 0;
  for (char c : text) {
    if (c < '0' || c > '9') return fallback;
    value = std::min<std::uint64_t>(value * 10 + static_cast<std::uint64_t>(c - '0'),
                                    std::uint64_t{1} << 62);
  }
  return value;
}

// Values a Collada transform element holds (0: not a transform).
std::size_t transformValues(std::string_view name) {
  if (name == "translate" || name == "scale") return 3;
  if (name == "rotate") return 4;
  if (name == "skew") return 7;
  if (name == "lookat") return 9;
  if (name == "matrix") return 16;
  return 0;
}

// The one number reader of the Assimp pre-checks: a plain decimal number
// (sign, at most 18 integer digits, one point, an exponent of at most 3
// digits) that is finite,
// the form Assimp's fast_atof reads as strtod does. Hex floats ("0x1p3"),
// "inf" and "nan" are refused: fast_atof reads them otherwise (the class of
// fuzz findings 6, 9, 19 and 26, where a pre-check and the library read
// different numbers). Not mesh_detail::parseNumberToken: that one follows
// OpenMesh's stream reader (from_chars, infinities kept for the caller).
constexpr std::size_t kMaxIntegerDigits = 18;

bool isPlainFiniteNumber(std::string_view token) {
  if (token.empty() || token.size() > 64) return false;
  std::size_t i = 0;
  if (token[i] == '-' || token[i] == '+') ++i;
  bool digits = false;
  const std::size_t integerStart = i;
  while (i < token.size() && std::isdigit(static_cast<unsigned char>(token[i]))) {
    ++i;
    digits = true;
  }
  // fast_atof reads the integer part into 64 bits: Assimp's SMD reader
  // asked for 11 GB on a 32-digit normal component (fuzz finding 39; 21
  // digits did it, 20 not). 18 digits always fit; larger magnitudes take an
  // exponent.
  if (i - integerStart > kMaxIntegerDigits) return false;
  if (i < token.size() && token[i] == '.') {
    ++i;
    while (i < token.size() && std::isdigit(static_cast<unsigned char>(token[i]))) {
      ++i;
      digits = true;
    }
  }
  if (!digits) return false;
  if (i < token.size() && (token[i] == 'e' || token[i] == 'E')) {
    ++i;
    if (i < token.size() && (token[i] == '-' || token[i] == '+')) ++i;
    const std::size_t exponent = i;
    while (i < token.size() && std::isdigit(static_cast<unsigned char>(token[i]))) ++i;
    if (i == exponent || i - exponent > 3) return false;
  }
  if (i != token.size()) return false;
  return std::isfinite(std::strtod(std::string(token).c_str(), nullptr));
}

// The whitespace-separated tokens of an element's text; false when one is
// not a plain finite number.
bool countNumbers(std::string_view text, std::uint64_t* count) {
  *count = 0;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && isXmlSpace(text[i])) ++i;
    if (i >= text.size()) break;
    const std::size_t start = i;
    while (i < text.size() && !isXmlSpace(text[i])) ++i;
    if (!isPlainFiniteNumber(text.substr(start, i - start))) return false;
    ++*count;
  }
  return true;
}

// Calls visit(line, number) for every line of text (split at '\n', the
// '\n' dropped, numbered from 1) until it returns an error.
template <typename Visit>
Status forEachLine(std::string_view text, Visit visit) {
  std::size_t number = 0;
  for (std::size_t at = 0; at < text.size();) {
    std::size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    THINLOD_RETURN_IF_ERROR(visit(text.substr(at, end - at), ++number));
    at = end + 1;
  }
  return Status();
}

// The first control character of `line` (a byte below 0x20 or DEL) that is
// not in `allowed`, or none. A vertical tab or form feed is a separator to
// one reader and text to another (fuzz findings 45 and 50), so the text
// formats handed to Assimp allow only the white space they are written with.
std::optional<unsigned char> controlCharacter(std::string_view line, std::string_view allowed) {
  for (const char c : line) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte < 0x20 || byte == 0x7F) && allowed.find(c) == std::string_view::npos) return byte;
  }
  return std::nullopt;
}

// The instance elements whose url Assimp needs resolved to build geometry.
// (Cameras, lights and effects it skips when their url names nothing: the
// package's cube_emptyTags.dae has such a camera and loads.)
bool isUrlInstance(std::string_view name) {
  return name == "instance_geometry" || name == "instance_node" ||
         name == "instance_controller" || name == "instance_visual_scene";
}

struct InstanceUrl {
  std::string_view element;
  std::string_view url;    // as written: "#id" is the only form read
  std::size_t at;          // byte after the tag
  std::uint32_t enclosing;  // the <node> it sits in, or kNoNode
};

constexpr std::uint32_t kNoNode = 0xffffffffu;

// A primitive's index lists (p, vcount, v, h).
bool isIndexList(std::string_view name) {
  return name == "p" || name == "vcount" || name == "v" || name == "h";
}

// Whitespace-separated decimal integers in [0, 2^31); their number and sum
// are added to *count and *sum.
bool allUnsignedIntegers(std::string_view text, std::uint64_t* count, std::uint64_t* sum) {
  std::size_t digits = 0;
  std::uint64_t value = 0;
  auto finish = [&] {
    if (digits == 0) return;
    ++*count;
    *sum += value;
  };
  for (const char c : text) {
    if (c >= '0' && c <= '9') {
      value = value * 10 + static_cast<std::uint64_t>(c - '0');
      if (++digits > 10 || value >= (std::uint64_t{1} << 31)) return false;
    } else if (isXmlSpace(c)) {
      finish();
      digits = 0;
      value = 0;
    } else {
      return false;
    }
  }
  finish();
  return true;
}

// A primitive element whose declared count Assimp checks with an assert
// (ColladaParser::ReadPrimitives: `actualPrimitives == numPrimitives`; the
// Debian library is built with asserts on, so a mismatch aborted the whole
// process: fuzz finding 44). lines, linestrips, trifans and tristrips are
// exempt there (a SketchUp workaround) and here.
bool isCountedPrimitive(std::string_view name) {
  return name == "triangles" || name == "polylist" || name == "polygons";
}

bool isArrayElement(std::string_view name) {
  return name == "float_array" || name == "int_array" || name == "Name_array" ||
         name == "bool_array" || name == "IDREF_array";
}

}  // namespace

Status precheckCollada(const std::string& path, std::string_view bytes,
                       const ImportLimits& limits) {
  // UTF-16 (a byte-order mark; the package has such a file): the markup is
  // ASCII, so the low bytes alone carry the structure.
  std::string narrowed;
  std::string_view xml = bytes;
  if (bytes.size() >= 2 &&
      (static_cast<unsigned char>(bytes[0]) == 0xFF ||
       static_cast<unsigned char>(bytes[0]) == 0xFE) &&
      (static_cast<unsigned char>(bytes[1]) == 0xFE ||
       static_cast<unsigned char>(bytes[1]) == 0xFF)) {
    const std::size_t low = static_cast<unsigned char>(bytes[0]) == 0xFF ? 0 : 1;  // LE : BE
    narrowed.reserve(bytes.size() / 2);
    for (std::size_t k = 2 + low; k < bytes.size(); k += 2) narrowed.push_back(bytes[k]);
    xml = narrowed;
  }
  const std::size_t maxXmlDepth = static_cast<std::size_t>(std::max(limits.maxDepth, 0)) + 64;
  struct Open {
    std::string_view name;
    std::uint32_t node;  // index of the enclosing <node> (this one if a node), or kNoNode
  };
  std::vector<Open> open;
  bool sawRoot = false;  // the document element has been opened
  std::vector<std::vector<std::uint32_t>> children;
  std::vector<std::uint32_t> roots;
  std::map<std::string_view, std::uint32_t> nodeById;
  std::set<std::string_view> ids;            // every element's id
  std::vector<InstanceUrl> instanceUrls;     // instance_* elements and their urls
  std::set<std::string_view> visualScenes;   // ids of <visual_scene>
  std::set<std::string_view> libraryKeys;    // ids of library nodes and visual scenes
  std::map<std::string_view, std::uint64_t> arrayCount;
  struct Accessor {
    std::string_view source;
    std::uint64_t count, stride;
  };
  std::vector<Accessor> accessors;
  // The counted primitive being read (isCountedPrimitive): its declared
  // count, its inputs' offsets (Assimp's numOffsets: the largest + 1) and
  // what its index lists hold.
  struct Primitive {
    std::string_view name;
    std::size_t depth = 0;  // open.size() inside it
    std::uint64_t count = 0;
    std::uint64_t offsets = 1;
    std::uint64_t indices = 0;  // in its <p> lists
    std::uint64_t lists = 0;    // <p> lists
    std::uint64_t vcountEntries = 0;
    std::uint64_t vcountSum = 0;
    bool holes = false;  // a polygons' <ph>: not checked
    std::size_t at = 0;
  };
  std::optional<Primitive> primitive;
  auto checkPrimitive = [&](const Primitive& p) {
    if (p.offsets > (std::uint64_t{1} << 16)) {
      return Status(ErrorCode::kParseError, path + ": <" + std::string(p.name) + "> at byte " +
                                                std::to_string(p.at) + ": an input offset of " +
                                                std::to_string(p.offsets - 1));
    }
    if (p.holes) return Status();
    // Division, not products: the declared numbers are the file's.
    std::uint64_t actual = 0;
    bool whole = true;  // the index lists hold whole primitives, nothing over
    if (p.name == "triangles") {
      actual = p.indices / (3 * p.offsets);
      whole = p.indices % (3 * p.offsets) == 0;
    } else if (p.name == "polylist") {
      actual = p.vcountEntries;
      whole = p.indices % p.offsets == 0 && p.indices / p.offsets == p.vcountSum;
    } else {
      actual = p.lists;
    }
    if (actual != p.count || !whole) {
      return Status(ErrorCode::kParseError,
                    path + ": <" + std::string(p.name) + "> at byte " + std::to_string(p.at) +
                        " declares count " + std::to_string(p.count) + " but its index lists hold " +
                        std::to_string(p.indices) + " indices for " + std::to_string(actual) +
                        " primitives of " + std::to_string(p.offsets) + " inputs each");
    }
    return Status();
  };
  auto unterminated = [&](const char* what, std::size_t at) {
    return Status(ErrorCode::kParseError, path + ": unterminated " + std::string(what) +
                                              " at byte " + std::to_string(at) +
                                              " (truncated or not XML)");
  };
  for (std::size_t i = xml.find('<'); i != std::string_view::npos; i = xml.find('<', i)) {
    const std::string_view rest = xml.substr(i);
    if (rest.rfind("<!--", 0) == 0) {
      const std::size_t end = xml.find("-->", i + 4);
      if (end == std::string_view::npos) return unterminated("comment", i);
      i = end + 3;
      continue;
    }
    if (rest.rfind("<![CDATA[", 0) == 0) {
      const std::size_t end = xml.find("]]>", i + 9);
      if (end == std::string_view::npos) return unterminated("CDATA section", i);
      i = end + 3;
      continue;
    }
    if (rest.rfind("<?", 0) == 0 || rest.rfind("<!", 0) == 0) {
      const std::size_t end = xml.find('>', i + 2);
      if (end == std::string_view::npos) return unterminated("declaration", i);
      i = end + 1;
      continue;
    }
    // A tag: up to the first '>' outside quotes.
    std::size_t end = i + 1;
    char quote = 0;
    for (; end < xml.size(); ++end) {
      const char c = xml[end];
      if (quote != 0) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '>') {
        break;
      }
    }
    if (end >= xml.size()) return unterminated("tag", i);
    const bool closing = xml[i + 1] == '/';
    const bool selfClosing = !closing && xml[end - 1] == '/';
    std::string_view tag =
        xml.substr(i + (closing ? 2 : 1), end - i - (closing ? 2 : 1) - (selfClosing ? 1 : 0));
    std::size_t nameEnd = 0;
    while (nameEnd < tag.size() && !isXmlSpace(tag[nameEnd])) {
      ++nameEnd;
    }
    const std::string_view name = tag.substr(0, nameEnd);
    const std::string_view attributes = tag.substr(nameEnd);
    i = end + 1;
    if (closing) {
      if (open.empty() || open.back().name != name) {
        return Status(ErrorCode::kParseError, path + ": mismatched closing tag </" +
                                                  std::string(name) + "> at byte " +
                                                  std::to_string(i));
      }
      open.pop_back();
      if (primitive && primitive->name == name && primitive->depth == open.size() + 1) {
        THINLOD_RETURN_IF_ERROR(checkPrimitive(*primitive));
        primitive.reset();
      }
      continue;
    }
    // One document element: Assimp reads the first and stops, while this
    // scan went on into a second one and resolved the first's urls against
    // it (fuzz finding 38: a second <COLLADA> after the first made "#scene"
    // look defined; Assimp threw on the first and leaked).
    if (open.empty()) {
      if (sawRoot) {
        return Status(ErrorCode::kParseError, path + ": a second document element <" +
                                                  std::string(name.substr(0, 64)) +
                                                  "> at byte " + std::to_string(i) +
                                                  " (XML has one)");
      }
      sawRoot = true;
    }
    const std::uint32_t enclosing = open.empty() ? kNoNode : open.back().node;
    std::uint32_t self = enclosing;
    // Counts, strides and offsets are unsigned integers. number() took "3x"
    // for absent (its fallback) while Assimp read 3: an accessor of 3 over
    // an array without a count passed here and Assimp read 9 values of an
    // empty array (a null read; fuzz finding 51).
    for (const char* key : {"count", "stride", "offset"}) {
      const std::string_view value = attribute(attributes, key);
      if (!value.empty() && value.find_first_not_of("0123456789") != std::string_view::npos) {
        return Status(ErrorCode::kParseError, path + ": <" + std::string(name) + "> at byte " +
                                                  std::to_string(i) + ": " + key + " \"" +
                                                  std::string(value.substr(0, 32)) +
                                                  "\" is not an unsigned integer");
      }
    }
    // Assimp keeps library_nodes' top nodes and the visual scenes in one
    // map by id (no id: the empty one), and a second entry with a key
    // already there leaks the first (fuzz finding 49).
    if (name == "visual_scene" ||
        (name == "node" && !open.empty() && open.back().name == "library_nodes")) {
      const std::string_view key = attribute(attributes, "id");
      if (!libraryKeys.insert(key).second) {
        return Status(ErrorCode::kParseError,
                      path + ": <" + std::string(name) + "> at byte " + std::to_string(i) +
                          (key.empty() ? std::string(" without an id")
                                       : " with id \"" + std::string(key.substr(0, 64)) + "\"") +
                          ": a second library node or visual scene with that id");
      }
    }
    if (name == "node") {
      self = static_cast<std::uint32_t>(children.size());
      children.emplace_back();
      if (enclosing != kNoNode) {
        children[enclosing].push_back(self);
      } else if (!open.empty() && open.back().name == "visual_scene") {
        roots.push_back(self);
      }
      const std::string_view id = attribute(attributes, "id");
      if (!id.empty()) nodeById.emplace(id, self);
      if (children.size() > limits.maxNodes) {
        return Status(ErrorCode::kResourceExhausted,
                      path + ": more than " + std::to_string(limits.maxNodes) + " nodes");
      }
    }
    if (const std::string_view id = attribute(attributes, "id"); !id.empty()) ids.insert(id);
    if (name == "visual_scene") visualScenes.insert(attribute(attributes, "id"));
    if (isUrlInstance(name)) {
      instanceUrls.push_back({name, attribute(attributes, "url"), i, enclosing});
    } else if (const std::size_t wanted = transformValues(name); wanted > 0) {
      // Assimp's Collada reader threw on a transform with too few values
      // and leaked the nodes it had built (fuzz finding 31).
      const std::size_t textEnd = selfClosing ? i : std::min(xml.find('<', i), xml.size());
      std::uint64_t values = 0;
      if (!countNumbers(xml.substr(i, textEnd - i), &values) || values != wanted) {
        return Status(ErrorCode::kParseError,
                      path + ": <" + std::string(name) + "> at byte " + std::to_string(i) +
                          " must hold " + std::to_string(wanted) + " finite numbers");
      }
    } else if (isIndexList(name) && !selfClosing) {
      // Assimp read a primitive's index list "<p>, 1 2</p>" as indices in
      // the billions and asked for 3 GB (fuzz finding 35): index lists hold
      // unsigned integers only.
      const std::size_t textEnd = std::min(xml.find('<', i), xml.size());
      std::uint64_t values = 0;
      std::uint64_t sum = 0;
      const bool inPrimitive = primitive && open.size() == primitive->depth;
      if (!allUnsignedIntegers(xml.substr(i, textEnd - i), &values, &sum)) {
        return Status(ErrorCode::kParseError,
                      path + ": <" + std::string(name) + "> at byte " + std::to_string(i) +
                          " must hold unsigned integers (indices below 2^31) only");
      }
      if (inPrimitive && name == "p") {
        primitive->indices += values;
        ++primitive->lists;
      } else if (inPrimitive && name == "vcount") {
        primitive->vcountEntries += values;
        primitive->vcountSum += sum;
      }
    } else if (isArrayElement(name)) {
      // Two data arrays with one id: the accessor check took the second's
      // count while Assimp read the first, past its end (fuzz finding 44's
      // input; ids are unique in XML).
      const std::string_view id = attribute(attributes, "id");
      if (!id.empty() && !arrayCount.emplace(id, number(attribute(attributes, "count"), 0)).second) {
        return Status(ErrorCode::kParseError, path + ": a second data array with id \"" +
                                                  std::string(id.substr(0, 64)) + "\" at byte " +
                                                  std::to_string(i));
      }
    } else if (name == "accessor") {
      std::string_view source = attribute(attributes, "source");
      if (!source.empty() && source.front() == '#') source.remove_prefix(1);
      accessors.push_back({source, number(attribute(attributes, "count"), 0),
                           number(attribute(attributes, "stride"), 1)});
    }
    if (isCountedPrimitive(name) && !primitive) {
      Primitive p;
      p.name = name;
      p.depth = open.size() + 1;
      p.count = number(attribute(attributes, "count"), 0);
      p.at = i;
      if (selfClosing) {
        THINLOD_RETURN_IF_ERROR(checkPrimitive(p));
      } else {
        primitive = p;
      }
    } else if (name == "input" && primitive && open.size() == primitive->depth) {
      const std::string_view offset = attribute(attributes, "offset");
      if (!offset.empty()) {
        primitive->offsets = std::max(primitive->offsets, number(offset, 0) + 1);
      }
    } else if (name == "ph" && primitive && open.size() == primitive->depth) {
      primitive->holes = true;
    }
    if (selfClosing) continue;
    open.push_back({name, self});
    if (open.size() > maxXmlDepth) {
      return Status(ErrorCode::kResourceExhausted,
                    path + ": XML elements nested deeper than " + std::to_string(maxXmlDepth));
    }
  }
  if (!open.empty()) {
    return Status(ErrorCode::kParseError, path + ": truncated: <" + std::string(open.back().name) +
                                              "> and " + std::to_string(open.size() - 1) +
                                              " enclosing elements are never closed");
  }
  for (const Accessor& a : accessors) {
    const auto array = arrayCount.find(a.source);
    if (array == arrayCount.end()) continue;  // another source kind: Assimp judges
    if (a.stride == 0 || a.count > array->second / a.stride) {
      return Status(ErrorCode::kParseError,
                    path + ": an accessor of " + std::to_string(a.count) + " x " +
                        std::to_string(a.stride) + " values reads past its array '" +
                        std::string(a.source) + "' of " + std::to_string(array->second));
    }
  }
  // Assimp's Collada reader leaked what it had built when an instance's url
  // was missing (fuzz finding 33) or named nothing in the file (29, the
  // shown scene's): every instance must name an element of the file, the
  // shown scene a visual scene. instance_node adds its target to the
  // enclosing node's children for the graph check.
  for (const InstanceUrl& instance : instanceUrls) {
    const std::string_view target = instance.url.substr(std::min<std::size_t>(1, instance.url.size()));
    if (instance.url.size() < 2 || instance.url.front() != '#' || ids.count(target) == 0) {
      return Status(ErrorCode::kParseError,
                    path + ": <" + std::string(instance.element) + "> at byte " +
                        std::to_string(instance.at) + " has a url \"" +
                        std::string(instance.url.substr(0, 64)) +
                        "\" that names no element of the file (only \"#id\" urls are read)");
    }
    if (instance.element == "instance_visual_scene" && visualScenes.count(target) == 0) {
      return Status(ErrorCode::kParseError,
                    path + ": <instance_visual_scene url=\"#" + std::string(target.substr(0, 64)) +
                        "\"> names no <visual_scene> of the file");
    }
    if (instance.element == "instance_node" && instance.enclosing != kNoNode) {
      const auto found = nodeById.find(target);
      if (found != nodeById.end()) children[instance.enclosing].push_back(found->second);
    }
  }
  return checkNodeGraph(path, children, roots, limits);
}


namespace {

// One SMD line split into tokens: whitespace separated, a double-quoted
// token (a node name) kept whole without its quotes; false when a quote is
// not closed on the line.
bool smdTokens(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i >= line.size()) break;
    if (line[i] == '"') {
      const std::size_t close = line.find('"', i + 1);
      if (close == std::string_view::npos) return false;
      tokens.push_back(line.substr(i + 1, close - i - 1));
      i = close + 1;
      continue;
    }
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    tokens.push_back(line.substr(start, i - start));
  }
  return true;
}

bool smdInteger(std::string_view token, long lo, long hi, long* out = nullptr) {
  if (token.empty() || token.size() > 11) return false;
  std::size_t i = token[0] == '-' ? 1 : 0;
  if (i == token.size()) return false;
  for (std::size_t k = i; k < token.size(); ++k) {
    if (!std::isdigit(static_cast<unsigned char>(token[k]))) return false;
  }
  const long value = std::strtol(std::string(token).c_str(), nullptr, 10);
  if (value < lo || value > hi) return false;
  if (out != nullptr) *out = value;
  return true;
}


}  // namespace

Status precheckSmd(const std::string& path, std::string_view bytes) {
  enum class Section { kNone, kNodes, kSkeleton, kTriangles, kVertexAnimation };
  Section section = Section::kNone;
  bool sawVersion = false;
  long nodes = 0;
  int triangleLine = 0;  // 0: the material line next, 1-3: a vertex line
  std::vector<std::string_view> tokens;
  THINLOD_RETURN_IF_ERROR(forEachLine(bytes, [&](std::string_view line, std::size_t lineNumber) {
    auto refuse = [&](const std::string& why) {
      return Status(ErrorCode::kParseError,
                    path + ": SMD line " + std::to_string(lineNumber) + ": " + why);
    };
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    // No control character but the tab (a NUL, a lone carriage return, ...):
    // a form feed before a triangle's material name was text to this scan
    // and white space or a separator to Assimp's reader, which then read the
    // lines after it out of step and asked for 1.6 GB (fuzz finding 45).
    if (const std::optional<unsigned char> byte = controlCharacter(line, "\t")) {
      return refuse("a control character (byte " + std::to_string(*byte) + ")");
    }
    const std::size_t comment = line.find("//");
    if (comment != std::string_view::npos) line = line.substr(0, comment);
    if (!smdTokens(line, tokens)) return refuse("a quote is not closed");
    if (tokens.empty()) {
      // Assimp's reader loops for good on a line of only spaces or tabs in
      // the nodes section (fuzz finding 46; an empty line, or one starting
      // with a comment, is fine there; `line` is cut at its comment).
      if (section == Section::kNodes && !line.empty()) {
        return refuse("a line of only white space in the nodes section");
      }
      return Status();
    }
    if (!sawVersion) {
      if (tokens.size() != 2 || tokens[0] != "version" || tokens[1] != "1") {
        return refuse("the file must start with 'version 1'");
      }
      sawVersion = true;
      return Status();
    }
    if (section == Section::kNone) {
      if (tokens.size() != 1) return refuse("a section name (nodes, skeleton, triangles) expected");
      if (tokens[0] == "nodes") {
        section = Section::kNodes;
      } else if (tokens[0] == "skeleton") {
        section = Section::kSkeleton;
      } else if (tokens[0] == "triangles") {
        section = Section::kTriangles;
        triangleLine = 0;
      } else if (tokens[0] == "vertexanimation") {
        section = Section::kVertexAnimation;
      } else {
        return refuse("unknown section");
      }
      if (section != Section::kNodes && nodes == 0) return refuse("a section before the nodes");
      return Status();
    }
    // Assimp's reader takes a nodes section's "end" only at the first byte
    // of its line and loops for good on one after white space (fuzz finding
    // 47, beside 46's blank line).
    if (section == Section::kNodes && tokens[0] == "end" && line.front() != 'e') {
      return refuse("'end' of the nodes section must start its line");
    }
    if (tokens.size() == 1 && tokens[0] == "end" &&
        !(section == Section::kTriangles && triangleLine != 0)) {
      if (section == Section::kNodes && nodes == 0) return refuse("no nodes");
      section = Section::kNone;
      return Status();
    }
    switch (section) {
      case Section::kNodes: {
        long id = 0;
        long parent = 0;
        if (tokens.size() != 3 || !smdInteger(tokens[0], 0, 65535, &id) || id != nodes ||
            !smdInteger(tokens[2], -1, 65535, &parent) || parent >= id) {
          return refuse("a node is 'id \"name\" parent', ids 0, 1, 2, ... and parents before them");
        }
        ++nodes;
        break;
      }
      case Section::kSkeleton:
      case Section::kVertexAnimation: {
        if (tokens[0] == "time") {
          if (tokens.size() != 2 || !smdInteger(tokens[1], 0, 1000000)) {
            return refuse("'time' takes one frame number");
          }
          break;
        }
        const long limit = section == Section::kSkeleton ? nodes - 1 : 10000000;
        if (tokens.size() != 7 || !smdInteger(tokens[0], 0, limit)) {
          return refuse("a key is 'bone x y z rx ry rz' with a known bone");
        }
        for (std::size_t k = 1; k < tokens.size(); ++k) {
          if (!isPlainFiniteNumber(tokens[k])) return refuse("not a finite number");
        }
        break;
      }
      case Section::kTriangles: {
        if (triangleLine == 0) {  // the material: any text
          triangleLine = 1;
          break;
        }
        long links = 0;
        const bool shaped =
            tokens.size() >= 9 && smdInteger(tokens[0], 0, nodes - 1) &&
            (tokens.size() == 9 ||
             (smdInteger(tokens[9], 0, 64, &links) &&
              tokens.size() == 10 + 2 * static_cast<std::size_t>(links)));
        if (!shaped) {
          return refuse(
              "a vertex is 'bone x y z nx ny nz u v [links (bone weight)...]' with known bones");
        }
        for (std::size_t k = 1; k < 9; ++k) {
          if (!isPlainFiniteNumber(tokens[k])) return refuse("not a finite number");
        }
        for (long l = 0; l < links; ++l) {
          const std::size_t at = 10 + 2 * static_cast<std::size_t>(l);
          if (!smdInteger(tokens[at], 0, nodes - 1) || !isPlainFiniteNumber(tokens[at + 1])) {
            return refuse("a link is 'bone weight' with a known bone");
          }
        }
        triangleLine = triangleLine == 3 ? 0 : triangleLine + 1;
        break;
      }
      case Section::kNone:
        break;
    }
    return Status();
  }));
  if (!sawVersion) return Status(ErrorCode::kParseError, path + ": SMD: no 'version 1' line");
  if (section != Section::kNone) {
    return Status(ErrorCode::kParseError,
                  path + ": SMD: a section is not closed by 'end' (the file is truncated)");
  }
  return Status();
}

namespace {

// The token kinds of Assimp's FBX ASCII tokenizer.
enum class FbxToken : std::uint8_t { kOpen, kClose, kData, kComma, kKey };

struct FbxTok {
  FbxToken type;
  std::size_t line;
};

bool fbxLineEnd(char c) { return c == '\r' || c == '\n' || c == '\0' || c == '\f'; }
bool fbxSpaceOrNewLine(char c) { return c == ' ' || c == '\t' || fbxLineEnd(c); }

// Assimp's parser over the tokens (Scope / Element), without building
// anything: returns the first error it would throw, or an empty string.
class FbxGrammar {
 public:
  FbxGrammar(const std::vector<FbxTok>& tokens, std::size_t maxDepth)
      : tokens_(tokens), maxDepth_(maxDepth) {}

  std::string parse() { return scope(true, 0); }

 private:
  const FbxTok* advance() {
    current_ = next_ < tokens_.size() ? &tokens_[next_++] : nullptr;
    return current_;
  }

  std::string scope(bool topLevel, std::size_t depth) {
    if (depth > maxDepth_) return "scopes nested deeper than " + std::to_string(maxDepth_);
    const FbxTok* n = advance();
    if (n == nullptr) return "unexpected end of file";
    while (n->type != FbxToken::kClose) {
      if (n->type != FbxToken::kKey) return "unexpected token, expected a key";
      if (std::string error = element(depth); !error.empty()) return error;
      n = current_;
      if (n == nullptr) return topLevel ? std::string() : "unexpected end of file";
    }
    return std::string();
  }

  std::string element(std::size_t depth) {
    const FbxTok* n = nullptr;
    do {
      n = advance();
      if (n == nullptr) return "unexpected end of file, expected a closing bracket";
      if (n->type == FbxToken::kData) {
        const FbxTok* previous = n;
        n = advance();
        if (n == nullptr) return "unexpected end of file, expected a bracket, comma or key";
        // Assimp accepts a missing comma before data on the next line.
        if (n->type == FbxToken::kData && n->line == previous->line + 1) continue;
        if (n->type == FbxToken::kData) return "unexpected token; expected a bracket, comma or key";
      }
      if (n->type == FbxToken::kOpen) {
        if (std::string error = scope(false, depth + 1); !error.empty()) return error;
        advance();  // past the closing bracket the scope ended on
        return std::string();
      }
    } while (n->type != FbxToken::kKey && n->type != FbxToken::kClose);
    return std::string();
  }

  const std::vector<FbxTok>& tokens_;
  std::size_t maxDepth_;
  std::size_t next_ = 0;
  const FbxTok* current_ = nullptr;
};

}  // namespace

Status precheckFbx(const std::string& path, std::string_view bytes, const ImportLimits& limits) {
  if (bytes.substr(0, 18) == "Kaydara FBX Binary") return Status();
  auto refuse = [&path](std::size_t line, const std::string& why) {
    return Status(ErrorCode::kParseError,
                  path + ": FBX line " + std::to_string(line) + ": " + why);
  };
  if (bytes.find('\0') != std::string_view::npos) return refuse(1, "a NUL byte");
  // The tokenizer, as Assimp's (its peek for a key after whitespace never
  // matches, so a token before spaces and a colon is data; a token left
  // unterminated at the end of the file is dropped; '\r' and '\n' each
  // count a line).
  std::vector<FbxTok> tokens;
  std::size_t line = 1;
  bool comment = false;
  bool inQuotes = false;
  bool pending = false;
  bool hasBegin = false;  // a token has started (Assimp: token_begin != nullptr)
  std::size_t begin = 0;
  std::size_t end = 0;
  auto dataToken = [&](FbxToken type, bool mustHaveToken) -> std::string {
    if (hasBegin) {
      bool quoted = false;
      for (std::size_t k = begin; k <= end; ++k) {
        if (bytes[k] == '"') quoted = !quoted;
        if (!quoted && fbxSpaceOrNewLine(bytes[k])) return "unexpected whitespace in a token";
      }
      if (quoted) return "a double quote is not closed";
      tokens.push_back({type, line});
    } else if (mustHaveToken) {
      return "unexpected character, expected a data token";
    }
    hasBegin = false;
    return std::string();
  };
  for (std::size_t at = 0; at < bytes.size(); ++at) {
    const char c = bytes[at];
    if (fbxLineEnd(c)) {
      comment = false;
      ++line;
    }
    if (comment) continue;
    std::string error;
    if (inQuotes) {
      if (c == '"') {
        inQuotes = false;
        end = at;
        error = dataToken(FbxToken::kData, false);
        pending = false;
      }
      if (!error.empty()) return refuse(line, error);
      continue;
    }
    bool handled = true;
    switch (c) {
      case '"':
        if (hasBegin) return refuse(line, "unexpected double quote");
        hasBegin = true;
        begin = at;
        inQuotes = true;
        break;
      case ';':
        error = dataToken(FbxToken::kData, false);
        comment = true;
        break;
      case '{':
      case '}':
        error = dataToken(FbxToken::kData, false);
        tokens.push_back({c == '{' ? FbxToken::kOpen : FbxToken::kClose, line});
        break;
      case ',':
        if (pending) error = dataToken(FbxToken::kData, true);
        tokens.push_back({FbxToken::kComma, line});
        break;
      case ':':
        if (!pending) return refuse(line, "unexpected colon");
        error = dataToken(FbxToken::kKey, true);
        break;
      default:
        handled = false;
    }
    if (!error.empty()) return refuse(line, error);
    if (handled) continue;
    if (fbxSpaceOrNewLine(c)) {
      if (hasBegin) error = dataToken(FbxToken::kData, false);
      if (!error.empty()) return refuse(line, error);
      pending = false;
    } else {
      end = at;
      if (!hasBegin) {
        hasBegin = true;
        begin = at;
      }
      pending = true;
    }
  }
  const std::size_t maxDepth = static_cast<std::size_t>(std::max(limits.maxDepth, 0)) + 64;
  FbxGrammar grammar(tokens, maxDepth);
  if (std::string error = grammar.parse(); !error.empty()) {
    return Status(ErrorCode::kParseError, path + ": FBX: " + error);
  }
  return Status();
}

Status checkObjStatementsForAssimp(const std::string& path, std::string_view text) {
  if (text.find('\0') != std::string_view::npos) {
    return Status(ErrorCode::kParseError, path + ": a NUL byte in an OBJ file");
  }
  static const std::set<std::string_view> kStatements = {"v", "vt", "vn", "f", "o", "g", "s",
                                                         "mtllib", "usemtl"};
  return forEachLine(text, [&](std::string_view line, std::size_t number) {
    // A vertical tab or form feed is a separator to one reader and text to
    // the other: "v 1 6 \v3" was three values here and fewer there, so a
    // later face named a vertex Assimp had not read and it leaked (fuzz
    // finding 50; SMD's finding 45 was the same). No control character but
    // the tab and the carriage return, comments included.
    if (const std::optional<unsigned char> byte = controlCharacter(line, "\t\r")) {
      return Status(ErrorCode::kParseError, path + ":" + std::to_string(number) +
                                                ": a control character (byte " +
                                                std::to_string(*byte) + ") in an OBJ line");
    }
    // Assimp joins a line that ends in a backslash (before the newline or a
    // carriage return) with the next one, so "# note\" swallowed the vertex
    // on the next line there and not here: the faces then named vertices it
    // had not read and it leaked (fuzz finding 52). Comments included.
    if (line.find("\\\r") != std::string_view::npos || (!line.empty() && line.back() == '\\')) {
      return Status(ErrorCode::kParseError,
                    path + ":" + std::to_string(number) +
                        ": an OBJ line continued by a backslash (Assimp joins it with the next)");
    }
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string_view::npos || line[first] == '#') return Status();
    const std::size_t tokenEnd = line.find_first_of(" \t\r", first);
    const std::string_view statement = line.substr(
        first, tokenEnd == std::string_view::npos ? std::string_view::npos : tokenEnd - first);
    if (kStatements.count(statement) == 0) {
      return Status(ErrorCode::kParseError,
                    path + ":" + std::to_string(number) + ": OBJ statement '" +
                        std::string(statement.substr(0, 32)) +
                        "' is not read (v vt vn f o g s mtllib usemtl only)");
    }
    // Assimp skips a line that does not start with its statement, so an
    // indented "v" is no vertex there (and the faces after it name others;
    // a face past the vertices it read made it throw and leak the meshes of
    // earlier materials: fuzz finding 48). Our reader would take it.
    if (first > 0) {
      return Status(ErrorCode::kParseError,
                    path + ":" + std::to_string(number) + ": OBJ statement '" +
                        std::string(statement.substr(0, 32)) +
                        "' indented (Assimp skips a line that does not start with its statement)");
    }
    // Assimp reads a vertex of 3, 4 (x y z w) or 6 (x y z r g b) numbers and
    // skips one of any other count without an error, so every later face
    // named other vertices there than here; a face past its vertices then
    // made it throw and leak the meshes it had built (fuzz finding 43: a
    // 5-number vertex). Texture coordinates have 2 or 3 numbers there,
    // normals 3.
    if (statement == "v" || statement == "vt" || statement == "vn") {
      std::string_view rest = tokenEnd == std::string_view::npos ? std::string_view()
                                                                   : line.substr(tokenEnd);
      rest = rest.substr(0, rest.find('#'));
      std::size_t values = 0;
      for (std::size_t i = 0; i < rest.size();) {
        i = rest.find_first_not_of(" \t\r", i);
        if (i == std::string_view::npos) break;
        ++values;
        i = rest.find_first_of(" \t\r", i);
        if (i == std::string_view::npos) break;
      }
      const bool read = statement == "v"    ? values == 3 || values == 4 || values == 6
                        : statement == "vt" ? values == 2 || values == 3
                                            : values == 3;
      if (!read) {
        return Status(ErrorCode::kParseError,
                      path + ":" + std::to_string(number) + ": OBJ '" + std::string(statement) +
                          "' with " + std::to_string(values) + " values (Assimp reads " +
                          (statement == "v" ? "3, 4 or 6" : statement == "vt" ? "2 or 3" : "3") +
                          ")");
      }
    }
    return Status();
  });
}

bool isPlainBase64(std::string_view text) {
  if (text.size() % 4 != 0) return false;
  std::size_t padding = 0;
  while (padding < 2 && padding < text.size() && text[text.size() - 1 - padding] == '=') ++padding;
  for (std::size_t i = 0; i + padding < text.size(); ++i) {
    const char c = text[i];
    const bool alphabet = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') ||
                          (c >= '0' && c <= '9') || c == '+' || c == '/';
    if (!alphabet) return false;
  }
  return true;
}

}  // namespace thinlod::scene::detail
