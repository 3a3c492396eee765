// Scheduler: one planning step of the backbone (facade of backbone/lib).
//
// Contract:
// - plan(scene, viewer, budget, state) picks one representation per visible
//   object and returns what to keep, send, request and remove. The scene must
//   have passed validateScene(); viewer, budget and config are checked here
//   (kInvalidArgument naming the field). Brute force returns
//   kResourceExhausted when the scene has too many combinations.
// - Budget: maxTriangles (triangles at the frontend), maxLinkBytesPerSecond
//   (a sent representation costs encodedBytes / plannedLifetime; bytes sent
//   over any window of plannedLifetime stay <= budget * window), and/or
//   fixedAccuracy (rad^-1). Budgets are hard caps on the plan of every step:
//   when even the cheapest representations do not fit, the least visible
//   objects are dropped (listed in Plan::dropped). With a fixed accuracy the
//   target is min(fixedAccuracy, the best accuracy within the budgets).
// - Accuracy semantics (paper 3.2-3.3): one uniform absolute target; an
//   object that cannot reach it renders its best (Plan::belowTarget).
// - PlannerState carries caches, hysteresis and in-flight requests from step
//   to step: use one per (scheduler, scene) pair, never shared between
//   threads. A Scheduler object is immutable after construction; plan() is
//   reentrant with distinct states.
// - Timing: Plan::row.schedulingMicroseconds is measured with steady_clock.
// - Methods: every selection method runs inside the same frame
//   (Scheduler::plan); schedulerCatalogue() lists them by name and
//   makeScheduler(name) builds one (a new method: selection_method.h).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "thinlod/backbone/allocation_schedulers.h"
#include "thinlod/backbone/decision_row.h"
#include "thinlod/backbone/pipeline.h"
#include "thinlod/backbone/time_critical_config.h"

