// Options of the time-critical (Gobbetti-Bouvier) scheduler, apart from its
// factory so SchedulerOptions can hold them (time_critical_scheduler.h has
// the contract).
#pragma once

#include <optional>
#include <vector>

#include "thinlod/common/core/frame_cost.h"
#include "thinlod/common/core/status.h"

namespace thinlod::backbone {

struct TimeCriticalConfig {
  std::optional<double> frameBudgetSeconds;  // set: frame-time mode
  FrameCostConstants costs;                  // frame-time mode: the calibrated constants
  double reserveSeconds = 0.0;   // fixed worst-case allowance for the system (paper 4.1)
  double viewportWidth = 640.0;  // pixels, for N_pix
  double viewportHeight = 480.0;
  double exponent = 1.0;  // k of the degradation s_i w_i / r_i^k
  // Reddy acuity from eccentricity and apparent speed; angles on screen are
  // converted to visual degrees by this factor (physical field of view of
  // the display / rendering field of view; 1 = the display fills the view).
  bool useAcuity = true;
  double visualDegreesPerViewDegree = 1.0;
  std::vector<double> objectImportance;  // w_s by object index; missing entries are 1
  // Hysteresis (not in the paper): the frontend's copy of an object is kept
  // while it fits the object's allowance r * T_max and reaches at least
  // 1 / (1 + share) of the accuracy the best candidate within it would; 0:
  // always switch to the best (the paper's behaviour).
  double keepCopyAccuracyShare = 0.15;
  int maxIterations = 10000;      // optimiser iteration cap per step
  double timeBoxSeconds = 0.005;  // optimiser time box per step (any-time)
};
Status validateTimeCriticalConfig(const TimeCriticalConfig& config);

}  // namespace thinlod::backbone
