// Recursive-descent parser for the VRML97 subset of docs/scene-format.md.
// Pure: text in, Scene out. Errors carry "<source>:<line>:<column>".
#include "thinlod/common/scene/scene_parser.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <optional>
#include <unordered_map>

namespace thinlod::scene {
namespace {

constexpr float kPi = 3.14159265358979f;

enum class TokenKind { kWord, kString, kLBrace, kRBrace, kLBracket, kRBracket, kEnd };

struct Token {
  TokenKind kind = TokenKind::kEnd;
  std::string_view text;  // kWord: the word; kString: raw (escapes unresolved)
  int line = 1;
  int column = 1;
};

const char* describe(TokenKind kind) {
  switch (kind) {
    case TokenKind::kWord:
      return "a word";
    case TokenKind::kString:
      return "a string";
    case TokenKind::kLBrace:
      return "'{'";
    case TokenKind::kRBrace:
      return "'}'";
    case TokenKind::kLBracket:
      return "'['";
    case TokenKind::kRBracket:
      return "']'";
    case TokenKind::kEnd:
      return "end of file";
  }
  return "?";
}

// What a DEF name stands for: scene-graph nodes are shared, value nodes
// (Appearance, Material, geometry, Coordinate, ConicRange) are copied on USE.
enum class DefKind {
  kSceneNode,
  kAppearance,
  kMaterial,
  kGeometry,
  kCoordinate,
  kConicRange,
  kImageTexture,
  kTextureCoordinate
};

const char* describe(DefKind kind) {
  switch (kind) {
    case DefKind::kSceneNode:
      return "a scene-graph node";
    case DefKind::kAppearance:
      return "an Appearance";
    case DefKind::kMaterial:
      return "a Material";
    case DefKind::kGeometry:
      return "a geometry node";
    case DefKind::kCoordinate:
      return "a Coordinate";
    case DefKind::kConicRange:
      return "a ConicRange";
    case DefKind::kImageTexture:
      return "an ImageTexture";
    case DefKind::kTextureCoordinate:
      return "a TextureCoordinate";
  }
  return "?";
}

struct DefEntry {
  DefKind kind = DefKind::kSceneNode;
  NodePtr node;
  Appearance appearance;
  Material material;
  Geometry geometry;
  std::vector<glm::vec3> points;
  ConicRange range;
  std::vector<std::string> textureUrls;   // kImageTexture
  std::vector<glm::vec2> texturePoints;   // kTextureCoordinate
};

class Parser {
 public:
  Parser(std::string_view text, const std::string& source, const ParseLimits& limits)
      : text_(text), source_(source), limits_(limits) {}

  Result<Scene> run() {
    if (text_.size() > limits_.maxBytes) {
      return Status(ErrorCode::kResourceExhausted,
                    source_ + ":1:1: file has " + std::to_string(text_.size()) + " bytes, limit " +
                        std::to_string(limits_.maxBytes));
    }
    // A UTF-8 byte-order mark is not part of the header.
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") text_.remove_prefix(3);
    if (!parseHeader()) return status_;
    advance();
    while (tok_.kind != TokenKind::kEnd) {
      NodePtr node;
      if (!parseChildStatement(&node)) return status_;
      if (node) scene_.roots.push_back(std::move(node));
    }
    if (!checkInstanceCount()) return status_;
    scene_.sourceName = source_;
    scene_.nodeCount = nextId_ - 1;
    return std::move(scene_);
  }

 private:
  // ------------------------------------------------------------ errors

  bool fail(ErrorCode code, int line, int column, const std::string& problem) {
    status_ = Status(
        code, source_ + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + problem);
    return false;
  }
  bool fail(const Token& at, const std::string& problem) {
    return fail(ErrorCode::kParseError, at.line, at.column, problem);
  }
  bool failLimit(const Token& at, const std::string& problem) {
    return fail(ErrorCode::kResourceExhausted, at.line, at.column, problem);
  }
  static std::string quoted(std::string_view s) {
    constexpr std::size_t kMax = 40;
    std::string out(s.substr(0, kMax));
    if (s.size() > kMax) out += "...";
    return "'" + out + "'";
  }
  bool unexpected(const std::string& expected) {
    if (tok_.kind == TokenKind::kEnd) {
      return fail(tok_, "unexpected end of file, expected " + expected);
    }
    const std::string found =
        tok_.kind == TokenKind::kWord ? quoted(tok_.text) : std::string(describe(tok_.kind));
    return fail(tok_, "expected " + expected + ", found " + found);
  }

  // ------------------------------------------------------------ lexer

  bool parseHeader() {
    std::size_t end = text_.find('\n');
    std::string_view first = text_.substr(0, end);
    if (!first.empty() && first.back() == '\r') first.remove_suffix(1);
    auto startsWith = [&](std::string_view p) { return first.substr(0, p.size()) == p; };
    if (startsWith("#VRML V2.0 utf8")) {
      scene_.header = "VRML V2.0 utf8";
    } else if (startsWith("#VRML ")) {
      return fail(ErrorCode::kVersionMismatch, 1, 1,
                  "unsupported VRML header " + quoted(first) + " (only '#VRML V2.0 utf8')");
    } else if (startsWith("#thinlod scene ")) {
      const std::string_view version = first.substr(15);
      int v = 0;
      auto [ptr, ec] = std::from_chars(version.data(), version.data() + version.size(), v);
      if (ec != std::errc() || ptr == version.data()) {
        return fail(ErrorCode::kParseError, 1, 16, "bad version in header " + quoted(first));
      }
      if (v != kSceneFormatVersion) {
        return fail(ErrorCode::kVersionMismatch, 1, 16,
                    "thinlod scene version " + std::to_string(v) + " is not supported (only " +
                        std::to_string(kSceneFormatVersion) + ")");
      }
      scene_.header = "thinlod " + std::to_string(v);
    } else {
      return fail(ErrorCode::kParseError, 1, 1,
                  "missing header: the first line must be '#VRML V2.0 utf8' or '#thinlod scene " +
                      std::to_string(kSceneFormatVersion) + "'");
    }
    // The header line is a comment for the lexer.
    return true;
  }

  char peekChar() const { return pos_ < text_.size() ? text_[pos_] : '\0'; }
  void bump() {
    if (text_[pos_] == '\n') {
      ++line_;
      column_ = 1;
    } else {
      ++column_;
    }
    ++pos_;
  }
  static bool isSeparator(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == ',' || c == '\f' || c == '\v';
  }
  static bool endsWord(char c) {
    return isSeparator(c) || c == '{' || c == '}' || c == '[' || c == ']' || c == '"' || c == '#';
  }

