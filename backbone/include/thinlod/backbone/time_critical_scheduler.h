// Time-critical scheduler (Gobbetti & Bouvier 1999): per-object resolutions
// r_i in (0, 1] chosen by the active-set optimiser to minimise the image
// degradation sum s_i w_i / r_i^k under a frame-time budget (the cost model
// t_init + t_final + sum t_setup + max(r T t_tri, N_pix t_pix), calibrated by
// frontend/bench/bench_calibrate) or under a polygon budget (t_tri = 1, all
// else 0). docs/scheduling.md, "Time-critical rendering".
//
// Contract:
// - Per visible leaf (an LOD resolves to its first eligible level, as for
//   greedy-fs93): T_max = triangles of its most accurate candidate; the floor
//   lo = max(cheapest candidate's triangles / T_max, r_fill); N_pix from the
//   bounding sphere seen from the near side of the predicted region; weight
//   = importance * Reddy acuity (eccentricity from the view direction,
//   apparent speed from the previous step's viewer) * N_pix / T_max.
//   The leaf then gets the most accurate candidate with at most r_i * T_max
//   triangles, so the modelled frame time (or the triangle count) stays
//   within the budget.
// - Budgets: frame-time mode when Budget::maxFrameSeconds (or, for tests,
//   TimeCriticalConfig::frameBudgetSeconds) is set; Budget::maxTriangles is
//   then an extra polygon cap (exact: both constraints are parallel, the
//   tighter binds). Otherwise polygon mode: Budget::maxTriangles is required. Link budgets
//   and fixed accuracies are kUnsupported. When even the floors do not fit, the least visible
//   objects are dropped (Plan::dropped) until they do.
// - Warm start: the previous step's resolutions (kept in the PlannerState).
// - Errors: invalid config is kInvalidArgument from the factory.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "thinlod/backbone/scheduler.h"
#include "thinlod/backbone/time_critical_config.h"

namespace thinlod::backbone {

// Registered as "active-set" (alias "time-critical") in the catalogue with a
// default TimeCriticalConfig (polygon mode).
Result<std::unique_ptr<Scheduler>> makeTimeCriticalScheduler(
    const SchedulerConfig& config, const TimeCriticalConfig& timeCritical);

}  // namespace thinlod::backbone
