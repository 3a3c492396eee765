#include "aslod_allocation.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace thinlod::backbone {
namespace {

// Whole triangle counts stay exact in a double up to 2^53.
constexpr double kMaxCount = 9007199254740992.0;

bool finiteNonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

// w_i^(1/alpha) up to one common factor: exp((log w_i - max log w) / alpha),
// which neither overflows for huge weights nor turns every share into 1 for
// huge alpha before the ratios are taken. Zero weights give 0.
std::vector<double> attenuatedShares(const std::vector<AslodObject>& objects, double alpha) {
  double maxLog = -std::numeric_limits<double>::infinity();
  for (const AslodObject& o : objects)
    if (o.weight > 0.0) maxLog = std::max(maxLog, std::log(o.weight));
  std::vector<double> shares(objects.size(), 0.0);
  for (std::size_t i = 0; i < objects.size(); ++i)
    if (objects[i].weight > 0.0)
      shares[i] = std::exp((std::log(objects[i].weight) - maxLog) / alpha);
  return shares;
}

// The lambda with sum_i clamp(lambda * s_i, lo_i, hi_i) = target, by a sweep
// over the breakpoints lo_i / s_i and hi_i / s_i (the sum is continuous,
// piecewise linear and non-decreasing in lambda).
// Precondition: sum lo <= target < sum hi.
double waterLevel(const std::vector<double>& shares, const std::vector<double>& lo,
                  const std::vector<double>& hi, double target) {
  struct Event {
    double lambda;
    std::size_t object;
    bool enters;  // lambda * s_i leaves lo_i here; otherwise it reaches hi_i
  };
  std::vector<Event> events;
  double base = 0.0;  // sum of the clamped objects' bounds at the current lambda
  for (std::size_t i = 0; i < shares.size(); ++i) {
    base += lo[i];
    if (shares[i] <= 0.0) continue;
    events.push_back({lo[i] / shares[i], i, true});
    events.push_back({hi[i] / shares[i], i, false});
  }
  std::sort(events.begin(), events.end(), [](const Event& a, const Event& b) {
    if (a.lambda != b.lambda) return a.lambda < b.lambda;
    return a.enters && !b.enters;
  });
  double active = 0.0;  // sum of s_i of objects strictly between their bounds
  for (const Event& e : events) {
    if (active > 0.0 && base + e.lambda * active >= target) return (target - base) / active;
    if (e.enters) {
      base -= lo[e.object];
      active += shares[e.object];
    } else {
      base += hi[e.object];
      active -= shares[e.object];
      if (active < 0.0) active = 0.0;
    }
  }
  // Only reachable through rounding: every object is at its maximum.
  return events.empty() ? 0.0 : events.back().lambda;
}

}  // namespace

Status validateAslodConfig(const AslodConfig& config) {
  if (!(std::isfinite(config.alpha) && config.alpha > 0.0))
    return Status(ErrorCode::kInvalidArgument, "AslodConfig.alpha must be finite and > 0");
  if (!finiteNonNegative(config.hysteresisTriangles))
    return Status(ErrorCode::kInvalidArgument,
                  "AslodConfig.hysteresisTriangles must be finite and >= 0");
  if (!finiteNonNegative(config.hysteresisShare))
    return Status(ErrorCode::kInvalidArgument,
                  "AslodConfig.hysteresisShare must be finite and >= 0");
  return Status::okStatus();
}