  // Reads the next token into tok_. A lexical error leaves a kEnd token and
  // sets lexError_ (reported by the next expect).
  void advance() {
    for (;;) {
      while (pos_ < text_.size() && isSeparator(peekChar())) bump();
      if (peekChar() == '#') {
        while (pos_ < text_.size() && peekChar() != '\n') bump();
        continue;
      }
      break;
    }
    tok_ = Token{};
    tok_.line = line_;
    tok_.column = column_;
    if (pos_ >= text_.size()) return;
    const char c = peekChar();
    const std::size_t start = pos_;
    switch (c) {
      case '{':
        tok_.kind = TokenKind::kLBrace;
        bump();
        return;
      case '}':
        tok_.kind = TokenKind::kRBrace;
        bump();
        return;
      case '[':
        tok_.kind = TokenKind::kLBracket;
        bump();
        return;
      case ']':
        tok_.kind = TokenKind::kRBracket;
        bump();
        return;
      case '"': {
        bump();
        const std::size_t contentStart = pos_;
        while (pos_ < text_.size() && peekChar() != '"') {
          if (peekChar() == '\\' && pos_ + 1 < text_.size()) bump();
          bump();
        }
        if (pos_ >= text_.size()) {
          tok_.kind = TokenKind::kEnd;
          lexError_ = "unterminated string";
          return;
        }
        tok_.kind = TokenKind::kString;
        tok_.text = text_.substr(contentStart, pos_ - contentStart);
        bump();
        return;
      }
      default:
        while (pos_ < text_.size() && !endsWord(peekChar())) bump();
        tok_.kind = TokenKind::kWord;
        tok_.text = text_.substr(start, pos_ - start);
        return;
    }
  }

  bool lexOk() {
    if (lexError_.empty()) return true;
    return fail(tok_, lexError_);
  }

  bool expect(TokenKind kind, const std::string& what) {
    if (!lexOk()) return false;
    if (tok_.kind != kind) return unexpected(what);
    advance();
    return true;
  }

  // ------------------------------------------------------------ values

  bool countValues(std::size_t n) {
    totalValues_ += n;
    if (totalValues_ > limits_.maxTotalValues) {
      return failLimit(
          tok_, "more than " + std::to_string(limits_.maxTotalValues) + " values in the file");
    }
    return true;
  }

  bool parseFloat(float* out) {
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kWord) return unexpected("a number");
    std::string_view t = tok_.text;
    if (!t.empty() && t[0] == '+') t.remove_prefix(1);
    double v = 0.0;
    auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ptr != t.data() + t.size() ||
        (ec != std::errc() && ec != std::errc::result_out_of_range)) {
      return fail(tok_, "bad number " + quoted(tok_.text));
    }
    if (ec == std::errc::result_out_of_range) {
      const std::string copy(t);
      v = std::strtod(copy.c_str(), nullptr);  // overflow -> inf, underflow -> ~0
    }
    if (!std::isfinite(v) || std::abs(v) > std::numeric_limits<float>::max()) {
      return fail(tok_, "number " + quoted(tok_.text) + " is not finite");
    }
    *out = static_cast<float>(v);
    if (!countValues(1)) return false;
    advance();
    return true;
  }