namespace thinlod::backbone {

struct Budget {
  std::optional<double> maxTriangles;
  std::optional<double> maxLinkBytesPerSecond;
  // The link shaper's bucket (bytes; with maxLinkBytesPerSecond). Larger
  // than rate x plannedLifetime, it widens the link window to burst / rate:
  // a representation bigger than one lifetime's bytes can then go once the
  // window has room (docs/scheduling.md, "Link accounting").
  std::optional<double> linkBurstBytes;
  std::optional<double> fixedAccuracy;  // rad^-1
  // The modelled frame time at the frontend (seconds; Gobbetti-Bouvier). Only
  // methods with a frame-cost model take it (active-set); others answer
  // kUnsupported.
  std::optional<double> maxFrameSeconds;
};
Status validateBudget(const Budget& budget);

enum class ObjectAction : std::uint8_t {
  kKeep = 0,     // the frontend copy stays
  kSend = 1,     // send a copy the backbone already has
  kRequest = 2,  // ask the simplifier for a new representation
  kAwait = 3,    // a requested copy is on its way; nothing new
  kRemove = 4,   // the object gets nothing (culled, dropped, no option)
};
const char* objectActionName(ObjectAction action);

struct ObjectDecision {
  std::uint32_t object = 0;
  ObjectAction action = ObjectAction::kRemove;
  std::int32_t option = -1;
  OptionKind kind = OptionKind::kOriginalMesh;
  CandidateSource source = CandidateSource::kNew;
  double relativeAccuracy = 0.0;  // of the representation (to generate, sent or kept)
  double absoluteAccuracy = 0.0;  // guaranteed over the predicted region, rad^-1
  double triangles = 0.0;
  double linkBytes = 0.0;  // sent for this decision (0 for keep/await)
  bool belowTarget = false;
};

enum class RequestReason : std::uint8_t {
  kMissing = 0,       // no usable copy at the frontend
  kExpiring = 1,      // the copy's validity no longer covers the keep ball
  kInsufficient = 2,  // the copy is valid but not accurate enough
  kCheaper = 3,       // a cheaper representation frees budget
};

struct RepresentationRequest {
  std::uint64_t requestId = 0;
  std::uint32_t object = 0;
  std::uint32_t option = 0;
  OptionKind kind = OptionKind::kOriginalMesh;
  RequestReason reason = RequestReason::kMissing;
  double relativeAccuracy = 0.0;  // generate at least this accurate
  double expectedTriangles = 0.0;
  double expectedBytes = 0.0;
  Sphere viewRegion;  // viewpoints it must serve (the reach ball)
  double plannedLifetime = 0.0;
  double secondsToExpiry = 0.0;  // of the copy it replaces (0 when none/unusable)
  double accuracyGainPerByte = 0.0;
};

struct Removal {
  std::uint32_t object = 0;
  std::uint32_t option = 0;
  std::uint64_t copyId = 0;
};

struct PlanStats {
  std::uint32_t visitedNodes = 0;
  std::uint32_t culledNodes = 0;
  std::uint32_t visibleObjects = 0;
  std::uint32_t mergedGroups = 0;         // subtrees converted relative -> absolute once
  std::uint32_t curveReuses = 0;          // node curves taken from the cache
  std::uint32_t curveComputes = 0;        // node curves computed this step
  std::uint32_t solverEvaluations = 0;    // two-resource / fallback feasibility passes
  std::uint32_t lagrangianDecisions = 0;  // accuracies decided by the Lagrangian screen
  std::uint32_t paretoPasses = 0;         // exact two-resource passes
  std::uint32_t paretoThinnings = 0;      // > 0: the two-resource result may be below optimal
  std::uint32_t undecidedAccuracies = 0;  // > 0: pass limit hit, result may be below optimal
  std::uint32_t hysteresisKeeps = 0;      // copies kept although a cheaper one was chosen
  std::uint32_t budgetFillUpgrades = 0;   // leaves raised above the target by the budget fill
  std::uint32_t expiredCopiesKept = 0;    // unrendered leaves keeping a copy past its validity
  // Triangles of the selection when the budget fill began (accuracy-curve,
  // fill on; 0 otherwise): the plan's predictedTriangles is at least this.
  double trianglesBeforeFill = 0.0;
  bool usedExactSolver = false;
};

struct Plan {
  const char* scheduler = "";
  const char* mode = "";
  PredictedRegion region;
  double targetAccuracy = 0.0;       // rad^-1
  double achievedMinAccuracy = 0.0;  // min guaranteed accuracy over rendered objects
                                     // (expired copies, with none, left out)
  double predictedTriangles = 0.0;
  double linkBytesThisStep = 0.0;
  double linkBytesPerSecond = 0.0;              // linkBytesThisStep / plannedLifetime
  std::vector<ObjectDecision> decisions;        // visible objects, then removals
  std::vector<RepresentationRequest> requests;  // most urgent first
  std::vector<Removal> removals;
  std::vector<std::uint32_t> belowTarget;  // objects rendering their best, below target
  std::vector<std::uint32_t> dropped;      // visible objects given nothing to fit budgets
  PlanStats stats;
  DecisionRow row;
};

struct PlannerStateImpl;
class PlannerState {
 public:
  // Request ids (RepresentationRequest::requestId, then the copy's id) count
  // up from `firstRequestId` (> 0) and never repeat within one state, not
  // even across reset(): a caller may put them on the wire as they are.
  explicit PlannerState(std::uint64_t firstRequestId = 1);
  ~PlannerState();
  PlannerState(PlannerState&&) noexcept;
  PlannerState& operator=(PlannerState&&) noexcept;
  PlannerState(const PlannerState&) = delete;
  PlannerState& operator=(const PlannerState&) = delete;

  void reset();  // forget caches, history, the link log and in-flight requests (not the id counter)
  std::uint64_t stepsPlanned() const;
  std::size_t pendingRequests() const;
  // An id from the same counter for a request the caller makes outside a
  // plan (the daemon's startup curve requests), so ids never collide.
  std::uint64_t allocateRequestId();

  // The link log: Budget::maxLinkBytesPerSecond plans against the bytes
  // logged within the last plannedLifetime. A plan logs each send and
  // request at plan time with its estimated bytes under the copy/request id
  // (a reservation). A caller that ships the bytes settles them:
  // settleLinkSend replaces the reservations of `id` by the bytes that went
  // out at `timeSeconds` (or logs them when nothing was reserved);
  // releaseLinkReservation drops the reservations of `id` (nothing will be
  // shipped: a failed or replaced request). Settled entries are what the
  // caller's link let through, so planner and link cannot disagree about it.
  void settleLinkSend(std::uint64_t id, double timeSeconds, double bytes);
  void releaseLinkReservation(std::uint64_t id);
  struct LinkLogTotals {
    double settledBytes = 0.0;   // shipped, as the caller reported them
    double reservedBytes = 0.0;  // planned, not settled yet
  };
  // Entries logged after `afterSeconds` (plans prune those older than
  // plannedLifetime).
  LinkLogTotals linkLogAfter(double afterSeconds) const;
  PlannerStateImpl& impl() { return *impl_; }

