// Scene-graph queries: bounds, instances, relative accuracy curves.
#include <algorithm>
#include <array>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <string>
#include <unordered_map>

#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/common/scene/scene.h"

namespace thinlod::scene {
namespace {

using BoundsMemo = std::unordered_map<const Node*, Bounds>;

bool hasChildren(NodeKind kind) {
  switch (kind) {
    case NodeKind::kGroup:
    case NodeKind::kTransform:
    case NodeKind::kLod:
    case NodeKind::kSimpleImposter:
    case NodeKind::kMeshedImposter:
    case NodeKind::kSimplifiedPolygon:
      return true;
    default:
      return false;
  }
}

Bounds unite(Bounds a, const Bounds& b) {
  if (b.empty) return a;
  a.extend(b.min);
  a.extend(b.max);
  return a;
}

// Memoised: a DAG built with DEF/USE can reach a node along many paths.
const Bounds& boundsOf(const Node& node, BoundsMemo& memo) {
  auto found = memo.find(&node);
  if (found != memo.end()) return found->second;
  Bounds b;
  if (const ShapeNode* shape = node.as<ShapeNode>()) {
    const Geometry& g = shape->geometry;
    if (g.kind == GeometryKind::kPrimitive) {
      b = primitiveBounds(g.primitive);
    } else if (g.mesh) {
      b = g.mesh->bounds();
    }
  } else if (hasChildren(node.kind)) {
    for (const NodePtr& child : node.children) {
      b = unite(b, transformBounds(boundsOf(*child, memo), child->localTransform()));
    }
  }
  return memo.emplace(&node, b).first->second;
}

glm::mat4 axisAngle(const glm::vec4& rotation) {
  const glm::vec3 axis(rotation);
  if (rotation.w == 0.0f || glm::length(axis) == 0.0f) return glm::mat4(1.0f);
  return glm::rotate(glm::mat4(1.0f), rotation.w, glm::normalize(axis));
}

// Largest eigenvalue of a symmetric 3x3 matrix (cyclic Jacobi).
double largestEigenvalue(std::array<std::array<double, 3>, 3> a) {
  for (int sweep = 0; sweep < 32; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= 1e-30 * diag || off == 0.0) break;
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        if (a[p][q] == 0.0) continue;
        const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0);
        const double s = t * c;
        for (int k = 0; k < 3; ++k) {  // A <- A J
          const double akp = a[k][p];
          const double akq = a[k][q];
          a[k][p] = c * akp - s * akq;
          a[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {  // A <- J^T A
          const double apk = a[p][k];
          const double aqk = a[q][k];
          a[p][k] = c * apk - s * aqk;
          a[q][k] = s * apk + c * aqk;
        }
      }
    }
  }
  return std::max({a[0][0], a[1][1], a[2][2]});
}

struct CurveContext {
  const PrimitiveCurveOptions& options;
  std::unordered_map<const Node*, BoundingSphere> spheres;
  std::unordered_map<const Node*, NodeCurve> curves;
};

// A node's reference sphere in its content frame (relative_accuracy.h):
// Shapes the object's, nodes with children the enclosingSphere of their
// children's mapped by the child transforms; radius 0 when nothing draws.
BoundingSphere sphereOf(const Node& node, CurveContext& ctx) {
  auto found = ctx.spheres.find(&node);
  if (found != ctx.spheres.end()) return found->second;
  BoundingSphere out;
  if (const ShapeNode* shape = node.as<ShapeNode>()) {
    const Geometry& g = shape->geometry;
    if (g.kind == GeometryKind::kPrimitive && validatePrimitive(g.primitive).ok()) {
      out = primitiveReferenceSphere(g.primitive);
    } else if ((g.kind == GeometryKind::kMeshFile || g.kind == GeometryKind::kIndexedFaceSet) &&
               g.mesh && g.mesh->triangleCount() > 0) {
      out = referenceSphere(*g.mesh);
    }
  } else if (hasChildren(node.kind)) {
    std::vector<BoundingSphere> children;
    for (const auto& child : node.children) {
      const BoundingSphere s = sphereOf(*child, ctx);
      if (s.radius == 0.0f) continue;  // draws nothing (non-finite radii propagate)
      const glm::mat4 transform = child->localTransform();
      children.push_back(mapReferenceSphere(s, transform, maxScale(transform)));
    }
    out = enclosingSphere(children);
  }
  ctx.spheres.emplace(&node, out);
  return out;
}

