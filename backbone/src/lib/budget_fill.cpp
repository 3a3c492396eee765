// Budget fill: spend what the uniform target leaves of the hard budget where
// the image gains most (budget_fill.h, docs/scheduling.md "Budget fill").
#include "budget_fill.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <queue>

#include "scheduler_common.h"

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Upgrade {
  double ratio;  // gain per extra primary resource (infinity: free)
  double gain;
  std::size_t item;
  std::size_t option;
  std::uint32_t version;
  // Max-heap: best ratio, then best gain, then lowest item / option index.
  bool operator<(const Upgrade& o) const {
    if (ratio != o.ratio) return ratio < o.ratio;
    if (gain != o.gain) return gain < o.gain;
    if (item != o.item) return item > o.item;
    return option > o.option;
  }
};

bool finiteCost(const FillOption& o) {
  return std::isfinite(o.error) && std::isfinite(o.triangles) && std::isfinite(o.linkBytes) &&
         std::isfinite(o.gainScale) && o.error >= 0.0 && o.gainScale > 0.0;
}

double shadingWeightFor(const LeafCandidate& candidate, const SchedulerConfig& config) {
  const RepresentationOption* option = candidate.representation;
  return option == nullptr ? config.fillShadingWeight
                           : fillShadingWeight(option->kind, config.fillShadingWeight);
}

}  // namespace

double fillImageError(double diameter, double distance, double frameAccuracy, double onScreen,
                      double shadingWeight) {
  if (!(frameAccuracy > 0.0) || !(distance > 0.0)) return kInf;
  const double size = diameter / distance;
  const double perArea = 1.0 / frameAccuracy + shadingWeight / std::sqrt(frameAccuracy);
  return onScreen * size * size * perArea;
}

double fillShadingWeight(OptionKind kind, double weight) {
  // An impostor shows the shading captured with its texture: its error is
  // the geometric (parallax) one alone.
  return kind == OptionKind::kMeshedImpostor || kind == OptionKind::kSimpleImpostor ? 0.0 : weight;
}

std::vector<double> fillTriangleLadder(double limit) {
  std::vector<double> ladder;
  if (!(limit >= 1.0)) return ladder;
  limit = std::min(limit, 1e9);
  // Each rung from the one before (never from the limit): every room gives a
  // prefix of the same sequence, and consecutive rungs differ by at most
  // max(1, 5 %).
  for (double t = 1.0; t <= limit; t = std::max(t + 1.0, std::floor(t * kFillLadderStep)))
    ladder.push_back(t);
  return ladder;
}

