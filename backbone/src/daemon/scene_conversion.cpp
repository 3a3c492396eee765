#include "scene_conversion.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <glm/geometric.hpp>
#include <limits>
#include <map>

#include "thinlod/common/core/relative_accuracy.h"

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

namespace {

bool sameTransform(const glm::mat4& a, const glm::mat4& b) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (std::abs(a[c][r] - b[c][r]) > 1e-6f * (1.0f + std::abs(a[c][r]))) return false;
  return true;
}

KindOffer notOffered() {
  KindOffer offer;
  offer.offered = false;
  return offer;
}

// `node` (may be null) and the map of its frame to world give the fixed
// frame of autocenter / autosize FALSE.
KindOffer explicitKind(const ConicRange& range, const scene::ImposterNode* node = nullptr,
                       const glm::mat4& nodeToWorld = glm::mat4(1.0f)) {
  KindOffer offer;
  offer.explicitNode = true;
  if (!range.isEverywhere()) offer.range = range;
  if (node != nullptr) {
    if (!node->autocenter) offer.frameCenter = glm::vec3(nodeToWorld * glm::vec4(node->center, 1.0f));
    if (!node->autosize) offer.frameSize = node->size * float(scene::maxScale(nodeToWorld));
  }
  return offer;
}

// The impostor kind an imposter node stands for (none for SimplifiedPolygon).
bool impostorKindOf(scene::NodeKind kind, bool& simple) {
  simple = kind == scene::NodeKind::kSimpleImposter;
  return kind == scene::NodeKind::kSimpleImposter || kind == scene::NodeKind::kMeshedImposter;
}

// Options of one object shown through an imposter node of `kind` (alone, not
// an LOD level): its full representation and the node's kind.
void offerFromImposterNode(ObjectRecord& record, const scene::NodeInstance& instance) {
  bool simple = false;
  const bool impostor = impostorKindOf(instance.node->kind, simple);
  const auto* node = static_cast<const scene::ImposterNode*>(instance.node);
  const KindOffer offer = explicitKind(ConicRange(), node, instance.contentToWorld);
  record.meshedImpostor = impostor && !simple ? offer : notOffered();
  record.simpleImpostor = impostor && simple ? offer : notOffered();
}

}  // namespace