Result<NodeCurve> curveOf(const Node& node, CurveContext& ctx);

// Child curves rescaled into the parent's relative accuracy (section 3.4):
// a child's absolute distortion d_c / a_c grows by at most maxScale(T)
// through its transform T, so relative to the parent diameter D its
// accuracy is a_c * D / (maxScale(T) * d_c).
Status rescaledChildren(const Node& node, double diameter, CurveContext& ctx,
                        std::vector<AccuracyCurve>* curves, std::vector<int>* childIndex) {
  for (std::size_t i = 0; i < node.children.size(); ++i) {
    const Node& child = *node.children[i];
    Result<NodeCurve> c = curveOf(child, ctx);
    if (!c.ok()) return c.status();
    if (c->curve.empty() || !(c->diameter > 0.0)) continue;
    const double stretch = maxScale(child.localTransform());
    if (!(stretch > 0.0) || !std::isfinite(stretch)) continue;  // collapsed: draws nothing
    // Float bounds overflow (scale 1e32 on a child, found by
    // fuzz/scene_file.cpp, seed fuzz/corpus/scene/crash-scale-overflow.wrl):
    // the factor is then inf, 0 or NaN, which scaledAccuracy's contract forbids.
    const double factor = diameter / (stretch * c->diameter);
    if (!(factor > 0.0) || !std::isfinite(factor)) {
      return Status(ErrorCode::kInvalidArgument,
                    std::string("relativeCurve: ") + nodeKindName(node.kind) + " node " +
                        std::to_string(node.id) + ": child " + std::to_string(child.id) +
                        " is scaled beyond what its bounds can represent (diameter " +
                        std::to_string(diameter) + ", child diameter " +
                        std::to_string(c->diameter) + ", scale " + std::to_string(stretch) + ")");
    }
    curves->push_back(c->curve.scaledAccuracy(factor));
    childIndex->push_back(static_cast<int>(i));
  }
  return Status();
}

Result<NodeCurve> computeCurve(const Node& node, CurveContext& ctx) {
  NodeCurve out;
  out.diameter = referenceLength(sphereOf(node, ctx));
  // Float overflow of a mapped sphere (scale 1e38 x 1e10, fuzz/scene_file.cpp).
  if (!std::isfinite(out.diameter))
    return Status(ErrorCode::kInvalidArgument,
                  std::string("relativeCurve: ") + nodeKindName(node.kind) + " node " +
                      std::to_string(node.id) +
                      ": scaled beyond what its bounds can represent (reference sphere overflows)");
  if (node.suppliedCurve) {
    out.curve = *node.suppliedCurve;
    return out;
  }
  if (const ShapeNode* shape = node.as<ShapeNode>()) {
    const Geometry& g = shape->geometry;
    switch (g.kind) {
      case GeometryKind::kNone:
        return out;
      case GeometryKind::kPrimitive: {
        Result<AccuracyCurve> c = primitiveAccuracyCurve(g.primitive, ctx.options);
        if (!c.ok()) return c.status();
        out.curve = std::move(*c);
        return out;
      }
      case GeometryKind::kMeshFile:
      case GeometryKind::kIndexedFaceSet:
        if (!g.mesh) {
          return Status(ErrorCode::kUnavailable,
                        "Shape " + std::to_string(node.id) + " (line " +
                            std::to_string(node.sourceLocation.line) + "): mesh '" +
                            (g.urls.empty() ? std::string("?") : g.urls.front()) +
                            "' is not loaded");
        }
        // The original mesh is exact relative to itself.
        out.curve = AccuracyCurve::point(kExactRelativeAccuracy,
                                         static_cast<double>(g.mesh->triangleCount()));
        return out;
    }
    return out;
  }
  if (!hasChildren(node.kind) || !(out.diameter > 0.0)) return out;
  std::vector<AccuracyCurve> curves;
  std::vector<int> childIndex;
  THINLOD_RETURN_IF_ERROR(rescaledChildren(node, out.diameter, ctx, &curves, &childIndex));
  std::vector<const AccuracyCurve*> pointers;
  for (const AccuracyCurve& c : curves) pointers.push_back(&c);
  if (node.kind == NodeKind::kLod) {
    std::vector<int> owner;
    out.curve = AccuracyCurve::lowerEnvelope(pointers, &owner);
    out.levelOfSegment.reserve(owner.size());
    for (int o : owner) out.levelOfSegment.push_back(o >= 0 ? childIndex[o] : -1);
  } else {
    out.curve = AccuracyCurve::sum(pointers);
  }
  return out;
}