 private:
  std::unique_ptr<PlannerStateImpl> impl_;
};

class SelectionMethod;  // private: backbone/src/lib/selection_method.h

// One planning step, the same for every selection method: validate, begin the
// step, predict the region, hard budget, the method's selection, hard-budget
// verification, plan building, timing. Only the selection differs.
class Scheduler {
 public:
  Scheduler(const SchedulerConfig& config, std::unique_ptr<const SelectionMethod> method);
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  const char* name() const;
  const SchedulerConfig& config() const { return config_; }
  // Replaces the config for the next steps (e.g. a measured generation
  // delay, delay_estimate.h); kInvalidArgument (config unchanged) when
  // validateConfig refuses it. Caches keyed by the config start over.
  Status setConfig(const SchedulerConfig& config);
  // kUnsupported when the method cannot honour this budget (greedy-fs93
  // without a polygon budget); plan() checks it too.
  Status accepts(const Budget& budget) const;
  Result<Plan> plan(const SchedulingScene& scene, const ViewerState& viewer, const Budget& budget,
                    PlannerState& state) const;

 private:
  SchedulerConfig config_;
  std::unique_ptr<const SelectionMethod> method_;
};

// The paper's method: accuracy curves, one uniform target, hysteresis.
Result<std::unique_ptr<Scheduler>> makeAccuracyCurveScheduler(const SchedulerConfig& config);

// VRML97-style static LOD: LOD levels by their range at the current viewer
// position, objects by distance bands (distance / diameter below
// bandDistanceOverDiameter[i] -> relative accuracy bandRelativeAccuracy[i],
// one more entry for beyond the last band). No prediction, no budgets.
struct VrmlStaticConfig {
  std::vector<double> bandDistanceOverDiameter{2.0, 8.0, 32.0};
  std::vector<double> bandRelativeAccuracy{200.0, 50.0, 12.0, 3.0};
};
Result<std::unique_ptr<Scheduler>> makeVrmlStaticScheduler(const SchedulerConfig& config,
                                                           const VrmlStaticConfig& vrml);

// Funkhouser-Sequin 1993 greedy cost/benefit under the polygon budget:
// benefit = (diameter / D) * a / (a + halfBenefitAccuracy), cost = triangles;
// each curve is sampled into levelsPerCurve levels; upgrades are taken in
// order of benefit gain per triangle while they fit.
struct GreedyConfig {
  int levelsPerCurve = 8;
  double halfBenefitAccuracy = 100.0;  // rad^-1
};
Result<std::unique_ptr<Scheduler>> makeGreedyScheduler(const SchedulerConfig& config,
                                                       const GreedyConfig& greedy);

// Enumerates every per-object and per-LOD choice and maximises the uniform
// target under the budgets (tests and benchmark only).
struct BruteForceConfig {
  double maxCombinations = 2.0e5;
};
Result<std::unique_ptr<Scheduler>> makeBruteForceScheduler(const SchedulerConfig& config,
                                                           const BruteForceConfig& brute);

// ------------------------------------------------------------- registry
// Every selection method by name, for --scheduler NAME (one name each; the
// alias is the short name older configs and scripts use).
struct SchedulerOptions {
  SchedulerConfig config;
  VrmlStaticConfig vrml;
  GreedyConfig greedy;
  BruteForceConfig bruteForce;
  AslodSchedulerConfig aslod;
  SpanOfLevelChangedConfig spanOfLevelChanged;
  TimeCriticalConfig timeCritical;
};

struct SchedulerEntry {
  const char* name;
  const char* alias;    // "" when none
  const char* summary;  // one line for --help
  bool forExperiments;  // true: tests and benchmarks only (not offered by the daemon)
};
const std::vector<SchedulerEntry>& schedulerCatalogue();
// Name or alias -> canonical name; kNotFound listing the known names.
Result<const char*> canonicalSchedulerName(const std::string& nameOrAlias);
Result<std::unique_ptr<Scheduler>> makeScheduler(const std::string& nameOrAlias,
                                                 const SchedulerOptions& options);
// "name (alias): summary" lines of the daemon's methods, for --help.
std::string schedulerHelp();

}  // namespace thinlod::backbone
