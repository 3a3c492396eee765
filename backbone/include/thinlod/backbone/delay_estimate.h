// A measured delay for the prediction horizon: how long the simplifier takes
// to deliver what a plan asked for (issue 13: "plan for the delays that
// really happen"). The backbone observes each plan request's time from
// submission to result and plans with a high quantile of the recent ones
// instead of a fixed --generation-delay.
//
// Contract:
// - observe(seconds): one delivered request; a non-finite or negative value
//   is ignored (returns false). The last `window` observations are kept.
// - estimate(floor): the `quantile` of the kept observations (nearest rank:
//   the ceil(q n)-th smallest), rounded up onto the grid floor x ratio^k
//   (k = 0, 1, ...), at most maxSeconds and never below `floor` (the
//   configured delay, >= 0), which is also the estimate while fewer than
//   `minSamples` are kept. The grid
//   makes the horizon, and with it the scheduler's caches keyed by its
//   config, change only when the measurement moves by a grid step; a floor
//   of 0 uses minStep as the grid's base.
// - Options are checked by validate(): window and minSamples >= 1,
//   minSamples <= window, quantile in (0, 1], ratio > 1, minStep > 0,
//   maxSeconds > 0, all finite.
// - Pure, no clock: the caller measures.
#pragma once

#include <cstddef>
#include <deque>

#include "thinlod/common/core/status.h"

namespace thinlod::backbone {

class DelayEstimate {
 public:
  struct Options {
    std::size_t window = 32;
    std::size_t minSamples = 4;
    double quantile = 0.9;
    double ratio = 1.25;     // grid step
    double minStep = 0.01;   // s, the grid's base when the floor is 0
    double maxSeconds = 60;  // s
  };

  static Status validate(const Options& options);
  DelayEstimate() = default;
  explicit DelayEstimate(Options options) : options_(options) {}

  bool observe(double seconds);
  double estimate(double floor) const;
  std::size_t samples() const { return observed_.size(); }
  // The quantile of the kept observations, unrounded (0 when none).
  double rawQuantile() const;

 private:
  Options options_;
  std::deque<double> observed_;
};

}  // namespace thinlod::backbone