Result<ConvertedScene> convertScene(const scene::Scene& sceneGraph,
                                    const std::vector<scene::SceneObject>& objects) {
  const std::vector<scene::NodeInstance> instances = scene::flattenInstances(sceneGraph);
  const std::size_t n = instances.size();
  // Objects of each instance: one, or a region Shape's N (scene_objects.h).
  std::vector<std::vector<std::uint32_t>> objectsOfInstance(n);
  for (std::size_t k = 0; k < objects.size(); ++k) {
    if (objects[k].id != k + 1)
      return Status(ErrorCode::kInvalidArgument,
                    "scene objects must be numbered 1..n in order (collectSceneObjects)");
    if (objects[k].instance < 0 || static_cast<std::size_t>(objects[k].instance) >= n)
      return Status(ErrorCode::kInvalidArgument, "scene object instance out of range");
    objectsOfInstance[objects[k].instance].push_back(static_cast<std::uint32_t>(k));
  }
  // Pre-order: the subtree of instance i is [i, subtreeEnd[i]).
  std::vector<std::size_t> subtreeEnd(n);
  for (std::size_t i = 0; i < n; ++i) subtreeEnd[i] = i + 1;
  for (std::size_t j = n; j-- > 0;) {
    const int p = instances[j].parent;
    if (p >= 0) subtreeEnd[p] = std::max(subtreeEnd[p], subtreeEnd[j]);
  }
  auto objectsBelow = [&](std::size_t i) {
    std::vector<std::uint32_t> below;
    for (std::size_t j = i; j < subtreeEnd[i]; ++j)
      below.insert(below.end(), objectsOfInstance[j].begin(), objectsOfInstance[j].end());
    return below;
  };

  ConvertedScene out;
  std::vector<TreeNode> tree(1);  // root group
  // Tree node that an instance's descendants attach to; for LOD instances
  // the LOD node itself (its child instances become level groups).
  std::vector<int> owner(n, 0);
  std::vector<int> levelsSeen(n, 0);
  std::vector<bool> meshOnly(n, false);  // below a SimplifiedPolygon of several objects
  std::uint32_t clusterCount = 0;

  auto plainRecord = [&](std::uint32_t k) {
    const scene::SceneObject& object = objects[k];
    ObjectRecord record;
    record.id = object.id;
    record.object = &object;
    record.members = {object.id};
    record.primitive =
        object.shape != nullptr && object.shape->geometry.kind == scene::GeometryKind::kPrimitive;
    record.fullTriangles = static_cast<double>(object.fullMesh->triangleCount());
    record.worldBoxDiagonal = object.worldBounds.diagonal();
    return record;
  };
  auto addLeaf = [&](int container, ObjectRecord record, const BoundingSphere& sphere) {
    const int leaf = addChild(tree, container, SceneNodeKind::kLeaf, ConicRange());
    tree[leaf].object = static_cast<std::uint32_t>(out.records.size());
    const double radius = std::max<double>(sphere.radius, 1e-9);
    tree[leaf].bounds = {glm::dvec3(sphere.center), radius};
    out.records.push_back(std::move(record));
  };
  auto levelRange = [&](std::size_t levelInstance) {
    const int parent = instances[levelInstance].parent;
    const auto* lod = instances[parent].node->as<scene::LodNode>();
    int level = 0;
    for (std::size_t j = static_cast<std::size_t>(parent) + 1; j < levelInstance;
         j = subtreeEnd[j])
      ++level;
    ConicRange range;
    if (lod != nullptr && level < static_cast<int>(lod->ranges.size()))
      range = rangeToWorld(lod->ranges[level], instances[parent].contentToWorld);
    return range;
  };

  // Figure 10: every level of the LOD at `i` is the same Shape under the
  // same transform (itself, a Transform / Group nest around it, or the one object of an imposter node). Fills
  // `record` (the first level's object, one option kind per level).
  auto collapseLod = [&](std::size_t i, ObjectRecord& record) -> bool {
    std::vector<std::size_t> levels;
    for (std::size_t j = i + 1; j < subtreeEnd[i]; j = subtreeEnd[j]) levels.push_back(j);
    if (levels.size() < 2) return false;
    const scene::ShapeNode* shape = nullptr;
    glm::mat4 transform(1.0f);
    int first = -1;
    for (std::size_t j : levels) {
      // A level is one object: the Shape itself, a Transform / Group nest
      // around it (the full representation), or an imposter node over it.
      const std::vector<std::uint32_t> below = objectsBelow(j);
      if (below.size() != 1) return false;
      for (std::size_t k = j + 1; k < subtreeEnd[j]; ++k) {
        const scene::NodeKind kind = instances[k].node->kind;
        if (kind == scene::NodeKind::kLod || scene::isImposterKind(kind)) return false;
      }
      const int object = static_cast<int>(below[0]);
      const scene::SceneObject& o = objects[static_cast<std::size_t>(object)];
      if (shape == nullptr) {
        shape = o.shape;
        transform = o.objectToWorld;
        first = object;
      } else if (o.shape != shape || !sameTransform(o.objectToWorld, transform)) {
        return false;
      }
    }
    record = plainRecord(static_cast<std::uint32_t>(first));
    record.mesh = notOffered();
    record.meshedImpostor = notOffered();
    record.simpleImpostor = notOffered();
    // The first level that names a kind decides its range.
    for (std::size_t j : levels) {
      const ConicRange range = levelRange(j);
      const scene::NodeKind kind = instances[j].node->kind;
      KindOffer* offer = kind == scene::NodeKind::kSimpleImposter   ? &record.simpleImpostor
                         : kind == scene::NodeKind::kMeshedImposter ? &record.meshedImpostor
                                                                    : &record.mesh;
      if (offer->offered) continue;
      *offer = explicitKind(range,
                            scene::isImposterKind(kind)
                                ? static_cast<const scene::ImposterNode*>(instances[j].node)
                                : nullptr,
                            instances[j].contentToWorld);
      if (offer == &record.mesh) offer->explicitNode = false;
    }
    return true;
  };

  std::vector<bool> handled(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    if (handled[i]) continue;
    const scene::NodeInstance& inst = instances[i];
    int container = inst.parent < 0 ? 0 : owner[inst.parent];
    if (inst.parent >= 0) meshOnly[i] = meshOnly[inst.parent];
    if (inst.parent >= 0 && instances[inst.parent].node->kind == scene::NodeKind::kLod) {
      const auto* lod = instances[inst.parent].node->as<scene::LodNode>();
      const int level = levelsSeen[inst.parent]++;
      ConicRange range;
      if (lod != nullptr && level < static_cast<int>(lod->ranges.size()))
        range = rangeToWorld(lod->ranges[level], instances[inst.parent].contentToWorld);
      container = addChild(tree, container, SceneNodeKind::kGroup, range);
    }
    owner[i] = container;
    auto markSubtree = [&]() {
      for (std::size_t j = i; j < subtreeEnd[i]; ++j) handled[j] = true;
    };
    if (inst.node->kind == scene::NodeKind::kLod) {
      ObjectRecord record;
      if (collapseLod(i, record)) {
        const BoundingSphere sphere = record.object->worldSphere;
        addLeaf(container, std::move(record), sphere);
        ++out.collapsedLods;
        markSubtree();
        continue;
      }
      owner[i] = addChild(tree, container, SceneNodeKind::kLod, ConicRange());
      ++out.lodNodes;
      continue;
    }
    if (scene::isImposterKind(inst.node->kind) && !meshOnly[i]) {
      const std::vector<std::uint32_t> below = objectsBelow(i);
      const auto* imposter = static_cast<const scene::ImposterNode*>(inst.node);
      bool simple = false;
      const bool impostor = impostorKindOf(inst.node->kind, simple);
      if (below.size() == 1) {
        ObjectRecord record = plainRecord(below[0]);
        offerFromImposterNode(record, inst);
        record.imposterNode = imposter;
        const BoundingSphere sphere = record.object->worldSphere;
        addLeaf(container, std::move(record), sphere);
        ++out.imposterLeaves;
        markSubtree();
        continue;
      }
      if (below.size() > 1 && !impostor) {
        meshOnly[i] = true;  // SimplifiedPolygon: transparent, mesh kinds only
        continue;
      }
      // An LOD inside: its levels are alternatives, not objects to show
      // together, so the node stays transparent (no cluster of them yet).
      bool lodInside = false;
      for (std::size_t j = i + 1; j < subtreeEnd[i]; ++j)
        lodInside = lodInside || instances[j].node->kind == scene::NodeKind::kLod;
      if (below.size() > 1 && !lodInside) {
        // LOD { Group { the objects, mesh kinds only }, cluster impostor }.
        const int lodNode = addChild(tree, container, SceneNodeKind::kLod, ConicRange());
        const int full = addChild(tree, lodNode, SceneNodeKind::kGroup, ConicRange());
        std::vector<BoundingSphere> spheres;
        Bounds box;
        ObjectRecord cluster = plainRecord(below[0]);
        cluster.members.clear();
        cluster.fullTriangles = 0.0;
        for (std::uint32_t k : below) {
          ObjectRecord member = plainRecord(k);
          member.meshedImpostor = notOffered();
          member.simpleImpostor = notOffered();
          spheres.push_back(objects[k].worldSphere);
          box.extend(objects[k].worldBounds.min);
          box.extend(objects[k].worldBounds.max);
          cluster.members.push_back(objects[k].id);
          cluster.fullTriangles += member.fullTriangles;
          addLeaf(full, std::move(member), objects[k].worldSphere);
        }
        cluster.id = objects.size() + 1 + clusterCount++;
        cluster.cluster = true;
        cluster.primitive = false;
        cluster.imposterNode = imposter;
        cluster.worldBoxDiagonal = box.diagonal();
        cluster.mesh = notOffered();
        offerFromImposterNode(cluster, inst);
        addLeaf(lodNode, std::move(cluster), enclosingSphere(spheres));
        ++out.clusters;
        markSubtree();
        continue;
      }
    }
    // Each object is a leaf: a region Shape's regions are leaves side by side.
    for (std::uint32_t k : objectsOfInstance[i]) {
      ObjectRecord record = plainRecord(k);
      if (meshOnly[i]) {
        record.meshedImpostor = notOffered();
        record.simpleImpostor = notOffered();
      }
      const BoundingSphere sphere = record.object->worldSphere;
      addLeaf(container, std::move(record), sphere);
    }
  }
  computeBounds(tree, 0);
  if (!tree[0].hasLeaves) tree[0].bounds = {glm::dvec3(0.0), 1.0};
  placeEmpty(tree, 0, tree[0].bounds);

  std::vector<std::uint32_t> leafOfRecord(out.records.size(), 0);
  layout(tree, 0, out.scheduling, leafOfRecord);
  out.scheduling.objects.resize(out.records.size());
  for (std::size_t k = 0; k < out.records.size(); ++k) {
    ObjectRecord& record = out.records[k];
    out.scheduling.objects[k].externalId = record.id;
    record.leafNode = leafOfRecord[k];
    record.bounds = out.scheduling.nodes[record.leafNode].bounds;
    record.diameter = 2.0 * record.bounds.radius;
  }
  return out;
}

}  // namespace thinlod::backbone_daemon
