#include "thinlod/backbone/scheduling_scene.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <string>

namespace thinlod::backbone {
namespace {

bool finite3(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

Status invalid(std::string message) {
  return Status(ErrorCode::kInvalidArgument, "scheduling scene: " + std::move(message));
}

std::string nodeName(std::size_t n) { return "node " + std::to_string(n); }
std::string optionName(std::size_t o) { return "option " + std::to_string(o); }

Status checkCopy(const RepresentationCopy& copy, std::size_t option, const char* where) {
  if (!copy.present) return Status::okStatus();
  const std::string name = optionName(option) + " " + where;
  if (!std::isfinite(copy.relativeAccuracy) || copy.relativeAccuracy <= 0.0)
    return invalid(name + ": relativeAccuracy must be finite and > 0");
  if (!std::isfinite(copy.triangles) || copy.triangles < 0.0)
    return invalid(name + ": triangles must be finite and >= 0");
  if (!std::isfinite(copy.encodedBytes) || copy.encodedBytes < 0.0)
    return invalid(name + ": encodedBytes must be finite and >= 0");
  return Status::okStatus();
}

Status checkCurve(const AccuracyCurve& curve, std::size_t option, const char* field) {
  if (curve.empty()) return invalid(optionName(option) + ": " + field + " is empty");
  if (!(curve.minAccuracy() > 0.0) || !std::isfinite(curve.maxAccuracy()))
    return invalid(optionName(option) + ": " + field +
                   " must cover positive, finite relative accuracies");
  return Status::okStatus();
}

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  // splitmix64 finaliser over the running hash: order-sensitive and cheap.
  std::uint64_t z = h ^ (v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2));
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

const char* optionKindName(OptionKind kind) {
  switch (kind) {
    case OptionKind::kOriginalMesh:
      return "original";
    case OptionKind::kSimplifiedMesh:
      return "simplified";
    case OptionKind::kMeshedImpostor:
      return "meshed-impostor";
    case OptionKind::kSimpleImpostor:
      return "simple-impostor";
    case OptionKind::kHybrid:
      return "hybrid";
  }
  return "unknown";
}

Status validateScene(const SchedulingScene& scene) {
  const std::size_t nodeCount = scene.nodes.size();
  if (nodeCount == 0) return invalid("no nodes (node 0 must be the root)");
  if (nodeCount >= 0xffffffffu) return invalid("too many nodes");
  if (scene.childRanges.size() != scene.children.size())
    return invalid("childRanges has " + std::to_string(scene.childRanges.size()) +
                   " entries, children has " + std::to_string(scene.children.size()));
  std::vector<std::uint8_t> parents(nodeCount, 0);
  std::vector<std::uint16_t> depth(nodeCount, 0);
  std::vector<std::uint8_t> objectUsed(scene.objects.size(), 0);
  for (std::size_t n = 0; n < nodeCount; ++n) {
    const SceneNode& node = scene.nodes[n];
    if (!finite3(node.bounds.center)) return invalid(nodeName(n) + ": non-finite bounds center");
    if (!std::isfinite(node.bounds.radius) || node.bounds.radius <= 0.0)
      return invalid(nodeName(n) + ": bounds radius must be finite and > 0");
    if (n > 0 && parents[n] != 1)
      return invalid(nodeName(n) + ": has " + std::to_string(parents[n]) +
                     " parents (children must follow their parent, one parent each)");
    if (depth[n] > kMaxSceneDepth)
      return invalid(nodeName(n) + ": deeper than " + std::to_string(kMaxSceneDepth));
    switch (node.kind) {
      case SceneNodeKind::kGroup:
      case SceneNodeKind::kLod: {
        const std::uint64_t end = std::uint64_t{node.firstChild} + node.childCount;
        if (end > scene.children.size())
          return invalid(nodeName(n) + ": children [" + std::to_string(node.firstChild) + ", " +
                         std::to_string(end) + ") exceed " + std::to_string(scene.children.size()) +
                         " child entries");
        for (std::uint64_t i = node.firstChild; i < end; ++i) {
          const std::uint32_t c = scene.children[i];
          if (c >= nodeCount || c <= n)
            return invalid(nodeName(n) + ": child " + std::to_string(c) +
                           " out of range or not after its parent");
          if (parents[c] != 0) return invalid(nodeName(c) + ": has more than one parent");
          parents[c] = 1;
          depth[c] = static_cast<std::uint16_t>(depth[n] + 1);
          const Sphere& cb = scene.nodes[c].bounds;
          const double reach = glm::length(cb.center - node.bounds.center) + cb.radius;
          const double slack = 1e-9 * (node.bounds.radius + glm::length(node.bounds.center));
          if (!(reach <= node.bounds.radius + slack))
            return invalid(nodeName(c) + ": bounds not inside parent " + nodeName(n) + " bounds");
        }
        break;
      }
      case SceneNodeKind::kLeaf: {
        if (node.object >= scene.objects.size())
          return invalid(nodeName(n) + ": object " + std::to_string(node.object) + " out of range");
        if (objectUsed[node.object]) return invalid(nodeName(n) + ": object used by two leaves");
        objectUsed[node.object] = 1;
        break;
      }
      default:
        return invalid(nodeName(n) + ": unknown kind " +
                       std::to_string(static_cast<int>(node.kind)));
    }
  }
  std::vector<std::uint8_t> optionUsed(scene.options.size(), 0);
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const SceneObject& object = scene.objects[o];
    const std::uint64_t end = std::uint64_t{object.firstOption} + object.optionCount;
    if (object.optionCount == 0)
      return invalid("object " + std::to_string(o) + ": has no representation option");
    if (end > scene.options.size())
      return invalid("object " + std::to_string(o) + ": options exceed " +
                     std::to_string(scene.options.size()));
    for (std::uint64_t k = object.firstOption; k < end; ++k) {
      if (optionUsed[k]) return invalid(optionName(k) + ": shared by two objects");
      optionUsed[k] = 1;
    }
  }
  for (std::size_t k = 0; k < scene.options.size(); ++k) {
    const RepresentationOption& option = scene.options[k];
    if (static_cast<int>(option.kind) > static_cast<int>(OptionKind::kHybrid))
      return invalid(optionName(k) + ": unknown kind");
    THINLOD_RETURN_IF_ERROR(checkCurve(option.relativeTriangles, k, "relativeTriangles"));
    THINLOD_RETURN_IF_ERROR(checkCurve(option.relativeLinkBytes, k, "relativeLinkBytes"));
    const AccuracyCurve& t = option.relativeTriangles;
    const AccuracyCurve& b = option.relativeLinkBytes;
    auto near = [](double x, double y) { return std::fabs(x - y) <= 1e-9 * std::max(x, y); };
    if (!near(t.minAccuracy(), b.minAccuracy()) || !near(t.maxAccuracy(), b.maxAccuracy()))
      return invalid(optionName(k) +
                     ": relativeTriangles and relativeLinkBytes must cover the same accuracies "
                     "(one representation family)");
    THINLOD_RETURN_IF_ERROR(checkCopy(option.atFrontend, k, "atFrontend"));
    THINLOD_RETURN_IF_ERROR(checkCopy(option.atBackbone, k, "atBackbone"));
  }
  return Status::okStatus();
}

void updateSubtreeVersions(SchedulingScene& scene) {
  for (std::size_t i = scene.nodes.size(); i-- > 0;) {
    SceneNode& node = scene.nodes[i];
    std::uint64_t h = mix(0x5eed, node.contentVersion);
    h = mix(h, static_cast<std::uint64_t>(node.kind));
    if (node.kind != SceneNodeKind::kLeaf) {
      const std::uint64_t end = std::uint64_t{node.firstChild} + node.childCount;
      for (std::uint64_t c = node.firstChild; c < end && c < scene.children.size(); ++c) {
        const std::uint32_t child = scene.children[c];
        if (child > i && child < scene.nodes.size()) h = mix(h, scene.nodes[child].subtreeVersion);
      }
    }
    node.subtreeVersion = h;
  }
}

}  // namespace thinlod::backbone
