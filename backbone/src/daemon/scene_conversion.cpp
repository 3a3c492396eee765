#include "scene_conversion.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <glm/geometric.hpp>
#include <limits>
#include <map>

namespace thinlod::backbone_daemon {
namespace {

using backbone::SceneNodeKind;
using backbone::Sphere;

// Tree under construction (before the preorder layout).
struct TreeNode {
  SceneNodeKind kind = SceneNodeKind::kGroup;
  std::vector<int> children;
  std::vector<ConicRange> childRanges;  // parallel to children
  std::uint32_t object = 0;             // leaf
  bool hasLeaves = false;
  Sphere bounds;
};

int addChild(std::vector<TreeNode>& tree, int parent, SceneNodeKind kind, const ConicRange& range) {
  tree.push_back(TreeNode{});
  tree.back().kind = kind;
  const int index = static_cast<int>(tree.size()) - 1;
  tree[parent].children.push_back(index);
  tree[parent].childRanges.push_back(range);
  return index;
}

// Bottom-up: a sphere enclosing the children that hold objects.
void computeBounds(std::vector<TreeNode>& tree, int n) {
  TreeNode& node = tree[n];
  if (node.kind == SceneNodeKind::kLeaf) {
    node.hasLeaves = true;
    return;
  }
  glm::dvec3 low(std::numeric_limits<double>::infinity());
  glm::dvec3 high(-std::numeric_limits<double>::infinity());
  for (int c : node.children) {
    computeBounds(tree, c);
    const TreeNode& child = tree[c];
    if (!child.hasLeaves) continue;
    node.hasLeaves = true;
    low = glm::min(low, child.bounds.center - glm::dvec3(child.bounds.radius));
    high = glm::max(high, child.bounds.center + glm::dvec3(child.bounds.radius));
  }
  if (!node.hasLeaves) return;
  const glm::dvec3 center = 0.5 * (low + high);
  double radius = 0.0;
  for (int c : node.children) {
    const TreeNode& child = tree[c];
    if (!child.hasLeaves) continue;
    radius = std::max(radius, glm::length(child.bounds.center - center) + child.bounds.radius);
  }
  // Room for rounding in validateScene's containment check.
  node.bounds = {center, radius * (1.0 + 1e-9) + 1e-12};
}

// Top-down: subtrees without objects get a tiny sphere inside their parent.
void placeEmpty(std::vector<TreeNode>& tree, int n, const Sphere& parent) {
  TreeNode& node = tree[n];
  if (!node.hasLeaves) node.bounds = {parent.center, std::max(parent.radius * 1e-3, 1e-9)};
  const Sphere own = node.bounds;
  for (int c : node.children) placeEmpty(tree, c, own);
}

// Preorder layout with contiguous child lists.
std::uint32_t layout(const std::vector<TreeNode>& tree, int n, backbone::SchedulingScene& out,
                     std::vector<std::uint32_t>& leafOfObject) {
  const TreeNode& node = tree[n];
  const auto index = static_cast<std::uint32_t>(out.nodes.size());
  backbone::SceneNode sceneNode;
  sceneNode.kind = node.kind;
  sceneNode.bounds = node.bounds;
  sceneNode.contentVersion = 1;
  if (node.kind == SceneNodeKind::kLeaf) {
    sceneNode.object = node.object;
    leafOfObject[node.object] = index;
    out.nodes.push_back(sceneNode);
    return index;
  }
  sceneNode.firstChild = static_cast<std::uint32_t>(out.children.size());
  sceneNode.childCount = static_cast<std::uint32_t>(node.children.size());
  out.nodes.push_back(sceneNode);
  out.children.resize(out.children.size() + node.children.size());
  out.childRanges.resize(out.children.size());
  for (std::size_t i = 0; i < node.children.size(); ++i) {
    const std::uint32_t child = layout(tree, node.children[i], out, leafOfObject);
    out.children[sceneNode.firstChild + i] = child;
    out.childRanges[sceneNode.firstChild + i] = node.childRanges[i];
  }
  return index;
}

}  // namespace

ConicRange rangeToWorld(const ConicRange& range, const glm::mat4& contentToWorld) {
  if (range.isEverywhere() || range.isEmpty()) return range;
  const glm::dmat4 m(contentToWorld);
  const double scale = scene::maxScale(contentToWorld);
  const glm::dvec3 center = glm::dvec3(m * glm::dvec4(range.center(), 1.0));
  glm::dvec3 direction = glm::dmat3(m) * range.direction();
  if (!(glm::length(direction) > 0.0)) direction = range.direction();
  Result<ConicRange> mapped = ConicRange::make(
      center, range.minDistance() * scale, range.maxDistance() * scale, direction, range.alpha());
  return mapped.ok() ? *mapped : ConicRange::nowhere();
}

Result<ConvertedScene> convertScene(const scene::Scene& sceneGraph,
                                    const std::vector<scene::SceneObject>& objects) {
  const std::vector<scene::NodeInstance> instances = scene::flattenInstances(sceneGraph);
  std::map<int, std::uint32_t> objectOfInstance;
  for (std::size_t k = 0; k < objects.size(); ++k) {
    if (objects[k].id != k + 1)
      return Status(ErrorCode::kInvalidArgument,
                    "scene objects must be numbered 1..n in order (collectSceneObjects)");
    objectOfInstance[objects[k].instance] = static_cast<std::uint32_t>(k);
  }

  ConvertedScene out;
  std::vector<TreeNode> tree(1);  // root group
  // Tree node that an instance's descendants attach to; for LOD instances
  // the LOD node itself (its child instances become level groups).
  std::vector<int> owner(instances.size(), 0);
  std::vector<int> levelsSeen(instances.size(), 0);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const scene::NodeInstance& inst = instances[i];
    int container = inst.parent < 0 ? 0 : owner[inst.parent];
    if (inst.parent >= 0 && instances[inst.parent].node->kind == scene::NodeKind::kLod) {
      const auto* lod = instances[inst.parent].node->as<scene::LodNode>();
      const int level = levelsSeen[inst.parent]++;
      ConicRange range;
      if (lod != nullptr && level < static_cast<int>(lod->ranges.size()))
        range = rangeToWorld(lod->ranges[level], instances[inst.parent].contentToWorld);
      container = addChild(tree, container, SceneNodeKind::kGroup, range);
    }
    owner[i] = container;
    if (inst.node->kind == scene::NodeKind::kLod) {
      owner[i] = addChild(tree, container, SceneNodeKind::kLod, ConicRange());
      ++out.lodNodes;
      continue;
    }
    auto found = objectOfInstance.find(static_cast<int>(i));
    if (found != objectOfInstance.end()) {
      const int leaf = addChild(tree, container, SceneNodeKind::kLeaf, ConicRange());
      tree[leaf].object = found->second;
      const scene::SceneObject& object = objects[found->second];
      const double radius = std::max<double>(object.worldSphere.radius, 1e-9);
      tree[leaf].bounds = {glm::dvec3(object.worldSphere.center), radius};
    }
  }
  computeBounds(tree, 0);
  if (!tree[0].hasLeaves) tree[0].bounds = {glm::dvec3(0.0), 1.0};
  placeEmpty(tree, 0, tree[0].bounds);

  std::vector<std::uint32_t> leafOfObject(objects.size(), 0);
  layout(tree, 0, out.scheduling, leafOfObject);
  out.scheduling.objects.resize(objects.size());
  out.records.resize(objects.size());
  for (std::size_t k = 0; k < objects.size(); ++k) {
    const scene::SceneObject& object = objects[k];
    out.scheduling.objects[k].externalId = object.id;
    ObjectRecord& record = out.records[k];
    record.id = object.id;
    record.object = &object;
    record.leafNode = leafOfObject[k];
    record.bounds = out.scheduling.nodes[record.leafNode].bounds;
    record.diameter = 2.0 * record.bounds.radius;
    record.primitive =
        object.shape != nullptr && object.shape->geometry.kind == scene::GeometryKind::kPrimitive;
    record.fullTriangles = static_cast<double>(object.fullMesh->triangleCount());
    record.worldBoxDiagonal = object.worldBounds.diagonal();
  }
  return out;
}

}  // namespace thinlod::backbone_daemon