Result<NodeCurve> curveOf(const Node& node, CurveContext& ctx) {
  auto found = ctx.curves.find(&node);
  if (found != ctx.curves.end()) return found->second;
  Result<NodeCurve> c = computeCurve(node, ctx);
  if (c.ok()) ctx.curves.emplace(&node, *c);
  return c;
}

}  // namespace

const char* nodeKindName(NodeKind kind) {
  switch (kind) {
    case NodeKind::kGroup:
      return "Group";
    case NodeKind::kTransform:
      return "Transform";
    case NodeKind::kShape:
      return "Shape";
    case NodeKind::kLod:
      return "LOD";
    case NodeKind::kSimpleImposter:
      return "SimpleImposter";
    case NodeKind::kMeshedImposter:
      return "MeshedImposter";
    case NodeKind::kSimplifiedPolygon:
      return "SimplifiedPolygon";
    case NodeKind::kViewpoint:
      return "Viewpoint";
    case NodeKind::kDirectionalLight:
      return "DirectionalLight";
    case NodeKind::kPointLight:
      return "PointLight";
  }
  return "?";
}

bool isImposterKind(NodeKind kind) {
  return kind == NodeKind::kSimpleImposter || kind == NodeKind::kMeshedImposter ||
         kind == NodeKind::kSimplifiedPolygon;
}

glm::mat4 Node::localTransform() const { return glm::mat4(1.0f); }

glm::mat4 TransformNode::localTransform() const {
  const glm::mat4 identity(1.0f);
  const glm::mat4 so = axisAngle(scaleOrientation);
  return glm::translate(identity, translation) * glm::translate(identity, center) *
         axisAngle(rotation) * so * glm::scale(identity, scale) * glm::transpose(so) *
         glm::translate(identity, -center);
}

Bounds contentBounds(const Node& node) {
  BoundsMemo memo;
  return boundsOf(node, memo);
}

Bounds transformBounds(const Bounds& bounds, const glm::mat4& transform) {
  Bounds out;
  if (bounds.empty) return out;
  for (int corner = 0; corner < 8; ++corner) {
    const glm::vec3 p((corner & 1) ? bounds.max.x : bounds.min.x,
                      (corner & 2) ? bounds.max.y : bounds.min.y,
                      (corner & 4) ? bounds.max.z : bounds.min.z);
    out.extend(glm::vec3(transform * glm::vec4(p, 1.0f)));
  }
  return out;
}

std::vector<NodeInstance> flattenInstances(const Scene& scene) {
  std::vector<NodeInstance> out;
  BoundsMemo memo;
  struct Pending {
    const Node* node;
    int parent;
    glm::mat4 parentContentToWorld;
  };
  std::vector<Pending> stack;
  for (auto it = scene.roots.rbegin(); it != scene.roots.rend(); ++it) {
    stack.push_back({it->get(), -1, glm::mat4(1.0f)});
  }
  while (!stack.empty()) {
    const Pending p = stack.back();
    stack.pop_back();
    NodeInstance inst;
    inst.node = p.node;
    inst.parent = p.parent;
    inst.contentToWorld = p.parentContentToWorld * p.node->localTransform();
    inst.worldBounds = transformBounds(boundsOf(*p.node, memo), inst.contentToWorld);
    const int index = static_cast<int>(out.size());
    out.push_back(inst);
    if (!hasChildren(p.node->kind)) continue;
    for (auto it = p.node->children.rbegin(); it != p.node->children.rend(); ++it) {
      stack.push_back({it->get(), index, inst.contentToWorld});
    }
  }
  return out;
}

Result<NodeCurve> relativeCurve(const Node& node, const PrimitiveCurveOptions& options) {
  CurveContext ctx{options, {}, {}};
  return curveOf(node, ctx);
}

double maxScale(const glm::mat4& m) {
  // sigma_max of the linear part = sqrt(largest eigenvalue of M^T M).
  std::array<std::array<double, 3>, 3> mtm{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double s = 0.0;
      for (int k = 0; k < 3; ++k) s += double(m[i][k]) * double(m[j][k]);  // columns i, j
      mtm[i][j] = s;
    }
  }
  return std::sqrt(std::max(0.0, largestEigenvalue(mtm)));
}

}  // namespace thinlod::scene