std::vector<std::size_t> fillByGain(const FillItems& flat, const FillCaps& caps, FillRetry retry) {
  // A view of item i (its options in the flat pool), so the loops below read
  // like the per-item layout.
  struct ItemRef {
    struct Options {
      const FillOption* data;
      std::size_t count;
      std::size_t size() const { return count; }
      const FillOption& operator[](std::size_t j) const { return data[j]; }
    } options;
    std::size_t current;
  };
  const std::size_t itemCount = flat.current.size();
  auto itemAt = [&](std::size_t i) {
    return ItemRef{{flat.options.data() + flat.begin[i], flat.begin[i + 1] - flat.begin[i]},
                   flat.current[i]};
  };
  std::vector<std::size_t> chosen(itemCount, 0);
  double usedTriangles = 0.0;
  double usedLink = 0.0;
  bool sane = true;
  for (std::size_t i = 0; i < itemCount; ++i) {
    const ItemRef item = itemAt(i);
    if (item.current >= item.options.size()) {
      sane = false;
      continue;
    }
    chosen[i] = item.current;
    const FillOption& c = item.options[item.current];
    sane &= finiteCost(c);
    usedTriangles += c.triangles;
    usedLink += c.linkBytes;
  }
  // No cap: nothing bounds the fill (a fixed accuracy alone), so nothing moves.
  // Already over a cap, or malformed input: leave the picks as they are.
  if (!sane || (!caps.useTriangles && !caps.useLink)) return chosen;
  if (caps.useTriangles && !(usedTriangles <= caps.triangles)) return chosen;
  if (caps.useLink && !(usedLink <= caps.linkBytes)) return chosen;

  // Free upgrades first: a lower error for no more of either resource (a
  // displayed copy better than the pick) never risks a cap.
  for (std::size_t i = 0; i < itemCount; ++i) {
    const ItemRef item = itemAt(i);
    const FillOption& now = item.options[chosen[i]];
    std::size_t best = chosen[i];
    for (std::size_t j = 0; j < item.options.size(); ++j) {
      const FillOption& o = item.options[j];
      if (!finiteCost(o) || o.triangles > now.triangles || o.linkBytes > now.linkBytes) continue;
      if (o.error < item.options[best].error) best = j;
    }
    usedTriangles += item.options[best].triangles - now.triangles;
    usedLink += item.options[best].linkBytes - now.linkBytes;
    chosen[i] = best;
  }

  std::vector<std::uint32_t> version(itemCount, 0);
  std::vector<std::size_t> stalled;  // items with no upgrade that fits
  std::priority_queue<Upgrade> heap;
  auto fits = [&](double extraTriangles, double extraLink) {
    return (!caps.useTriangles || usedTriangles + extraTriangles <= caps.triangles) &&
           (!caps.useLink || usedLink + extraLink <= caps.linkBytes);
  };
  // FillRetry::kIndexed: a stalled item waits in a min-heap keyed by the
  // least extra it needs in the first capped resource (over its options
  // with a lower error, fitting or not; they do not change while it is
  // stalled). Floating-point addition is monotone, so "some option fits
  // that resource" is exactly "used + least extra <= cap": when room grows,
  // only items passing that test (and the same test on the second cap) can
  // find an upgrade; the others would be pushed back unchanged.
  struct StalledItem {
    double keyExtra;    // least extra in the first capped resource
    double otherExtra;  // least extra in the second capped resource (both caps)
    std::size_t item;
    bool operator>(const StalledItem& o) const {
      if (keyExtra != o.keyExtra) return keyExtra > o.keyExtra;
      return item > o.item;
    }
  };
  std::priority_queue<StalledItem, std::vector<StalledItem>, std::greater<StalledItem>> waiting;
  auto stall = [&](std::size_t i, double leastTriangles, double leastLink) {
    if (caps.useTriangles) {
      waiting.push({leastTriangles, leastLink, i});
    } else {
      waiting.push({leastLink, leastTriangles, i});
    }
  };
  auto pushBest = [&](std::size_t i) {
    const ItemRef item = itemAt(i);
    const FillOption& now = item.options[chosen[i]];
    bool found = false;
    bool better = false;  // some option has a lower error (fitting or not)
    double leastTriangles = kInf;
    double leastLink = kInf;
    Upgrade best{0.0, 0.0, i, 0, version[i]};
    for (std::size_t j = 0; j < item.options.size(); ++j) {
      const FillOption& o = item.options[j];
      if (j == chosen[i] || !finiteCost(o) || !(o.error < now.error)) continue;
      const double extraTriangles = o.triangles - now.triangles;
      const double extraLink = o.linkBytes - now.linkBytes;
      better = true;
      leastTriangles = std::min(leastTriangles, extraTriangles);
      leastLink = std::min(leastLink, extraLink);
      if (!fits(extraTriangles, extraLink)) continue;
      const double extra = caps.useTriangles ? extraTriangles : extraLink;
      const double gain = (now.error - o.error) * o.gainScale;
      const double ratio = extra > 0.0 ? gain / extra : kInf;
      const Upgrade candidate{ratio, gain, i, j, version[i]};
      if (!found || best < candidate) {
        best = candidate;
        found = true;
      }
    }
    if (found) {
      heap.push(best);
    } else if (retry == FillRetry::kIndexed) {
      if (better) stall(i, leastTriangles, leastLink);  // else it never moves again
    } else {
      stalled.push_back(i);
    }
  };
  auto retryIndexed = [&]() {
    std::vector<StalledItem> ready;
    for (;;) {
      if (waiting.empty()) break;
      const StalledItem& top = waiting.top();
      const bool keyFits = caps.useTriangles ? usedTriangles + top.keyExtra <= caps.triangles
                                             : usedLink + top.keyExtra <= caps.linkBytes;
      if (!keyFits) break;
      ready.push_back(top);
      waiting.pop();
    }
    for (const StalledItem& w : ready) {
      if (caps.useTriangles && caps.useLink && !(usedLink + w.otherExtra <= caps.linkBytes)) {
        waiting.push(w);  // still nothing fits the link cap
        continue;
      }
      ++version[w.item];
      pushBest(w.item);
    }
  };
  for (std::size_t i = 0; i < itemCount; ++i) pushBest(i);
  while (!heap.empty()) {
    const Upgrade u = heap.top();
    heap.pop();
    if (u.version != version[u.item]) continue;
    const FillOption& now = itemAt(u.item).options[chosen[u.item]];
    const FillOption& next = itemAt(u.item).options[u.option];
    const double extraTriangles = next.triangles - now.triangles;
    const double extraLink = next.linkBytes - now.linkBytes;
    ++version[u.item];
    if (!fits(extraTriangles, extraLink)) {
      pushBest(u.item);  // something smaller may still fit
      continue;
    }
    usedTriangles += extraTriangles;
    usedLink += extraLink;
    chosen[u.item] = u.option;
    pushBest(u.item);
    if (retry == FillRetry::kIndexed) {
      // Only room grown in a capped resource lets a stalled item fit.
      if ((caps.useTriangles && extraTriangles < 0.0) || (caps.useLink && extraLink < 0.0))
        retryIndexed();
    } else if (extraTriangles < 0.0 || extraLink < 0.0) {
      // Room grew in one resource: upgrades that did not fit may fit now
      // (only the stalled items; the others are re-checked when popped).
      std::vector<std::size_t> again;
      again.swap(stalled);
      for (std::size_t i : again) {
        ++version[i];
        pushBest(i);
      }
    }
  }
  return chosen;
}

