// Cuts through the hybrid graph and its units-vs-error curve (see
// hybrid_graph.h). A node may be applied only when every primitive it
// consumes is in the cut (all its children are applied), and unapplied only
// when every primitive it produced is in the cut (no parent is applied).
// Node errors and spheres are monotone towards the source, so "allowed" is
// closed under children and the fixpoint reached from any previous cut is the
// set of allowed nodes.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <unordered_map>

#include "thinlod/simplifier/hybrid_graph.h"

namespace thinlod::simplifier {

double HybridGraph::unitsRemovedBy(std::uint32_t node) const {
  const HybridNode& n = nodes_[node];
  double units = 0.0;
  for (std::uint32_t i = n.consumedBegin; i < n.consumedEnd; ++i) {
    units += primitiveUnits(primitives_[consumed_[i]]);
  }
  for (std::uint32_t i = n.producedBegin; i < n.producedEnd; ++i) {
    units -= primitiveUnits(primitives_[produced_[i]]);
  }
  return units;
}

std::vector<HybridCurveStep> HybridGraph::unitsVersusError() const {
  std::vector<std::uint32_t> order;
  for (std::uint32_t n = 1; n + 1 < nodes_.size(); ++n) order.push_back(n);
  std::stable_sort(order.begin(), order.end(), [this](std::uint32_t a, std::uint32_t b) {
    return nodes_[a].error < nodes_[b].error;
  });
  std::vector<HybridCurveStep> steps;
  HybridCurveStep current;
  current.triangles = stats_.inputTriangles;
  current.units = static_cast<double>(stats_.inputTriangles);
  steps.push_back(current);
  // Counts are exact integers; units are recomputed from them (no drift).
  for (std::size_t i = 0; i < order.size(); ++i) {
    const HybridNode& n = nodes_[order[i]];
    for (std::uint32_t k = n.consumedBegin; k < n.consumedEnd; ++k) {
      if (primitives_[consumed_[k]].kind == HybridPrimitiveKind::kTriangle) {
        --current.triangles;
      } else {
        --current.points;
      }
    }
    for (std::uint32_t k = n.producedBegin; k < n.producedEnd; ++k) {
      if (primitives_[produced_[k]].kind == HybridPrimitiveKind::kTriangle) {
        ++current.triangles;
      } else {
        ++current.points;
      }
    }
    if (i + 1 < order.size() && nodes_[order[i + 1]].error == n.error) continue;
    current.error = n.error;
    current.units =
        static_cast<double>(current.triangles) + static_cast<double>(current.points) / kappa_;
    if (current.error == steps.back().error) {
      steps.back() = current;
    } else {
      steps.push_back(current);
    }
  }
  return steps;
}

Result<AccuracyCurve> hybridAccuracyCurve(const HybridGraph& graph, double minRelativeError,
                                          int maxSegments) {
  if (!(minRelativeError > 0.0) || !(graph.diagonal() > 0.0)) {
    return Status(ErrorCode::kInvalidArgument,
                  "hybridAccuracyCurve: minRelativeError and the diagonal must be > 0");
  }
  std::vector<AccuracySample> samples;
  const double floor = minRelativeError * graph.diagonal();
  for (const HybridCurveStep& s : graph.unitsVersusError()) {
    samples.push_back({graph.diagonal() / std::max(s.error, floor), s.units});
  }
  return AccuracyCurve::fitConservative(std::move(samples), maxSegments);
}

HybridCut::HybridCut(const HybridGraph& graph)
    : graph_(&graph), applied_(graph.nodes().size(), 0), slot_(graph.primitives().size(), kAbsent) {
  applied_[HybridGraph::kDrain] = 1;
  const HybridNode& drain = graph.nodes()[HybridGraph::kDrain];
  for (std::uint32_t i = drain.producedBegin; i < drain.producedEnd; ++i) {
    add(graph.producedList()[i]);
  }
}

void HybridCut::add(std::uint32_t primitive) {
  slot_[primitive] = static_cast<std::uint32_t>(cut_.size());
  cut_.push_back(primitive);
  if (graph_->primitives()[primitive].kind == HybridPrimitiveKind::kTriangle) ++triangles_;
}

void HybridCut::remove(std::uint32_t primitive) {
  const std::uint32_t slot = slot_[primitive];
  const std::uint32_t last = cut_.back();
  cut_[slot] = last;
  slot_[last] = slot;
  cut_.pop_back();
  slot_[primitive] = kAbsent;
  if (graph_->primitives()[primitive].kind == HybridPrimitiveKind::kTriangle) --triangles_;
}

template <typename Allowed>
void HybridCut::adapt(const Allowed& allowed) {
  const auto& nodes = graph_->nodes();
  const auto& prims = graph_->primitives();
  const auto& consumed = graph_->consumedList();
  const auto& produced = graph_->producedList();
  const std::uint32_t source = graph_->sourceNode();
  moved_ = 0;
  std::vector<std::uint32_t> work;
  // Coarser than allowed: unapply from the top of the applied set down.
  for (std::uint32_t p : cut_) {
    const std::uint32_t n = prims[p].producer;
    if (n != HybridGraph::kDrain && !allowed(n)) work.push_back(n);
  }
  while (!work.empty()) {
    const std::uint32_t n = work.back();
    work.pop_back();
    if (!applied_[n] || allowed(n)) continue;
    const HybridNode& node = nodes[n];
    bool top = true;
    for (std::uint32_t i = node.producedBegin; i < node.producedEnd && top; ++i) {
      top = contains(produced[i]);
    }
    if (!top) continue;  // a parent is still applied; it comes first
    for (std::uint32_t i = node.producedBegin; i < node.producedEnd; ++i) remove(produced[i]);
    for (std::uint32_t i = node.consumedBegin; i < node.consumedEnd; ++i) {
      add(consumed[i]);
      const std::uint32_t child = prims[consumed[i]].producer;
      if (child != HybridGraph::kDrain && !allowed(child)) work.push_back(child);
    }
    applied_[n] = 0;
    ++moved_;
  }
  // Finer than needed: apply nodes whose children are all applied.
  for (std::uint32_t p : cut_) {
    const std::uint32_t n = prims[p].consumer;
    if (n != source && allowed(n)) work.push_back(n);
  }
  while (!work.empty()) {
    const std::uint32_t n = work.back();
    work.pop_back();
    if (applied_[n] || !allowed(n)) continue;
    const HybridNode& node = nodes[n];
    bool ready = true;
    for (std::uint32_t i = node.consumedBegin; i < node.consumedEnd && ready; ++i) {
      ready = contains(consumed[i]);
    }
    if (!ready) continue;  // a child is not applied yet; it will push n
    for (std::uint32_t i = node.consumedBegin; i < node.consumedEnd; ++i) remove(consumed[i]);
    for (std::uint32_t i = node.producedBegin; i < node.producedEnd; ++i) {
      add(produced[i]);
      const std::uint32_t parent = prims[produced[i]].consumer;
      if (parent != source && allowed(parent)) work.push_back(parent);
    }
    applied_[n] = 1;
    ++moved_;
  }
}

void HybridCut::adaptToError(double maxError) {
  const auto& nodes = graph_->nodes();
  adapt([&nodes, maxError](std::uint32_t n) { return nodes[n].error <= maxError; });
}

void HybridCut::adaptToScreen(const HybridView& view, double tolerancePixels) {
  const auto& nodes = graph_->nodes();
  const double nearDistance = view.nearDistance > 0.0 ? view.nearDistance : 1e-9;
  adapt([&](std::uint32_t n) {
    const HybridNode& node = nodes[n];
    // Distance to the node's sphere: nested spheres make it non-increasing
    // towards the source, so the pixel error is non-decreasing.
    const double z =
        std::max(glm::length(node.sphereCentre - view.eye) - node.sphereRadius, nearDistance);
    return node.error * view.pixelsPerRadian / z <= tolerancePixels;
  });
}

double HybridCut::units() const {
  return static_cast<double>(triangleCount()) + static_cast<double>(pointCount()) / graph_->kappa();
}

double HybridCut::errorBound() const {
  double bound = 0.0;
  for (std::uint32_t p : cut_) bound = std::max(bound, graph_->primitives()[p].error);
  return bound;
}

IndexedMesh HybridCut::triangleMesh() const {
  IndexedMesh mesh;
  std::unordered_map<std::uint32_t, std::uint32_t> vertexIndex;
  const auto& vertices = graph_->vertices();
  const auto& colors = graph_->vertexColors();
  for (std::uint32_t p : cut_) {
    const HybridPrimitive& prim = graph_->primitives()[p];
    if (prim.kind != HybridPrimitiveKind::kTriangle) continue;
    for (std::uint32_t v : graph_->triangles()[prim.index]) {
      auto [it, inserted] =
          vertexIndex.emplace(v, static_cast<std::uint32_t>(mesh.positions.size()));
      if (inserted) {
        mesh.positions.emplace_back(vertices[v]);
        if (!colors.empty()) mesh.colors.push_back(colors[v]);
      }
      mesh.indices.push_back(it->second);
    }
  }
  return mesh;
}

std::vector<HybridPoint> HybridCut::pointList() const {
  std::vector<HybridPoint> points;
  for (std::uint32_t p : cut_) {
    const HybridPrimitive& prim = graph_->primitives()[p];
    if (prim.kind == HybridPrimitiveKind::kPoint) points.push_back(graph_->points()[prim.index]);
  }
  return points;
}

HybridGeometry hybridGeometry(const HybridCut& cut) {
  HybridGeometry out;
  out.triangles = cut.triangleMesh();
  const std::vector<HybridPoint> points = cut.pointList();
  out.points.centres.reserve(points.size());
  out.points.normals.reserve(points.size());
  out.points.radii.reserve(points.size());
  out.points.colors.reserve(points.size());
  for (const HybridPoint& p : points) {
    out.points.centres.emplace_back(p.centre);
    out.points.normals.emplace_back(p.normal);
    out.points.radii.push_back(static_cast<float>(p.radius));
    out.points.colors.push_back(p.color);
  }
  return out;
}

}  // namespace thinlod::simplifier
