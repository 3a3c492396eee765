#include "import_precheck.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <map>
#include <utility>

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

// Value of attribute `name` in a start tag's text (after the element name),
// empty when absent.
std::string_view attribute(std::string_view tag, std::string_view name) {
  std::size_t at = 0;
  while (at < tag.size()) {
    const std::size_t eq = tag.find('=', at);
    if (eq == std::string_view::npos) return {};
    std::size_t keyEnd = eq;
    while (keyEnd > at && std::isspace(static_cast<unsigned char>(tag[keyEnd - 1]))) --keyEnd;
    std::size_t keyStart = keyEnd;
    while (keyStart > at && !std::isspace(static_cast<unsigned char>(tag[keyStart - 1]))) {
      --keyStart;
    }
    std::size_t q = eq + 1;
    while (q < tag.size() && std::isspace(static_cast<unsigned char>(tag[q]))) ++q;
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
  constexpr std::uint32_t kNoNode = 0xffffffffu;
  std::vector<Open> open;
  std::vector<std::vector<std::uint32_t>> children;
  std::vector<std::uint32_t> roots;
  std::map<std::string_view, std::uint32_t> nodeById;
  std::vector<std::pair<std::uint32_t, std::string_view>> instances;  // node, target id
  std::map<std::string_view, std::uint64_t> arrayCount;
  struct Accessor {
    std::string_view source;
    std::uint64_t count, stride;
  };
  std::vector<Accessor> accessors;
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
    while (nameEnd < tag.size() && !std::isspace(static_cast<unsigned char>(tag[nameEnd]))) {
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
      continue;
    }
    const std::uint32_t enclosing = open.empty() ? kNoNode : open.back().node;
    std::uint32_t self = enclosing;
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
    } else if (name == "instance_node" && enclosing != kNoNode) {
      std::string_view url = attribute(attributes, "url");
      if (!url.empty() && url.front() == '#') url.remove_prefix(1);
      instances.push_back({enclosing, url});
    } else if (isArrayElement(name)) {
      const std::string_view id = attribute(attributes, "id");
      if (!id.empty()) arrayCount[id] = number(attribute(attributes, "count"), 0);
    } else if (name == "accessor") {
      std::string_view source = attribute(attributes, "source");
      if (!source.empty() && source.front() == '#') source.remove_prefix(1);
      accessors.push_back({source, number(attribute(attributes, "count"), 0),
                           number(attribute(attributes, "stride"), 1)});
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
  for (const auto& [node, target] : instances) {
    const auto found = nodeById.find(target);
    if (found != nodeById.end()) children[node].push_back(found->second);
  }
  return checkNodeGraph(path, children, roots, limits);
}

}  // namespace thinlod::scene::detail