std::vector<std::size_t> fillByGain(const std::vector<FillItem>& items, const FillCaps& caps,
                                    FillRetry retry) {
  FillItems flat;
  for (const FillItem& item : items)
    flat.add(item.options.data(), item.options.size(), item.current);
  return fillByGain(flat, caps, retry);
}

namespace {

// What one option of the fill stands for in the selections.
struct OptionSource {
  std::uint32_t candidate = 0;  // index into the leaf's candidates
  double generateAt = 0.0;      // relative accuracy a new representation is made for
};

// The reference path (SchedulerConfig::reuseLeafWork = false): the fill as
// first written, kept so the fast path below can be checked against it.
FillOutcome fillReference(const SchedulingScene& scene, const SchedulerConfig& config,
                          const ViewerState& viewer, const PredictedRegion& region,
                          const PlannerStateImpl& state, const JointBudget& hard,
                          std::vector<LeafSelection>& selections) {
  FillOutcome outcome;
  for (const LeafSelection& s : selections)
    if (s.rendered) outcome.trianglesBefore += s.cost.triangles;
  outcome.trianglesAfter = outcome.trianglesBefore;
  if (!hard.useTriangles && !hard.useLink) return outcome;
  const ViewCone cone(viewer);

  const CandidateCost used = renderedCost(selections);
  const double roomTriangles = hard.useTriangles ? hard.triangles - used.triangles : kInf;
  const double roomLink = hard.useLink ? hard.linkBytes - used.linkBytes : kInf;
  if (!(roomTriangles > 0.0) || !(roomLink > 0.0)) return outcome;

  std::vector<FillItem> items;
  std::vector<std::size_t> itemSelection;
  std::vector<std::vector<OptionSource>> sources;
  std::vector<std::vector<LeafCandidate>> candidatesOf;
  std::vector<LeafCandidate> candidates;
  for (std::size_t i = 0; i < selections.size(); ++i) {
    const LeafSelection& s = selections[i];
    if (!s.rendered || !(s.diameter > 0.0)) continue;
    // Nothing on display yet: its first representation is the cheapest that
    // meets the target, so it arrives soonest (a larger first request left
    // the city walk's first second blank); the fill raises it later.
    const SceneObject& object = scene.objects[s.object];
    bool displayed = false;
    for (std::uint32_t k = 0; k < object.optionCount && !displayed; ++k)
      displayed = scene.options[object.firstOption + k].atFrontend.present;
    if (!displayed) continue;
    const SceneNode& node = scene.nodes[s.node];
    collectLeafCandidates(scene, s.object, region, config, CandidateContext::kExact,
                          pendingFor(state, s.object), node.bounds, candidates);
    const double nowDistance =
        conversionDistance(viewer.position, 0.0, node.bounds, config.minimalDistance);
    const double onScreen = cone.onScreenWeight(node.bounds);
    FillItem item;
    std::vector<OptionSource> itemSources;
    // The current pick first (its own cost, as the push-down charged it).
    item.options.push_back({fillImageError(s.diameter, nowDistance, s.frameAccuracy, onScreen,
                                           shadingWeightFor(s.candidate, config)),
                            s.cost.triangles, s.cost.linkBytes, 1.0});
    itemSources.push_back({0, -1.0});
    const double floor = s.need * (1.0 - kAccuracyTolerance);
    for (std::uint32_t c = 0; c < candidates.size(); ++c) {
      const LeafCandidate& k = candidates[c];
      if (!(k.maxRelativeAccuracy >= floor)) continue;
      if (k.source != CandidateSource::kNew) {
        if (k.fixedTriangles - s.cost.triangles > roomTriangles ||
            k.fixedLinkBytes - s.cost.linkBytes > roomLink)
          continue;
        item.options.push_back({fillImageError(s.diameter, nowDistance, k.maxRelativeAccuracy,
                                               onScreen, shadingWeightFor(k, config)),
                                k.fixedTriangles, k.fixedLinkBytes, 1.0});
        itemSources.push_back({c, -1.0});
        continue;
      }
      const RepresentationOption& option = *k.representation;
      const double start =
          std::max(option.relativeTriangles.minAccuracy(), option.relativeLinkBytes.minAccuracy());
      const double low = std::max(s.need, start);
      if (!(low <= k.maxRelativeAccuracy)) continue;
      // Levels: the best accuracy within each rung of the ladder, up to what
      // the room allows, and the option's top when it fits.
      const double limit = s.cost.triangles + roomTriangles;
      std::vector<double> accuracies;
      int rungs = 0;
      for (double rung : fillTriangleLadder(std::min(limit, 1e7))) {
        if (rung < s.cost.triangles) continue;
        // Bounded work per leaf (the fill stays linear in the visible
        // leaves): at most kMaxFillRungs rungs above the pick, then the top.
        if (++rungs > kMaxFillRungs) break;
        const std::optional<double> a = option.relativeTriangles.maxAccuracyWithin(rung);
        if (!a) continue;
        const double at = std::min(*a, k.maxRelativeAccuracy);
        if (at < low) continue;
        if (accuracies.empty() || at > accuracies.back()) accuracies.push_back(at);
        if (at >= k.maxRelativeAccuracy) break;  // the top: later rungs add nothing
      }
      if (accuracies.empty() || accuracies.back() < k.maxRelativeAccuracy)
        accuracies.push_back(k.maxRelativeAccuracy);
      for (double at : accuracies) {
        const CandidateCost cost = candidateCost(k, at);
        if (cost.triangles - s.cost.triangles > roomTriangles ||
            cost.linkBytes - s.cost.linkBytes > roomLink)
          continue;
        item.options.push_back(
            {fillImageError(s.diameter, nowDistance, at, onScreen, shadingWeightFor(k, config)),
             cost.triangles, cost.linkBytes, kNewGenerationGainScale});
        itemSources.push_back({c, at});
      }
    }
    if (item.options.size() < 2) continue;
    items.push_back(std::move(item));
    itemSelection.push_back(i);
    sources.push_back(std::move(itemSources));
    candidatesOf.push_back(candidates);
  }
  if (items.empty()) return outcome;

  FillCaps caps;
  caps.useTriangles = hard.useTriangles;
  caps.useLink = hard.useLink;
  caps.triangles = hard.triangles;
  caps.linkBytes = hard.linkBytes;
  // The core sees only the fillable leaves; the others' costs come off the caps.
  double fixedTriangles = used.triangles;
  double fixedLink = used.linkBytes;
  for (std::size_t k = 0; k < items.size(); ++k) {
    fixedTriangles -= items[k].options[0].triangles;
    fixedLink -= items[k].options[0].linkBytes;
  }
  caps.triangles -= fixedTriangles;
  caps.linkBytes -= fixedLink;
  const std::vector<std::size_t> chosen = fillByGain(items, caps, FillRetry::kEveryStalled);

  const std::vector<LeafSelection> before = selections;
  for (std::size_t k = 0; k < items.size(); ++k) {
    if (chosen[k] == 0) continue;
    LeafSelection& s = selections[itemSelection[k]];
    const OptionSource& source = sources[k][chosen[k]];
    const LeafCandidate& candidate = candidatesOf[k][source.candidate];
    const double need = s.need;
    const double at = source.generateAt > 0.0 ? source.generateAt : need;
    s = makeSelection(s.node, s.object, candidate, at, s.distance, s.diameter);
    s.need = need;  // the target's need stays what the plan reports
    ++outcome.upgraded;
  }
  if (!withinBudget(selections, hard)) {
    selections = before;  // rounding: the cap is hard, the fill is optional
    outcome.upgraded = 0;
    return outcome;
  }
  outcome.trianglesAfter = 0.0;
  for (const LeafSelection& s : selections)
    if (s.rendered) outcome.trianglesAfter += s.cost.triangles;
  return outcome;
}

}  // namespace

