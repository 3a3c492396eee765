// What a PlannerState remembers between planning steps (private).
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "thinlod/backbone/scheduler.h"

namespace thinlod::backbone {

struct LeafSelection;  // selection.h (PlannerStateImpl is built and destroyed in planner_state.cpp)

// Absolute curve of a node for exactly one predicted region (reused only
// when the region, the subtree and the in-flight requests are unchanged).
// Entries of a subtree are written in the same pass as their ancestor, so a
// reused ancestor can read its descendants' entries during push-down.
struct AbsoluteEntry {
  bool valid = false;
  std::uint64_t subtreeVersion = 0;
  std::uint64_t pendingGeneration = 0;
  PredictedRegion region;
  Visibility visibility = Visibility::kCulled;
  bool merged = false;    // curve = relative curve of the subtree, converted once
  double distance = 0.0;  // conversion distance D of leaves and merged nodes
  AccuracyCurve curve;
};

// Relative curve of a subtree (relative to the node's own diameter), valid
// for every predicted region inside `region` (conservative candidates).
struct RelativeEntry {
  bool valid = false;
  std::uint64_t subtreeVersion = 0;
  PredictedRegion region;
  AccuracyCurve curve;
};

struct ResourceCache {
  std::vector<AbsoluteEntry> absolute;
  std::vector<RelativeEntry> relative;
};

// The exact candidates of each leaf selection of this step as the push-down
// collected them (selection i owns pool[begin[i], begin[i] + count[i])), so
// the hysteresis pass need not collect them again (SchedulerConfig::
// reuseLeafWork). Only valid right after a push-down; cleared before any
// other producer of selections runs.
struct StepCandidates {
  bool valid = false;
  std::vector<LeafCandidate> pool;
  std::vector<std::uint32_t> begin;
  std::vector<std::uint32_t> count;

  void reset() {
    valid = false;
    pool.clear();
    begin.clear();
    count.clear();
  }
};

// A leaf whose decision the push-down put off to decide all leaves in
// object order (curve_propagation.cpp); kept here so the buffers survive
// the step.
struct DeferredLeaf {
  std::uint32_t object = 0;
  std::uint32_t slot = 0;  // index of its selection
  std::uint32_t node = 0;
  Sphere bounds;  // the node's, read while the traversal has it in cache
  double absoluteAccuracy = 0.0;
  double relativeCap = 0.0;
  // Its candidates from this evaluation (EvaluatedCandidates), looked up
  // while the traversal is in tree order; evaluated == false: collect them.
  bool evaluated = false;
  std::uint32_t candidatesBegin = 0;
  std::uint32_t candidateCount = 0;
};

// Exact candidates a leaf's absolute curve was built from in the current
// evaluation (epoch), so its push-down need not collect them again (same
// region, scene and in-flight requests within one step).
struct EvaluatedCandidates {
  std::uint64_t epoch = 0;  // bumped by every evaluateRoot
  std::vector<LeafCandidate> pool;
  struct Span {
    std::uint64_t epoch = 0;
    std::uint32_t begin = 0;
    std::uint32_t count = 0;
  };
  std::vector<Span> byNode;
};

// One entry of the link log (PlannerState::settleLinkSend): a plan's
// reservation until the caller settles it with what it shipped.
struct LinkSend {
  double time = 0.0;
  double bytes = 0.0;
  std::uint64_t id = 0;  // copy / request id
  bool settled = false;
};

// Buffers of the budget fill's fast path (budget_fill.cpp), kept between
// steps so a step does not allocate and page-fault them in again.
struct FillScratch;
struct FillScratchDeleter {
  void operator()(FillScratch* scratch) const;
};

struct PlannerStateImpl {
  std::uint64_t steps = 0;
  std::uint64_t configFingerprint = 0;
  std::size_t nodeCount = 0;
  std::size_t objectCount = 0;
  ResourceCache cache[2];  // [0] triangles, [1] link bytes
  StepCandidates stepCandidates;
  EvaluatedCandidates evaluatedCandidates;
  std::size_t lastSelectionCount = 0;  // capacity hint for the next step's selections
  // The previous step's selection vector, handed back by the frame after
  // the plan is built (scheduler.cpp), so a method reusing leaf work does
  // not allocate (and page-fault in) megabytes of selections every step.
  std::vector<LeafSelection> spareSelections;  // complete in selection.h
  std::vector<DeferredLeaf> deferredLeaves;
  std::vector<DeferredLeaf> deferredSorted;  // radix-sort buffer
  std::unique_ptr<FillScratch, FillScratchDeleter> fillScratch;
  std::uint64_t pendingGeneration = 1;
  std::uint64_t nextRequestId = 1;
  std::unordered_map<std::uint32_t, std::vector<PendingCopy>> pending;  // by object
  std::deque<LinkSend> linkLog;
  std::optional<double> previousTarget;
  std::vector<std::uint16_t> switchCounters;  // per object
  std::vector<std::uint32_t> lastRendered;    // objects rendered by the previous plan
  bool scannedFrontend = false;
  double lastTime = -std::numeric_limits<double>::infinity();
  // ASLOD hysteresis: each visible object's triangle allocation of the
  // previous step (by object; rewritten every aslod step).
  std::unordered_map<std::uint32_t, std::int64_t> aslodAllocations;
  // active-set (time_critical_scheduler.cpp): the previous step's resolution
  // per object (NaN: not rendered; the optimiser's warm start) and viewer
  // (for apparent speeds).
  std::vector<double> timeCriticalResolution;
  std::optional<ViewerState> timeCriticalViewer;

  void clearCaches() {
    for (ResourceCache& c : cache) {
      c.absolute.clear();
      c.relative.clear();
    }
  }
};

}  // namespace thinlod::backbone
