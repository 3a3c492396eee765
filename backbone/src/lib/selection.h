// Per-leaf selections and the plan builder shared by every scheduler
// (private). A scheduler decides one LeafSelection per visible leaf; the
// builder turns them into keep/send/request/remove actions, orders the
// requests, updates in-flight requests and the link log, and fills the row.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "planner_state_impl.h"
#include "thinlod/backbone/scheduler.h"

namespace thinlod::backbone {

inline constexpr double kAccuracyTolerance = 1e-12;

struct LeafSelection {
  std::uint32_t node = 0;
  std::uint32_t object = 0;
  bool rendered = false;  // false: nothing eligible, or dropped
  bool dropped = false;
  LeafCandidate candidate;
  double need = 0.0;              // relative accuracy (leaf frame) the target asks for
  double frameAccuracy = 0.0;     // relative accuracy (leaf frame) it reaches
  double relativeAccuracy = 0.0;  // of the representation itself (generate at / copy's)
  double distance = 0.0;          // D of the reach ball
  double diameter = 0.0;
  CandidateCost cost;

  double absoluteAccuracy() const { return frameAccuracy * distance / diameter; }
};

// Tie-break rank among equal-cost candidates: copies already on (or on their
// way to) the frontend first, new generations last (lower is preferred).
int candidateSourceRank(CandidateSource source);
// Index of the cheapest candidate reaching `need` (primary resource first,
// then the other, then copies before new ones, then option order), or -1.
// `pickedCost` (optional) receives candidateCost(pick, need).
int pickCandidate(const std::vector<LeafCandidate>& candidates, double need, bool trianglesFirst,
                  CandidateCost* pickedCost = nullptr);
// Highest maxRelativeAccuracy among candidates (-infinity when none).
double bestCandidateAccuracy(const std::vector<LeafCandidate>& candidates);
// Lowest accuracy any candidate is defined from (left end of its curve).
double lowestCandidateAccuracy(const std::vector<LeafCandidate>& candidates);

LeafSelection makeSelection(std::uint32_t node, std::uint32_t object,
                            const LeafCandidate& candidate, double need, double distance,
                            double diameter);
// The same with candidateCost(candidate, need) already known (pickCandidate
// computed it): identical result, two curve look-ups fewer.
LeafSelection makeSelection(std::uint32_t node, std::uint32_t object,
                            const LeafCandidate& candidate, double need, double distance,
                            double diameter, const CandidateCost& cost);

// Book-keeping before planning: resets caches when the scene shape or the
// config changed, retires confirmed/expired in-flight requests, trims the link
// log to `linkWindow` (linkWindowSeconds() of the step's budget).
void beginStep(PlannerStateImpl& state, const SchedulingScene& scene, const SchedulerConfig& config,
               const ViewerState& viewer, double linkWindow);
// Bytes sent in (now - window, now].
double recentLinkBytes(const PlannerStateImpl& state, double now, double window);
const std::vector<PendingCopy>* pendingFor(const PlannerStateImpl& state, std::uint32_t object);

struct PlanContext {
  const SchedulingScene& scene;
  const SchedulerConfig& config;
  const ViewerState& viewer;
  const PredictedRegion& region;
  PlannerStateImpl& state;
};

// Fills every field of `plan` except stats fields the scheduler set and
// scheduler/mode/target; selections are consumed in order.
//
// Expired copies: a visible leaf the selection does not render (dropped, or
// nothing eligible) whose frontend still holds a copy keeps that copy, most
// visible leaf first, while its triangles fit in `expiredCopyRoom` (the
// triangle budget left by the rendered leaves; nullopt: never keep one). Such
// a copy costs no link bytes, is kept (ObjectAction::kKeep) with absolute
// accuracy 0 (its validity no longer covers the region, so nothing is
// guaranteed) and is listed in Plan::belowTarget, not Plan::dropped; it is
// left out of Plan::achievedMinAccuracy (counted in expiredCopiesKept). Of
// an object's held copies the most accurate that fits stays.
void finishPlan(const PlanContext& context, std::vector<LeafSelection>& selections,
                double targetAccuracy, std::optional<double> expiredCopyRoom, Plan& plan);

}  // namespace thinlod::backbone
