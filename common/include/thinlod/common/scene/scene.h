// Scene graph: VRML97-style nodes plus the paper's LOD extensions
// (Pasman & Jansen 2002, sections 3.4-3.6): ConicRange, SimpleImposter,
// MeshedImposter, SimplifiedPolygon.
//
// Contract:
// - Ownership: nodes are std::shared_ptr<Node>. DEF/USE sharing is real
//   sharing: a node USEd twice is one object listed in two parents'
//   `children`, so the graph is a DAG (the parser rejects cycles by
//   construction: USE only refers to already-finished nodes). Nodes hold no
//   parent pointers; per-path data (world transform, world bounds) comes from
//   flattenInstances().
// - Frames: a node's "content frame" is the frame its geometry/children live
//   in; for a Transform that is inside its transform, for every other node
//   the frame of its parent. contentBounds() and relative curves are in that
//   frame. Units: metres, radians.
// - Node::id is unique within a Scene and stable for a given file (pre-order
//   of first appearance); use it to name nodes on the wire.
// - Accuracy curves (relative, resources = triangles): see relativeCurve().
// - Not thread-safe for mutation (setAccuracyCurve); const use from many
//   threads is fine.
#pragma once

#include <cstdint>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/core/conic_range.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/mesh/primitives.h"

namespace thinlod::scene {

enum class NodeKind : std::uint8_t {
  kGroup,
  kTransform,
  kShape,
  kLod,
  kSimpleImposter,
  kMeshedImposter,
  kSimplifiedPolygon,
  kViewpoint,
  kDirectionalLight,
  kPointLight,
};
const char* nodeKindName(NodeKind kind);  // the VRML node name, e.g. "SimpleImposter"

struct SourceLocation {
  int line = 0;  // 1-based; 0 = not from a file
  int column = 0;
};

struct Material {
  glm::vec3 diffuseColor{0.8f, 0.8f, 0.8f};
  glm::vec3 emissiveColor{0.0f};
  glm::vec3 specularColor{0.0f};
  float ambientIntensity = 0.2f;
  float shininess = 0.2f;
  float transparency = 0.0f;
};

struct Appearance {
  bool hasMaterial = false;  // VRML: no material means unlit (emissive white)
  Material material;
  // Base-colour texture as the file names it (an imported material,
  // scene_import.h, or a VRML ImageTexture's first url); empty when there is
  // none. textureAlternatives: an ImageTexture's further urls, tried in order
  // when the first names no file. texturePath: the file it resolved to
  // (resolveTextures), empty when it did not resolve. Drawn by the frontend's
  // reference and, through the link's shared textures (docs/protocol.md), by
  // the frontend's textured mesh representations and the simplifier's impostors.
  std::string textureUrl;
  std::vector<std::string> textureAlternatives;
  std::string texturePath;
};

enum class GeometryKind : std::uint8_t { kNone, kPrimitive, kMeshFile, kIndexedFaceSet };

// A skinned, animated mesh file (an Inline with an `animation` field,
// docs/scene-format.md "Animated Inline"): Geometry::mesh holds its vertices
// in mesh (bind) space, deformed by `skin` and the clip into the file's
// world frame (core/skinning.h). `palette` lists the bones the skin names,
// ascending; paletteSkin is `skin` with every bone replaced by its index in
// `palette`: the per-frame bone poses carry one matrix per palette entry.
struct SkinnedAnimation {
  anim::Skeleton skeleton;
  std::vector<anim::VertexSkin> skin;  // one per mesh vertex, skeleton bones
  anim::AnimationClip clip;            // the one the scene names, validated
  anim::SkinPalette palette;
  // Largest distance of a vertex from its bind position over the clip
  // (sampledMaxDeviationFromBind, kMotionSamples steps; mesh units, finite):
  // the object's reach grows by it (scene_objects.h).
  double motionBound = 0.0;
  static constexpr std::size_t kMotionSamples = 128;
};

struct Geometry {
  GeometryKind kind = GeometryKind::kNone;
  PrimitiveShape primitive;                 // kPrimitive
  std::vector<std::string> urls;            // kMeshFile: as written, first one that loads wins
  std::string resolvedPath;                 // kMeshFile: set by resolveMeshes()
  std::shared_ptr<const IndexedMesh> mesh;  // kMeshFile once loaded; kIndexedFaceSet always
  std::vector<std::string> loadWarnings;    // kMeshFile: from the mesh loader
  // kMeshFile: the clip an Inline's `animation` field names (its name, or
  // "#N" for the file's N-th clip); empty: a static mesh. resolveMeshes()
  // then imports the file skinned and sets `animation` beside `mesh`.
  std::string animationClip;
  std::shared_ptr<const SkinnedAnimation> animation;
  // An Inline's `animationOffset` (seconds, |offset| <= kMaxAnimationOffset):
  // the clip is sampled at pose time + offset, so instances of one clip need
  // not move in step. 0 without the field.
  float animationOffset = 0.0f;
  // kMeshFile: an Inline's `regions N` (2..kMaxInlineRegions; 0: none).
  // collectSceneObjects makes the mesh N objects, one per region
  // (scene_objects.h; docs/regions.md, "In the running system").
  std::uint32_t regionCount = 0;
};
inline constexpr std::uint32_t kMaxInlineRegions = 1024;
// A day: more is no phase a looped clip could need, and it keeps pose time +
// offset exact enough in the double the clock uses.
inline constexpr float kMaxAnimationOffset = 86400.0f;

struct Node;
using NodePtr = std::shared_ptr<Node>;

struct Node {
  virtual ~Node() = default;

