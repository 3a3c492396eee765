// Per-step pipeline pieces shared by every scheduler: viewer prediction,
// culling, relative -> absolute conversion, and the candidate
// representations of a leaf.
//
// Contract:
// - Units: metres, seconds, radians; accuracy in rad^-1 (absolute) or as a
//   fraction of the object's diameter (relative); resources in triangles and
//   encoded bytes.
// - predictRegion: the viewer can reach the ball (position, reachRadius)
//   before a representation requested now is replaced, with reachRadius =
//   maxSpeed * (plannedLifetime + linkDelay + generationDelay); the ball of
//   keepRadius = maxSpeed * (linkDelay + generationDelay + keepSlack) before
//   a replacement requested now could arrive (a displayed copy is kept while
//   it stays valid over that smaller ball). The view cone is the frustum's
//   bounding cone widened by maxAngularSpeed * the same time as reachRadius
//   (or viewConeHorizon when shorter).
// - classifySphere is conservative: kCulled only when no point of the sphere
//   can be seen from anywhere in the region; kInside only when all of it is
//   seen from everywhere in it.
// - conversionDistance D is the distance from a ball to a bounding sphere,
//   clamped below by minimalDistance (> 0); a_abs = a_rel * D / diameter.
// - Pure functions of their arguments; no allocation except into `out`.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "thinlod/backbone/scheduling_scene.h"
#include "thinlod/common/core/status.h"

namespace thinlod::backbone {

struct ViewerState {
  std::uint64_t frame = 0;
  double timeSeconds = 0.0;
  glm::dvec3 position{0.0};
  glm::dvec3 viewDirection{0.0, 0.0, -1.0};   // non-zero, need not be unit
  double horizontalFov = 1.0471975511965976;  // rad, full angle
  double verticalFov = 0.7853981633974483;    // rad, full angle
};

struct SchedulerConfig {
  // Prediction (paper 4.1 uses 0.1 m/s in a small room and ~1 s lifetime).
  double maxSpeed = 0.1;         // m/s (the paper's walking viewer; the daemon's --max-speed)
  double maxAngularSpeed = 1.0;  // rad/s
  double plannedLifetime = 1.0;  // s; also the link accounting window
  double linkDelay = 0.05;       // s
  double generationDelay = 0.1;  // s
  double keepSlack = 0.0;        // s added to the keep horizon
  // The view cone is widened by maxAngularSpeed times min(this, the reach
  // horizon). Infinity (the paper): every object the viewer could turn to
  // within a representation's planned lifetime is planned now. A shorter
  // time defers an object the viewer cannot turn to before a representation
  // requested at a later step could arrive (keep horizon plus one planning
  // step, docs/scheduling.md "Deferred visibility"): it is culled, its copy
  // removed, until it enters the narrower cone.
  double viewConeHorizon = std::numeric_limits<double>::infinity();  // s
  double minimalDistance = 0.1;  // m, lower clamp of D
  double maxViewDistance = std::numeric_limits<double>::infinity();  // m
  // Curve propagation: a group converts relative -> absolute once when
  // D >= mergeDistanceFactor * its diameter (paper 3.4 suggests ~1; the
  // guarantee then understates a child's accuracy by at most a factor
  // 1 + 1/mergeDistanceFactor; infinity disables).
  double mergeDistanceFactor = 4.0;
  // Reuse: merged subtree curves are computed for the region grown by
  // cacheDistanceMargin * D (and the cone by cacheAngleMargin) and reused
  // while the predicted region stays inside. 0 disables the growth.
  double cacheDistanceMargin = 0.05;
  double cacheAngleMargin = 0.05;  // rad
  // Group and LOD curves with many knots are replaced by an upper bound
  // within (1 + curveTolerance) of the exact resources (per tree level), so
  // a curve stays small however many leaves are below it. 0: exact curves.
  double curveTolerance = 0.002;
  // Stability (docs/scheduling.md, "Hysteresis"). All keep budgets hard.
  double budgetReserveShare = 0.05;  // share of each budget kept for keeping copies
  double preferCurrentShare = 0.15;  // keep a copy costing <= (1+share) x the best
  int switchDelaySteps = 2;          // keep a valid copy this many steps before a voluntary switch
  double targetHysteresis = 0.02;    // ignore target increases below this fraction
  double rangeHysteresis = 0.0;      // m: a new kind must fit the region grown by this
  // Two-resource solver (docs/scheduling.md): a Lagrangian screen decides
  // most accuracies; the rest get an exact Pareto pass, at most
  // maxParetoPasses per plan, with per-node sets thinned above paretoCap.
  // Either limit can only lower the answer (never break a budget); both are
  // counted in PlanStats.
  int paretoCap = 64;
  int maxParetoPasses = 16;
  // Speed only, never the plan: true reuses per-step and per-leaf work of
  // the accuracy-curve scheduler (the push-down's candidates in the
  // hysteresis pass, cached leaf envelopes while a leaf's candidates are
  // unchanged, scratch buffers kept across steps). false is the slower
  // reference path kept so bench_scheduler can check, in the same run, that
  // both give identical plans (docs/scheduling.md).
  bool reuseLeafWork = true;
  // Accuracy-curve method: after the uniform target, spend the rest of the
  // hard budget where the image gains most (docs/scheduling.md "Budget fill").
  bool fillBudget = true;
  // A fill round raises a leaf at most kMaxFillRungs rungs of its ladder
  // (about 3.2x its triangles); further rounds start from the raised picks
  // while the previous one moved something, up to this many (1..16).
  int fillRounds = 3;
  // Budget fill's image error per leaf: (size)^2 * (1 / a + w / sqrt(a)),
  // size = diameter / distance. The first term is the silhouette (the
  // geometric error the accuracy measures); the second, with this weight,
  // stands for shading: a faceted curved surface turns its normals by about
  // sqrt(2 d / R) for a deviation d on a radius R, so 1 / sqrt(a) in the
  // leaf frame, over the whole projected area. 0: silhouette only.
  double fillShadingWeight = 0.0;
};

Status validateConfig(const SchedulerConfig& config);
// `config` with every approximation and stability device off (no merging, no
// cache growth, exact curves, unlimited Pareto passes, no reserve, no
// preference for current copies, no delays or hysteresis, no budget fill): the plain model
// of the paper, whose target the brute-force scheduler reproduces exactly.
// Prediction settings (speeds, lifetime, delays, distances) are kept.
SchedulerConfig withoutApproximations(SchedulerConfig config);
Status validateViewer(const ViewerState& viewer);

struct PredictedRegion {
  glm::dvec3 center{0.0};
  double reachRadius = 0.0;
  double keepRadius = 0.0;
  glm::dvec3 viewDirection{0.0, 0.0, -1.0};  // unit
  double viewHalfAngle = 0.0;                // rad; >= pi: every direction
  double maxViewDistance = std::numeric_limits<double>::infinity();

