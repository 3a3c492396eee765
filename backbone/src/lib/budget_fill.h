// Budget fill (private): after the accuracy-curve method has fixed the
// uniform target and picked the cheapest representation meeting it for every
// leaf, spend what is left of the hard budget where the image gains most
// (docs/scheduling.md, "Budget fill").
//
// Contract:
// - fillByGain (pure core): each item lists ways to show one object, each
//   with an image error (lower is better) and its costs; `current` is the
//   pick at the target. Every option the caller lists must already meet the
//   target (the core never checks accuracies, only errors and costs). The
//   result moves an item only to an option with a lower error, and the sum
//   of the chosen options' costs never exceeds the caps (when the current
//   picks already exceed a cap, nothing moves). Deterministic: ties keep
//   item and option order. O(items * options^2) worst case.
// - fillRemainingBudget (adapter): builds the items from the selections and
//   each leaf's candidates (copies at their accuracy, new representations
//   on a fixed ladder of triangle counts), runs the core, and rewrites the
//   selections it upgraded. Only objects that already show something at the
//   frontend are raised (a first representation stays the cheapest, so it
//   arrives soonest). No selection ends below its `need` (the target
//   in its frame); the selections stay within `hard` (checked on the
//   selections themselves; on any rounding overshoot the fill is undone).
#pragma once

#include <cstdint>
#include <vector>

#include "joint_solver.h"
#include "scheduler_common.h"
#include "selection.h"

namespace thinlod::backbone {

struct FillOption {
  double error = 0.0;  // image error, >= 0 (lower is better)
  double triangles = 0.0;
  double linkBytes = 0.0;
  // The error reduction moving to this option is worth this much (0..1]: a
  // representation still to be generated may arrive late, so its gain is
  // discounted against a copy that is already there.
  double gainScale = 1.0;
};

struct FillItem {
  std::vector<FillOption> options;
  std::size_t current = 0;  // index into options: the pick at the target
};

struct FillCaps {
  bool useTriangles = false;
  bool useLink = false;
  double triangles = 0.0;
  double linkBytes = 0.0;
};

// How stalled items (no upgrade fits) are re-checked when an upgrade frees
// room. kEveryStalled: all of them after any cheaper move (the reference,
// O(stalled) per such move: 13-15 s steps at 10^5 objects). kIndexed: only
// after room grows in a capped resource, and only the items whose least
// extra cost now fits (a min-heap; same choices, docs/scheduling.md).
enum class FillRetry : std::uint8_t { kIndexed = 0, kEveryStalled = 1 };

// The same items in one pool (no allocation per item): item i owns
// options[begin[i], begin[i + 1]); current[i] indexes its own options.
struct FillItems {
  std::vector<FillOption> options;
  std::vector<std::uint32_t> begin{0};
  std::vector<std::size_t> current;

  std::size_t size() const { return current.size(); }
  void clear() {
    options.clear();
    begin.assign(1, 0);
    current.clear();
  }
  void add(const FillOption* first, std::size_t count, std::size_t currentOption) {
    options.insert(options.end(), first, first + count);
    begin.push_back(static_cast<std::uint32_t>(options.size()));
    current.push_back(currentOption);
  }
};

// Chosen option index per item (same order as `items`); identical for both
// FillRetry values and both layouts.
std::vector<std::size_t> fillByGain(const FillItems& items, const FillCaps& caps,
                                    FillRetry retry = FillRetry::kIndexed);
std::vector<std::size_t> fillByGain(const std::vector<FillItem>& items, const FillCaps& caps,
                                    FillRetry retry = FillRetry::kIndexed);

// Image error of showing a leaf at relative accuracy `frameAccuracy` (leaf
// frame, relative to the diameter): the silhouette length in radians
// (~ diameter / distance) times the angular error (1 / absolute accuracy =
// diameter / (frameAccuracy * distance)), times `onScreen` (time-on-screen
// weight): onScreen * (diameter / distance)^2 / frameAccuracy; plus, with
// `shadingWeight` (SchedulerConfig::fillShadingWeight), shadingWeight /
// sqrt(frameAccuracy) per projected area for the shading of faceted curved
// surfaces.
double fillImageError(double diameter, double distance, double frameAccuracy, double onScreen,
                      double shadingWeight = 0.0);
// The shading weight for a representation kind: `weight` for meshes (original,
// simplified, hybrid), 0 for impostors, whose texture carries the shading.
double fillShadingWeight(OptionKind kind, double weight);

// Triangle counts of the ladder on which new representations are offered:
// t_0 = 1, t_{k+1} = max(t_k + 1, floor(kFillLadderStep * t_k)) up to `limit`
// (1..40 one by one, then about 5 % apart).
// Fixed (not relative to the current pick) so an object asks for the same
// counts from step to step and outstanding requests are re-labelled rather
// than superseded (docs/backbone.md, "One pose").
inline constexpr double kFillLadderStep = 1.05;
std::vector<double> fillTriangleLadder(double limit);

struct FillOutcome {
  std::uint32_t upgraded = 0;  // selections changed
  double trianglesBefore = 0.0;
  double trianglesAfter = 0.0;
};

// See the contract above. `viewer` gives the time-on-screen weight (objects
// outside the current view cone count kOffScreenWeight).
FillOutcome fillRemainingBudget(const SchedulingScene& scene, const SchedulerConfig& config,
                                const ViewerState& viewer, const PredictedRegion& region,
                                PlannerStateImpl& state, const JointBudget& hard,
                                std::vector<LeafSelection>& selections);

// Rungs offered per new representation, from the pick's triangle count up
// (24 rungs: 24 more triangles, or about 3.2x, whichever is more), plus the
// representation's top when it fits: a step raises a leaf at most that far.
inline constexpr int kMaxFillRungs = 24;
inline constexpr double kNewGenerationGainScale = 0.8;

}  // namespace thinlod::backbone
