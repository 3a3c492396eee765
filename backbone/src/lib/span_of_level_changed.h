// Span-of-level-changed LOD selection (Yu, Liang & Chen, "A Level of Detail
// Selection Method for Multi-Type Objects Based on The Span of Level
// Changed"), private and pure.
//
// Contract:
// - Level of a representation with M faces: l = round(log2 M) (the paper's
//   eq. 1 is garbled in our copy; its worked example, 5000 faces -> 12 and
//   2000 -> 11, fixes it as round half up). Fewer than one face is level 0.
// - SLC of a change from level i to level j: max(l_i, l_j) * |l_i - l_j|
//   (eq. 2). Importance of an object's next change (eq. 6):
//   f = d * SLC(current, next coarser) / S, S = PA / PA_smallest (eq. 5) and
//   d = D_nearest / D (eq. 4, kNearestFirst, literal: the NEAREST objects get
//   the largest f and are coarsened first) or its inverse D / D_nearest
//   (kFarthestFirst, an option of ours).
// - Selection (Fig. 3): every object starts at its finest level; while the
//   budget (eq. 3: sum 2^l_i <= M with kPowerOfTwo, or sum of real triangles
//   with kTriangles) is exceeded, the object on top of a max-heap of f drops
//   one level, its f is recomputed, and an object at its coarsest level leaves
//   the heap. budgetMet = false when every object is at its coarsest and the
//   budget still does not hold. Ties: lower object index first.
// - O(m) heap build, O(log m) per change (heap comparisons are counted).
// - Errors: kInvalidArgument for empty level lists, levels outside [0, 62] or
//   not strictly decreasing, triangles NaN/Inf/negative or increasing towards
//   coarser levels, distance or projected area not finite and > 0, budget NaN
//   or negative. No I/O, no globals.
#pragma once

#include <cstdint>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod::backbone {

// Precondition: faces finite and >= 0.
int levelOfFaces(double faces);
double spanOfLevelChanged(int fromLevel, int toLevel);

struct SlcLevel {
  int level = 0;
  double triangles = 0.0;  // real cost (used with SlcBudgetMeasure::kTriangles)
};

struct SlcObject {
  std::vector<SlcLevel> levels;  // finest first
  double distance = 1.0;         // D_current, > 0
  double projectedArea = 1.0;    // PA_current, > 0
};

enum class SlcDistanceRule : std::uint8_t {
  kNearestFirst = 0,   // the paper's d = D_nearest / D
  kFarthestFirst = 1,  // d = D / D_nearest
};
enum class SlcBudgetMeasure : std::uint8_t {
  kPowerOfTwo = 0,  // the paper's sum 2^l
  kTriangles = 1,   // sum of SlcLevel::triangles
};

struct SlcConfig {
  SlcDistanceRule distanceRule = SlcDistanceRule::kNearestFirst;
  SlcBudgetMeasure measure = SlcBudgetMeasure::kPowerOfTwo;
};

struct SlcSelection {
  std::vector<std::uint32_t> levelIndex;  // per object, into its levels
  double total = 0.0;                     // in the configured measure
  bool budgetMet = true;
  std::uint64_t changes = 0;  // one-level reductions
  std::uint64_t heapBuildComparisons = 0;
  std::uint64_t heapUpdateComparisons = 0;  // over all changes
  std::vector<std::uint32_t> changesPerObject;
  std::vector<double> spanPerObject;  // sum of the SLC of the object's changes
};

// Cost of one level in the configured measure.
double slcLevelCost(const SlcLevel& level, SlcBudgetMeasure measure);

Result<SlcSelection> selectBySpanOfLevelChanged(const std::vector<SlcObject>& objects,
                                                double budget, const SlcConfig& config);

}  // namespace thinlod::backbone