  Sphere reachBall() const { return {center, reachRadius}; }
  Sphere keepBall() const { return {center, keepRadius}; }
};

PredictedRegion predictRegion(const ViewerState& viewer, const SchedulerConfig& config);
// The region grown by a distance (both radii) and an angle.
PredictedRegion growRegion(const PredictedRegion& region, double distance, double angle);
// True when every position/direction of `inner` is one of `outer`.
bool regionContains(const PredictedRegion& outer, const PredictedRegion& inner);

enum class Visibility : std::uint8_t { kCulled = 0, kPartial = 1, kInside = 2 };
Visibility classifySphere(const PredictedRegion& region, const Sphere& bounds);

double conversionDistance(const glm::dvec3& center, double radius, const Sphere& bounds,
                          double minimalDistance);

// ---- Candidate representations of one leaf object ----

enum class CandidateSource : std::uint8_t {
  kNew = 0,           // generate (simplifier) and send
  kFrontendCopy = 1,  // keep the displayed copy
  kBackboneCopy = 2,  // send an already generated copy
  kPending = 3,       // a requested copy that is on its way
};
const char* candidateSourceName(CandidateSource source);

// A copy this planner requested that has not been confirmed at the frontend.
struct PendingCopy {
  std::uint32_t option = 0;  // index into SchedulingScene::options
  std::uint64_t requestId = 0;
  double relativeAccuracy = 0.0;
  double triangles = 0.0;
  double encodedBytes = 0.0;
  Sphere servesRegion;  // the reach ball it was generated for
  double issuedAt = 0.0;
};

struct LeafCandidate {
  std::uint32_t option = 0;
  CandidateSource source = CandidateSource::kNew;
  const RepresentationOption* representation = nullptr;
  // Highest relative accuracy it reaches in the leaf's frame (absolute
  // accuracy = a_rel * D_reach / diameter).
  double maxRelativeAccuracy = 0.0;
  double fixedTriangles = 0.0;  // copies: what they cost
  double fixedLinkBytes = 0.0;
  std::uint64_t copyId = 0;
};

struct CandidateCost {
  double triangles = 0.0;
  double linkBytes = 0.0;
};
// Precondition: relativeAccuracy <= candidate.maxRelativeAccuracy.
CandidateCost candidateCost(const LeafCandidate& candidate, double relativeAccuracy);

// kExact: candidates for exactly `region` (copies are credited with the
// accuracy they have over the keep ball, pending copies count). kConservative:
// valid for every region inside `region` (used for cached curves): copies get
// no keep credit and pending copies are ignored.
enum class CandidateContext : std::uint8_t { kExact = 0, kConservative = 1 };

// `bounds` is the leaf's sphere; the leaf frame uses D = conversionDistance
// of the reach ball. `pending` (may be null) holds this object's in-flight
// copies.
void collectLeafCandidates(const SchedulingScene& scene, std::uint32_t object,
                           const PredictedRegion& region, const SchedulerConfig& config,
                           CandidateContext context, const std::vector<PendingCopy>* pending,
                           const Sphere& bounds, std::vector<LeafCandidate>& out);

}  // namespace thinlod::backbone