Result<AslodAllocation> allocateAslod(const std::vector<AslodObject>& objects, double budget,
                                      const AslodConfig& config) {
  THINLOD_RETURN_IF_ERROR(validateAslodConfig(config));
  if (!finiteNonNegative(budget))
    return Status(ErrorCode::kInvalidArgument, "ASLOD budget must be finite and >= 0");
  const std::size_t n = objects.size();
  std::vector<double> lo(n);
  std::vector<double> hi(n);
  double sumLo = 0.0;
  double sumHi = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const AslodObject& o = objects[i];
    const std::string at = "ASLOD object " + std::to_string(i) + ": ";
    if (!finiteNonNegative(o.weight))
      return Status(ErrorCode::kInvalidArgument, at + "weight must be finite and >= 0");
    if (!finiteNonNegative(o.minTriangles) || !finiteNonNegative(o.maxTriangles) ||
        o.maxTriangles > kMaxCount)
      return Status(ErrorCode::kInvalidArgument,
                    at + "triangle bounds must be finite, >= 0 and <= 2^53");
    if (o.minTriangles > o.maxTriangles)
      return Status(ErrorCode::kInvalidArgument, at + "minTriangles exceeds maxTriangles");
    lo[i] = std::ceil(o.minTriangles);
    hi[i] = std::ceil(o.maxTriangles);
    sumLo += lo[i];
    sumHi += hi[i];
  }
  if (sumHi > kMaxCount)
    return Status(ErrorCode::kInvalidArgument, "ASLOD: more than 2^53 triangles in total");
  const double cap = std::floor(std::min(budget, kMaxCount));
  if (sumLo > cap)
    return Status(ErrorCode::kResourceExhausted, "ASLOD: the cheapest representations need " +
                                                     std::to_string(sumLo) + " triangles, budget " +
                                                     std::to_string(cap));

  AslodAllocation result;
  const std::vector<double> shares = attenuatedShares(objects, config.alpha);
  // An object without share (zero weight, or w^(1/alpha) below the smallest
  // double next to the others) stays at its minimum: nothing is
  // redistributed to it, so budget the others cannot use stays unused.
  double usable = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (shares[i] <= 0.0) hi[i] = lo[i];
    usable += hi[i];
  }
  const double target = std::min(cap, usable);
  result.target = static_cast<std::int64_t>(target);
  const double shareSum = std::accumulate(shares.begin(), shares.end(), 0.0);
  result.paperShare.assign(n, 0.0);
  if (shareSum > 0.0)
    for (std::size_t i = 0; i < n; ++i) result.paperShare[i] = budget * shares[i] / shareSum;

  // Continuous allocation with clamping and redistribution.
  std::vector<double> exact(n);
  if (target >= usable) {
    exact = hi;
  } else {
    const double lambda = waterLevel(shares, lo, hi, target);
    for (std::size_t i = 0; i < n; ++i) exact[i] = std::clamp(lambda * shares[i], lo[i], hi[i]);
  }
  for (std::size_t i = 0; i < n; ++i) {
    result.clampedLow += exact[i] <= lo[i] && result.paperShare[i] < lo[i];
    result.clampedHigh += exact[i] >= hi[i] && result.paperShare[i] > hi[i];
  }

  // Largest remainder rounding to whole triangles summing to exactly target
  // (floating-point error in lambda is absorbed here: passes repeat until
  // the sum is exact; sumLo <= target <= sumHi makes that always possible).
  std::vector<std::int64_t> p(n);
  std::int64_t sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    p[i] = static_cast<std::int64_t>(std::clamp(std::floor(exact[i]), lo[i], hi[i]));
    sum += p[i];
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return exact[a] - std::floor(exact[a]) > exact[b] - std::floor(exact[b]);
  });
  // First pass: only objects with a fractional part (exact arithmetic needs
  // no more); later passes, if rounding left more, anyone below its maximum.
  for (std::size_t i : order) {
    if (sum >= result.target) break;
    if (exact[i] > std::floor(exact[i]) && static_cast<double>(p[i]) < hi[i]) {
      ++p[i];
      ++sum;
    }
  }
  // Rounding error in lambda only: fill (or trim) whole gaps, O(n).
  for (std::size_t i : order) {
    if (sum >= result.target) break;
    const std::int64_t room = static_cast<std::int64_t>(hi[i]) - p[i];
    const std::int64_t add = std::min(room, result.target - sum);
    p[i] += add;
    sum += add;
  }
  for (auto it = order.rbegin(); it != order.rend() && sum > result.target; ++it) {
    const std::int64_t room = p[*it] - static_cast<std::int64_t>(lo[*it]);
    const std::int64_t take = std::min(room, sum - result.target);
    p[*it] -= take;
    sum -= take;
  }

  // Hysteresis: hold the previous count within epsilon, undo raises while
  // the sum is above target.
  struct Held {
    std::size_t object;
    std::int64_t raise;  // previous - new (> 0: holding costs triangles)
  };
  std::vector<Held> held;
  std::vector<std::int64_t> fresh = p;
  for (std::size_t i = 0; i < n; ++i) {
    if (!objects[i].previous) continue;
    const std::int64_t prev = *objects[i].previous;
    if (static_cast<double>(prev) < lo[i] || static_cast<double>(prev) > hi[i]) continue;
    const double epsilon =
        std::max(config.hysteresisTriangles, config.hysteresisShare * static_cast<double>(prev));
    const std::int64_t delta = prev - p[i];
    if (delta == 0 || std::fabs(static_cast<double>(delta)) > epsilon) continue;
    held.push_back({i, delta});
    sum += delta;
    p[i] = prev;
  }
  std::stable_sort(held.begin(), held.end(),
                   [](const Held& a, const Held& b) { return a.raise > b.raise; });
  std::size_t undone = 0;
  for (const Held& h : held) {
    if (sum <= result.target || h.raise <= 0) break;
    sum -= h.raise;
    p[h.object] = fresh[h.object];
    ++undone;
  }
  result.heldByHysteresis = held.size() - undone;
  result.triangles = std::move(p);
  result.total = sum;
  return result;
}

}  // namespace thinlod::backbone