  NodeKind kind;
  std::uint32_t id = 0;
  std::string defName;            // empty unless DEF'd
  SourceLocation sourceLocation;  // where the node starts in the scene file
  // Group, Transform, LOD (the levels, in order), imposters, SimplifiedPolygon.
  std::vector<NodePtr> children;
  // A curve supplied from outside (the simplifier's measured curve for a
  // mesh Shape, an imposter's or a SimplifiedPolygon's curve). When set it
  // replaces the node's computed curve in relativeCurve().
  std::optional<AccuracyCurve> suppliedCurve;

  void setAccuracyCurve(AccuracyCurve curve) { suppliedCurve = std::move(curve); }
  // Maps the content frame to the parent's frame (identity except Transform).
  virtual glm::mat4 localTransform() const;

  template <typename T>
  const T* as() const {
    return kind == T::kKind ? static_cast<const T*>(this) : nullptr;
  }
  template <typename T>
  T* as() {
    return kind == T::kKind ? static_cast<T*>(this) : nullptr;
  }

 protected:
  explicit Node(NodeKind k) : kind(k) {}
};

struct GroupNode : Node {
  static constexpr NodeKind kKind = NodeKind::kGroup;
  GroupNode() : Node(kKind) {}
};

struct TransformNode : Node {
  static constexpr NodeKind kKind = NodeKind::kTransform;
  TransformNode() : Node(kKind) {}
  glm::vec3 translation{0.0f};
  glm::vec4 rotation{0.0f, 0.0f, 1.0f, 0.0f};  // axis xyz, angle w (radians)
  glm::vec3 scale{1.0f};
  glm::vec4 scaleOrientation{0.0f, 0.0f, 1.0f, 0.0f};
  glm::vec3 center{0.0f};
  // VRML97: T * C * R * SR * S * -SR * -C.
  glm::mat4 localTransform() const override;
};

struct ShapeNode : Node {
  static constexpr NodeKind kKind = NodeKind::kShape;
  ShapeNode() : Node(kKind) {}
  Appearance appearance;
  Geometry geometry;
};

struct LodNode : Node {
  static constexpr NodeKind kKind = NodeKind::kLod;
  LodNode() : Node(kKind) {}
  glm::vec3 center{0.0f};
  // One per level (children.size()), in the LOD's content frame; a level
  // without a range is everywhere (ConicRange {} in Figure 10). A plain
  // VRML `range [d1 d2 ...]` is converted: level i gets distances
  // [d_{i-1}, d_i] around `center`, full angle (0 and infinity at the ends).
  std::vector<ConicRange> ranges;
};

// SimpleImposter, MeshedImposter, SimplifiedPolygon: "replace their children
// with a single simplification" (section 3.6, Figure 9).
struct ImposterNode : Node {
  explicit ImposterNode(NodeKind k) : Node(k) {}
  glm::vec2 size{2.0f, 2.0f};
  bool autosize = true;
  glm::vec3 center{0.0f};
  bool autocenter = true;
};
bool isImposterKind(NodeKind kind);  // the three kinds above

struct ViewpointNode : Node {
  static constexpr NodeKind kKind = NodeKind::kViewpoint;
  ViewpointNode() : Node(kKind) {}
  glm::vec3 position{0.0f, 0.0f, 10.0f};
  glm::vec4 orientation{0.0f, 0.0f, 1.0f, 0.0f};
  float fieldOfView = 0.785398f;
  std::string description;
};

struct DirectionalLightNode : Node {
  static constexpr NodeKind kKind = NodeKind::kDirectionalLight;
  DirectionalLightNode() : Node(kKind) {}
  glm::vec3 direction{0.0f, 0.0f, -1.0f};
  glm::vec3 color{1.0f};
  float intensity = 1.0f;
  float ambientIntensity = 0.0f;
  bool on = true;
};

struct PointLightNode : Node {
  static constexpr NodeKind kKind = NodeKind::kPointLight;
  PointLightNode() : Node(kKind) {}
  glm::vec3 location{0.0f};
  glm::vec3 color{1.0f};
  glm::vec3 attenuation{1.0f, 0.0f, 0.0f};
  float intensity = 1.0f;
  float ambientIntensity = 0.0f;
  float radius = 100.0f;
  bool on = true;
};

struct Scene {
  std::string sourceName;  // file name used in messages
  std::string header;      // "VRML V2.0 utf8" or "thinlod 1"
  std::vector<NodePtr> roots;
  std::map<std::string, NodePtr> defs;  // DEF'd scene-graph nodes (last DEF wins)
  std::uint32_t nodeCount = 0;          // distinct nodes (ids 1..nodeCount)
  std::vector<std::string> warnings;    // from mesh and texture loading
  // loadSceneFile(): sceneFingerprint() of the file's text and its meshes
  // (0 for a scene parsed from text alone). Daemons compare it at the
  // handshake: equal scene text and mesh geometry give equal fingerprints.
  std::uint64_t fingerprint = 0;
};

// FNV-1a 64 of the scene text, then of every loaded mesh's positions and
// triangle indices in the order Shapes first name them. Independent of where
// the files were found.
std::uint64_t sceneFingerprint(const std::string& text, const Scene& scene);

// Bounds of what the node draws, in its content frame; empty for lights,
// viewpoints, empty groups and unloaded meshes.
Bounds contentBounds(const Node& node);
// Axis-aligned bounds of the 8 transformed corners.
Bounds transformBounds(const Bounds& bounds, const glm::mat4& transform);

// One node on one path from a root: a node USEd twice appears twice.
struct NodeInstance {
  const Node* node = nullptr;
  int parent = -1;  // index into the same vector, -1 for roots
  glm::mat4 contentToWorld{1.0f};
  Bounds worldBounds;  // contentBounds mapped to world
};
// Pre-order over all roots. Lights and viewpoints are included.
std::vector<NodeInstance> flattenInstances(const Scene& scene);

// A node's relative accuracy curve (section 3.4) in its content frame.
// Rules: suppliedCurve if set; Shape: primitive -> primitiveAccuracyCurve,
// mesh/IndexedFaceSet -> point (kExactRelativeAccuracy, triangles) (the
// original is exact), unloaded mesh -> kUnavailable; Group, Transform,
// imposters and SimplifiedPolygon without a supplied curve -> sum of the
// children, each child's accuracy first multiplied by
// diameter / (maxScale(child localTransform) * childDiameter); LOD -> lower
// envelope of the levels after the same rescaling, `levelOfSegment` filled;
// lights, viewpoints, empty groups -> empty curve, diameter 0. `diameter` is
// the node's reference length (core/relative_accuracy.h): a Shape's object
// reference sphere, a parent's enclosingSphere of its children's spheres
// mapped by their transforms (so one child under a uniform scale keeps its
// relative accuracy exactly).
struct NodeCurve {
  AccuracyCurve curve;
  double diameter = 0.0;            // reference length L, content frame
  std::vector<int> levelOfSegment;  // LOD only: level index per curve segment
};
Result<NodeCurve> relativeCurve(const Node& node, const PrimitiveCurveOptions& options = {});

// Largest factor by which the linear part of `m` stretches a length.
double maxScale(const glm::mat4& m);

}  // namespace thinlod::scene