  bool parseInt(std::int32_t* out) {
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kWord) return unexpected("an integer");
    std::string_view t = tok_.text;
    if (!t.empty() && t[0] == '+') t.remove_prefix(1);
    std::int64_t v = 0;
    auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || ptr != t.data() + t.size() ||
        v < std::numeric_limits<std::int32_t>::min() ||
        v > std::numeric_limits<std::int32_t>::max()) {
      return fail(tok_, "bad integer " + quoted(tok_.text));
    }
    *out = static_cast<std::int32_t>(v);
    if (!countValues(1)) return false;
    advance();
    return true;
  }

  bool parseBool(bool* out) {
    if (!lexOk()) return false;
    if (tok_.kind == TokenKind::kWord && tok_.text == "TRUE") {
      *out = true;
    } else if (tok_.kind == TokenKind::kWord && tok_.text == "FALSE") {
      *out = false;
    } else {
      return unexpected("TRUE or FALSE");
    }
    advance();
    return true;
  }

  bool parseVec2(glm::vec2* out) { return parseFloat(&out->x) && parseFloat(&out->y); }
  bool parseVec3(glm::vec3* out) {
    return parseFloat(&out->x) && parseFloat(&out->y) && parseFloat(&out->z);
  }
  bool parseColor(glm::vec3* out) {
    const Token at = tok_;
    if (!parseVec3(out)) return false;
    for (int i = 0; i < 3; ++i) {
      if ((*out)[i] < 0.0f || (*out)[i] > 1.0f)
        return fail(at, "colour components must be in [0, 1]");
    }
    return true;
  }
  bool parseUnitFloat(float* out, const char* what) {
    const Token at = tok_;
    if (!parseFloat(out)) return false;
    if (*out < 0.0f || *out > 1.0f) return fail(at, std::string(what) + " must be in [0, 1]");
    return true;
  }
  bool parsePositive(float* out, const char* what) {
    const Token at = tok_;
    if (!parseFloat(out)) return false;
    if (!(*out > 0.0f)) return fail(at, std::string(what) + " must be positive");
    return true;
  }
  bool parseRotation(glm::vec4* out) {
    const Token at = tok_;
    if (!parseFloat(&out->x) || !parseFloat(&out->y) || !parseFloat(&out->z) ||
        !parseFloat(&out->w)) {
      return false;
    }
    const glm::vec3 axis(*out);
    const float len = glm::length(axis);
    if (!(len > 0.0f)) {
      if (out->w != 0.0f) return fail(at, "rotation axis is zero");
      *out = glm::vec4(0.0f, 0.0f, 1.0f, 0.0f);
      return true;
    }
    *out = glm::vec4(axis / len, out->w);
    return true;
  }

  bool parseString(std::string* out) {
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kString) return unexpected("a string");
    if (tok_.text.size() > limits_.maxStringLength) {
      return failLimit(tok_, "string longer than " + std::to_string(limits_.maxStringLength));
    }
    out->clear();
    for (std::size_t i = 0; i < tok_.text.size(); ++i) {
      if (tok_.text[i] == '\\' && i + 1 < tok_.text.size()) ++i;
      out->push_back(tok_.text[i]);
    }
    advance();
    return true;
  }

  bool parseMFString(std::vector<std::string>* out) {
    out->clear();
    if (tok_.kind != TokenKind::kLBracket) {
      std::string s;
      if (!parseString(&s)) return false;
      out->push_back(std::move(s));
      return true;
    }
    advance();
    while (tok_.kind != TokenKind::kRBracket) {
      std::string s;
      if (!parseString(&s)) return false;
      out->push_back(std::move(s));
      if (out->size() > limits_.maxValuesPerField) return failLimit(tok_, "too many strings");
    }
    advance();
    return true;
  }

  // `[ v v ... ]` or a single value.
  template <typename T, typename ParseOne>
  bool parseMF(std::vector<T>* out, ParseOne parseOne) {
    out->clear();
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kLBracket) {
      T v{};
      if (!parseOne(&v)) return false;
      out->push_back(v);
      return true;
    }
    advance();
    while (true) {
      if (!lexOk()) return false;
      if (tok_.kind == TokenKind::kRBracket) break;
      if (out->size() >= limits_.maxValuesPerField) {
        return failLimit(tok_, "more than " + std::to_string(limits_.maxValuesPerField) +
                                   " values in one field");
      }
      T v{};
      if (!parseOne(&v)) return false;
      out->push_back(v);
    }
    advance();
    return true;
  }

  // ------------------------------------------------------------ nodes

  // Depth and node-count accounting around one node body.
  struct NodeScope {
    Parser& p;
    bool ok;
    NodeScope(Parser& parser, const Token& at) : p(parser) {
      ++p.depth_;
      ++p.nodesParsed_;
      ok = true;
      if (p.depth_ > p.limits_.maxDepth) {
        ok =
            p.failLimit(at, "nesting deeper than " + std::to_string(p.limits_.maxDepth) + " nodes");
      } else if (p.nodesParsed_ > p.limits_.maxNodes) {
        ok = p.failLimit(at, "more than " + std::to_string(p.limits_.maxNodes) + " nodes");
      }
    }
    ~NodeScope() { --p.depth_; }
  };

  // Reads `{ field value ... }`, dispatching each field name to onField,
  // which must consume the value. `type` names the node in messages.
  bool parseBody(const Token& typeToken,
                 const std::function<bool(std::string_view, const Token&)>& onField) {
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kLBrace) {
      return unexpected("'{' after " + quoted(typeToken.text));
    }
    advance();
    for (;;) {
      if (!lexOk()) return false;
      if (tok_.kind == TokenKind::kRBrace) break;
      if (tok_.kind == TokenKind::kEnd) {
        return fail(tok_, "unexpected end of file: " + quoted(typeToken.text) + " opened at " +
                              std::to_string(typeToken.line) + ":" +
                              std::to_string(typeToken.column) + " is not closed");
      }
      if (tok_.kind != TokenKind::kWord) return unexpected("a field name or '}'");
      const Token field = tok_;
      advance();
      if (!onField(field.text, field)) {
        if (status_.ok()) {
          return fail(field,
                      "unknown field " + quoted(field.text) + " in " + quoted(typeToken.text));
        }
        return false;
      }
    }
    advance();
    return true;
  }

  bool validName(const Token& t) {
    if (t.kind != TokenKind::kWord) return false;
    const char c = t.text[0];
    return !(c >= '0' && c <= '9') && c != '+' && c != '-' && c != '.';
  }

  // DEF name / USE name handling shared by every node context. Returns the
  // DEF name (empty if none) and leaves tok_ at the node type.
  bool parseDefPrefix(std::string* defName) {
    defName->clear();
    if (tok_.kind == TokenKind::kWord && tok_.text == "DEF") {
      advance();
      if (!lexOk()) return false;
      if (!validName(tok_)) return unexpected("a name after DEF");
      if (tok_.text.size() > limits_.maxStringLength) return failLimit(tok_, "name too long");
      *defName = std::string(tok_.text);
      advance();
    }
    return true;
  }

  // If tok_ is USE, resolves it (checking the kind) into *entry.
  bool parseUse(DefKind wanted, const DefEntry** entry, bool* isUse) {
    *isUse = false;
    if (!(tok_.kind == TokenKind::kWord && tok_.text == "USE")) return true;
    *isUse = true;
    advance();
    if (!lexOk()) return false;
    if (!validName(tok_)) return unexpected("a name after USE");
    auto found = defs_.find(std::string(tok_.text));
    if (found == defs_.end()) {
      return fail(tok_, "USE of undefined name " + quoted(tok_.text));
    }
    if (found->second.kind != wanted) {
      return fail(tok_, "USE " + quoted(tok_.text) + " names " + describe(found->second.kind) +
                            ", expected " + describe(wanted));
    }
    *entry = &found->second;
    advance();
    return true;
  }

  bool parseChildStatement(NodePtr* out) {
    if (!lexOk()) return false;
    if (tok_.kind == TokenKind::kWord &&
        (tok_.text == "PROTO" || tok_.text == "EXTERNPROTO" || tok_.text == "ROUTE")) {
      return fail(tok_, quoted(tok_.text) + " is not supported");
    }
    const DefEntry* used = nullptr;
    bool isUse = false;
    if (!parseUse(DefKind::kSceneNode, &used, &isUse)) return false;
    if (isUse) {
      *out = used->node;
      return true;
    }
    std::string defName;
    if (!parseDefPrefix(&defName)) return false;
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kWord) return unexpected("a node");
    const Token type = tok_;
    advance();
    NodePtr node;
    if (!parseChildNode(type, &node)) return false;
    if (!defName.empty()) {
      node->defName = defName;
      DefEntry e;
      e.kind = DefKind::kSceneNode;
      e.node = node;
      defs_[defName] = e;
      scene_.defs[defName] = node;
    }
    *out = std::move(node);
    return true;
  }

  template <typename T, typename... Args>
  std::shared_ptr<T> make(const Token& at, Args&&... args) {
    auto node = std::make_shared<T>(std::forward<Args>(args)...);
    node->id = nextId_++;
    node->sourceLocation = SourceLocation{at.line, at.column};
    return node;
  }

  bool parseChildren(std::vector<NodePtr>* children) {
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kLBracket) {  // a single node without brackets
      NodePtr n;
      if (!parseChildStatement(&n)) return false;
      children->push_back(std::move(n));
      return true;
    }
    advance();
    for (;;) {
      if (!lexOk()) return false;
      if (tok_.kind == TokenKind::kRBracket) break;
      if (tok_.kind != TokenKind::kWord) return unexpected("a node or ']'");
      if (children->size() >= limits_.maxValuesPerField) {
        return failLimit(tok_, "too many children");
      }
      NodePtr n;
      if (!parseChildStatement(&n)) return false;
      children->push_back(std::move(n));
    }
    advance();
    return true;
  }

  static bool isField(std::string_view name, std::initializer_list<std::string_view> names) {
    for (std::string_view n : names) {
      if (n == name) return true;
    }
    return false;
  }

  // Accepted and ignored (VRML bounding-box hints).
  bool skipBboxField(std::string_view name) {
    glm::vec3 ignored;
    if (name == "bboxCenter" || name == "bboxSize") return parseVec3(&ignored);
    return false;
  }

  bool parseChildNode(const Token& type, NodePtr* out) {
    NodeScope scope(*this, type);
    if (!scope.ok) return false;
    const std::string_view t = type.text;
    if (t == "Group" || t == "Transform") {
      std::shared_ptr<Node> node;
      std::shared_ptr<TransformNode> transform;
      if (t == "Group") {
        node = make<GroupNode>(type);
      } else {
        transform = make<TransformNode>(type);
        node = transform;
      }
      bool ok = parseBody(type, [&](std::string_view f, const Token&) {
        if (f == "children") return parseChildren(&node->children);
        if (isField(f, {"bboxCenter", "bboxSize"})) return skipBboxField(f);
        if (!transform) return false;
        if (f == "translation") return parseVec3(&transform->translation);
        if (f == "rotation") return parseRotation(&transform->rotation);
        if (f == "scale") return parseScale(&transform->scale);
        if (f == "scaleOrientation") return parseRotation(&transform->scaleOrientation);
        if (f == "center") return parseVec3(&transform->center);
        return false;
      });
      if (!ok) return false;
      *out = node;
      return true;
    }
    if (t == "Shape") {
      auto shape = make<ShapeNode>(type);
      bool ok = parseBody(type, [&](std::string_view f, const Token&) {
        if (f == "appearance") return parseAppearanceField(&shape->appearance);
        if (f == "geometry") return parseGeometryField(&shape->geometry);
        return false;
      });
      if (!ok) return false;
      *out = shape;
      return true;
    }
    if (t == "Inline") {  // a mesh file as a Shape with a default, lit material
      auto shape = make<ShapeNode>(type);
      shape->appearance.hasMaterial = true;
      if (!parseInlineBody(type, &shape->geometry)) return false;
      *out = shape;
      return true;
    }
    if (t == "LOD") return parseLod(type, out);
    if (t == "SimpleImposter" || t == "MeshedImposter" || t == "SimplifiedPolygon") {
      const NodeKind kind = t == "SimpleImposter"   ? NodeKind::kSimpleImposter
                            : t == "MeshedImposter" ? NodeKind::kMeshedImposter
                                                    : NodeKind::kSimplifiedPolygon;
      auto node = make<ImposterNode>(type, kind);
      bool ok = parseBody(type, [&](std::string_view f, const Token&) {
        if (f == "children") return parseChildren(&node->children);
        if (f == "size") return parseVec2(&node->size);
        if (f == "autosize") return parseBool(&node->autosize);
        if (f == "center") return parseVec3(&node->center);
        if (f == "autocenter") return parseBool(&node->autocenter);
        return false;
      });
      if (!ok) return false;
      if (!(node->size.x > 0.0f) || !(node->size.y > 0.0f)) {
        return fail(type, quoted(t) + " size must be positive");
      }
      *out = node;
      return true;
    }
    if (t == "Viewpoint") {
      auto vp = make<ViewpointNode>(type);
      bool ok = parseBody(type, [&](std::string_view f, const Token& at) {
        if (f == "position") return parseVec3(&vp->position);
        if (f == "orientation") return parseRotation(&vp->orientation);
        if (f == "fieldOfView") {
          if (!parseFloat(&vp->fieldOfView)) return false;
          if (!(vp->fieldOfView > 0.0f && vp->fieldOfView < kPi)) {
            return fail(at, "fieldOfView must be in (0, pi)");
          }
          return true;
        }
        if (f == "description") return parseString(&vp->description);
        bool ignored;
        if (f == "jump") return parseBool(&ignored);
        return false;
      });
      if (!ok) return false;
      *out = vp;
      return true;
    }
    if (t == "DirectionalLight") {
      auto light = make<DirectionalLightNode>(type);
      bool ok = parseBody(type, [&](std::string_view f, const Token& at) {
        if (f == "direction") {
          if (!parseVec3(&light->direction)) return false;
          if (!(glm::length(light->direction) > 0.0f)) return fail(at, "direction is zero");
          light->direction = glm::normalize(light->direction);
          return true;
        }
        return parseLightCommon(f, &light->color, &light->intensity, &light->ambientIntensity,
                                &light->on);
      });
      if (!ok) return false;
      *out = light;
      return true;
    }
    if (t == "PointLight") {
      auto light = make<PointLightNode>(type);
      bool ok = parseBody(type, [&](std::string_view f, const Token& at) {
        if (f == "location") return parseVec3(&light->location);
        if (f == "radius") return parsePositive(&light->radius, "radius");
        if (f == "attenuation") {
          if (!parseVec3(&light->attenuation)) return false;
          if (light->attenuation.x < 0 || light->attenuation.y < 0 || light->attenuation.z < 0) {
            return fail(at, "attenuation must be >= 0");
          }
          return true;
        }
        return parseLightCommon(f, &light->color, &light->intensity, &light->ambientIntensity,
                                &light->on);
      });
      if (!ok) return false;
      *out = light;
      return true;
    }
    if (isValueNodeName(t)) {
      return fail(type, quoted(t) +
                            " cannot be used here (expected a grouping, shape, "
                            "LOD, imposter, viewpoint or light node)");
    }
    return fail(type, "unknown node type " + quoted(t));
  }

  static bool isValueNodeName(std::string_view t) {
    return t == "Appearance" || t == "Material" || t == "Sphere" || t == "Cylinder" || t == "Box" ||
           t == "Cone" || t == "IndexedFaceSet" || t == "Coordinate" || t == "ConicRange" ||
           t == "ImageTexture" || t == "TextureCoordinate";
  }

  bool parseScale(glm::vec3* out) {
    const Token at = tok_;
    if (!parseVec3(out)) return false;
    if (out->x == 0.0f || out->y == 0.0f || out->z == 0.0f) return fail(at, "scale has a zero");
    return true;
  }

  bool parseLightCommon(std::string_view f, glm::vec3* color, float* intensity, float* ambient,
                        bool* on) {
    if (f == "color") return parseColor(color);
    if (f == "intensity") return parseUnitFloat(intensity, "intensity");
    if (f == "ambientIntensity") return parseUnitFloat(ambient, "ambientIntensity");
    if (f == "on") return parseBool(on);
    return false;
  }

  bool parseLod(const Token& type, NodePtr* out) {
    auto lod = make<LodNode>(type);
    std::vector<ConicRange> ranges;
    std::vector<float> distances;
    Token rangeToken = type;
    bool ok = parseBody(type, [&](std::string_view f, const Token& at) {
      if (f == "level") return parseChildren(&lod->children);
      if (f == "center") return parseVec3(&lod->center);
      if (f == "range") {
        rangeToken = at;
        return parseRanges(&ranges, &distances);
      }
      return false;
    });
    if (!ok) return false;
    const std::size_t levels = lod->children.size();
    if (!distances.empty()) {
      if (distances.size() + 1 != levels) {
        return fail(rangeToken, std::to_string(distances.size()) + " range distances need " +
                                    std::to_string(distances.size() + 1) + " levels, found " +
                                    std::to_string(levels));
      }
      for (std::size_t i = 0; i < levels; ++i) {
        const double lo = i == 0 ? 0.0 : distances[i - 1];
        const double hi =
            i < distances.size() ? distances[i] : std::numeric_limits<double>::infinity();
        Result<ConicRange> r =
            ConicRange::make(glm::dvec3(lod->center), lo, hi, glm::dvec3(0.0, 0.0, 1.0), kPi);
        if (!r.ok()) {
          return fail(rangeToken,
                      "range distances must be >= 0 and ascending: " + r.status().message());
        }
        lod->ranges.push_back(*r);
      }
    } else {
      if (ranges.size() > levels) {
        return fail(rangeToken, std::to_string(ranges.size()) + " ranges for " +
                                    std::to_string(levels) + " levels");
      }
      lod->ranges = std::move(ranges);
      lod->ranges.resize(levels, ConicRange::everywhere());
    }
    *out = lod;
    return true;
  }

  // `range` holds ConicRange nodes (the paper's extension) or VRML floats.
  bool parseRanges(std::vector<ConicRange>* ranges, std::vector<float>* distances) {
    auto parseOne = [&]() -> bool {
      if (tok_.kind == TokenKind::kWord &&
          (tok_.text == "ConicRange" || tok_.text == "DEF" || tok_.text == "USE")) {
        if (!distances->empty()) return fail(tok_, "range mixes numbers and ConicRange nodes");
        ConicRange r;
        if (!parseConicRangeValue(&r)) return false;
        ranges->push_back(r);
        return true;
      }
      if (!ranges->empty()) return fail(tok_, "range mixes numbers and ConicRange nodes");
      float d = 0.0f;
      if (!parseFloat(&d)) return false;
      distances->push_back(d);
      return true;
    };
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kLBracket) return parseOne();
    advance();
    for (;;) {
      if (!lexOk()) return false;
      if (tok_.kind == TokenKind::kRBracket) break;
      if (tok_.kind == TokenKind::kEnd) return unexpected("']'");
      if (ranges->size() + distances->size() >= limits_.maxValuesPerField) {
        return failLimit(tok_, "too many ranges");
      }
      if (!parseOne()) return false;
    }
    advance();
    return true;
  }

  bool parseConicRangeValue(ConicRange* out) {
    const DefEntry* used = nullptr;
    bool isUse = false;
    if (!parseUse(DefKind::kConicRange, &used, &isUse)) return false;
    if (isUse) {
      *out = used->range;
      return true;
    }
    std::string defName;
    if (!parseDefPrefix(&defName)) return false;
    if (!lexOk()) return false;
    if (!(tok_.kind == TokenKind::kWord && tok_.text == "ConicRange")) {
      return unexpected("ConicRange");
    }
    const Token type = tok_;
    advance();
    NodeScope scope(*this, type);
    if (!scope.ok) return false;
    glm::vec3 center(0.0f);
    glm::vec2 distance(0.0f, std::numeric_limits<float>::max());
    bool distanceGiven = false;
    glm::vec3 direction(0.0f, 0.0f, 1.0f);
    float alpha = kPi;
    bool ok = parseBody(type, [&](std::string_view f, const Token&) {
      if (f == "center") return parseVec3(&center);
      if (f == "distance") {
        distanceGiven = true;
        return parseVec2(&distance);
      }
      if (f == "direction") return parseVec3(&direction);
      if (f == "alpha") return parseFloat(&alpha);
      return false;
    });
    if (!ok) return false;
    const double maxDistance =
        distanceGiven ? double(distance.y) : std::numeric_limits<double>::infinity();
    Result<ConicRange> r =
        ConicRange::make(glm::dvec3(center), distance.x, maxDistance, glm::dvec3(direction), alpha);
    if (!r.ok()) return fail(type, "invalid ConicRange: " + r.status().message());
    *out = *r;
    if (!defName.empty()) {
      DefEntry e;
      e.kind = DefKind::kConicRange;
      e.range = *r;
      defs_[defName] = e;
    }
    return true;
  }

  bool parseAppearanceField(Appearance* out) {
    if (tok_.kind == TokenKind::kWord && tok_.text == "NULL") {
      advance();
      *out = Appearance();
      return true;
    }
    const DefEntry* used = nullptr;
    bool isUse = false;
    if (!parseUse(DefKind::kAppearance, &used, &isUse)) return false;
    if (isUse) {
      *out = used->appearance;
      return true;
    }
    std::string defName;
    if (!parseDefPrefix(&defName)) return false;
    if (!lexOk()) return false;
    if (!(tok_.kind == TokenKind::kWord && tok_.text == "Appearance")) {
      return unexpected("Appearance");
    }
    const Token type = tok_;
    advance();
    NodeScope scope(*this, type);
    if (!scope.ok) return false;
    Appearance a;
    bool ok = parseBody(type, [&](std::string_view f, const Token& at) {
      if (f == "material") return parseMaterialField(&a);
      if (f == "texture") return parseTextureField(&a);
      if (f == "textureTransform") {
        return fail(at, quoted(f) + " is not supported (texture coordinates are used as given)");
      }
      return false;
    });
    if (!ok) return false;
    *out = a;
    if (!defName.empty()) {
      DefEntry e;
      e.kind = DefKind::kAppearance;
      e.appearance = a;
      defs_[defName] = e;
    }
    return true;
  }

  // texture ImageTexture { url [...] repeatS repeatT } | USE name | NULL.
  // Every url must pass checkUrl (a relative file name): a parse error here.
  bool parseTextureField(Appearance* appearance) {
    std::vector<std::string> urls;
    if (tok_.kind == TokenKind::kWord && tok_.text == "NULL") {
      advance();
      appearance->textureUrl.clear();
      appearance->textureAlternatives.clear();
      return true;
    }
    const DefEntry* used = nullptr;
    bool isUse = false;
    if (!parseUse(DefKind::kImageTexture, &used, &isUse)) return false;
    if (isUse) {
      urls = used->textureUrls;
    } else {
      std::string defName;
      if (!parseDefPrefix(&defName)) return false;
      if (!lexOk()) return false;
      if (!(tok_.kind == TokenKind::kWord && tok_.text == "ImageTexture")) {
        if (tok_.kind == TokenKind::kWord &&
            (tok_.text == "PixelTexture" || tok_.text == "MovieTexture")) {
          return fail(tok_, quoted(tok_.text) + " is not supported (only ImageTexture)");
        }
        return unexpected("ImageTexture");
      }
      const Token type = tok_;
      advance();
      NodeScope scope(*this, type);
      if (!scope.ok) return false;
      bool ignoredBool = false;
      Token urlToken = type;
      bool ok = parseBody(type, [&](std::string_view f, const Token& at) {
        if (f == "url") {
          urlToken = at;
          return parseMFString(&urls);
        }
        if (f == "repeatS" || f == "repeatT") return parseBool(&ignoredBool);
        return false;
      });
      if (!ok) return false;
      if (urls.empty()) return fail(urlToken, "ImageTexture has no url");
      for (const std::string& url : urls) {
        const Status checked = checkUrl(url, "ImageTexture");
        if (!checked.ok()) {
          return fail(checked.code(), urlToken.line, urlToken.column, checked.message());
        }
      }
      if (!defName.empty()) {
        DefEntry e;
        e.kind = DefKind::kImageTexture;
        e.textureUrls = urls;
        defs_[defName] = e;
      }
    }
    appearance->textureUrl = urls.front();
    appearance->textureAlternatives.assign(urls.begin() + 1, urls.end());
    return true;
  }

  bool parseMaterialField(Appearance* appearance) {
    if (tok_.kind == TokenKind::kWord && tok_.text == "NULL") {
      advance();
      appearance->hasMaterial = false;
      return true;
    }
    const DefEntry* used = nullptr;
    bool isUse = false;
    if (!parseUse(DefKind::kMaterial, &used, &isUse)) return false;
    if (isUse) {
      appearance->hasMaterial = true;
      appearance->material = used->material;
      return true;
    }
    std::string defName;
    if (!parseDefPrefix(&defName)) return false;
    if (!lexOk()) return false;
    if (!(tok_.kind == TokenKind::kWord && tok_.text == "Material")) return unexpected("Material");
    const Token type = tok_;
    advance();
    NodeScope scope(*this, type);
    if (!scope.ok) return false;
    Material m;
    bool ok = parseBody(type, [&](std::string_view f, const Token&) {
      if (f == "diffuseColor") return parseColor(&m.diffuseColor);
      if (f == "emissiveColor") return parseColor(&m.emissiveColor);
      if (f == "specularColor") return parseColor(&m.specularColor);
      if (f == "ambientIntensity") return parseUnitFloat(&m.ambientIntensity, "ambientIntensity");
      if (f == "shininess") return parseUnitFloat(&m.shininess, "shininess");
      if (f == "transparency") return parseUnitFloat(&m.transparency, "transparency");
      return false;
    });
    if (!ok) return false;
    appearance->hasMaterial = true;
    appearance->material = m;
    if (!defName.empty()) {
      DefEntry e;
      e.kind = DefKind::kMaterial;
      e.material = m;
      defs_[defName] = e;
    }
    return true;
  }

  bool parseInlineBody(const Token& type, Geometry* g) {
    g->kind = GeometryKind::kMeshFile;
    bool emptyAnimation = false;
    bool animation = false;
    std::optional<Token> regionsField;
    std::optional<Token> offsetField;
    bool ok = parseBody(type, [&](std::string_view f, const Token& field) {
      if (f == "url") return parseMFString(&g->urls);
      // thinlod extension: the clip of a skinned, animated file to play.
      if (f == "animation") {
        if (!parseString(&g->animationClip)) return false;
        emptyAnimation = g->animationClip.empty();
        animation = true;
        return true;
      }
      // thinlod extension: the clip's phase (seconds added to pose time).
      if (f == "animationOffset") {
        if (!parseFloat(&g->animationOffset)) return false;
        if (std::abs(g->animationOffset) > kMaxAnimationOffset) {
          return fail(field, "Inline animationOffset must be within +-" +
                                 std::to_string(static_cast<int>(kMaxAnimationOffset)) + " s");
        }
        offsetField = field;
        return true;
      }
      // thinlod extension: split the mesh into this many region objects
      // (docs/regions.md, "In the running system").
      if (f == "regions") {
        std::int32_t n = 0;
        if (!parseInt(&n)) return false;
        if (n < 2 || n > static_cast<std::int32_t>(kMaxInlineRegions)) {
          return fail(field, "Inline regions is " + std::to_string(n) + ", must be in [2, " +
                                 std::to_string(kMaxInlineRegions) + "]");
        }
        g->regionCount = static_cast<std::uint32_t>(n);
        regionsField = field;
        return true;
      }
      if (isField(f, {"bboxCenter", "bboxSize"})) return skipBboxField(f);
      return false;
    });
    if (!ok) return false;
    if (g->urls.empty()) return fail(type, "Inline needs a url");
    if (emptyAnimation) {
      return fail(type, "Inline animation is empty; name a clip or \"#N\" for the N-th");
    }
    if (offsetField && !animation) {
      return fail(*offsetField, "Inline animationOffset needs animation (the clip it shifts)");
    }
    if (regionsField && animation) {
      return fail(*regionsField, "Inline regions cannot be combined with animation");
    }
    return true;
  }

  bool parseGeometryField(Geometry* out) {
    if (tok_.kind == TokenKind::kWord && tok_.text == "NULL") {
      advance();
      *out = Geometry();
      return true;
    }
    const DefEntry* used = nullptr;
    bool isUse = false;
    if (!parseUse(DefKind::kGeometry, &used, &isUse)) return false;
    if (isUse) {
      *out = used->geometry;
      return true;
    }
    std::string defName;
    if (!parseDefPrefix(&defName)) return false;
    if (!lexOk()) return false;
    if (tok_.kind != TokenKind::kWord) return unexpected("a geometry node");
    const Token type = tok_;
    advance();
    NodeScope scope(*this, type);
    if (!scope.ok) return false;
    Geometry g;
    const std::string_view t = type.text;
    bool ok = true;
    if (t == "Sphere") {
      g.kind = GeometryKind::kPrimitive;
      g.primitive = PrimitiveShape::sphere(1.0f);
      ok = parseBody(type, [&](std::string_view f, const Token&) {
        if (f == "radius") return parsePositive(&g.primitive.radius, "radius");
        return false;
      });
    } else if (t == "Box") {
      g.kind = GeometryKind::kPrimitive;
      g.primitive = PrimitiveShape::box(glm::vec3(2.0f));
      ok = parseBody(type, [&](std::string_view f, const Token& at) {
        if (f == "size") {
          if (!parseVec3(&g.primitive.boxSize)) return false;
          const glm::vec3& s = g.primitive.boxSize;
          if (!(s.x > 0 && s.y > 0 && s.z > 0)) return fail(at, "Box size must be positive");
          return true;
        }
        return false;
      });
    } else if (t == "Cylinder") {
      g.kind = GeometryKind::kPrimitive;
      g.primitive = PrimitiveShape::cylinder(1.0f, 2.0f);
      ok = parseBody(type, [&](std::string_view f, const Token&) {
        PrimitiveShape& p = g.primitive;
        if (f == "radius") return parsePositive(&p.radius, "radius");
        if (f == "height") return parsePositive(&p.height, "height");
        if (f == "side") return parseBool(&p.side);
        if (f == "top") return parseBool(&p.top);
        if (f == "bottom") return parseBool(&p.bottom);
        return false;
      });
    } else if (t == "Cone") {
      g.kind = GeometryKind::kPrimitive;
      g.primitive = PrimitiveShape::cone(1.0f, 2.0f);
      ok = parseBody(type, [&](std::string_view f, const Token&) {
        PrimitiveShape& p = g.primitive;
        if (f == "bottomRadius") return parsePositive(&p.radius, "bottomRadius");
        if (f == "height") return parsePositive(&p.height, "height");
        if (f == "side") return parseBool(&p.side);
        if (f == "bottom") return parseBool(&p.bottom);
        return false;
      });
    } else if (t == "Inline") {
      ok = parseInlineBody(type, &g);
    } else if (t == "IndexedFaceSet") {
      ok = parseIndexedFaceSet(type, &g);
    } else {
      return fail(type, (isValueNodeName(t) ? quoted(t) + " is not a geometry node"
                                            : "unknown geometry node " + quoted(t)));
    }
    if (!ok) return false;
    if (g.kind == GeometryKind::kPrimitive) {
      const Status valid = validatePrimitive(g.primitive);
      if (!valid.ok()) return fail(type, valid.message());
    }
    *out = g;
    if (!defName.empty()) {
      DefEntry e;
      e.kind = DefKind::kGeometry;
      e.geometry = g;
      defs_[defName] = e;
    }
    return true;
  }

  // `coord Coordinate { point [...] }` and `texCoord TextureCoordinate { point
  // [...] }`: a point-list value node, or USE of one, or NULL.
  template <typename Point, typename ParseOne>
  bool parsePointNodeField(const char* nodeName, DefKind kind, std::vector<Point> DefEntry::*stored,
                           std::vector<Point>* points, ParseOne parseOne) {
    if (tok_.kind == TokenKind::kWord && tok_.text == "NULL") {
      advance();
      points->clear();
      return true;
    }
    const DefEntry* used = nullptr;
    bool isUse = false;
    if (!parseUse(kind, &used, &isUse)) return false;
    if (isUse) {
      *points = used->*stored;
      return true;
    }
    std::string defName;
    if (!parseDefPrefix(&defName)) return false;
    if (!lexOk()) return false;
    if (!(tok_.kind == TokenKind::kWord && tok_.text == nodeName)) return unexpected(nodeName);
    const Token type = tok_;
    advance();
    NodeScope scope(*this, type);
    if (!scope.ok) return false;
    bool ok = parseBody(type, [&](std::string_view f, const Token&) {
      if (f == "point") return parseMF<Point>(points, parseOne);
      return false;
    });
    if (!ok) return false;
    if (!defName.empty()) {
      DefEntry e;
      e.kind = kind;
      e.*stored = *points;
      defs_[defName] = e;
    }
    return true;
  }

  bool parseCoordinateField(std::vector<glm::vec3>* points) {
    return parsePointNodeField<glm::vec3>("Coordinate", DefKind::kCoordinate, &DefEntry::points,
                                          points, [&](glm::vec3* v) { return parseVec3(v); });
  }

  bool parseTextureCoordinateField(std::vector<glm::vec2>* points) {
    return parsePointNodeField<glm::vec2>("TextureCoordinate", DefKind::kTextureCoordinate,
                                          &DefEntry::texturePoints, points,
                                          [&](glm::vec2* v) { return parseVec2(v); });
  }

  bool parseIndexedFaceSet(const Token& type, Geometry* g) {
    std::vector<glm::vec3> points;
    std::vector<std::int32_t> coordIndex;
    std::vector<glm::vec2> texPoints;
    std::vector<std::int32_t> texCoordIndex;
    bool hasTexCoord = false;
    Token texIndexToken = type;
    Token indexToken = type;
    bool ccw = true;
    bool ignoredBool = false;
    float ignoredFloat = 0.0f;
    bool ok = parseBody(type, [&](std::string_view f, const Token& at) {
      if (f == "coord") return parseCoordinateField(&points);
      if (f == "coordIndex") {
        indexToken = at;
        return parseMF<std::int32_t>(&coordIndex, [&](std::int32_t* v) { return parseInt(v); });
      }
      if (f == "ccw") return parseBool(&ccw);
      if (isField(f, {"solid", "convex", "colorPerVertex", "normalPerVertex"})) {
        return parseBool(&ignoredBool);
      }
      if (f == "creaseAngle") return parseFloat(&ignoredFloat);
      if (f == "texCoord") {
        if (texCoordIndex.empty()) texIndexToken = at;
        hasTexCoord = true;
        return parseTextureCoordinateField(&texPoints);
      }
      if (f == "texCoordIndex") {
        texIndexToken = at;
        return parseMF<std::int32_t>(&texCoordIndex, [&](std::int32_t* v) { return parseInt(v); });
      }
      if (isField(f, {"color", "normal", "colorIndex", "normalIndex"})) {
        return fail(at, quoted(f) + " is not supported in IndexedFaceSet");
      }
      return false;
    });
    if (!ok) return false;
    auto mesh = std::make_shared<IndexedMesh>();
    // With texture coordinates a vertex is a (coordIndex, texCoordIndex)
    // pair (VRML97 6.23: texCoordIndex parallels coordIndex, or coordIndex
    // indexes the TextureCoordinate too when it is empty).
    const bool textured = hasTexCoord && !texPoints.empty();
    if (!textured && !texCoordIndex.empty()) {
      return fail(texIndexToken, "texCoordIndex without a TextureCoordinate");
    }
    if (textured && !texCoordIndex.empty() && texCoordIndex.size() != coordIndex.size()) {
      return fail(texIndexToken, "texCoordIndex has " + std::to_string(texCoordIndex.size()) +
                                     " entries, coordIndex " + std::to_string(coordIndex.size()));
    }
    std::map<std::pair<std::int32_t, std::int32_t>, std::uint32_t> pairVertex;
    if (!textured) mesh->positions = points;
    std::vector<std::uint32_t> polygon;
    auto flush = [&]() -> bool {
      if (polygon.empty()) return true;
      if (polygon.size() < 3) {
        return fail(indexToken, "coordIndex has a face with " + std::to_string(polygon.size()) +
                                    " vertices (needs at least 3)");
      }
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {  // fan
        if (ccw) {
          mesh->indices.insert(mesh->indices.end(), {polygon[0], polygon[k], polygon[k + 1]});
        } else {
          mesh->indices.insert(mesh->indices.end(), {polygon[0], polygon[k + 1], polygon[k]});
        }
      }
      polygon.clear();
      return true;
    };
    for (std::size_t i = 0; i < coordIndex.size(); ++i) {
      const std::int32_t v = coordIndex[i];
      if (v == -1) {
        if (textured && !texCoordIndex.empty() && texCoordIndex[i] != -1) {
          return fail(texIndexToken, "texCoordIndex entry " + std::to_string(i) + " is " +
                                         std::to_string(texCoordIndex[i]) +
                                         " where coordIndex ends a face (-1)");
        }
        if (!flush()) return false;
        continue;
      }
      if (v < 0 || static_cast<std::size_t>(v) >= points.size()) {
        return fail(indexToken, "coordIndex entry " + std::to_string(i) + " is " +
                                    std::to_string(v) + " but Coordinate has " +
                                    std::to_string(points.size()) + " points");
      }
      if (!textured) {
        polygon.push_back(static_cast<std::uint32_t>(v));
        continue;
      }
      const std::int32_t t = texCoordIndex.empty() ? v : texCoordIndex[i];
      if (t < 0 || static_cast<std::size_t>(t) >= texPoints.size()) {
        const char* field = texCoordIndex.empty() ? "coordIndex" : "texCoordIndex";
        return fail(texCoordIndex.empty() ? indexToken : texIndexToken,
                    std::string(field) + " entry " + std::to_string(i) + " is " +
                        std::to_string(t) + " but TextureCoordinate has " +
                        std::to_string(texPoints.size()) + " points");
      }
      auto [slot, added] = pairVertex.emplace(std::make_pair(v, t),
                                              static_cast<std::uint32_t>(mesh->positions.size()));
      if (added) {
        mesh->positions.push_back(points[static_cast<std::size_t>(v)]);
        mesh->uvs.push_back(texPoints[static_cast<std::size_t>(t)]);
      }
      polygon.push_back(slot->second);
    }
    if (!flush()) return false;
    mesh->computeNormals();
    g->kind = GeometryKind::kIndexedFaceSet;
    g->mesh = std::move(mesh);
    return true;
  }

  // DEF/USE can make a small file expand into a huge tree (each level USEs
  // the previous twice); every consumer walks instances, so bound them here.
  bool checkInstanceCount() {
    std::unordered_map<const Node*, std::uint64_t> memo;
    const std::uint64_t cap = limits_.maxInstances + 1;
    std::function<std::uint64_t(const Node&)> count = [&](const Node& n) -> std::uint64_t {
      auto found = memo.find(&n);
      if (found != memo.end()) return found->second;
      std::uint64_t total = 1;
      for (const NodePtr& c : n.children) total = std::min(cap, total + count(*c));
      memo.emplace(&n, total);
      return total;
    };
    std::uint64_t total = 0;
    for (const NodePtr& root : scene_.roots) {
      total = std::min(cap, total + count(*root));
      if (total > limits_.maxInstances) {
        return fail(ErrorCode::kResourceExhausted, root->sourceLocation.line,
                    root->sourceLocation.column,
                    "the scene expands (DEF/USE) to more than " +
                        std::to_string(limits_.maxInstances) + " node instances");
      }
    }
    return true;
  }

  std::string_view text_;
  const std::string& source_;
  const ParseLimits& limits_;
  std::size_t pos_ = 0;
  int line_ = 1;
  int column_ = 1;
  Token tok_;
  std::string lexError_;
  Status status_;
  Scene scene_;
  std::map<std::string, DefEntry> defs_;
  std::uint32_t nextId_ = 1;
  int depth_ = 0;
  std::size_t nodesParsed_ = 0;
  std::size_t totalValues_ = 0;
};

}  // namespace

Result<Scene> parseScene(std::string_view text, const std::string& sourceName,
                         const ParseLimits& limits) {
  Parser parser(text, sourceName, limits);
  return parser.run();
}

}  // namespace thinlod::scene
