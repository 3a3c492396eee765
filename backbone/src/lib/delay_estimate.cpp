#include "thinlod/backbone/delay_estimate.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace thinlod::backbone {

Status DelayEstimate::validate(const Options& o) {
  auto bad = [](const std::string& what) {
    return Status(ErrorCode::kInvalidArgument, "delay estimate: " + what);
  };
  if (o.window < 1 || o.minSamples < 1 || o.minSamples > o.window)
    return bad("window and minSamples must be >= 1 with minSamples <= window");
  if (!(o.quantile > 0.0 && o.quantile <= 1.0)) return bad("quantile must be in (0, 1]");
  if (!(o.ratio > 1.0) || !std::isfinite(o.ratio)) return bad("ratio must be finite and > 1");
  if (!(o.minStep > 0.0) || !std::isfinite(o.minStep)) return bad("minStep must be finite and > 0");
  if (!(o.maxSeconds > 0.0) || !std::isfinite(o.maxSeconds))
    return bad("maxSeconds must be finite and > 0");
  return Status();
}

bool DelayEstimate::observe(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) return false;
  observed_.push_back(seconds);
  while (observed_.size() > options_.window) observed_.pop_front();
  return true;
}

double DelayEstimate::rawQuantile() const {
  if (observed_.empty()) return 0.0;
  std::vector<double> sorted(observed_.begin(), observed_.end());
  const std::size_t n = sorted.size();
  // Nearest rank: the ceil(q n)-th smallest (1-based), at least the first.
  const auto rank = static_cast<std::size_t>(std::ceil(options_.quantile * double(n)));
  const std::size_t index = std::min(n, std::max<std::size_t>(rank, 1)) - 1;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(index),
                   sorted.end());
  return sorted[index];
}

double DelayEstimate::estimate(double floor) const {
  const double lowest = std::isfinite(floor) && floor > 0.0 ? floor : 0.0;
  if (observed_.size() < options_.minSamples) return lowest;
  const double q = rawQuantile();
  if (q <= lowest) return lowest;
  // Up onto base x ratio^k: the first grid point at or above q, at most
  // maxSeconds, never below the floor (std::clamp would be undefined for a
  // floor above maxSeconds).
  const double base = lowest > 0.0 ? lowest : options_.minStep;
  double value = base;
  while (value < q && value < options_.maxSeconds) value *= options_.ratio;
  return std::max(lowest, std::min(value, options_.maxSeconds));
}

}  // namespace thinlod::backbone
