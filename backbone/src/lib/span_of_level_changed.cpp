#include "span_of_level_changed.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

namespace thinlod::backbone {
namespace {

constexpr int kMaxLevel = 62;

// Binary max-heap of object indices keyed by importance; counts comparisons
// so tests can check O(log m) work per change.
class ImportanceHeap {
 public:
  ImportanceHeap(const std::vector<double>& key, std::uint64_t& comparisons)
      : key_(key), comparisons_(&comparisons) {}

  void build(std::vector<std::uint32_t> items) {
    items_ = std::move(items);
    for (std::size_t i = items_.size() / 2; i-- > 0;) siftDown(i);
  }
  bool empty() const { return items_.empty(); }
  std::uint32_t top() const { return items_.front(); }
  // The top's key changed (it can only have gone down or up by any amount).
  void topChanged() { siftDown(0); }
  void pop() {
    items_.front() = items_.back();
    items_.pop_back();
    if (!items_.empty()) siftDown(0);
  }
  void countInto(std::uint64_t& comparisons) { comparisons_ = &comparisons; }

 private:
  // a before b: larger key, then lower index.
  bool before(std::uint32_t a, std::uint32_t b) {
    ++*comparisons_;
    if (key_[a] != key_[b]) return key_[a] > key_[b];
    return a < b;
  }
  void siftDown(std::size_t i) {
    const std::size_t n = items_.size();
    for (;;) {
      const std::size_t l = 2 * i + 1;
      if (l >= n) return;
      std::size_t best = l;
      if (l + 1 < n && before(items_[l + 1], items_[l])) best = l + 1;
      if (!before(items_[best], items_[i])) return;
      std::swap(items_[best], items_[i]);
      i = best;
    }
  }

  const std::vector<double>& key_;
  std::uint64_t* comparisons_;
  std::vector<std::uint32_t> items_;
};

Status validateObjects(const std::vector<SlcObject>& objects) {
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const SlcObject& o = objects[i];
    const std::string at = "SLC object " + std::to_string(i) + ": ";
    if (o.levels.empty()) return Status(ErrorCode::kInvalidArgument, at + "no levels");
    if (!(std::isfinite(o.distance) && o.distance > 0.0))
      return Status(ErrorCode::kInvalidArgument, at + "distance must be finite and > 0");
    if (!(std::isfinite(o.projectedArea) && o.projectedArea > 0.0))
      return Status(ErrorCode::kInvalidArgument, at + "projected area must be finite and > 0");
    for (std::size_t k = 0; k < o.levels.size(); ++k) {
      const SlcLevel& l = o.levels[k];
      if (l.level < 0 || l.level > kMaxLevel)
        return Status(ErrorCode::kInvalidArgument,
                      at + "level " + std::to_string(l.level) + " outside [0, 62]");
      if (!(std::isfinite(l.triangles) && l.triangles >= 0.0))
        return Status(ErrorCode::kInvalidArgument, at + "triangles must be finite and >= 0");
      if (k > 0 && !(l.level < o.levels[k - 1].level))
        return Status(ErrorCode::kInvalidArgument,
                      at + "levels must be strictly decreasing (finest first)");
      if (k > 0 && l.triangles > o.levels[k - 1].triangles)
        return Status(ErrorCode::kInvalidArgument,
                      at + "triangles must not increase towards coarser levels");
    }
  }
  return Status::okStatus();
}

}  // namespace

int levelOfFaces(double faces) {
  if (!(faces >= 1.0)) return 0;
  return static_cast<int>(std::floor(std::log2(faces) + 0.5));
}

double spanOfLevelChanged(int fromLevel, int toLevel) {
  return double(std::max(fromLevel, toLevel)) * double(std::abs(fromLevel - toLevel));
}

double slcLevelCost(const SlcLevel& level, SlcBudgetMeasure measure) {
  return measure == SlcBudgetMeasure::kPowerOfTwo ? std::ldexp(1.0, level.level) : level.triangles;
}

Result<SlcSelection> selectBySpanOfLevelChanged(const std::vector<SlcObject>& objects,
                                                double budget, const SlcConfig& config) {
  if (!(budget >= 0.0)) return Status(ErrorCode::kInvalidArgument, "SLC budget must be >= 0");
  THINLOD_RETURN_IF_ERROR(validateObjects(objects));
  const std::size_t m = objects.size();
  SlcSelection result;
  result.levelIndex.assign(m, 0);
  result.changesPerObject.assign(m, 0);
  result.spanPerObject.assign(m, 0.0);
  auto cost = [&](std::size_t i) {
    return slcLevelCost(objects[i].levels[result.levelIndex[i]], config.measure);
  };
  auto exactTotal = [&]() {
    double t = 0.0;
    for (std::size_t i = 0; i < m; ++i) t += cost(i);
    return t;
  };
  result.total = exactTotal();
  if (result.total <= budget) return result;

  // Per object, the constant part d / S of eq. 6.
  double nearest = std::numeric_limits<double>::infinity();
  double smallestArea = std::numeric_limits<double>::infinity();
  for (const SlcObject& o : objects) {
    nearest = std::min(nearest, o.distance);
    smallestArea = std::min(smallestArea, o.projectedArea);
  }
  std::vector<double> factor(m);
  for (std::size_t i = 0; i < m; ++i) {
    const double d = config.distanceRule == SlcDistanceRule::kNearestFirst
                         ? nearest / objects[i].distance
                         : objects[i].distance / nearest;
    const double s = objects[i].projectedArea / smallestArea;
    factor[i] = d / s;
  }
  std::vector<double> key(m, 0.0);
  auto nextSpan = [&](std::size_t i) {
    const auto& levels = objects[i].levels;
    const std::uint32_t k = result.levelIndex[i];
    return spanOfLevelChanged(levels[k].level, levels[k + 1].level);
  };
  std::vector<std::uint32_t> items;
  for (std::size_t i = 0; i < m; ++i) {
    if (objects[i].levels.size() < 2) continue;
    key[i] = factor[i] * nextSpan(i);
    items.push_back(static_cast<std::uint32_t>(i));
  }
  ImportanceHeap heap(key, result.heapBuildComparisons);
  heap.build(std::move(items));
  heap.countInto(result.heapUpdateComparisons);
  double total = result.total;
  for (;;) {
    while (total > budget && !heap.empty()) {
      const std::uint32_t i = heap.top();
      const double before = cost(i);
      result.spanPerObject[i] += nextSpan(i);
      ++result.levelIndex[i];
      ++result.changesPerObject[i];
      ++result.changes;
      total -= before - cost(i);
      if (result.levelIndex[i] + 1 >= objects[i].levels.size()) {
        heap.pop();
      } else {
        key[i] = factor[i] * nextSpan(i);
        heap.topChanged();
      }
    }
    // The running sum can drift by rounding: decide on a fresh sum.
    total = exactTotal();
    if (total <= budget || heap.empty()) break;
  }
  result.total = total;
  result.budgetMet = total <= budget;
  return result;
}

}  // namespace thinlod::backbone
