// Exact uniform-accuracy solver on the visible tree, for two resources at
// once and as the fallback of the curve path (private).
//
// For a target a, every node gets the set of (triangles, link bytes) totals
// it can be rendered with at accuracy a (same clamping as the curves: a node
// renders min(a, its best)): a leaf's candidates, a Group's pairwise sums, an
// LOD's union over levels reaching it. Dominated points and points above a
// budget are dropped, so the root set is non-empty iff some choice of one
// representation per object and one level per LOD meets both budgets at a
// (exact while no set exceeds paretoCap; larger sets are thinned, which can
// only make the answer lower, never over budget). Feasibility is monotone in
// a, so maximise() bisects (geometric, relative tolerance 1e-11). With a
// single budget feasibility is "the cheapest choice fits": O(visible nodes).
// With two, a Lagrangian screen first: the choice minimising
// triangles + w * link for a weight w either fits both budgets (a feasible
// certificate) or its value exceeds budgetT + w * budgetL (a proof that
// nothing fits); only accuracies it leaves undecided get a Pareto pass.
// With two, the single-budget optima bound the answer from above first, and
// Pareto partial sums are pruned against the budget minus the least the rest
// of the tree needs (exact: such points cannot be part of a feasible choice).
#pragma once

#include <optional>
#include <vector>

#include "selection.h"

namespace thinlod::backbone {

struct JointBudget {
  bool useTriangles = false;
  bool useLink = false;
  double triangles = std::numeric_limits<double>::infinity();
  double linkBytes = std::numeric_limits<double>::infinity();
};

class JointSolver {
 public:
  JointSolver(const SchedulingScene& scene, const SchedulerConfig& config,
              const PredictedRegion& region, const PlannerStateImpl& state,
              const JointBudget& budget, PlanStats& stats);

  bool anythingVisible() const { return leafCount_ > 0; }
  double lowestAccuracy() const;
  double highestAccuracy() const;
  bool feasible(double accuracy);
  // Drops the least visible leaves (lowest keepPriority, scheduler_common.h)
  // until the cheapest plan fits; returns how many. Leaves that cost nothing
  // in every budget the cheapest plan overruns (a held copy when the link is
  // what overruns) are dropped only if dropping all the others is not enough.
  std::size_t dropUntilFeasible(const ViewerState& viewer);
  // The largest feasible accuracy <= cap, or nullopt when even the cheapest
  // plan does not fit. `hint` (optional) narrows the bisection.
  std::optional<double> maximise(std::optional<double> cap, std::optional<double> hint);
  // Selections of a feasible accuracy (visible leaves of chosen levels).
  void extract(double accuracy, std::vector<LeafSelection>& out);

 private:
  struct Node {
    SceneNodeKind kind = SceneNodeKind::kGroup;
    std::uint32_t sceneNode = 0;
    std::uint32_t firstChild = 0;  // into children_
    std::uint32_t childCount = 0;
    std::uint32_t firstCandidate = 0;  // into candidates_
    std::uint32_t candidateCount = 0;
    std::uint32_t firstStage = 0;  // into stages_ (groups)
    double distance = 0.0;
    double diameter = 0.0;
    double maxAccuracy = 0.0;  // absolute; -inf: renders nothing
    double minAccuracy = 0.0;
    bool dropped = false;
  };
  struct Point {
    double triangles;
    double link;
    std::int32_t from;   // leaf: candidate; LOD: child position; group: previous stage index
    std::int32_t child;  // LOD/group: index in the child's set
    std::int32_t tie;    // prefers copies among equal costs
  };
  struct Span {
    std::uint32_t begin = 0;
    std::uint32_t size = 0;
  };

  std::int32_t build(std::uint32_t sceneNode, bool parentInside);
  void refreshAccuracyBounds();
  // Fewest triangles / bytes of each subtree at `accuracy` (each resource
  // alone): the rest of the tree needs at least that much, which bounds
  // what a partial sum may use.
  // Per-accuracy preparation: each leaf candidate's cost (NaN when it does
  // not reach what the clamping asks) and which LOD levels qualify.
  void prepareCosts(std::uint32_t k, double accuracy);
  void computeMinima(std::uint32_t k);
  // Totals of the choice minimising triangles + weight * link (weight
  // +infinity: link first); from prepared costs.
  void scalarPass(std::uint32_t k, double weight, double& triangles, double& link);
  // reuseLeafWork: records node k's totals and whether its choice is the
  // same for every weight (then later passes of this accuracy reuse them).
  void markInvariant(std::uint32_t k, double t, double l);
  void extractScalar(std::uint32_t k, double accuracy, double weight,
                     std::vector<LeafSelection>& out);
  enum class Verdict : std::uint8_t { kFeasible, kInfeasible, kUnknown };
  Verdict lagrangianScreen(double& certificateWeight);
  bool paretoFeasible(double accuracy);
  Span evaluate(std::uint32_t k, double accuracy, double limitTriangles, double limitLink);
  Span finish(std::uint32_t begin, double limitTriangles, double limitLink);
  std::optional<double> search(double lo, double hi, std::optional<double> hint);
  void reportNothing(std::uint32_t k, bool underLod, std::vector<LeafSelection>& out) const;
  void extractNode(std::uint32_t k, double accuracy, std::uint32_t index,
                   std::vector<LeafSelection>& out);

  const SchedulingScene& scene_;
  const SchedulerConfig& config_;
  const PredictedRegion& region_;
  const PlannerStateImpl& state_;
  JointBudget budget_;
  PlanStats& stats_;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> children_;
  std::vector<LeafCandidate> candidates_;
  std::vector<Point> arena_;
  std::vector<Span> nodeSet_;
  std::vector<Span> stages_;
  std::vector<double> minTriangles_;
  std::vector<double> minLink_;
  // reuseLeafWork: the curves of every new-representation candidate copied
  // once per solver into one pool in tree order, so the ~40 prepareCosts
  // passes of a bisection read contiguous memory instead of two scattered
  // heap blocks per candidate (same values: curveCost mirrors resourcesFor).
  struct PooledCurve {
    std::uint32_t begin = 0;
    std::uint32_t count = 0;  // 0: empty curve
    double maxAccuracy = 0.0;
  };
  struct PooledCosts {
    PooledCurve triangles;
    PooledCurve link;
  };
  PooledCurve poolCurve(const AccuracyCurve& curve);
  double curveCost(const PooledCurve& curve, double accuracy) const;
  std::vector<CurveSegment> segmentPool_;
  std::vector<PooledCosts> pooled_;    // per candidate (copies: unused)
  std::vector<double> costTriangles_;  // per candidate, for the prepared accuracy
  std::vector<double> costLink_;
  std::vector<std::uint8_t> levelOk_;  // per children_ entry of LODs
  std::vector<double> scalarT_;
  std::vector<double> scalarL_;
  std::vector<std::int32_t> scalarPick_;  // leaf: candidate; LOD: child position
  std::vector<std::uint8_t> invariant_;   // per node: choice independent of the weight
  bool invariantReady_ = false;           // invariant_ / scalarT_ / scalarL_ hold this accuracy's
  int paretoPasses_ = 0;
  // How the last feasible() call decided: a scalar weight, or Pareto.
  bool lastByScalar_ = false;
  double lastWeight_ = 0.0;
  std::size_t leafCount_ = 0;
  std::int32_t root_ = -1;
};

}  // namespace thinlod::backbone