// Buffers of the fast path, kept in the planner state between steps.
struct FillScratch {
  FillItems items;
  std::vector<std::size_t> itemSelection;
  std::vector<OptionSource> sources;  // parallel to items.options
  std::vector<LeafCandidate> candidatePool;
  std::vector<std::uint32_t> candidateBegin;  // per item, into candidatePool
  std::vector<LeafCandidate> collected;
  std::vector<double> ladder;
  std::vector<double> accuracies;
  std::vector<std::pair<std::size_t, LeafSelection>> undo;
};

namespace {

// The same fill with less work (reuseLeafWork): the push-down's stored
// candidates instead of collecting them again, one pool for every item's
// options and candidates (no allocation per leaf), one shared ladder with a
// binary search for the pick's rung, the view-cone angle computed once, and
// an undo log of the changed selections instead of a copy of all of them.
// Every value is computed by the same expressions in the same order, so the
// choices are those of fillReference (ReuseLeafWork tests, bench_scheduler).
FillOutcome fillFast(const SchedulingScene& scene, const SchedulerConfig& config,
                     const ViewerState& viewer, const PredictedRegion& region,
                     PlannerStateImpl& state, const JointBudget& hard,
                     std::vector<LeafSelection>& selections) {
  FillOutcome outcome;
  for (const LeafSelection& s : selections)
    if (s.rendered) outcome.trianglesBefore += s.cost.triangles;
  outcome.trianglesAfter = outcome.trianglesBefore;
  if (!hard.useTriangles && !hard.useLink) return outcome;

  const CandidateCost used = renderedCost(selections);
  const double roomTriangles = hard.useTriangles ? hard.triangles - used.triangles : kInf;
  const double roomLink = hard.useLink ? hard.linkBytes - used.linkBytes : kInf;
  if (!(roomTriangles > 0.0) || !(roomLink > 0.0)) return outcome;

  if (!state.fillScratch) state.fillScratch.reset(new FillScratch);
  FillScratch& w = *state.fillScratch;
  w.items.clear();
  w.itemSelection.clear();
  w.sources.clear();
  w.candidatePool.clear();
  w.candidateBegin.clear();
  w.undo.clear();
  // The ladder is a prefix-stable sequence: one copy up to the largest limit
  // any leaf can have serves every leaf.
  double largest = 0.0;
  for (const LeafSelection& s : selections)
    if (s.rendered) largest = std::max(largest, s.cost.triangles + roomTriangles);
  w.ladder = fillTriangleLadder(std::min(largest, 1e7));
  const StepCandidates& kept = state.stepCandidates;
  const bool stored = kept.valid && kept.begin.size() == selections.size() &&
                      kept.count.size() == selections.size();
  const ViewCone cone(viewer);

  for (std::size_t i = 0; i < selections.size(); ++i) {
    const LeafSelection& s = selections[i];
    if (!s.rendered || !(s.diameter > 0.0)) continue;
    const LeafCandidate* candidates = nullptr;
    std::size_t candidateCount = 0;
    bool displayed = false;
    if (stored) {
      candidates = kept.pool.data() + kept.begin[i];
      candidateCount = kept.count[i];
      for (std::size_t c = 0; c < candidateCount && !displayed; ++c)
        displayed = candidates[c].source == CandidateSource::kFrontendCopy;
    }
    if (!displayed) {  // a copy on display may be invalid here: not a candidate
      const SceneObject& object = scene.objects[s.object];
      for (std::uint32_t k = 0; k < object.optionCount && !displayed; ++k)
        displayed = scene.options[object.firstOption + k].atFrontend.present;
    }
    if (!displayed) continue;
    const SceneNode& node = scene.nodes[s.node];
    if (!stored) {
      collectLeafCandidates(scene, s.object, region, config, CandidateContext::kExact,
                            pendingFor(state, s.object), node.bounds, w.collected);
      candidates = w.collected.data();
      candidateCount = w.collected.size();
    }
    const double nowDistance =
        conversionDistance(viewer.position, 0.0, node.bounds, config.minimalDistance);
    const double weight = cone.onScreenWeight(node.bounds);
    const std::size_t optionsBefore = w.items.options.size();
    // The current pick first (its own cost, as the push-down charged it).
    w.items.options.push_back(
        {fillImageError(s.diameter, nowDistance, s.frameAccuracy, weight,
                        shadingWeightFor(s.candidate, config)),
         s.cost.triangles, s.cost.linkBytes, 1.0});
    w.sources.push_back({0, -1.0});
    const double floor = s.need * (1.0 - kAccuracyTolerance);
    for (std::uint32_t c = 0; c < candidateCount; ++c) {
      const LeafCandidate& k = candidates[c];
      if (!(k.maxRelativeAccuracy >= floor)) continue;
      if (k.source != CandidateSource::kNew) {
        if (k.fixedTriangles - s.cost.triangles > roomTriangles ||
            k.fixedLinkBytes - s.cost.linkBytes > roomLink)
          continue;
        w.items.options.push_back({fillImageError(s.diameter, nowDistance, k.maxRelativeAccuracy,
                                                  weight, shadingWeightFor(k, config)),
                                   k.fixedTriangles, k.fixedLinkBytes, 1.0});
        w.sources.push_back({c, -1.0});
        continue;
      }
      const RepresentationOption& option = *k.representation;
      const double start =
          std::max(option.relativeTriangles.minAccuracy(), option.relativeLinkBytes.minAccuracy());
      const double low = std::max(s.need, start);
      if (!(low <= k.maxRelativeAccuracy)) continue;
      const double limit = std::min(s.cost.triangles + roomTriangles, 1e7);
      w.accuracies.clear();
      int rungs = 0;
      const std::size_t firstRung = static_cast<std::size_t>(
          std::lower_bound(w.ladder.begin(), w.ladder.end(), s.cost.triangles) - w.ladder.begin());
      for (std::size_t r = firstRung; r < w.ladder.size(); ++r) {
        const double rung = w.ladder[r];
        if (!(rung <= limit)) break;  // the shared ladder runs to the largest limit
        if (rung < s.cost.triangles) continue;
        if (++rungs > kMaxFillRungs) break;
        const std::optional<double> a = option.relativeTriangles.maxAccuracyWithin(rung);
        if (!a) continue;
        const double at = std::min(*a, k.maxRelativeAccuracy);
        if (at < low) continue;
        if (w.accuracies.empty() || at > w.accuracies.back()) w.accuracies.push_back(at);
        if (at >= k.maxRelativeAccuracy) break;
      }
      if (w.accuracies.empty() || w.accuracies.back() < k.maxRelativeAccuracy)
        w.accuracies.push_back(k.maxRelativeAccuracy);
      for (double at : w.accuracies) {
        const CandidateCost cost = candidateCost(k, at);
        if (cost.triangles - s.cost.triangles > roomTriangles ||
            cost.linkBytes - s.cost.linkBytes > roomLink)
          continue;
        w.items.options.push_back(
            {fillImageError(s.diameter, nowDistance, at, weight, shadingWeightFor(k, config)),
             cost.triangles, cost.linkBytes, kNewGenerationGainScale});
        w.sources.push_back({c, at});
      }
    }
    if (w.items.options.size() - optionsBefore < 2) {  // nothing to gain: no item
      w.items.options.resize(optionsBefore);
      w.sources.resize(optionsBefore);
      continue;
    }
    w.items.begin.push_back(static_cast<std::uint32_t>(w.items.options.size()));
    w.items.current.push_back(0);
    w.itemSelection.push_back(i);
    w.candidateBegin.push_back(static_cast<std::uint32_t>(w.candidatePool.size()));
    w.candidatePool.insert(w.candidatePool.end(), candidates, candidates + candidateCount);
  }
  if (w.items.size() == 0) return outcome;

  FillCaps caps;
  caps.useTriangles = hard.useTriangles;
  caps.useLink = hard.useLink;
  caps.triangles = hard.triangles;
  caps.linkBytes = hard.linkBytes;
  double fixedTriangles = used.triangles;
  double fixedLink = used.linkBytes;
  for (std::size_t k = 0; k < w.items.size(); ++k) {
    fixedTriangles -= w.items.options[w.items.begin[k]].triangles;
    fixedLink -= w.items.options[w.items.begin[k]].linkBytes;
  }
  caps.triangles -= fixedTriangles;
  caps.linkBytes -= fixedLink;
  const std::vector<std::size_t> chosen = fillByGain(w.items, caps, FillRetry::kIndexed);

  for (std::size_t k = 0; k < w.items.size(); ++k) {
    if (chosen[k] == 0) continue;
    LeafSelection& s = selections[w.itemSelection[k]];
    w.undo.emplace_back(w.itemSelection[k], s);
    const OptionSource& source = w.sources[w.items.begin[k] + chosen[k]];
    const LeafCandidate& candidate = w.candidatePool[w.candidateBegin[k] + source.candidate];
    const double need = s.need;
    const double at = source.generateAt > 0.0 ? source.generateAt : need;
    s = makeSelection(s.node, s.object, candidate, at, s.distance, s.diameter);
    s.need = need;
    ++outcome.upgraded;
  }
  if (!withinBudget(selections, hard)) {
    for (const auto& [index, before] : w.undo) selections[index] = before;
    outcome.upgraded = 0;
    return outcome;
  }
  outcome.trianglesAfter = 0.0;
  for (const LeafSelection& s : selections)
    if (s.rendered) outcome.trianglesAfter += s.cost.triangles;
  return outcome;
}

}  // namespace

void FillScratchDeleter::operator()(FillScratch* scratch) const { delete scratch; }

FillOutcome fillRemainingBudget(const SchedulingScene& scene, const SchedulerConfig& config,
                                const ViewerState& viewer, const PredictedRegion& region,
                                PlannerStateImpl& state, const JointBudget& hard,
                                std::vector<LeafSelection>& selections) {
  if (!config.reuseLeafWork)
    return fillReference(scene, config, viewer, region, state, hard, selections);
  return fillFast(scene, config, viewer, region, state, hard, selections);
}

}  // namespace thinlod::backbone
