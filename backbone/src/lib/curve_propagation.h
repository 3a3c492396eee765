// Hierarchical accuracy-curve propagation for one resource (private).
//
// evaluateRoot() builds the absolute curve of the root: Group = sum, LOD =
// lower envelope over levels whose range holds the reach ball, leaves = the
// lower envelope of their candidates converted with D / diameter. A fully
// visible group with D >= mergeDistanceFactor * diameter is converted once
// from the relative curve of its subtree (paper 3.4), which is cached and
// reused while the predicted region stays inside the (grown) region it was
// computed for. pushDown() then hands the target down the same structure and
// picks one candidate per visible leaf; the cost of every pick is at most
// what the root curve charged for it, so the root budget test holds for the
// plan.
#pragma once

#include <vector>

#include "selection.h"

namespace thinlod::backbone {

enum class Resource : std::uint8_t { kTriangles = 0, kLink = 1 };

class CurvePropagator {
 public:
  CurvePropagator(const SchedulingScene& scene, const SchedulerConfig& config,
                  const PredictedRegion& region, PlannerStateImpl& state, Resource resource,
                  PlanStats& stats);

  const AccuracyCurve& evaluateRoot();
  void pushDown(double targetAccuracy, std::vector<LeafSelection>& out);

 private:
  struct Slack {
    double distance = 0.0;
    double angle = 0.0;
  };

  const AccuracyCurve& evaluateAbsolute(std::uint32_t n, bool parentInside);
  const AccuracyCurve& evaluateRelative(std::uint32_t n, const PredictedRegion& computeRegion,
                                        Slack& slack);
  AccuracyCurve leafRelativeCurve(std::uint32_t n, const PredictedRegion& region,
                                  CandidateContext context);
  void pushAbsolute(std::uint32_t n, double accuracy);
  void pushRelative(std::uint32_t n, double relativeAccuracy, double absoluteAccuracy);
  // Reference path: decides the leaf now, in tree order.
  void chooseLeaf(std::uint32_t n, double absoluteAccuracy, double relativeCap);
  // reuseLeafWork: keeps the leaf's slot in tree order and decides it later,
  // in object order (the scene's objects and options are then read nearly
  // sequentially instead of at random; the decision itself is the same).
  void deferLeaf(std::uint32_t n, double absoluteAccuracy, double relativeCap);
  void decideDeferredLeaves();
  // `evaluated`: the leaf's exact candidates from this evaluation, or null.
  LeafSelection decideLeaf(std::uint32_t n, std::uint32_t object, const Sphere& bounds,
                           double absoluteAccuracy, double relativeCap,
                           const EvaluatedCandidates::Span* evaluated);
  const EvaluatedCandidates::Span* evaluatedSpan(std::uint32_t n) const;
  LeafSelection unrenderedLeaf(std::uint32_t n) const;
  void reportUnrenderable(std::uint32_t n);
  // Appends a selection and, when reusing leaf work, its candidates.
  void emit(const LeafSelection& selection, const std::vector<LeafCandidate>* candidates);

  const SchedulingScene& scene_;
  const SchedulerConfig& config_;
  const PredictedRegion& region_;
  PlannerStateImpl& state_;
  ResourceCache& cache_;
  Resource resource_;
  PlanStats& stats_;
  std::vector<LeafCandidate> scratch_;
  std::vector<LeafSelection>* out_ = nullptr;
};

}  // namespace thinlod::backbone
