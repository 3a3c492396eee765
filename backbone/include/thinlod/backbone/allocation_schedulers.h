// Two seed selection methods from other papers, as schedulers of the shared
// frame (docs/scheduling.md, "ASLOD allocation" and "Span of level changed").
//
// Contract:
// - Both need Budget::maxTriangles (kUnsupported otherwise) and keep the plan
//   within it: the least visible objects (smallest diameter / D) are dropped
//   when even the cheapest representations do not fit. A link budget on top
//   is enforced only by the frame's drop of the least visible objects.
// - Projected area: the solid angle of the object's bounding sphere seen from
//   the nearest point of the reach ball (a deviation: the papers use the
//   projected area of a tight oriented bounding box, which scenes here lack).
// - aslod (Schmalstieg-Fuhrmann): p_i = P w_i^(1/alpha) / sum w_j^(1/alpha),
//   clamped to what each object's candidates can use, rounded so sum p_i <= P,
//   with hysteresis epsilon = max(hysteresisTriangles, hysteresisShare *
//   previous); each object renders the most accurate candidate costing <= p_i.
// - span-of-level-changed (Yu-Liang-Chen): levels l = round(log2 triangles)
//   sampled from the candidates' curves at 2^l triangles, a max-heap of
//   f = d * SLC / S coarsening one level at a time until the real triangle sum
//   fits. d = D_nearest / D (the paper's, nearest first) or D / D_nearest
//   (coarsenFarthestFirst).
#pragma once

#include <memory>

#include "thinlod/backbone/pipeline.h"

namespace thinlod::backbone {

class Scheduler;

struct AslodSchedulerConfig {
  double alpha = 1.0;                // > 0; 1: proportional to area, 3: Funkhouser-Sequin
  double hysteresisTriangles = 0.0;  // epsilon, absolute
  double hysteresisShare = 0.05;     // epsilon, share of the previous allocation
};
Result<std::unique_ptr<Scheduler>> makeAslodScheduler(const SchedulerConfig& config,
                                                      const AslodSchedulerConfig& aslod);

struct SpanOfLevelChangedConfig {
  bool coarsenFarthestFirst = false;  // false: the paper's literal d = D_nearest / D
};
Result<std::unique_ptr<Scheduler>> makeSpanOfLevelChangedScheduler(
    const SchedulerConfig& config, const SpanOfLevelChangedConfig& slc);

}  // namespace thinlod::backbone
